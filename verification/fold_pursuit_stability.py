"""Is the dynamic steady state of Fig. 11a's damping path a stable equilibrium?  (issue 12 item 5;
docs/verification.md, the Fig. 11 row)

square-on-disc 30x240 is relaxed on the paper's alpha = 5 1/s path (Rayleigh alpha 50 with the
director masses x100, the same run as paper_figures/fig11.py (a)), from the flat sheet ("flat") or
from a 10-fold start of 2 cm ("pert10", fold_pursuit's sod30-relax-a50-pert10); the static energy
Newton then starts from the relaxed state and reports its verdict on the equilibrium it converges
to: the free-dof tangent's positive definiteness and smallest eigenvalue [gf/cm], the fold count
and angles, and how far the state moved.

    python verification/fold_pursuit_stability.py flat|pert10     # ~17 min relaxation + the static solve

Writes verification/out/fold_pursuit/stability-<tag>.json.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent / "out" / "fold_pursuit"
KEYS = (
    "converged",
    "message",
    "drape_coefficient",
    "fold_count",
    "fold_angles_deg",
    "steps",
    "iterations",
    "positive_definite",
    "min_tangent_eigenvalue",
    "max_interpenetrated_nodes",
    "interpenetrated_nodes",
)
START = {
    "flat": None,
    "pert10": {
        "perturbation.shape": "folds",
        "perturbation.folds": 10,
        "perturbation.amplitude": 2.0,
        "perturbation.phase": 0.0,
    },
}


def main(tag: str) -> dict:
    from solidshell import run_scene

    t = time.perf_counter()
    relaxed = run_scene(
        "square-on-disc",
        mesh="30x240",
        solver="relax",
        out_dir=None,
        progress=False,
        overrides=START[tag],
        damping="rayleigh",
        alpha=50.0,
        mass_scaling=100.0,
        mass_scaling_mode="director",
    )
    out = {
        "tag": tag,
        "relax": {k: relaxed.summary.get(k) for k in KEYS if k in relaxed.summary},
        "relax_wall_s": time.perf_counter() - t,
    }
    t = time.perf_counter()
    U = np.asarray(relaxed.U)
    static = run_scene("square-on-disc", mesh="30x240", solver="static", out_dir=None, progress=False, U0=U)
    out["static_from_relaxed"] = {k: static.summary.get(k) for k in KEYS if k in static.summary}
    out["max_move_cm"] = float(np.max(np.linalg.norm((np.asarray(static.U) - U)[:, :3], axis=1)))
    out["static_wall_s"] = time.perf_counter() - t
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / f"stability-{tag}.json").write_text(json.dumps(out, indent=1, default=float) + "\n")
    print(json.dumps(out, default=float))
    return out


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in START:
        sys.exit(f"usage: python verification/fold_pursuit_stability.py {'|'.join(START)}")
    main(sys.argv[1])
