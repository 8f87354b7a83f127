"""The sphere scene statically (issue 36): a stable minimum, and its DC against the relaxation's.

The static solver's contact is frictionless, so its sphere run holds the sheet's centre node
in-plane and the next node along +X in y (scenes/paper/sphere.toml, [supports.static]).  The
relaxation that solves the same problem is therefore the frictionless one with the same holds.
Three runs on one mesh:

* ``relax``       : that relaxation (FIRE, the scene's preset), from the flat sheet;
* ``from_relax``  : the static energy Newton started at the relaxed state -- is it a static
                    equilibrium, stable (positive-definite free-dof tangent), and how far does it move;
* ``static``      : ``solidshell run sphere --solver static``, from the flat sheet.

Each reports DC, folds, the solver's stability verdict, interpenetrated nodes (the sheet through
itself, n_p . d_p < 0) and the contact contract by solidshell.penetration (5 x 5 lattice).

    python verification/sphere_static.py [--mesh 60x60]     # ~4 min on two cores (100x100: ~10 min)

Writes verification/out/sphere_static-<mesh>.json.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from solidshell.analysis import drape_summary
from solidshell.penetration import check
from solidshell.run import run_scene
from solidshell.scenes import load
from solidshell.scenes.build import build_problem, build_scene_mesh
from solidshell.solvers.static import solve_static

OUT = Path(__file__).resolve().parent / "out"
SAME_PROBLEM = {"contact.0.friction": 0.0, "supports.fixed_x": "centre", "supports.fixed_y": ["centre", "centre_east"]}
"""Overrides that make the relaxation solve the static run's problem (frictionless, the same holds)."""


def _record(mesh, U, problem, info, wall) -> dict:
    d = drape_summary(mesh, U, center=(0.0, 0.0))
    pen = check(mesh, U, problem.contact, problem.model.material.thickness)[0]
    keys = ("iterations", "steps", "positive_definite", "min_tangent_eigenvalue", "contact_augment_updates")
    return {
        "drape_coefficient": d["drape_coefficient"],
        "fold_count": d["fold_count"],
        "fold_angles_deg": d["fold_angles_deg"],
        **{k: info.get(k) for k in keys},
        "interpenetrated_nodes": int(problem.model.interpenetrated_nodes(np.asarray(U).reshape(-1, 6)).sum()),
        "nodes_beyond": pen["nodes_beyond"],
        "face_points_beyond": pen["face_points_beyond"],
        "deepest_face_point_cm": pen["deepest_face_point_cm"],
        "wall_s": wall,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="60x60")
    a = ap.parse_args(argv)
    out = {}
    t = time.perf_counter()
    rel = run_scene("sphere", mesh=a.mesh, solver="relax", out_dir=None, progress=False, overrides=SAME_PROBLEM)
    out["relax"] = _record(rel.mesh, rel.U, rel.problem, rel.summary, time.perf_counter() - t)
    sc = load("sphere")
    mesh, _ = build_scene_mesh(sc, a.mesh, "static")
    prob = build_problem(sc, mesh, kind="static")
    t = time.perf_counter()
    U0 = np.asarray(rel.U, float).reshape(mesh.n_nodes, 6)
    r = solve_static(prob.model, prob.fixed, prob.loads, contact=prob.contact, U0=U0, predictor=False)
    out["from_relax"] = _record(mesh, r.U, prob, r.info, time.perf_counter() - t)
    out["from_relax"]["max_move_cm"] = float(np.abs(r.U[:, :3] - U0[:, :3]).max())
    t = time.perf_counter()
    st = run_scene("sphere", mesh=a.mesh, solver="static", out_dir=None, progress=False)
    out["static"] = _record(st.mesh, st.U, st.problem, st.summary, time.perf_counter() - t)
    for tag, rec in out.items():
        print(f"{tag:>10}: " + ", ".join(f"{k} {v}" for k, v in rec.items() if k != "fold_angles_deg"), flush=True)
    OUT.mkdir(exist_ok=True)
    (OUT / f"sphere_static-{a.mesh}.json").write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
