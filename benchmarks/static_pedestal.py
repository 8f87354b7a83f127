"""Static solvers on a drape with folds: Section 3.3's circular sheet on a circular pedestal.

For each solver setting: converged?, iterations, factorisations, wall time (and its ratio to the
default solver measured in this run), the stability of the final state (positive definite tangent,
smallest eigenvalue) and the drape measures (drape coefficient, fold count).  The drape is
multi-stable (the paper gets 4 or 8 folds depending on lambda of Eq. 18), so different solvers may
legitimately land on different stable states; a state with an indefinite tangent is a saddle, not a
drape.

Run:  python benchmarks/static_pedestal.py [--scene-mesh 10x40] [--json out.json]
Not part of the test run (about a minute on 10x40).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

SETTINGS = [
    ("newton (default)", dict(method="newton")),
    ("paper Eq. 18, c = 1e-2", dict(method="paper", c=1e-2)),
    ("paper Eq. 18, c = 2e-2", dict(method="paper", c=2e-2)),
    ("arc-length", dict(method="arclength")),
]


def main(argv=None):
    from solidshell.analysis import drape_summary
    from solidshell.boundary import clamp, gravity_loads
    from solidshell.material import Fabric
    from solidshell.meshing import build_mesh
    from solidshell.model import Model
    from solidshell.solvers.static import solve_static

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="10x40")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    mesh = build_mesh("disc_on_disc", a.mesh)
    model = Model(mesh, Fabric.wool())
    fixed, P = clamp(mesh, "clamped"), gravity_loads(model)
    ped = np.pi * 12.7**2 / 4
    model.force_and_tangent(np.zeros((mesh.n_nodes, 6)))  # warm-up (numba), not timed
    rows = []
    t_ref = None
    print(f"disc 25.4 on pedestal 12.7 cm, mesh {a.mesh} ({mesh.n_elements} quads)")
    print(
        f"{'solver':26} {'conv':>5} {'iters':>6} {'factor':>6} {'time [s]':>8} {'x dflt':>6} "
        f"{'PD':>5} {'min eig':>9} {'DC':>6} {'folds':>5}"
    )
    for name, kw in SETTINGS:
        t0 = time.perf_counter()
        r = solve_static(model, fixed, P, **kw)
        wall = time.perf_counter() - t0
        t_ref = wall if t_ref is None else t_ref
        s = drape_summary(mesh, r.U, pedestal_area=ped, center=(0.0, 0.0))
        row = dict(
            solver=name,
            converged=r.converged,
            iterations=r.info["iterations"],
            factorizations=r.info["factorizations"],
            wall_time_s=wall,
            time_ratio_to_default=wall / t_ref,
            positive_definite=r.info.get("positive_definite"),
            min_tangent_eigenvalue=r.info.get("min_tangent_eigenvalue"),
            drape_coefficient=s["drape_coefficient"],
            fold_count=s["fold_count"],
        )
        rows.append(row)
        me = row["min_tangent_eigenvalue"]
        print(
            f"{name:26} {str(r.converged):>5} {row['iterations']:6d} {row['factorizations']:6d} "
            f"{wall:8.2f} {wall / t_ref:6.2f} {str(row['positive_definite']):>5} "
            f"{(me if me is not None else float('nan')):9.2e} {row['drape_coefficient']:6.3f} "
            f"{row['fold_count']:5d}",
            flush=True,
        )
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return rows


if __name__ == "__main__":
    main()
