"""Which static states a drape has on the uniform meshes, and which one the adaptive relaxation
reaches (issue 10, the §6 table; docs/adaptivity.md).

A drape is multi-stable, so a DC that differs between the uniform and the adaptive run is a finding
only when both states are shown to be stable equilibria.  For one scene this study:

1. solves the scene statically from the flat sheet on each uniform mesh of its case (the paper's
   uniform mesh, and the uniform mesh of the adaptive run's finest level);
2. prolongs each of those equilibria onto the other uniform mesh (solvers/sequence.prolong) and
   solves from there;
3. relaxes the scene adaptively with the case's §6 settings and solves statically from its final
   state on its final mesh, with the same per-quad membranes (``RunOutput.problem``);
4. prolongs that adaptive state onto each uniform mesh and solves from there: a state of the
   uniform mesh too when it stays near the adaptive one;
5. ``--ladder``, instead of 1-4: relaxes adaptively (3), solves from its final state on its own mesh
   with its own and with the scene's membrane on every quad, and prolongs that state onto the
   case's ladder of uniform meshes, coarse to fine, and solves there: the DC of one state against
   the mesh size, the yardstick for "DC within 1 %" (docs/adaptivity.md).

Each static state is reported with the solver's verdict: the free-dof tangent's positive
definiteness and smallest eigenvalue [gf/cm] (a stable equilibrium has both), how far the state
moved from its start [cm], and its fold angles [deg] (two states with the same fold count differ
in where the folds lie).

    python -m verification.drape_states --scene large-square-pedestal   # ~3 min on 2 cores
    python -m verification.drape_states --scene square-on-disc          # ~4 min
    python -m verification.drape_states --scene square-on-disc --path paper   # ~25 min
    python -m verification.drape_states --scene square-on-disc --path paper --ladder   # ~5 min

``--path paper``: the adaptive run takes the paper's relaxation to t = 40 s (:data:`PAPER`) with the
scene's own [adapt] table (the §6 settings) instead of the case's settings, and the paper's uniform
mesh is relaxed on the same path too and solved statically from its final state: both relaxations
stop at t = 40 s before their steady state, so each final state is shown to lie by a stable
equilibrium.  Writes verification/out/<report>.{json,md} (``CASES[scene]["report"]``, with
``_paper`` appended for that path and ``_ladder`` for step 5).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parent / "out"
KINETIC = {
    "solver.relax.damping": "kinetic",
    "solver.relax.mass_scaling": 1e4,
    "solver.relax.mass_scaling_mode": "director",
    "solver.relax.t_max": 8.0,
}
"""benchmarks/adaptive_vs_uniform.py's relaxation (kinetic damping, director masses x1e4)"""
PAPER = {"solver.relax.preset": "paper", "solver.relax.t_max": 40.0}
"""the §6 table's path (docs/adaptivity.md: Rayleigh alpha 5 1/s, all masses x100, to t = 40 s); its
adaptive settings are the scenes' [adapt] tables"""
CASES = {
    # FIRE with director masses x100 and const 0.4: the §6 rows of docs/adaptivity.md that first
    # showed the two states
    "large-square-pedestal": dict(
        report="lsp_states",
        meshes=("45x15x4", "48x16x4"),
        ladder=("45x15x4", "48x16x4", "90x30x4", "96x32x4", "135x45x4"),
        adaptive={
            "solver.relax.damping": "fire",
            "solver.relax.mass_scaling": 100.0,
            "solver.relax.mass_scaling_mode": "director",
            "adapt.coarse_membrane": "ans",
            "adapt.const": 0.4,
        },
    ),
    # the freeze that lets this scene settle (docs/adaptivity.md, the freeze_on = "changes"
    # table): 3427 nodes, DC -3.5 % against the uniform relaxation
    "square-on-disc": dict(
        report="sod_states",
        meshes=("30x240", "32x256"),
        ladder=("8x64", "16x128", "24x192", "32x256"),
        adaptive={
            **KINETIC,
            "adapt.coarse_membrane": "ans",
            "adapt.const": 0.6,
            "adapt.freeze_leaves": 10,
            "adapt.freeze_after": 1.5,
            "adapt.freeze_on": "changes",
        },
    ),
}
QUIET = {"output.pictures": [], "output.snapshots": []}


def _row(label, mesh_name, U, U_start, res, analysed, wall):
    info = res.info
    moved = None if U_start is None else float(np.max(np.linalg.norm((U - U_start)[:, :3], axis=1)))
    return dict(
        state=label,
        mesh=mesh_name,
        converged=bool(res.converged),
        iterations=info.get("iterations"),
        drape_coefficient=analysed.get("drape_coefficient"),
        fold_count=analysed.get("fold_count"),
        fold_angles_deg=analysed.get("fold_angles_deg"),
        interpenetrated_nodes=analysed.get("interpenetrated_nodes"),
        positive_definite=info.get("positive_definite"),
        min_tangent_eigenvalue=info.get("min_tangent_eigenvalue"),
        moved_cm=moved,
        wall_s=wall,
    )


def _relaxed_row(label, mesh_name, s, wall):
    """The row of a relaxation's final state from its run summary ``s``."""
    return dict(
        state=label,
        mesh=mesh_name,
        converged=s["converged"],
        steps=s.get("steps"),
        drape_coefficient=s.get("drape_coefficient"),
        fold_count=s.get("fold_count"),
        fold_angles_deg=s.get("fold_angles_deg"),
        interpenetrated_nodes=s.get("interpenetrated_nodes"),
        max_interpenetrated_nodes=s.get("max_interpenetrated_nodes"),
        wall_s=wall,
    )


def _static_from(scene, problem, mesh, mesh_name, U0, label):
    from solidshell.run.summary import analyse
    from solidshell.solvers import static

    t = time.perf_counter()
    res = static.run(problem, {"U0": U0})
    U = np.asarray(res.U, float).reshape(mesh.n_nodes, 6)
    return _row(label, mesh_name, U, U0, res, analyse(scene, mesh, U, problem.model), time.perf_counter() - t)


def main(scene: str = "large-square-pedestal", path: str = "case", ladder: bool = False) -> dict:
    case = CASES[scene]
    if ladder and "ladder" not in case:
        print(f"--ladder: scene {scene} has no ladder of meshes (CASES)", file=sys.stderr)
        raise SystemExit(2)
    if path == "paper":
        case = {**case, "report": case["report"] + "_paper", "adaptive": PAPER}
    rows = []

    def emit(row):
        rows.append(row)
        print(json.dumps(row), flush=True)

    if ladder:
        _ladder(scene, case, emit)
    else:
        _states(scene, path, case, emit)
    flags = (" --path paper" if path == "paper" else "") + (" --ladder" if ladder else "")
    _write(scene, case["report"] + ("_ladder" if ladder else ""), case["adaptive"], rows, f"--scene {scene}{flags}")
    return {"rows": rows}


def _adaptive(scene, case, emit):
    """Step 3 (module docstring): the adaptive relaxation with the case's settings and the static
    solve from its final state on its own mesh, both rows emitted; returns (RunOutput, final U)."""
    from solidshell import run_scene

    t = time.perf_counter()
    ad = run_scene(
        scene, solver="relax", adaptive=True, out_dir=None, progress=False, overrides={**QUIET, **case["adaptive"]}
    )
    s = ad.summary
    emit(
        _relaxed_row(
            "adaptive relaxation (final)",
            f"{s['max_active_nodes']} nodes at most, {ad.mesh.n_nodes} at the end",
            s,
            time.perf_counter() - t,
        )
    )
    U_ad = np.asarray(ad.U, float)
    emit(_static_from(scene, ad.problem, ad.mesh, "adaptive (final)", U_ad, "from the adaptive relaxation's state"))
    return ad, U_ad


def _states(scene, path, case, emit):
    """Steps 1-4 (module docstring)."""
    from solidshell import run_scene
    from solidshell.scenes.build import build_problem
    from solidshell.solvers.sequence import prolong

    meshes = case["meshes"]
    flat, problems = {}, {}
    for d in meshes:
        out = run_scene(scene, mesh=d, solver="static", out_dir=None, progress=False, overrides=QUIET)
        flat[d] = (out.mesh, np.asarray(out.U, float))
        problems[d] = build_problem(scene, out.mesh)
        emit(_row("from the flat sheet", d, flat[d][1], None, out.result, out.summary, out.summary["wall_time_s"]))
    for d, src in ((meshes[0], meshes[1]), (meshes[1], meshes[0])):
        mesh = flat[d][0]
        emit(
            _static_from(
                scene, problems[d], mesh, d, prolong(flat[src][0], flat[src][1], mesh), f"from the {src} equilibrium"
            )
        )
    ad, U_ad = _adaptive(scene, case, emit)
    for d in meshes:
        mesh = flat[d][0]
        emit(
            _static_from(
                scene, problems[d], mesh, d, prolong(ad.mesh, U_ad, mesh), "from the adaptive relaxation's state"
            )
        )
    if path == "paper":
        d = meshes[0]
        un = run_scene(scene, mesh=d, solver="relax", out_dir=None, progress=False, overrides={**QUIET, **PAPER})
        emit(_relaxed_row("uniform relaxation (final)", d, un.summary, un.summary.get("wall_time_s")))
        emit(
            _static_from(
                scene, problems[d], flat[d][0], d, np.asarray(un.U, float), "from the uniform relaxation's state"
            )
        )


def _ladder(scene, case, emit):
    """Step 5 (module docstring): step 3, the same state on its own mesh with the scene's membrane,
    then on the ladder of uniform meshes."""
    from solidshell.scenes import load
    from solidshell.scenes.build import build_problem, build_scene_mesh
    from solidshell.solvers.sequence import prolong

    ad, U_ad = _adaptive(scene, case, emit)
    emit(
        _static_from(
            scene,
            build_problem(scene, ad.mesh),
            ad.mesh,
            "adaptive (final), scene membrane",
            U_ad,
            "from the adaptive relaxation's state",
        )
    )
    for d in case["ladder"]:
        mesh = build_scene_mesh(load(scene), d, allow_large=True)[0]
        emit(
            _static_from(
                scene,
                build_problem(scene, mesh),
                mesh,
                d,
                prolong(ad.mesh, U_ad, mesh),
                "from the adaptive relaxation's state",
            )
        )


def _angles(r) -> str:
    a = r.get("fold_angles_deg")
    return "–" if not a else " ".join(f"{x:.0f}" for x in a)


def _write(scene, report, adaptive, rows, args) -> None:
    from verification.cases import cell, load_average, utc_now, write_report

    lines = [
        f"# {scene}: static states and the adaptive relaxation's ({utc_now()}, load {load_average()})",
        "",
        f"Written by `python -m verification.drape_states {args}` (module docstring); the "
        f"adaptive run's settings: `{json.dumps(adaptive)}`.",
        "",
        "| mesh | start | iterations | DC | folds | fold angles [deg] | interp. nodes | positive definite "
        "| smallest eigenvalue [gf/cm] | moved [cm] |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            "| "
            + " | ".join(
                [
                    str(r["mesh"]),
                    r["state"],
                    cell(r.get("iterations", r.get("steps"))),
                    cell(r.get("drape_coefficient"), ".4f"),
                    cell(r.get("fold_count")),
                    _angles(r),
                    cell(r.get("interpenetrated_nodes")),
                    cell(r.get("positive_definite")),
                    cell(r.get("min_tangent_eigenvalue"), ".2e"),
                    cell(r.get("moved_cm"), ".3f"),
                ]
            )
            + " |"
        )
    write_report(OUT, report, "\n".join(lines) + "\n", {"scene": scene, "rows": rows})


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", choices=sorted(CASES), default="large-square-pedestal")
    ap.add_argument(
        "--path",
        choices=("case", "paper"),
        default="case",
        help="the adaptive run's settings: the case's own, or the §6 table's paper path",
    )
    ap.add_argument(
        "--ladder",
        action="store_true",
        help="instead of steps 1-4, the adaptive state on the case's ladder of uniform meshes (step 5)",
    )
    a = ap.parse_args()
    main(a.scene, a.path, a.ladder)
