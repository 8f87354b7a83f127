"""Section 3 scenes with the static solvers (issue 4): every scene on the paper's meshes with the
energy Newton ("newton", the default) and the paper's lambda-scaled Newton-Raphson (Eqs. 16-18,
"paper", c = 1e-2), plus the circle-pedestal multi-stability study (c = 1e-2 vs 2e-2, arc-length).

Each case is run by :func:`run_case` and its row cached as JSON in ``verification/out/static_scenes/``
(so the long ones -- square-on-disc 30x240 -- can run in background processes and the table be
collected later); run directories with pictures go to ``--runs`` (default /tmp/static_scenes_runs).

    python -m verification.static_scenes                    # run every missing case, write the table
    python -m verification.static_scenes --case square-on-disc:30x240:newton   # one case only
    python -m verification.static_scenes --collect          # only (re)write the table from the cache
    python -m verification.static_scenes --perturbed circle-pedestal:20x80:4:3.0   # perturbed start
    python -m verification.static_scenes --pedestal-contact # square-on-disc with a pedestal body

A case key is ``scene:mesh:label`` with label ``newton``, ``paper-c<c>`` or ``arclength``
(optionally ``...:maxiter<N>``).  The paper scheme is capped at ``PAPER_MAX_ITER`` iterations: past
that it is reported as not converged with its iteration count.

Outputs: ``verification/out/static_scenes.md`` and ``.json``.
"""

from __future__ import annotations

import json
import sys
import time
import traceback
from pathlib import Path

from verification import cases
from verification.cases import cell

HERE = Path(__file__).resolve().parent
OUT = HERE / "out"
CACHE = OUT / "static_scenes"
RUNS = Path("/tmp/static_scenes_runs")

PAPER_MAX_ITER = 3000  # cap of the paper scheme (needs >= max|U| / (c L_f) iterations)

SCENES = [
    ("strip-warp", "20x1"),
    ("strip-warp", "10x1"),
    ("strip-weft", "20x1"),
    ("strip-weft", "10x1"),
    ("square-pedestal", "24x8x4"),
    ("square-pedestal", "48x16x4"),
    ("circle-pedestal", "10x40"),
    ("circle-pedestal", "20x80"),
    ("large-square-pedestal", "45x15x4"),
    ("square-on-disc", "30x240"),
]
SOLVERS = ["newton", "paper-c0.01"]
# circle-pedestal multi-stability: doubled lambda (c = 2e-2) and the arc-length method
EXTRA = [("circle-pedestal", m, lab) for m in ("10x40", "20x80") for lab in ("paper-c0.02", "arclength")]

KEYS = [
    "converged",
    "drape_coefficient",
    "fold_count",
    "fold_angles_deg",
    "iterations",
    "linear_solves",
    "factorizations",
    "wall_time_s",
    "positive_definite",
    "min_tangent_eigenvalue",
    "asymmetry_mirror_x",
    "asymmetry_mirror_y",
    "asymmetry_rot90",
    "message",
    "final_relative_residual",
    "load_factor",
    "cutbacks",
    "shifted_iterations",
    "min_multiplier",
    "max_negative_eigenvalues_on_path",
    "peak_memory_mb",
    "tip_position",
    "max_displacement",
    "min_z",
    "free_length",
]


def case_key(scene, mesh, label):
    return f"{scene}:{mesh}:{label}"


def parse_label(label: str) -> dict:
    """Solver settings of a label: newton | paper-c<c> | arclength, optional ':maxiter<N>'."""
    parts = label.split(":")
    base, extra = parts[0], parts[1:]
    if base == "newton":
        s = {"method": "newton"}
    elif base.startswith("paper-c"):
        s = {"method": "paper", "c": float(base[len("paper-c") :]), "max_iter": PAPER_MAX_ITER}
    elif base == "arclength":
        s = {"method": "arclength"}
    else:
        raise SystemExit(f"unknown solver label {label!r}")
    for e in extra:
        if e.startswith("maxiter"):
            s["max_iter"] = int(e[len("maxiter") :])
    return s


def cache_name(key: str) -> str:
    return key.replace(":", "__")


def cache_path(key: str) -> Path:
    return cases.cache_file(CACHE, cache_name(key))


def run_case(scene, mesh, label, runs=RUNS, overrides=None, tag=None) -> dict:
    """Run one case; return its row (never raises: an exception becomes the row's message)."""
    from solidshell.run import run_scene

    settings = parse_label(label)
    key = case_key(scene, mesh, label) + (f":{tag}" if tag else "")
    out_dir = Path(runs) / key.replace(":", "__")
    row = {
        "scene": scene,
        "mesh": mesh,
        "solver": label,
        "settings": settings,
        "overrides": dict(overrides or {}),
        "run_dir": str(out_dir),
    }
    t0 = time.perf_counter()
    try:
        out = run_scene(
            scene, mesh=mesh, solver="static", out_dir=out_dir, progress=False, overrides=overrides, **settings
        )
        s = out.summary
        for k in KEYS:
            row[k] = s.get(k)
        row["n_nodes"] = s.get("counts", {}).get("nodes") if isinstance(s.get("counts"), dict) else None
        row["run_dir_written"] = (out_dir / "summary.json").exists() and (out_dir / "result.vtu").exists()
    except Exception as exc:  # noqa: BLE001 - report, never lose the table
        row["converged"] = False
        row["message"] = f"EXCEPTION {type(exc).__name__}: {exc}"
        row["traceback"] = traceback.format_exc()
        row["run_dir_written"] = (out_dir / "summary.json").exists()
    row["total_time_s"] = time.perf_counter() - t0
    return row


def run_perturbed(scene, mesh, folds, amp, method="newton", c=1e-2, runs=RUNS) -> dict:
    """A static solve from a perturbed start U0: the mid-surface lifted/lowered by
    amp * (rho / rho_max)^2 * cos(folds * theta) [cm] (rho = distance from the clamped nodes), to
    look for a second stable state (multi-stability).  Built from the runner's pieces because the
    registry entry takes no starting state; the row has the same keys as :func:`run_case`."""
    import numpy as np

    from solidshell import analysis
    from solidshell import io as sio
    from solidshell.model import Model
    from solidshell.plotting import render
    from solidshell.run.summary import pedestal_area
    from solidshell.scenes import load
    from solidshell.scenes.build import build_scene_mesh, contact_bodies, scene_loads, support_mask
    from solidshell.solvers.static import solve_static

    label = f"{method}{'-c' + format(c, 'g') if method == 'paper' else ''}-pert{folds}x{amp:g}"
    key = case_key(scene, mesh, label)
    out_dir = Path(runs) / key.replace(":", "__")
    out_dir.mkdir(parents=True, exist_ok=True)
    row = {
        "scene": scene,
        "mesh": mesh,
        "solver": label,
        "run_dir": str(out_dir),
        "settings": {"method": method, "c": c, "perturbation": {"folds": folds, "amp_cm": amp}},
    }
    t0 = time.perf_counter()
    try:
        sc = load(scene)
        m, _ = build_scene_mesh(sc, mesh)
        fixed = support_mask(sc, m)
        model = Model(m, sc.material_object(), thickness_strain=sc.model["thickness_strain"], mu=sc.model["mu"])
        P = scene_loads(sc, model)
        X = m.nodes
        clamped = fixed.any(axis=1)
        from scipy.spatial import cKDTree

        rho, _ = cKDTree(X[clamped]).query(X)
        th = np.arctan2(X[:, 1], X[:, 0])
        U0 = np.zeros((m.n_nodes, 6))
        U0[:, 2] = amp * (rho / rho.max()) ** 2 * np.cos(folds * th)
        U0[fixed] = 0.0
        kw = dict(method=method, U0=U0, contact=contact_bodies(sc))
        if method == "paper":
            kw.update(c=c, max_iter=PAPER_MAX_ITER)
        res = solve_static(model, fixed, P, **kw)
        info = dict(res.info)
        for k in KEYS:
            if k in info:
                row[k] = info[k]
        row["converged"], row["message"] = res.converged, res.message
        U = res.U
        if np.all(np.isfinite(U)):
            d = analysis.drape_summary(m, U, pedestal_area=pedestal_area(sc) or 0.0)
            d.pop("projected_boundary", None)
            for k in KEYS:
                if k in d:
                    row[k] = d[k]
            sub = (
                f"mesh {mesh}, {label}, DC = {row.get('drape_coefficient', float('nan')):.3f}, "
                f"{row.get('fold_count')} folds" + ("" if res.converged else ", NOT CONVERGED")
            )
            for view in ("top", "iso"):
                render(out_dir / f"{view}.png", m, U, view=view, title=sc.title, scene=sc, subtitle=sub)
            sio.write_mesh_file(out_dir / "result.vtu", m, U)
        sio.write_json(out_dir / "summary.json", sio.to_jsonable(row))
        row["run_dir_written"] = True
    except Exception as exc:  # noqa: BLE001
        row["converged"] = False
        row["message"] = f"EXCEPTION {type(exc).__name__}: {exc}"
        row["traceback"] = traceback.format_exc()
    row["total_time_s"] = time.perf_counter() - t0
    return row


def asym(row):
    vals = [row.get(k) for k in ("asymmetry_mirror_x", "asymmetry_mirror_y", "asymmetry_rot90")]
    if any(v is None for v in vals):
        return "–"
    return "/".join(f"{v:.3f}" for v in vals)


def table(rows) -> str:
    hdr = (
        "| scene | mesh | solver | converged | DC | folds | iterations | linear solves | "
        "wall [s] | pos. def. | asymmetry mx/my/rot90 | note |"
    )
    lines = [hdr, "|" + "---|" * 12]
    for r in rows:
        note = ""
        if not r.get("converged"):
            note = (r.get("message") or "")[:110].replace("|", "/")
        elif r.get("tip_position") is not None:
            note = "tip " + ", ".join(f"{x:.3f}" for x in r["tip_position"])
        lines.append(
            "| "
            + " | ".join(
                [
                    r["scene"],
                    r["mesh"],
                    r["solver"],
                    cell(r.get("converged")),
                    cell(r.get("drape_coefficient"), ".3f"),
                    cell(r.get("fold_count")),
                    cell(r.get("iterations")),
                    cell(r.get("linear_solves")),
                    cell(r.get("wall_time_s"), ".1f"),
                    cell(r.get("positive_definite")),
                    asym(r),
                    note,
                ]
            )
            + " |"
        )
    return "\n".join(lines)


def all_cases():
    todo = [(sc, m, lab) for sc, m in SCENES for lab in SOLVERS]
    todo += EXTRA
    return todo


def collect(extra_text="") -> list:
    rows = []
    for sc, m, lab in all_cases():
        p = cache_path(case_key(sc, m, lab))
        if p.exists():
            rows.append(json.loads(p.read_text()))
        elif list(CACHE.glob(p.stem + "__maxiter*.json")):
            for q in sorted(CACHE.glob(p.stem + "__maxiter*.json")):  # the capped variant instead
                rows.append(json.loads(q.read_text()))
        else:
            rows.append(
                {
                    "scene": sc,
                    "mesh": m,
                    "solver": lab,
                    "converged": None,
                    "message": "not run (no result in the cache)",
                }
            )
    # any further cached cases (perturbed starts etc.)
    known = {cache_path(case_key(*c)).name for c in all_cases()}
    for p in sorted(CACHE.glob("*.json")):
        if p.name not in known and not any(p.name.startswith(k[:-5] + "__maxiter") for k in known):
            r = json.loads(p.read_text())
            if r.get("overrides") and " + " not in str(r.get("solver")):  # a variant (static_convergence.py)
                r["solver"] = f"{r.get('solver')} [{', '.join(f'{k}={v}' for k, v in r['overrides'].items())}]"
            rows.append(r)
    md = [
        "# Section 3 scenes with the static solvers",
        "",
        "Generated by `verification/static_scenes.py`.  newton = energy Newton (trust region, tangent "
        "shift); paper-c<c> = Eqs. 16-18 with lambda = c L_f / max|dD|, capped at "
        f"{PAPER_MAX_ITER} iterations; arclength = Crisfield.  DC = drape coefficient, folds from "
        "the projected boundary, asymmetry = relative mirror-x / mirror-y / 90-degree-rotation "
        "asymmetry of the projected boundary, pos. def. = tangent positive definite at the end "
        "(a stable equilibrium).  Wall time is the solver's own (excludes meshing and pictures); "
        "the machine is 2 cores shared with other jobs.",
        "",
        table(rows),
        "",
    ]
    circ = [r for r in rows if r["scene"] == "circle-pedestal"]
    if circ:
        md += [
            "## circle-pedestal multi-stability (paper: 4 folds; 8 with lambda doubled)",
            "",
            "| mesh | solver | converged | folds | fold angles [deg] | DC | pos. def. | min eig |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for r in circ:
            ang = r.get("fold_angles_deg")
            ang = ", ".join(f"{a:.0f}" for a in ang) if ang else "–"
            md.append(
                f"| {r['mesh']} | {r['solver']} | {cell(r.get('converged'))} | "
                f"{cell(r.get('fold_count'))} | {ang} | {cell(r.get('drape_coefficient'), '.3f')} | "
                f"{cell(r.get('positive_definite'))} | {cell(r.get('min_tangent_eigenvalue'), '.3g')} |"
            )
        md.append("")
    if extra_text:
        md += [extra_text, ""]
    notes = OUT / "static_scenes_notes.md"
    if notes.exists():
        md += [notes.read_text()]
    cases.write_report(OUT, "static_scenes", "\n".join(md), rows)
    return rows


def main(argv=None):
    ap = cases.parser(__doc__)
    ap.add_argument("--case", action="append", default=[], help="scene:mesh:label (repeatable)")
    ap.add_argument(
        "--perturbed",
        action="append",
        default=[],
        help="scene:mesh:folds:amp[:method[:c]] -- a solve from a perturbed start",
    )
    ap.add_argument(
        "--pedestal-contact",
        action="store_true",
        help="square-on-disc 30x240 newton with a disc pedestal contact body added",
    )
    ap.add_argument("--collect", action="store_true", help="only write the table from the cache")
    ap.add_argument("--force", action="store_true", help="re-run cached cases")
    ap.add_argument(
        "--skip",
        default="square-on-disc",
        help="comma list of scenes to skip in the full run (they are run separately in the background); '' for none",
    )
    ap.add_argument("--runs", default=str(RUNS))
    a = ap.parse_args(argv)
    CACHE.mkdir(parents=True, exist_ok=True)
    if not a.collect:
        if a.perturbed:
            for spec in a.perturbed:  # scene:mesh:folds:amp[:method[:c]]
                f = spec.split(":")
                sc, m, nf, amp = f[0], f[1], int(f[2]), float(f[3])
                meth = f[4] if len(f) > 4 else "newton"
                c = float(f[5]) if len(f) > 5 else 1e-2
                print(f"running perturbed {spec} ...", flush=True)
                row = run_perturbed(sc, m, nf, amp, method=meth, c=c, runs=a.runs)
                cases.store(CACHE, cache_name(case_key(sc, m, row["solver"])), row)
                print(
                    f"  converged={row.get('converged')} DC={row.get('drape_coefficient')} "
                    f"folds={row.get('fold_count')} it={row.get('iterations')} "
                    f"pd={row.get('positive_definite')} :: {row.get('message')}",
                    flush=True,
                )
            todo = []
        elif a.pedestal_contact:
            # square-on-disc with a pedestal contact body (the scene has none: the hanging sheet
            # may swing into the pedestal's footprint)
            ov = {
                "contact": [
                    {
                        "type": "pedestal",
                        "shape": "disc",
                        "diameter": 20.0,
                        "centre": [0.0, 0.0, 0.0],
                        "height": 10.0,
                        "offset": 0.03,
                    }
                ]
            }
            print("running square-on-disc 30x240 newton with a pedestal contact body ...", flush=True)
            row = run_case("square-on-disc", "30x240", "newton", runs=a.runs, overrides=ov, tag="pedestal-contact")
            row["solver"] = "newton + pedestal contact body"
            cases.store(CACHE, cache_name(case_key("square-on-disc", "30x240", "newton-pedestal-contact")), row)
            todo = []
        elif a.case:
            todo = [tuple(c.split(":", 2)) for c in a.case]
        else:
            skip = {s for s in a.skip.split(",") if s}
            todo = [c for c in all_cases() if c[0] not in skip]
        for sc, m, lab in todo:
            p = cache_path(case_key(sc, m, lab))
            if p.exists() and not a.force:
                continue
            print(f"running {sc} {m} {lab} ...", flush=True)
            row = run_case(sc, m, lab, runs=a.runs)
            cases.store(CACHE, cache_name(case_key(sc, m, lab)), row)
            print(
                f"  converged={row.get('converged')} DC={row.get('drape_coefficient')} "
                f"folds={row.get('fold_count')} it={row.get('iterations')} "
                f"t={row.get('wall_time_s')} pd={row.get('positive_definite')} :: {row.get('message')}",
                flush=True,
            )
    rows = collect()
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
