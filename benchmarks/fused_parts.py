"""Per-part cost of the explicit loop's element pass on an adapted mesh, triangles by core and by lanes.

An adapted ``square-pedestal`` mesh (level 0 6x2x4, three rounds of random splits, seed 1: about
930 quads, "ans" where coarse and "full" at the finest level, and 147 transition triangles) at a
random sagging state.  Two FusedForces on it: ``core`` with the triangles through core.energy_force
(which needs Model._current every step: the state before elements/lanes_tri.py) and ``lanes`` with
them through lanes_tri.  Per pass (``--passes``, default 5, alternating the two so that the
machine's drift hits both), each part's kernel alone (ns per element), ``_current`` and the whole
element_pass; the table gives the medians.  Run with one numba thread for per-element costs:

    NUMBA_NUM_THREADS=1 python benchmarks/fused_parts.py [--passes 5] [--calls 300]

(Started from /work/dbg/s7/fusedbench.py, the lead's measurement; prints only, writes nothing.)
"""

from __future__ import annotations

import argparse
import os
import time
from unittest import mock

import numpy as np
from numba import get_num_threads

from solidshell.adapt.background import BackgroundMesh
from solidshell.adapt.forest import AdaptiveMesh
from solidshell.elements import core, lanes_tri
from solidshell.scenes import load
from solidshell.scenes.build import build_problem, build_scene_mesh
from solidshell.solvers.explicit.fused import FusedForces


def adapted_problem():
    sc = load("square-pedestal")
    lvl0, _ = build_scene_mesh(sc, "6x2x4")
    bg = BackgroundMesh.from_level0(lvl0, 3, None)
    f = AdaptiveMesh(bg)
    rng = np.random.default_rng(1)
    for _ in range(3):
        sel = np.array([(lv, e) for lv, e in f.leaves() if lv < 3])
        f.split(sel[rng.random(len(sel)) < 0.45])
    act = f.active_mesh()
    m = act.mesh
    coarse = act.elem_leaf[: len(m.quads), 0] < 3
    prob = build_problem(sc, m, membrane=np.where(coarse, "ans", "full").tolist())
    D6 = np.zeros((m.n_nodes, 6))
    D6[:, 2] = -0.01 * rng.random(m.n_nodes)
    return prob, D6


def timeit(fn, n):
    fn()
    t = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t) / n


def part_timers(ff, D6):
    """[(label, elements, callable)] for each part's kernel alone, as element_pass calls it."""
    xo, xn, Uc = ff.model._current(D6)
    out = []
    for (kind, b, pk, _, _), (fe, we) in zip(ff.parts, ff.views):
        if kind == "lanes":
            label = pk["kernel"].__name__

            def fn(pk=pk, fe=fe, we=we):
                return pk["kernel"](
                    ff.X,
                    ff.Xn,
                    D6,
                    pk["conn"],
                    pk["Cmb"],
                    pk["Cs"],
                    pk["Cz"],
                    pk["r_z"],
                    ff.quasi,
                    ff.mu,
                    pk["xs"],
                    pk["fe"],
                    we,
                    pk["bounds"],
                    pk["dest"],
                    ff.F_all,
                    False,
                )
        else:
            label = f"core({b.module.__name__.rsplit('.', 1)[1]})"

            def fn(b=b, fe=fe, we=we):
                return core.energy_force(*b.args(xo, xn, Uc, ff.quasi, ff.mu), fe, we, get_num_threads())

        out.append((label, len(b.conn), fn))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--passes", type=int, default=5)
    ap.add_argument("--calls", type=int, default=300)
    a = ap.parse_args()
    prob, D6 = adapted_problem()
    m = prob.model.mesh
    with mock.patch.object(lanes_tri, "covers", lambda c: False):
        ff_core = FusedForces(prob.model)
    ff_lanes = FusedForces(prob.model)
    assert ff_core.needs_current and not ff_lanes.needs_current
    for ff in (ff_core, ff_lanes):
        ff.element_pass(D6)
    F0, E0 = ff_core.internal(D6.ravel(), True)
    F1, E1 = ff_lanes.internal(D6.ravel(), True)
    print(
        f"nodes {m.n_nodes}, quads {len(m.quads)}, triangles {len(m.tris)}, numba threads {get_num_threads()}, "
        f"load before {os.getloadavg()}"
    )
    print(
        f"lanes vs core triangles: |dF| / |F| = {np.abs(F1 - F0).max() / np.abs(F0).max():.1e}, "
        f"dE / E = {abs(E1 - E0) / abs(E0):.1e}"
    )
    rows = {}
    timers = {name: part_timers(ff, D6) for name, ff in (("core", ff_core), ("lanes", ff_lanes))}
    for _ in range(a.passes):
        for name, ff in (("core", ff_core), ("lanes", ff_lanes)):
            rows.setdefault((name, "element_pass", 0), []).append(timeit(lambda: ff.element_pass(D6), a.calls))
            for label, M, fn in timers[name]:
                rows.setdefault((name, label, M), []).append(timeit(fn, a.calls))
            if name == "core":
                rows.setdefault((name, "_current", 0), []).append(timeit(lambda: prob.model._current(D6), a.calls))
    print(f"{'path':6s} {'part':20s} {'elements':>8s} {'us (median)':>12s} {'ns/element':>11s}   passes (us)")
    for (name, label, M), ts in rows.items():
        t = float(np.median(ts))
        per = f"{t / M * 1e9:11.1f}" if M else " " * 11
        print(f"{name:6s} {label:20s} {M or '':>8} {t * 1e6:12.1f} {per}   " + " ".join(f"{x * 1e6:.0f}" for x in ts))
    ep = {n: float(np.median(rows[(n, "element_pass", 0)])) for n in ("core", "lanes")}
    print(f"element_pass lanes / core = {ep['lanes'] / ep['core']:.3f};  load after {os.getloadavg()}")


if __name__ == "__main__":
    main()
