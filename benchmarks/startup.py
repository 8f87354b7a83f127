"""Whole-process time of a small run (issue 13, target 4): ``python -m solidshell run strip-warp``
(20 elements) end to end -- interpreter start, imports, compiled-kernel cache load, meshing, static
solve, files -- for two trees interleaved in one run (default /work/main against this worktree),
with pictures and with ``--no-pictures`` (tree B only: the option is new; tree A gets
``--set output.pictures=[]`` for the same effect).

Per variant: median wall time and median CPU time (user + system of the child process, from
getrusage) over ``--repeats`` runs, the load average before each run, and the ratios A/B.  On a
machine shared with other jobs the CPU time is the steadier figure: wall time waits for a core.

    python benchmarks/startup.py [--repeats 3] [--a /work/main] [--b .]
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def one(tree: Path, extra: list[str]) -> tuple[float, float]:
    out = tempfile.mkdtemp(prefix="startup_")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-m", "solidshell", "run", "strip-warp", "--out", out,
                        "--no-progress", *extra], cwd=str(tree), capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    shutil.rmtree(out, ignore_errors=True)
    if p.returncode:
        raise RuntimeError(f"{tree}: exit {p.returncode}: {p.stderr[-1500:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--a", default="/work/main")
    ap.add_argument("--b", default=str(ROOT))
    a = ap.parse_args(argv)
    A, B = Path(a.a).resolve(), Path(a.b).resolve()
    variants = {
        "A pictures": (A, []), "B pictures": (B, []),
        "A no pictures": (A, ["--set", "output.pictures=[]"]), "B --no-pictures": (B, ["--no-pictures"]),
    }
    one(B, ["--no-pictures"])                      # compile/cache warm-up of both trees' kernels
    one(A, ["--set", "output.pictures=[]"])
    res = {k: [] for k in variants}
    for i in range(a.repeats):
        for k, (tree, extra) in variants.items():
            load = os.getloadavg()
            w, c = one(tree, extra)
            res[k].append((w, c))
            print(f"run {i + 1} {k:16s} wall {w:6.2f} s  cpu {c:5.2f} s  load {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}",
                  flush=True)
    med = {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in res.items()}
    print(f"\nA = {A}\nB = {B}")
    for k, (w, c) in med.items():
        print(f"median {k:16s} wall {w:6.2f} s  cpu {c:5.2f} s")
    for x, y in (("A pictures", "B pictures"), ("A no pictures", "B --no-pictures"), ("A pictures", "B --no-pictures")):
        print(f"ratio {x} / {y}: wall {med[x][0] / med[y][0]:.2f}, cpu {med[x][1] / med[y][1]:.2f}")
    return med


if __name__ == "__main__":
    main()
