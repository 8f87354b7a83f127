"""Mesh convergence of the drape coefficient (issue 4): ``square-pedestal`` with the static energy
Newton on 24x8x4 -> 48x16x4 -> 96x32x4, and the relative change of DC between the two finest meshes
(issue target < 1 %).  Rows are shared with verification/static_scenes.py (same cache, same
settings), so a mesh already solved there is not solved again.

    python -m verification.static_convergence          # writes verification/out/static_convergence.{md,json}
"""

from __future__ import annotations

import json
import sys

from verification.static_scenes import CACHE, OUT, RUNS, cache_path, case_key, run_case

SCENE = "square-pedestal"
MESHES = ["24x8x4", "48x16x4", "96x32x4"]
LABEL = "newton"


def _f(v, spec):
    return "–" if v is None else format(v, spec)


def rows(run=True):
    CACHE.mkdir(parents=True, exist_ok=True)
    out = []
    for m in MESHES:
        p = cache_path(case_key(SCENE, m, LABEL))
        if p.exists():
            out.append(json.loads(p.read_text()))
        elif run:
            print(f"running {SCENE} {m} {LABEL} ...", flush=True)
            r = run_case(SCENE, m, LABEL, runs=RUNS)
            p.write_text(json.dumps(r, indent=1, default=str))
            out.append(r)
        else:
            out.append({"scene": SCENE, "mesh": m, "solver": LABEL, "converged": None,
                        "message": "not run"})
    return out


def report(rs):
    lines = ["# square-pedestal: mesh convergence of the drape coefficient (static newton)", "",
             "| mesh | nodes | converged | DC | rel. change vs previous | folds | iterations | wall [s] | pos. def. |",
             "|---|---|---|---|---|---|---|---|---|"]
    prev = None
    res = {"scene": SCENE, "solver": LABEL, "rows": rs}
    for r in rs:
        dc = r.get("drape_coefficient")
        ch = "–"
        if dc is not None and prev is not None:
            rel = abs(dc - prev) / abs(dc)
            ch = f"{100 * rel:.2f} %"
            res.setdefault("relative_changes", []).append(rel)
        lines.append(f"| {r['mesh']} | {r.get('n_nodes', '–')} | {r.get('converged')} | "
                     f"{_f(dc, '.4f')} | {ch} | {r.get('fold_count', '–')} | "
                     f"{r.get('iterations', '–')} | "
                     f"{_f(r.get('wall_time_s'), '.1f')} | "
                     f"{r.get('positive_definite', '–')} |")
        prev = dc if dc is not None else prev
    dcs = [r.get("drape_coefficient") for r in rs[-2:]]
    if len(rs) >= 3 and all(d is not None for d in dcs) and all(r.get("converged") for r in rs[-2:]):
        rel = abs(dcs[1] - dcs[0]) / abs(dcs[1])
        res["finest_relative_change"] = rel
        res["meets_1_percent_target"] = bool(rel < 0.01)
        lines += ["", f"Relative change of DC between {rs[-2]['mesh']} and {rs[-1]['mesh']}: "
                  f"{100 * rel:.2f} % (target < 1 %: {'met' if rel < 0.01 else 'NOT met'})."]
    else:
        lines += ["", "The two finest meshes did not both converge: no convergence figure."]
    OUT.mkdir(exist_ok=True)
    (OUT / "static_convergence.json").write_text(json.dumps(res, indent=1, default=str))
    (OUT / "static_convergence.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return res


def main(argv=None):
    run = "--collect" not in (argv if argv is not None else sys.argv[1:])
    report(rows(run=run))
    return 0


if __name__ == "__main__":
    sys.exit(main())
