"""The static solvers' Cholesky factorisations side by side: CHOLMOD (cvxopt) and MKL PARDISO.

For each mesh of square-pedestal: the free-dof tangent at the flat sheet (the static solver's own
assembly, linear.LowerCSC), then numeric factorisation and one solve by each factorisation,
interleaved, ``--repeat`` times; medians, their ratio, the factor's fill where it is known and the
largest difference of the two solutions.  The fill-reducing analysis is done once per
factorisation before timing (as in a solve: once per pattern).

Run:  python benchmarks/factorizations.py [--meshes 12x4x4 24x8x4 48x16x4] [--repeat 9]
Not part of the test run (~10 s).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np


def tangent(density):
    from solidshell.scenes import load
    from solidshell.scenes.build import build_problem, build_scene_mesh
    from solidshell.solvers.static.system import System

    sc = load("square-pedestal")
    mesh = build_scene_mesh(sc, density)[0]
    pb = build_problem(sc, mesh)
    sys_ = System(pb.model, pb.fixed, pb.loads, pb.prescribed, pb.contact, None, "cholmod")
    return sys_.free_tangent(np.zeros(6 * mesh.n_nodes))[1]


def main(argv=None):
    from solidshell.solvers import pardiso
    from solidshell.solvers.linear import positive_definite_factor

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=["12x4x4", "24x8x4", "48x16x4"])
    ap.add_argument("--repeat", type=int, default=9)
    a = ap.parse_args(argv)
    kinds = ["cholmod"] + (["pardiso"] if pardiso.available() else [])
    if len(kinds) == 1:
        print(f"PARDISO not compared: {pardiso.unavailable_reason()}")
    print(f"load average before: {' '.join(open('/proc/loadavg').read().split()[:3])}")
    print(
        "| free dofs (mesh) | "
        + " | ".join(f"{k} factor / solve [ms]" for k in kinds)
        + " | factor ratio | max |dx| / |x| |"
    )
    print("|---" * (len(kinds) + 3) + "|")
    for d in a.meshes:
        A = tangent(d)
        n = A.shape[0]
        b = np.random.default_rng(0).standard_normal(n)
        facs = {k: positive_definite_factor(k) for k in kinds}
        for f in facs.values():
            if not f.factor(A):
                raise SystemExit(f"{d}: the flat-sheet tangent is not positive definite")
        tf = {k: [] for k in kinds}
        ts = {k: [] for k in kinds}
        x = {}
        for _ in range(a.repeat):
            for k, f in facs.items():
                t = time.perf_counter()
                f.factor(A)
                tf[k].append(time.perf_counter() - t)
                t = time.perf_counter()
                x[k] = f.solve(b)
                ts[k].append(time.perf_counter() - t)
        med = {k: (1e3 * np.median(tf[k]), 1e3 * np.median(ts[k])) for k in kinds}
        ratio = med[kinds[-1]][0] / med["cholmod"][0]
        dx = max(np.abs(x[k] - x["cholmod"]).max() for k in kinds) / np.abs(x["cholmod"]).max()
        print(
            f"| {n} ({d}) | "
            + " | ".join(f"{med[k][0]:.2f} / {med[k][1]:.2f}" for k in kinds)
            + f" | {ratio:.2f} | {dx:.1e} |"
        )
    print(
        f"load average after: {' '.join(open('/proc/loadavg').read().split()[:3])}; "
        f"threads: NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')}, "
        "PARDISO sequential"
    )


if __name__ == "__main__":
    main()
