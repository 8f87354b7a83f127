"""What the sheet's self-contact costs in the explicit loop (contact_self_penalty.py), and how often
its penalty lets layers through.

Three parts, each printing the load average:

* ``scaling``: two sheets resting on each other 0.8 h apart (every node of both in contact: the
  heaviest case) with 10^3 ... 10^5 nodes: one candidate search [ms], one force pass [us], the
  candidates and pairs in contact, and the pass's cost per node -- near-linear growth shows as a
  flat last column.
* ``loop``: the sphere scene (Sec. 4.2, 30 x 30 cm wool, friction 0.3) relaxed on an n x n mesh
  with self-contact on, then two integrators take the same relaxation steps from that draped
  state, interleaved in rounds so that both see the same machine load: with and without
  self-contact.  Printed: element-steps per second of each and the self-contact's share of a step.
* ``drops``: random drops (height, angle, place) of a 6 cm sheet onto a 10 cm one on a floor,
  relaxed; counted: runs ending with intersecting triangle pairs (layers.self_intersections: the
  IPC Toolkit's test, no code shared with the penalty) -- the penalty's failure rate.
* ``full`` (not run by default: minutes): the sphere n x n relaxation from the flat sheet, whole,
  with and without self-contact: wall times, steps, DC and folds, self-intersections.

    python benchmarks/self_contact_cost.py [--parts scaling,loop,drops] [--n 100] [--drops 20]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import time

import numpy as np

from solidshell import Fabric, Model
from solidshell.boundary import gravity_loads
from solidshell.contact import Plane
from solidshell.contact_self_penalty import SelfPenalty
from solidshell.layers import self_intersections
from solidshell.mesh import ShellMesh
from solidshell.meshing import square
from solidshell.problem import Problem

H = Fabric.wool().thickness


def load() -> str:
    return "load average " + " ".join(f"{v:.2f}" for v in os.getloadavg())


def turned(nodes, deg: float, shift) -> np.ndarray:
    th = math.radians(deg)
    R = np.array([[math.cos(th), -math.sin(th), 0], [math.sin(th), math.cos(th), 0], [0, 0, 1]])
    return nodes @ R.T + np.asarray(shift, dtype=float)


def stacked(n: int, spacing: float = 0.3):
    """Two n x n sheets, the upper turned 10 degrees, references 1 cm apart, U puts them 0.8 h apart."""
    a = square((n, n), size=spacing * n)  # elements of one size (5 h) at every n: the same local work
    XB = turned(a.nodes, 10.0, (0.0, 0.0, 1.0))
    mesh = ShellMesh(np.vstack([a.nodes, XB]), np.vstack([a.quads, a.quads + a.n_nodes]))
    U = np.zeros((mesh.n_nodes, 6))
    U[a.n_nodes :, 2] = 0.8 * H - 1.0
    return mesh, U


def scaling(reps: int = 5) -> None:
    print(f"\nscaling: two resting layers 0.8 h apart ({load()})")
    print("| nodes | search [ms] | pass [us] | candidates | in contact | pass per node [ns] |")
    print("|---|---|---|---|---|---|")
    for n in (22, 70, 223):
        mesh, U = stacked(n)
        sp = SelfPenalty(mesh, H, 1.0)
        D = U.ravel().copy()
        C = np.zeros_like(D)
        sp.add_forces(D, C)  # compile, first search
        x = np.ascontiguousarray(mesh.nodes + U[:, :3])
        ts, tp = [], []
        for _ in range(reps):
            t = time.perf_counter()
            sp.search(x)
            ts.append(time.perf_counter() - t)
            t = time.perf_counter()
            for _ in range(20):
                _, n_act = sp.add_forces(D, C)
            tp.append((time.perf_counter() - t) / 20)
        N = mesh.n_nodes
        p = statistics.median(tp)
        print(
            f"| {N} | {1e3 * statistics.median(ts):.2f} | {1e6 * p:.0f} | {len(sp.vf)} | {n_act} | {1e9 * p / N:.0f} |"
        )


def loop(n: int, steps: int, rounds: int) -> None:
    from solidshell.run import run_scene
    from solidshell.solvers.explicit import Integrator
    from solidshell.solvers.explicit.settings import RELAX_PRESETS

    t0 = time.perf_counter()
    out = run_scene("sphere", mesh=f"{n}x{n}", out_dir=None, progress=False, overrides={"self_contact.enabled": True})
    print(
        f"\nloop: sphere {n}x{n} draped with self-contact in {time.perf_counter() - t0:.0f} s: DC "
        f"{out.summary['drape_coefficient']:.4f}, {out.summary['fold_count']} folds, self-intersections "
        f"{out.summary.get('self_intersections')}, most pairs in contact {out.summary.get('self_contact_max_pairs')}"
    )
    on = out.problem
    off = Problem(on.model, on.fixed, on.loads, on.prescribed, on.contact, on.name, self_contact=False)
    U = np.asarray(out.U, float).reshape(-1, 6)
    s = {**RELAX_PRESETS["fast"], "U0": U, "max_steps": 10 * steps * rounds, "check_every": 10 * steps * rounds}
    integ = {"self-contact": Integrator(on, s, relax=True), "without": Integrator(off, s, relax=True)}
    for it in integ.values():
        it.advance(5)
    wall: dict[str, list[float]] = {k: [] for k in integ}
    for _ in range(rounds):
        for k, it in integ.items():
            t = time.perf_counter()
            it.advance(steps)
            wall[k].append(time.perf_counter() - t)
    M = on.model.mesh.n_elements
    rate = {k: M * steps / statistics.median(v) for k, v in wall.items()}
    sc = integ["self-contact"].forces.selfc
    print(
        f"  {M} elements, {rounds} rounds of {steps} steps ({load()}): with self-contact "
        f"{rate['self-contact'] / 1e6:.2f} M element-steps/s, without {rate['without'] / 1e6:.2f} M; share of a "
        f"step {1 - rate['self-contact'] / rate['without']:.1%}; margin {sc.margin / H:.2f} h, "
        f"{sc.searches} searches, {len(sc.vf)} candidates"
    )


def _stack(n, drop, turn, shift, on=True):
    a, b = square((n, n), size=10.0), square((n, n), size=6.0)
    XB = turned(b.nodes, turn, (shift[0], shift[1], drop))
    mesh = ShellMesh(np.vstack([a.nodes, XB]), np.vstack([a.quads, b.quads + a.n_nodes]))
    model = Model(mesh, Fabric.wool())
    N = mesh.n_nodes
    return Problem(model, np.zeros((N, 6), bool), gravity_loads(model), contact=[Plane((0, 0, 0))], self_contact=on)


def drops(count: int, seed: int = 0) -> None:
    from solidshell.solvers.explicit import run_relax

    rng = np.random.default_rng(seed)
    print(f"\ndrops: {count} random drops of a 6 cm sheet (12x12) onto a 10 cm one (12x12) on a floor ({load()})")
    bad, t0 = 0, time.perf_counter()
    for i in range(count):
        drop, turn = rng.uniform(0.2, 5.0), rng.uniform(0.0, 90.0)
        sx, sy = rng.uniform(-2.0, 2.0, 2)
        prob = _stack(12, drop, turn, (sx, sy))
        res = run_relax(prob, {"t_max": 1.5})
        k = len(self_intersections(prob.model.mesh, res.U))
        bad += k > 0
        print(f"  drop {i + 1}: height {drop:.2f} cm, turn {turn:.0f} deg, at ({sx:.2f}, {sy:.2f}): {k} crossing pairs")
    print(f"  {bad} of {count} ended with layers through each other ({time.perf_counter() - t0:.0f} s)")


def full(n: int) -> None:
    from solidshell.run import run_scene

    print(f"\nfull: sphere {n}x{n} relaxation from the flat sheet ({load()})")
    for on in (False, True):
        t = time.perf_counter()
        out = run_scene("sphere", mesh=f"{n}x{n}", out_dir=None, progress=False, overrides={"self_contact.enabled": on})
        s = out.summary
        print(
            f"  self-contact {'on ' if on else 'off'}: {time.perf_counter() - t:.0f} s, {s['steps']} steps, DC "
            f"{s['drape_coefficient']:.4f}, {s['fold_count']} folds, self-intersections {s.get('self_intersections')},"
            f" min layer gap {s.get('min_layer_gap')} ({load()})"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parts", default="scaling,loop,drops", help="comma list of scaling, loop, drops, full")
    ap.add_argument("--n", type=int, default=100, help="the sphere's mesh n x n (loop, full)")
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--drops", type=int, default=20)
    a = ap.parse_args()
    parts = a.parts.split(",")
    if "scaling" in parts:
        scaling()
    if "loop" in parts:
        loop(a.n, a.steps, a.rounds)
    if "drops" in parts:
        drops(a.drops)
    if "full" in parts:
        full(a.n)


if __name__ == "__main__":
    main()
