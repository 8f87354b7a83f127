"""Static solves of one tree against another (default: /work/main against this worktree), interleaved
in one run so that both see the same machine load.

Each case runs in a fresh subprocess per tree (``python -c`` with that tree first on sys.path), A B A B
... ``--repeats`` times: the whole run_scene (meshing, set-up, static solve, analysis; no files
unless ``--pictures``) after a warm-up that loads the compiled kernels.  Reported per tree: the
median solver wall time, the median process CPU time of the solve, the median whole run_scene
time, the peak resident memory of the process (ru_maxrss), iterations, factorisations, DC and
fold count; then the ratios A/B of the medians and max|U_A - U_B| / max|U_A| of the final
states.  The load average is printed with every run (2 cores shared with other jobs: the ratios
are the figures to trust, the absolute times are upper bounds).

    python benchmarks/static_vs_main.py --cases square-pedestal:48x16x4 [--repeats 2]
        [--a /work/main] [--b .] [--settings-b '{"sequence": "auto"}'] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, os, resource, sys, time
sys.path.insert(0, sys.argv[1])
import numpy as np
from solidshell.run import run_scene
scene, mesh, out, settings = sys.argv[2], sys.argv[3], sys.argv[4], json.loads(sys.argv[5])
run_scene("strip-warp", mesh="10x1", solver="static", out_dir=None, progress=False)  # warm-up
t0, c0 = time.perf_counter(), time.process_time()
r = run_scene(scene, mesh=mesh, solver="static", out_dir=None, progress=False, **settings)
total, cpu = time.perf_counter() - t0, time.process_time() - c0
s = r.summary
np.save(out + ".npy", np.asarray(r.U))
json.dump({"total_s": total, "cpu_s": cpu, "solver_s": s.get("wall_time_s"),
           "iterations": s.get("iterations"), "factorizations": s.get("factorizations"),
           "converged": s.get("converged"), "dc": s.get("drape_coefficient"),
           "folds": s.get("fold_count"), "pd": s.get("positive_definite"),
           "min_eig": s.get("min_tangent_eigenvalue"),
           "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
           "load": os.getloadavg()}, open(out + ".json", "w"))
"""


def run_one(tree, scene, mesh, settings, tag):
    out = os.path.join(tempfile.gettempdir(), f"svm_{os.getpid()}_{tag}")
    p = subprocess.run(
        [sys.executable, "-c", CHILD, str(tree), scene, mesh, out, json.dumps(settings)],
        capture_output=True,
        text=True,
        cwd=str(tree),
    )
    if p.returncode:
        raise RuntimeError(f"{tree} {scene} {mesh}: {p.stderr[-2000:]}")
    import numpy as np

    d = json.load(open(out + ".json"))
    d["U"] = np.load(out + ".npy")
    return d


def main(argv=None):
    import numpy as np

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default="square-pedestal:48x16x4")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--a", default="/work/main")
    ap.add_argument("--b", default=str(ROOT))
    ap.add_argument("--settings-a", default="{}")
    ap.add_argument("--settings-b", default="{}")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    trees = {"A": (Path(a.a).resolve(), json.loads(a.settings_a)), "B": (Path(a.b).resolve(), json.loads(a.settings_b))}
    print(f"A = {trees['A'][0]} {trees['A'][1]}\nB = {trees['B'][0]} {trees['B'][1]}")
    report = {}
    for case in a.cases.split(","):
        scene, mesh = case.split(":")
        runs = {"A": [], "B": []}
        for i in range(a.repeats):
            for k in ("A", "B") if i % 2 == 0 else ("B", "A"):
                tree, st = trees[k]
                d = run_one(tree, scene, mesh, st, f"{k}{i}")
                runs[k].append(d)
                print(
                    f"{scene} {mesh} {k} run {i + 1}: solver {d['solver_s']:.2f} s, cpu {d['cpu_s']:.2f} s, "
                    f"total {d['total_s']:.2f} s, {d['iterations']} it, {d['factorizations']} fact, "
                    f"DC {d['dc']}, folds {d['folds']}, PD {d['pd']}, peak {d['peak_mb']:.0f} MB, "
                    f"load {' '.join(f'{x:.2f}' for x in d['load'])}",
                    flush=True,
                )
        med = {
            k: {q: statistics.median([d[q] for d in runs[k]]) for q in ("solver_s", "cpu_s", "total_s", "peak_mb")}
            for k in runs
        }
        UA, UB = runs["A"][0]["U"], runs["B"][0]["U"]
        du = float(np.abs(UA - UB).max() / max(np.abs(UA).max(), 1e-300))
        ratio = {q: med["A"][q] / med["B"][q] for q in med["A"]}
        print(
            f"{scene} {mesh}: medians A {med['A']}\n{' ' * len(scene + mesh)}   medians B {med['B']}\n"
            f"  ratios A/B: "
            + ", ".join(f"{q} {v:.2f}" for q, v in ratio.items())
            + f";  max|U_A - U_B| / max|U_A| = {du:.2e}",
            flush=True,
        )
        report[case] = {
            "medians": med,
            "ratios_A_over_B": ratio,
            "rel_state_difference": du,
            "runs": {k: [{q: v for q, v in d.items() if q != "U"} for d in runs[k]] for k in runs},
        }
    if a.json:
        Path(a.json).write_text(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    main()
