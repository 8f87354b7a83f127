"""Whole-process time of a small run (issue 13, target 4): ``python -m solidshell run strip-warp``
(20 elements) end to end -- interpreter start, imports, compiled-kernel cache load, meshing, static
solve, files -- for two trees interleaved in one run (default /work/main against this worktree),
with pictures and with ``--no-pictures`` (tree B only: the option is new; tree A gets
``--set output.pictures=[]`` for the same effect).

Per variant: median wall time and median CPU time (user + system of the child process, from
getrusage) over ``--repeats`` runs, the load average before each run, and the ratios A/B.  On a
machine shared with other jobs the CPU time is the steadier figure: wall time waits for a core.

    python benchmarks/startup.py [--repeats 3] [--a /work/main] [--b .]
    python benchmarks/startup.py --floor [--repeats 5]

``--floor`` measures what any process that runs a compiled kernel pays before solidshell does
anything, interleaved with the strip run (``--no-pictures``) of this tree: the bare interpreter,
``import numpy, scipy.sparse``, then ``numba`` too, then one call of a one-line ``@njit(cache=True)``
function whose cache is already on disk (numba's first cached call sets up its compiler context).
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
    p = subprocess.run(
        [sys.executable, "-m", "solidshell", "run", "strip-warp", "--out", out, "--no-progress", *extra],
        cwd=str(tree),
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    shutil.rmtree(out, ignore_errors=True)
    if p.returncode:
        raise RuntimeError(f"{tree}: exit {p.returncode}: {p.stderr[-1500:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


FLOOR = {
    "python": "pass",
    "numpy + scipy.sparse": "import numpy, scipy.sparse",
    "+ numba": "import numpy, scipy.sparse, numba",
    "+ one cached kernel": "import numpy, scipy.sparse, kernel; kernel.f(1.0)",
}
KERNEL = "from numba import njit\n\n\n@njit(cache=True)\ndef f(x):\n    return 2.0 * x\n"


def floor(repeats: int) -> dict:
    """Median wall / CPU of the FLOOR snippets and of the strip run, interleaved ``repeats`` times."""
    d = Path(tempfile.mkdtemp(prefix="startup_floor_"))
    (d / "kernel.py").write_text(KERNEL)
    subprocess.run([sys.executable, "-c", FLOOR["+ one cached kernel"]], cwd=d, check=True)  # cache it

    def snippet(code):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], cwd=d, check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        return time.perf_counter() - t0, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)

    runs = {
        **{k: (lambda c=c: snippet(c)) for k, c in FLOOR.items()},
        "strip-warp --no-pictures": lambda: one(ROOT, ["--no-pictures"]),
    }
    runs["strip-warp --no-pictures"]()
    res = {k: [] for k in runs}
    for i in range(repeats):
        load = os.getloadavg()[0]
        for k, fn in runs.items():
            res[k].append(fn())
        print(f"round {i + 1} load {load:.2f}", flush=True)
    med = {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in res.items()}
    for k, (w, c) in med.items():
        print(f"median {k:26s} wall {w:5.2f} s  cpu {c:5.2f} s")
    shutil.rmtree(d, ignore_errors=True)
    return med


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--a", default="/work/main")
    ap.add_argument("--b", default=str(ROOT))
    ap.add_argument("--floor", action="store_true", help="the start-up floor of any compiled-kernel process")
    a = ap.parse_args(argv)
    if a.floor:
        return floor(a.repeats)
    A, B = Path(a.a).resolve(), Path(a.b).resolve()
    variants = {
        "A pictures": (A, []),
        "B pictures": (B, []),
        "A no pictures": (A, ["--set", "output.pictures=[]"]),
        "B --no-pictures": (B, ["--no-pictures"]),
    }
    one(B, ["--no-pictures"])  # compile/cache warm-up of both trees' kernels
    one(A, ["--set", "output.pictures=[]"])
    res = {k: [] for k in variants}
    for i in range(a.repeats):
        for k, (tree, extra) in variants.items():
            load = os.getloadavg()
            w, c = one(tree, extra)
            res[k].append((w, c))
            print(
                f"run {i + 1} {k:16s} wall {w:6.2f} s  cpu {c:5.2f} s  load {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}",
                flush=True,
            )
    med = {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in res.items()}
    print(f"\nA = {A}\nB = {B}")
    for k, (w, c) in med.items():
        print(f"median {k:16s} wall {w:6.2f} s  cpu {c:5.2f} s")
    for x, y in (("A pictures", "B pictures"), ("A no pictures", "B --no-pictures"), ("A pictures", "B --no-pictures")):
        print(f"ratio {x} / {y}: wall {med[x][0] / med[y][0]:.2f}, cpu {med[x][1] / med[y][1]:.2f}")
    return med


if __name__ == "__main__":
    main()
