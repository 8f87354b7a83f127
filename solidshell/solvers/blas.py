"""Keep BLAS single-threaded inside the solvers (and the element kernels serial on small meshes).

The solvers' parallel work runs in the numba element kernels (their own threads) and in SuperLU
(serial); BLAS only sees level-1 calls (dot products, norms) and ARPACK's small dense work.  A
threaded OpenBLAS turns each such call into a thread hand-off: measured here, a 19 000-long np.dot
took 3.5 us with one BLAS thread and 2-8 ms with two while the other core was busy, and the
static solver of square-pedestal 48x16x4 spent 6.3 s in 575 such calls.  The limit is scoped to
the solver call (threadpoolctl), so the user's own process settings are left alone afterwards.
"""

from __future__ import annotations

import contextlib
import functools

from threadpoolctl import threadpool_limits

SERIAL_KERNEL_ELEMENTS = 1000
"""Below this many elements the static solver runs the element kernels on one numba thread: a
parallel region costs a hand-off to the other thread, which on a shared machine waits for a time
slice.  Measured on the 20-element strip at load ~11 on 2 cores: a force + force-tangent call pair
took 15-60 ms wall (4-16 ms CPU, spinning OpenMP workers) on 2 threads and 1-2 ms (0.3 ms CPU) on
one; on square-pedestal 48x16x4 (3072 quads) one thread was still faster at that load (104-115 ms
against 129-156 ms), but on a quiet machine two threads halve the kernel time of a large mesh."""


def single_threaded_blas(fn):
    """Decorator: run ``fn`` with BLAS limited to one thread."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        # threadpoolctl limits only the BLAS libraries loaded when the limit is set, and scipy
        # ships its own OpenBLAS (ARPACK's, SuperLU's), loaded by its first import: loaded
        # inside the solver, it ran ARPACK's reorthogonalisation on 2 threads.  Measured on the
        # sphere 100x100 critical-step estimate (882 force evaluations, load 5): 48 s -> 27 s,
        # of which 20 s -> 8 s outside the force evaluations.
        import scipy.linalg  # noqa: F401

        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)

    return wrapper


@contextlib.contextmanager
def kernel_threads(n_elements: int):
    """numba threads for the element kernels of a solve on ``n_elements`` elements: one below
    ``SERIAL_KERNEL_ELEMENTS``, else the process setting; restored afterwards."""
    if n_elements >= SERIAL_KERNEL_ELEMENTS:
        yield
        return
    import numba

    old = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(old)
