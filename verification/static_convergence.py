"""Mesh convergence of the drape coefficient (issue 4): ``square-pedestal`` with the static energy
Newton on 24x8x4 -> 48x16x4 -> 96x32x4, and the relative change of DC between the two finest meshes
(issue target < 1 %), for four variants of the discretisation:

- the paper's element (2x2 Gauss membrane) on the paper's uniform meshes;
- the assumed membrane field (``model.membrane = "ans"``, solidshell/elements/quad4.py), which
  removes the bilinear membrane's parasitic in-plane shear;
- both on meshes graded towards the pedestal corners (``geometry.grading = 8``: element sizes grow
  eightfold from the pedestal to the sheet edge along the diagonals, and a gmsh "Bump" 1/8 along the
  edges), where the clamped square's re-entrant corners make the membrane stresses singular.

For each variant: the DC per mesh, the relative change |DC_h - DC_2h| / DC_h, the observed order
p = log2(d1 / d2) of the two differences and the Richardson limit DC_96 - d2 / (2^p - 1).  Rows
are cached in verification/out/static_scenes/ (the uniform paper-element rows are shared with
verification/static_scenes.py).

    python -m verification.static_convergence [--collect]   # writes verification/out/static_convergence.{md,json}
"""

from __future__ import annotations

import json
import math
import sys

from verification.static_scenes import CACHE, OUT, RUNS, cache_path, case_key, run_case

SCENE = "square-pedestal"
MESHES = ["24x8x4", "48x16x4", "96x32x4"]
LABEL = "newton"
VARIANTS = [
    ("paper element, uniform meshes", None, {}),
    ("assumed membrane, uniform meshes", "ans", {"model.membrane": "ans"}),
    ("paper element, graded meshes (grading 8)", "g8", {"geometry.grading": 8.0}),
    ("assumed membrane, graded meshes (grading 8)", "ans-g8", {"model.membrane": "ans", "geometry.grading": 8.0}),
]


def _f(v, spec):
    return "–" if v is None else format(v, spec)


def rows(tag, overrides, run=True):
    CACHE.mkdir(parents=True, exist_ok=True)
    out = []
    for m in MESHES:
        key = case_key(SCENE, m, LABEL) + (f":{tag}" if tag else "")
        p = cache_path(key)
        if p.exists():
            out.append(json.loads(p.read_text()))
        elif run:
            print(f"running {SCENE} {m} {LABEL} {tag or ''} ...", flush=True)
            r = run_case(SCENE, m, LABEL, runs=RUNS, overrides=overrides, tag=tag)
            p.write_text(json.dumps(r, indent=1, default=str))
            out.append(r)
        else:
            out.append({"scene": SCENE, "mesh": m, "solver": LABEL, "converged": None, "message": "not run"})
    return out


def study(name, rs):
    """Lines of the report and the JSON record of one variant."""
    lines = [
        f"## {name}",
        "",
        "| mesh | nodes | converged | DC | rel. change vs previous | folds | iterations | wall [s] | pos. def. |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    prev = None
    res = {"variant": name, "rows": rs}
    for r in rs:
        dc = r.get("drape_coefficient")
        ch = "–"
        if dc is not None and prev is not None:
            rel = abs(dc - prev) / abs(dc)
            ch = f"{100 * rel:.2f} %"
            res.setdefault("relative_changes", []).append(rel)
        lines.append(
            f"| {r['mesh']} | {r.get('n_nodes', '–')} | {r.get('converged')} | "
            f"{_f(dc, '.4f')} | {ch} | {r.get('fold_count', '–')} | "
            f"{r.get('iterations', '–')} | {_f(r.get('wall_time_s'), '.1f')} | "
            f"{r.get('positive_definite', '–')} |"
        )
        prev = dc if dc is not None else prev
    dcs = [r.get("drape_coefficient") for r in rs]
    if all(d is not None for d in dcs) and all(r.get("converged") for r in rs):
        rel = abs(dcs[2] - dcs[1]) / abs(dcs[2])
        res["finest_relative_change"] = rel
        res["meets_1_percent_target"] = bool(rel < 0.01)
        d1, d2 = dcs[0] - dcs[1], dcs[1] - dcs[2]
        text = (
            f"Change between {MESHES[1]} and {MESHES[2]}: {100 * rel:.2f} % "
            f"(target < 1 %: {'met' if rel < 0.01 else 'NOT met'})."
        )
        if d1 * d2 > 0 and abs(d1) > abs(d2):
            p = math.log2(d1 / d2)
            lim = dcs[2] - d2 / (2.0**p - 1.0)
            res.update(observed_order=p, richardson_limit=lim)
            text += (
                f" Observed order {p:.2f}; Richardson limit {lim:.4f}, i.e. the finest mesh "
                f"is {100 * (dcs[2] - lim) / lim:+.2f} % from it."
            )
        lines += ["", text]
    else:
        lines += ["", "Not every mesh converged: no convergence figure."]
    return lines, res


def main(argv=None):
    run = "--collect" not in (argv if argv is not None else sys.argv[1:])
    lines = [
        "# square-pedestal: mesh convergence of the drape coefficient (static newton)",
        "",
        "DC = (A_proj - A_ped) / (A_sheet - A_ped).  Wall times are the solver's, on a 2-core "
        "machine shared with other jobs.",
        "",
    ]
    records = []
    for name, tag, over in VARIANTS:
        ls, rec = study(name, rows(tag, over, run=run))
        lines += ls + [""]
        records.append(rec)
    OUT.mkdir(exist_ok=True)
    (OUT / "static_convergence.json").write_text(
        json.dumps({"scene": SCENE, "solver": LABEL, "variants": records}, indent=1, default=str)
    )
    (OUT / "static_convergence.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
