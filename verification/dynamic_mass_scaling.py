"""What director-only mass scaling costs in a true dynamic drape (Section 4.1 scene).

The 20 x 20 cm wool sheet hung by two adjacent corners falls from rest under gravity (alpha =
5 1/s).  It is run unscaled and with only the director (U_n) masses scaled by s = 10, 100, 1000
(``mass_scaling_mode="director"``): the thickness mode that limits the step is slowed by sqrt(s),
while the translational masses -- the weight's inertia -- are untouched.  Uniform scaling (the
paper's relaxation setting) is not a dynamic option: it slows the whole motion by sqrt(s).

Printed per s: the step, the number of steps, the wall time relative to the unscaled run (a ratio
inside one run), and the largest difference of any node's position from the unscaled run at each
snapshot, relative to the largest displacement then.  This is a self-convergence comparison (the
unscaled run is the reference for the *scaling* error only), not an independent reference.

    python -m verification.dynamic_mass_scaling [--n 20] [--t-end 0.2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from solidshell import Fabric
from solidshell.boundary import clamp, gravity_loads
from solidshell.meshing import build_mesh
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers import explicit

from . import write_json


def hung_sheet(n: int, size: float = 20.0) -> Problem:
    """The Section 4.1 sheet: size x size cm wool, n x n quads, the two corners at y = +size/2 held
    (all six dofs), self-weight -- built from the library's scene pieces."""
    mesh = build_mesh("square", f"{n}x{n}", size=size)
    model = Model(mesh, Fabric.wool())
    return Problem(model, clamp(mesh, "hung"), gravity_loads(model), name=f"hung {n}x{n}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20, help="elements per side (paper: 40)")
    ap.add_argument("--t-end", type=float, default=0.2)
    ap.add_argument("--scales", type=float, nargs="+", default=[10.0, 100.0, 1000.0])
    a = ap.parse_args(argv)
    prob = hung_sheet(a.n)
    snaps = [a.t_end * k / 4 for k in (1, 2, 3, 4)]
    runs = {}
    for s in [1.0] + a.scales:
        t0 = time.perf_counter()
        r = explicit.run(
            prob,
            {"t_end": a.t_end, "alpha": 5.0, "mass_scaling": s, "mass_scaling_mode": "director", "snapshots": snaps},
        )
        runs[s] = (r, time.perf_counter() - t0)
        print(
            f"director x{s:<6g} dt {r.info['dt']:.3e} s  {r.info['steps']:>7} steps  wall {runs[s][1]:6.1f} s  "
            f"energy err {r.info['energy_balance_error']:.1e}  {r.info['status']}",
            flush=True,
        )
    ref, ref_wall = runs[1.0]
    X = prob.model.mesh.nodes
    ref_t = np.array([t for t, _ in ref.frames])
    rows = []
    for s in a.scales:
        r, wall = runs[s]
        diffs = []
        for t, U in r.frames:
            if t == 0.0:
                continue
            # snapshots fall on the nearest step, so the times differ by up to half a step; the
            # sheet moves < 300 cm/s, i.e. < 0.02 cm in 6e-5 s (s = 1000), a 1e-3 relative blur
            j = int(np.argmin(np.abs(ref_t - t)))
            Ur = ref.frames[j][1]
            scale = np.max(np.linalg.norm(Ur[:, :3], axis=1))
            d = np.max(np.linalg.norm((X + U[:, :3]) - (X + Ur[:, :3]), axis=1))
            diffs.append(dict(t=t, max_position_difference=d, relative=d / scale))
        rows.append(
            dict(
                director_scaling=s,
                dt=r.info["dt"],
                steps=r.info["steps"],
                wall_s=wall,
                wall_ratio_to_unscaled=wall / ref_wall,
                snapshots=diffs,
                energy_balance_error=r.info["energy_balance_error"],
            )
        )
        print(
            f"x{s:<6g} wall/unscaled {wall / ref_wall:.3f}  position difference / max displacement at "
            + ", ".join(f"t={d['t']:.3g}: {d['relative']:.2e}" for d in diffs)
        )
    p = write_json(
        "dynamic_mass_scaling",
        dict(
            mesh=f"{a.n}x{a.n}",
            t_end=a.t_end,
            unscaled_dt=ref.info["dt"],
            unscaled_steps=ref.info["steps"],
            unscaled_wall_s=ref_wall,
            rows=rows,
        ),
    )
    print(f"wrote {p}")


if __name__ == "__main__":
    main()
