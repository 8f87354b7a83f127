"""Keep BLAS single-threaded inside the solvers.

The solvers' parallel work runs in the numba element kernels (their own threads) and in SuperLU
(serial); BLAS only sees level-1 calls (dot products, norms) and ARPACK's small dense work.  A
threaded OpenBLAS turns each such call into a thread hand-off: measured here, a 19 000-long np.dot
took 3.5 us with one BLAS thread and 2-8 ms with two while the other core was busy, and the
static solver of square-pedestal 48x16x4 spent 6.3 s in 575 such calls.  The limit is scoped to
the solver call (threadpoolctl), so the user's own process settings are left alone afterwards.
"""

from __future__ import annotations

import functools

from threadpoolctl import threadpool_limits


def single_threaded_blas(fn):
    """Decorator: run ``fn`` with BLAS limited to one thread."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)

    return wrapper
