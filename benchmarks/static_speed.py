"""Wall time of the static energy Newton on the Section 3 scenes, after compilation (issue 4).

A warm-up run (strip-warp 10x1) compiles the kernels first; then each case runs ``--repeats`` times
(default 2) in this process and the median is reported: the solver's own wall time (``wall_time_s``:
assembly, factorisations, stability check) and the whole run_scene time (meshing, model set-up,
analysis; no files are written).  Targets (issue 4): strip-warp 20x1 < 0.5 s, square-pedestal
48x16x4 < 30 s, square-on-disc 30x240 < 5 min.  The machine load (``uptime``) is recorded before and
after each case: the machine has 2 cores shared with other jobs, so the figures are upper bounds of
what an idle machine gives.

A cProfile of one square-pedestal 48x16x4 run follows: the top items by own time, grouped as
factorisation (SuperLU), assembly (solidshell.assembly, scipy.sparse construction), kernel
(solidshell.elements, the compiled element routines), other.

    python benchmarks/static_speed.py [--cases strip,pedestal,disc] [--repeats 2] [--no-profile]
writes benchmarks/out/static_speed.{md,json}
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
OUT = ROOT / "benchmarks" / "out"

CASES = {
    "strip": ("strip-warp", "20x1", 0.5),
    "pedestal": ("square-pedestal", "48x16x4", 30.0),
    "disc": ("square-on-disc", "30x240", 300.0),
}


def uptime() -> str:
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True, timeout=5).stdout.strip()
    except Exception:  # noqa: BLE001
        return "load " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def one_run(scene, mesh, **settings):
    from solidshell.run import run_scene

    t0 = time.perf_counter()
    out = run_scene(scene, mesh=mesh, solver="static", out_dir=None, progress=False, **settings)
    total = time.perf_counter() - t0
    s = out.summary
    return {
        "total_s": total,
        "solver_s": s.get("wall_time_s"),
        "converged": s.get("converged"),
        "iterations": s.get("iterations"),
        "linear_solves": s.get("linear_solves"),
        "drape_coefficient": s.get("drape_coefficient"),
        "fold_count": s.get("fold_count"),
    }


def _category(fn_key) -> str:
    filename, _, name = fn_key
    f = filename.replace("\\", "/")
    n = name.lower()
    if (
        "gstrf" in n
        or "superlu" in n
        or "splu" in n
        or name in ("_factor", "_shifted_factor")
        or "dsolve" in f
        or name == "spsolve"
        or "cholmod" in n
        or "cholmod" in f
        or f.endswith("solidshell/solvers/linear.py")
    ):
        return "factorisation / solve (CHOLMOD, SuperLU)"
    if "eigsh" in n or "arpack" in f or "aupd" in n or "eupd" in n:
        return "stability check (eigsh)"
    if "solidshell/elements" in f:
        return "kernel (element routines)"
    if (
        "solidshell/assembly" in f
        or "scipy/sparse" in f
        or "sparsetools" in n
        or "coo" in n
        or "csr" in n
        or "csc" in n
    ):
        return "assembly / sparse bookkeeping"
    return "other"


def profile(scene="square-pedestal", mesh="48x16x4", top=10) -> dict:
    from solidshell.run import run_scene

    pr = cProfile.Profile()
    t0 = time.perf_counter()
    pr.enable()
    out = run_scene(scene, mesh=mesh, solver="static", out_dir=None, progress=False)
    pr.disable()
    wall = time.perf_counter() - t0
    st = pstats.Stats(pr)
    items = []
    for k, (cc, nc, tt, ct, _callers) in st.stats.items():
        items.append(
            {
                "function": f"{Path(k[0]).name}:{k[1]}({k[2]})",
                "ncalls": nc,
                "tottime_s": tt,
                "cumtime_s": ct,
                "category": _category(k),
            }
        )
    items.sort(key=lambda d: -d["tottime_s"])
    by_cat = {}
    for it in items:
        by_cat[it["category"]] = by_cat.get(it["category"], 0.0) + it["tottime_s"]
    cum = io.StringIO()
    pstats.Stats(pr, stream=cum).sort_stats("cumulative").print_stats(25)
    return {
        "scene": scene,
        "mesh": mesh,
        "wall_s": wall,
        "converged": out.summary.get("converged"),
        "iterations": out.summary.get("iterations"),
        "top_tottime": items[:top],
        "factorizations": out.summary.get("factorizations"),
        "own_time_by_category_s": dict(sorted(by_cat.items(), key=lambda kv: -kv[1])),
        "cumulative_listing": cum.getvalue(),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default="strip,pedestal,disc")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--no-profile", action="store_true")
    ap.add_argument(
        "--keep", action="store_true", help="update the stored cases instead of moving them to previous_sessions"
    )
    a = ap.parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    res_path = OUT / "static_speed.json"
    res = json.loads(res_path.read_text()) if res_path.exists() else {}
    if res.get("cases") and "--keep" not in (argv or sys.argv[1:]):
        # keep the last session's figures for comparison, under previous_sessions
        res.setdefault("previous_sessions", []).insert(
            0, {"note": res.get("note", "the previous run of this script"), "cases": res["cases"]}
        )
        res["cases"] = {}
    res.setdefault("cases", {})
    res["note"] = (
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, CHOLMOD Cholesky (cvxopt) for the Newton tangents"
    )
    res["cpu_count"] = os.cpu_count()
    print("warm-up (compilation): strip-warp 10x1 ...", flush=True)
    t0 = time.perf_counter()
    one_run("strip-warp", "10x1")
    res["warmup_s"] = time.perf_counter() - t0
    for c in [c for c in a.cases.split(",") if c]:
        scene, mesh, target = CASES[c]
        runs = []
        load_before = uptime()
        for i in range(a.repeats):
            r = one_run(scene, mesh)
            r["uptime_after"] = uptime()
            runs.append(r)
            print(
                f"{scene} {mesh} run {i + 1}: solver {r['solver_s']:.2f} s, total {r['total_s']:.2f} s, "
                f"converged={r['converged']}, {r['iterations']} it  [{r['uptime_after']}]",
                flush=True,
            )
        med = statistics.median([r["solver_s"] for r in runs])
        medt = statistics.median([r["total_s"] for r in runs])
        res["cases"][c] = {
            "scene": scene,
            "mesh": mesh,
            "target_s": target,
            "runs": runs,
            "median_solver_s": med,
            "median_total_s": medt,
            "meets_target": bool(medt < target),
            "uptime_before": load_before,
            "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
        }
        res_path.write_text(json.dumps(res, indent=1, default=str))
    if not a.no_profile:
        print("profiling square-pedestal 48x16x4 ...", flush=True)
        load_before = uptime()
        p = profile()
        p["uptime_before"] = load_before
        p["uptime_after"] = uptime()
        res["profile"] = p
        res_path.write_text(json.dumps(res, indent=1, default=str))
    write_md(res)
    return 0


def write_md(res):
    L = [
        "# Static solver speed (energy Newton, after compilation)",
        "",
        f"Warm-up run (compilation) {res.get('warmup_s', float('nan')):.1f} s; {res.get('cpu_count')} "
        "CPUs, shared with other jobs (see the load).  solver = the solver's wall time; total = "
        "run_scene (meshing, set-up, solve, analysis, no files).  Median of the runs.",
        "",
        "| scene | mesh | target | median solver [s] | median total [s] | runs total [s] | iterations | "
        "meets target | load (uptime) before / after |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for c in ("strip", "pedestal", "disc"):
        d = res.get("cases", {}).get(c)
        if not d:
            continue
        runs = ", ".join(f"{r['total_s']:.2f}" for r in d["runs"])
        its = ", ".join(str(r["iterations"]) for r in d["runs"])
        la = d["runs"][-1]["uptime_after"].split("load average:")[-1].strip()
        lb = d["uptime_before"].split("load average:")[-1].strip()
        L.append(
            f"| {d['scene']} | {d['mesh']} | < {d['target_s']:g} s | {d['median_solver_s']:.2f} | "
            f"{d['median_total_s']:.2f} | {runs} | {its} | {'yes' if d['meets_target'] else 'NO'} | "
            f"{lb} / {la} |"
        )
    for prev in res.get("previous_sessions", []):
        L += [
            "",
            f"Earlier session ({prev.get('note', '')}):",
            "",
            "| scene | mesh | median solver [s] | runs total [s] | load before / after |",
            "|---|---|---|---|---|",
        ]
        for c, d in prev["cases"].items():
            L.append(
                f"| {d['scene']} | {d['mesh']} | {d['median_solver_s']:.2f} | "
                + ", ".join(f"{r['total_s']:.2f}" for r in d["runs"])
                + " | "
                f"{d['uptime_before'].split('load average:')[-1].strip()} / "
                f"{d['runs'][-1]['uptime_after'].split('load average:')[-1].strip()} |"
            )
    p = res.get("profile")
    if p:
        L += [
            "",
            f"## cProfile: {p['scene']} {p['mesh']} ({p['wall_s']:.1f} s under the profiler, "
            f"{p['iterations']} iterations, load {p['uptime_before'].split('load average:')[-1].strip()})",
            "",
            "Own time by category: " + ", ".join(f"{k} {v:.1f} s" for k, v in p["own_time_by_category_s"].items()),
            "",
            "| function | calls | own [s] | cumulative [s] | category |",
            "|---|---|---|---|---|",
        ]
        for it in p["top_tottime"]:
            L.append(
                f"| `{it['function']}` | {it['ncalls']} | {it['tottime_s']:.2f} | {it['cumtime_s']:.2f} | "
                f"{it['category']} |"
            )
    (OUT / "static_speed.md").write_text("\n".join(L) + "\n")
    print("\n".join(L))


if __name__ == "__main__":
    sys.exit(main())
