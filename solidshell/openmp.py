"""How long an idle OpenMP thread spins before it sleeps: ``GOMP_SPINCOUNT`` = SPINCOUNT by default.

NumPy-free: ``solidshell/__init__.py`` applies it before numba's or MKL's OpenMP runtime (GNU
libgomp, which MKL's GNU threading layer shares here) is loaded, because libgomp reads its
environment once, when it loads.  A value the user set is kept (``os.environ.setdefault``); other
OpenMP runtimes ignore the variable.

Why: by default libgomp lets a thread that finished its share of a parallel region spin for about
300,000 iterations before sleeping.  On a 2-core machine where any other process is busy, the
spinning thread takes the core the lagging thread of the same region needs, and every region of
the explicit loop waits for the scheduler.  Measured with ``benchmarks/explicit_throughput.py
--sizes 100 --steps 300 --threads 2`` (10^4 quads, 2026-12-06, two passes per variant, variants
interleaved; "loaded": two single-thread solidshell runs beside it, "quiet": those stopped):

| GOMP_SPINCOUNT / OMP_WAIT_POLICY | loaded [M element-steps/s] | quiet |
|---|---|---|
| unset (libgomp's default) | 2.4-3.3 | 10.9-11.6 |
| 100000 | 3.4-3.7 | 10.5-11.0 |
| 30000 | 4.3-4.4 | 11.1-11.3 |
| 10000 | 5.2-6.3 | 9.9-11.3 |
| 1000 | 6.8-7.0 | 9.6-9.8 |
| OMP_WAIT_POLICY=passive (no spinning) | 6.1-7.7 | 8.9-10.7 |

10000 keeps the quiet machine's figure within its noise and doubles the loaded one."""

from __future__ import annotations

import os

SPINCOUNT = "10000"


def configure() -> None:
    """Set ``GOMP_SPINCOUNT`` to SPINCOUNT unless the user set it (or OMP_WAIT_POLICY, which
    libgomp then follows instead)."""
    if "OMP_WAIT_POLICY" not in os.environ:
        os.environ.setdefault("GOMP_SPINCOUNT", SPINCOUNT)
