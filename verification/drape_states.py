"""large-square-pedestal: which static states exist on the uniform meshes, and which one the
adaptive relaxation reaches (issue 10, the §6 table; docs/adaptivity.md).

The §6 comparison of this scene gave DC 0.155 on the uniform 45x15x4 mesh and 0.132 adaptively
(-15 %), both with 4 corner folds.  A drape is multi-stable, so a DC that differs is a finding only
when both states are shown to be stable equilibria.  This study:

1. solves the scene statically from the flat sheet on 45x15x4 (the paper's uniform mesh) and on
   48x16x4 (the uniform mesh of the adaptive run's finest level: the 6x2x4 level 0 split 3 times);
2. prolongs each equilibrium onto the other mesh (solvers/sequence.prolong) and solves from there;
3. relaxes the scene adaptively (FIRE, director masses x100, coarse "ans", const 0.4: the §6 rows
   of docs/adaptivity.md) and solves statically from its final state on its final mesh, with the
   same per-quad membranes (``RunOutput.problem``).

Each static state is reported with the solver's verdict: the free-dof tangent's positive
definiteness and smallest eigenvalue [gf/cm] (a stable equilibrium has both), and how far the
state moved from its start [cm].

    python -m verification.lsp_states        # ~3 min on 2 cores

Writes verification/out/lsp_states.{json,md}.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent / "out"
SCENE = "large-square-pedestal"
MESHES = ("45x15x4", "48x16x4")
ADAPTIVE = {"solver.relax.damping": "fire", "solver.relax.mass_scaling": 100.0,
            "solver.relax.mass_scaling_mode": "director", "adapt.coarse_membrane": "ans",
            "adapt.const": 0.4}
QUIET = {"output.pictures": [], "output.snapshots": []}


def _row(label, mesh_name, U, U_start, res, analysed, wall):
    info = res.info
    moved = None if U_start is None else float(np.max(np.linalg.norm((U - U_start)[:, :3], axis=1)))
    return dict(state=label, mesh=mesh_name, converged=bool(res.converged), iterations=info.get("iterations"),
                drape_coefficient=analysed.get("drape_coefficient"), fold_count=analysed.get("fold_count"),
                fold_angles_deg=analysed.get("fold_angles_deg"),
                interpenetrated_nodes=analysed.get("interpenetrated_nodes"),
                positive_definite=info.get("positive_definite"),
                min_tangent_eigenvalue=info.get("min_tangent_eigenvalue"), moved_cm=moved, wall_s=wall)


def _static_from(problem, mesh, mesh_name, U0, label):
    from solidshell.runner import analyse
    from solidshell.solvers import static

    t = time.perf_counter()
    res = static.run(problem, {"U0": U0})
    U = np.asarray(res.U, float).reshape(mesh.n_nodes, 6)
    return _row(label, mesh_name, U, U0, res, analyse(SCENE, mesh, U, problem.model), time.perf_counter() - t)


def main() -> dict:
    from solidshell import run_scene
    from solidshell.runner import build_problem
    from solidshell.solvers.sequence import prolong

    rows, flat = [], {}
    for d in MESHES:
        out = run_scene(SCENE, mesh=d, solver="static", out_dir=None, progress=False, overrides=QUIET)
        flat[d] = (out.mesh, np.asarray(out.U, float))
        rows.append(_row("from the flat sheet", d, flat[d][1], None, out.result, out.summary,
                         out.summary["wall_time_s"]))
        print(json.dumps(rows[-1]), flush=True)
    for d, src in ((MESHES[0], MESHES[1]), (MESHES[1], MESHES[0])):
        mesh = flat[d][0]
        U0 = prolong(flat[src][0], flat[src][1], mesh)
        rows.append(_static_from(build_problem(SCENE, mesh), mesh, d, U0, f"from the {src} equilibrium"))
        print(json.dumps(rows[-1]), flush=True)
    t = time.perf_counter()
    ad = run_scene(SCENE, solver="relax", adaptive=True, out_dir=None, progress=False, overrides={**QUIET, **ADAPTIVE})
    s = ad.summary
    relax = dict(state="adaptive relaxation (final)", mesh=f"{s['max_active_nodes']} nodes at most, "
                 f"{ad.mesh.n_nodes} at the end", converged=s["converged"], steps=s.get("steps"),
                 drape_coefficient=s.get("drape_coefficient"), fold_count=s.get("fold_count"),
                 interpenetrated_nodes=s.get("interpenetrated_nodes"),
                 max_interpenetrated_nodes=s.get("max_interpenetrated_nodes"), wall_s=time.perf_counter() - t)
    rows.append(relax)
    print(json.dumps(relax), flush=True)
    rows.append(_static_from(ad.problem, ad.mesh, "adaptive (final)", np.asarray(ad.U, float),
                             "from the adaptive relaxation's state"))
    print(json.dumps(rows[-1]), flush=True)
    _write(rows)
    return {"rows": rows}


def _write(rows) -> None:
    from verification.cases import cell, load_average, utc_now, write_report

    lines = [f"# {SCENE}: static states and the adaptive relaxation's ({utc_now()}, load {load_average()})", "",
             "Written by `python -m verification.lsp_states` (module docstring).", "",
             "| mesh | start | iterations | DC | folds | interp. nodes | positive definite | smallest eigenvalue [gf/cm] | moved [cm] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| " + " | ".join([str(r["mesh"]), r["state"], cell(r.get("iterations", r.get("steps"))),
                                         cell(r.get("drape_coefficient"), ".4f"), cell(r.get("fold_count")),
                                         cell(r.get("interpenetrated_nodes")), cell(r.get("positive_definite")),
                                         cell(r.get("min_tangent_eigenvalue"), ".2e"), cell(r.get("moved_cm"), ".3f")]) + " |")
    write_report(OUT, "lsp_states", "\n".join(lines) + "\n", {"rows": rows})


if __name__ == "__main__":
    main()
