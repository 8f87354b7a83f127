"""Dynamic relaxation settings against each other on a paper scene (work against result).

Runs one scene (default: the 20 x 20 cm sheet on the 10 x 10 cm square pedestal, Section 3.2 /
4.2, mesh 24x8x4) with ``solver="relax"`` in several ways and prints, for each, the steps, the
simulated and wall time, the wall time relative to the paper's settings (a ratio inside one run),
the drape coefficient and fold count, and the largest node-position difference from the paper's
settings' steady state.  The variants:

* ``paper``    alpha = 5 1/s, all masses x100 (Section 4.2);
* ``kinetic``  Cundall kinetic damping, all masses x100;
* ``kin+dir``  kinetic damping, only the director masses scaled (x1e4): a longer step, since the
               thickness mode no longer limits it.

    python benchmarks/explicit_relaxation.py [--scene square-pedestal] [--mesh 24x8x4] [--variants ...]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from solidshell.runner import run_scene

VARIANTS = {
    "paper": dict(damping="rayleigh", alpha=5.0, mass_scaling=100, mass_scaling_mode="uniform"),
    "kinetic": dict(damping="kinetic", mass_scaling=100, mass_scaling_mode="uniform"),
    "kin+dir": dict(damping="kinetic", mass_scaling=1e4, mass_scaling_mode="director"),
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="square-pedestal")
    ap.add_argument("--mesh", default="24x8x4")
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    ap.add_argument("--max-wall", type=float, default=900.0, help="wall-time limit per run [s]")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    rows, states = [], {}
    for name in a.variants:
        t0 = time.perf_counter()
        out = run_scene(a.scene, mesh=a.mesh, solver="relax", out_dir=None, progress=False,
                        max_wall_time=a.max_wall, **VARIANTS[name])
        wall = time.perf_counter() - t0
        s = out.summary
        states[name] = np.asarray(out.U)[:, :3]
        row = dict(variant=name, settings=VARIANTS[name], converged=s.get("converged"), steps=s.get("steps"),
                   dt=s.get("dt"), t_sim=s.get("t_final"), wall_s=wall, drape_coefficient=s.get("drape_coefficient"),
                   fold_count=s.get("fold_count"), energy_balance_error=s.get("energy_balance_error"),
                   max_interpenetrated_nodes=s.get("max_interpenetrated_nodes"), message=s.get("message"))
        rows.append(row)
        print(f"{name:<8} {'steady' if row['converged'] else 'NOT steady'}  {row['steps']:>7} steps of {row['dt']:.3e} s"
              f"  t_sim {row['t_sim']:.3f} s  wall {wall:7.1f} s  DC {row['drape_coefficient']}  folds {row['fold_count']}",
              flush=True)
    if "paper" in states:
        ref = states["paper"]
        ref_wall = next(r["wall_s"] for r in rows if r["variant"] == "paper")
        for r in rows:
            d = float(np.max(np.linalg.norm(states[r["variant"]] - ref, axis=1)))
            r["max_position_difference_to_paper_cm"] = d
            r["wall_ratio_to_paper"] = r["wall_s"] / ref_wall
            print(f"{r['variant']:<8} wall / paper {r['wall_ratio_to_paper']:.3f}   max |x - x_paper| = {d:.2e} cm")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1, default=str)


if __name__ == "__main__":
    main()
