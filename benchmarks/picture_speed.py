"""Issue 41 item 3: how long a run's pictures make its user wait, with the pictures' child process
(solidshell/render/server.py, the default) and without it (``SOLIDSHELL_RENDER_SERVER=0``: drawn in
the run's own process after its other files), against the same run with ``--no-pictures``.

Each case is a new process running the CLI (``solidshell run SCENE --out TMP -q``), as a user runs
it; the three variants run one after the other in each round, ``rounds`` times (default 2), with the
load average (1 min) before each round and after the last.  Figures per run:

* ``process_s``  the whole process, wall [s] (interpreter start to exit);
* ``write_s``    summary.json ``timings.write_results``: from the solved state to the last file;
* ``pictures_after_solve_s`` = write_s - write_s of the same round's --no-pictures run: what the
  pictures add after the solve (the child's share overlapped with the other files is not counted).

Targets (issue 41): the two default pictures (top, iso) of square-pedestal <= 0.5 s after the solve;
strip-warp (three pictures: top, iso, side) whole process <= 1.2 s; square-pedestal <= 5 s.

    python benchmarks/picture_speed.py [--rounds 2] [--scenes strip-warp,square-pedestal] [--json F]

``measure()`` returns the same figures as a dict (for benchmarks/targets.py or a notebook).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("strip-warp", "square-pedestal")
VARIANTS = {
    # name: (extra CLI arguments, extra environment)
    "child": ([], {}),
    "in-process": ([], {"SOLIDSHELL_RENDER_SERVER": "0"}),
    "no-pictures": (["--no-pictures"], {}),
}
TARGETS = {
    ("square-pedestal", "pictures_after_solve_s"): 0.5,
    ("strip-warp", "process_s"): 1.2,
    ("square-pedestal", "process_s"): 5.0,
}


def run_once(scene: str, variant: str, tmp: str) -> dict:
    """One CLI run of ``scene`` in ``variant`` (VARIANTS): its wall time and summary timings."""
    extra, env = VARIANTS[variant]
    out = Path(tmp) / f"{scene}-{variant}"
    cmd = [sys.executable, "-m", "solidshell", "run", scene, "--out", str(out), "--force", "-q", *extra]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=ROOT, env={**os.environ, **env}, capture_output=True, text=True, timeout=900)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {r.returncode}: {r.stderr.strip()[-300:]}")
    t = json.loads((out / "summary.json").read_text())["timings"]
    return {"process_s": round(wall, 3), "write_s": t.get("write_results"), "solve_s": t.get("solve")}


def measure(rounds: int = 2, scenes=SCENES) -> dict:
    """{"rounds": [{"load_before": l, "runs": {scene: {variant: figures}}}], "load_after": l,
    "median": {scene: {variant: figures}}} (module docstring)."""
    out: dict = {"rounds": [], "cpus": os.cpu_count()}
    with tempfile.TemporaryDirectory(prefix="picture_speed-") as tmp:
        for _ in range(rounds):
            rnd: dict = {"load_before": round(os.getloadavg()[0], 2), "runs": {}}
            for scene in scenes:
                runs = {v: run_once(scene, v, tmp) for v in VARIANTS}
                base = runs["no-pictures"]["write_s"]
                for v in ("child", "in-process"):
                    runs[v]["pictures_after_solve_s"] = round(runs[v]["write_s"] - base, 3)
                rnd["runs"][scene] = runs
            out["rounds"].append(rnd)
    out["load_after"] = round(os.getloadavg()[0], 2)
    med: dict = {}
    for scene in scenes:
        for v in VARIANTS:
            figs = [r["runs"][scene][v] for r in out["rounds"]]
            med.setdefault(scene, {})[v] = {
                k: round(statistics.median(f[k] for f in figs), 3) for k in figs[0] if figs[0][k] is not None
            }
    out["median"] = med
    out["targets"] = {
        f"{s} {k} <= {lim}": {"median": med[s]["child"].get(k), "met": med[s]["child"].get(k, float("inf")) <= lim}
        for (s, k), lim in TARGETS.items()
        if s in med
    }
    return out


def table(res: dict) -> str:
    lines = ["| round | load | scene | variant | process [s] | solve [s] | write [s] | pictures after solve [s] |"]
    lines.append("|---|---|---|---|---|---|---|---|")
    for i, rnd in enumerate(res["rounds"], 1):
        for scene, runs in rnd["runs"].items():
            for v, f in runs.items():
                lines.append(
                    f"| {i} | {rnd['load_before']} | {scene} | {v} | {f['process_s']:.2f} | {f['solve_s']:.2f} | "
                    f"{f['write_s']:.2f} | {f.get('pictures_after_solve_s', '')} |"
                )
    lines.append(f"\nload after: {res['load_after']}")
    for k, v in res["targets"].items():
        lines.append(f"target {k}: median {v['median']} -> {'met' if v['met'] else 'NOT met'}")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--json", help="also write the figures to this JSON file")
    a = ap.parse_args(argv)
    res = measure(a.rounds, tuple(s for s in a.scenes.split(",") if s))
    print(table(res))
    if a.json:
        Path(a.json).write_text(json.dumps(res, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
