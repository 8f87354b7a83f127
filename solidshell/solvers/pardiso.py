"""Intel MKL PARDISO's sparse Cholesky, with :class:`solidshell.solvers.linear.Cholesky`'s interface,
and its LDL^T with inertia (:class:`PardisoLDL`).

It needs the ``mkl`` wheel, a dependency of solidshell on Linux x86-64 (pyproject.toml; elsewhere
the static solvers use CHOLMOD, and ``factorization="pardiso"`` says in one line that MKL is
missing).  This module is a thin ctypes binding of the one routine ``pardiso`` in ``libmkl_rt``
(``pypardiso`` wraps the same routine but hashes the matrix on every solve and cannot keep the
analysis for new values).  Why: it factorises the drapes' free-dof tangents in about half
CHOLMOD's time at the same fill, and factorisations are most of a static solve (measurements:
docs/solvers.md, section 5).

Matrix type 2 (real symmetric positive definite): a Cholesky LL^T without pivot perturbation, so a
matrix that is not positive definite fails (MKL error -4, "zero pivot"), which is the answer the
energy Newton asks for (linear.Cholesky).  The input is the lower triangle in CSC
(sparse.LowerCSC) read as the upper triangle in CSR, the form PARDISO takes, zero-based
(iparm[34] = 1): no copy of the pattern.  The analysis (minimum-degree ordering, symbolic
factorisation) is done once per pattern; ``factor`` runs the numeric phase only.

Threads: a factorisation of at least ``THREADED_MFLOP`` (PARDISO's own count from the analysis)
runs on numba's thread count (``numba.get_num_threads()`` at the analysis: ``NUMBA_NUM_THREADS``
governs both), in MKL's conditional numerical reproducibility mode (``iparm[33]``), so that its
factor and solutions are the same bits on one thread or two.  Smaller ones run on one thread
without that mode.  MKL runs on its GNU OpenMP layer, the libgomp whose thread pool numba's "omp"
layer already uses, so the two never hold four threads on two cores (sequential where that layer
is not installed).  Measurements: docs/solvers.md, section 5.
"""

from __future__ import annotations

import ctypes
import glob
import os
import sys
from ctypes.util import find_library

import numpy as np

from .sparse import SINGULAR_PIVOT, PatternFactor

__all__ = ["Pardiso", "PardisoLDL", "available", "unavailable_reason"]

_LIB = None
_REASON = None
_SEQUENTIAL = 1  # MKL_THREADING_SEQUENTIAL (mkl_service.h)
_GNU_OPENMP = 3  # MKL_THREADING_GNU
_CNR = 2  # iparm[33] > 0: reproducible mode (the value: threads to tune for; the
# factors were the same bits for 1-8 and on 1 or 2 threads)

THREADED_MFLOP = 1000
"""Factorisations of at least this many Mflop run threaded.  square-on-disc 30x240 (1,875 Mflop):
100 -> 60-80 ms per factorisation on two threads; square-pedestal 48x16x4 (394 Mflop): 35 -> 18-24
ms, but its solves, which outnumber the factorisations 3 to 1 there, went 5 -> 9 ms and the run was
slower (docs/solvers.md, section 5)."""
_MTYPE_SPD = 2
_MTYPE_SYM_INDEFINITE = -2
_INT = ctypes.c_int32
_IP = ctypes.POINTER(ctypes.c_int32)
_DP = ctypes.POINTER(ctypes.c_double)


def _candidates():
    own = os.environ.get("SOLIDSHELL_MKL_RT")
    if own:
        yield own
    for base in (sys.prefix, getattr(sys, "base_prefix", sys.prefix)):
        yield from sorted(glob.glob(os.path.join(base, "lib", "libmkl_rt.so*")), key=len)
    name = find_library("mkl_rt")
    if name:
        yield name


def _has_gnu_layer(path):
    """True when MKL's GNU OpenMP layer is installed with the library at ``path`` and the GNU
    OpenMP runtime it needs loads (MKL ends the process when a layer it was told to use cannot be
    loaded)."""
    if os.sep in path:
        dirs = [os.path.dirname(os.path.realpath(path))]
    else:
        dirs = [os.path.join(b, "lib") for b in (sys.prefix, sys.base_prefix)]
    if not any(glob.glob(os.path.join(d, "libmkl_gnu_thread.so*")) for d in dirs):
        return False
    try:
        ctypes.CDLL("libgomp.so.1")
    except OSError:
        return False
    return True


def _load():
    """The mkl_rt library with PARDISO's argument types declared, or None (reason in _REASON)."""
    global _LIB, _REASON
    if _LIB is not None or _REASON is not None:
        return _LIB
    for path in _candidates():
        try:
            lib = ctypes.CDLL(path)
            lib.pardiso
        except (OSError, AttributeError):
            continue
        lib.MKL_Set_Threading_Layer.argtypes = [ctypes.c_int]
        lib.MKL_Set_Threading_Layer(_GNU_OPENMP if _has_gnu_layer(path) else _SEQUENTIAL)
        lib.MKL_Set_Num_Threads_Local.argtypes = [ctypes.c_int]
        lib.MKL_Set_Num_Threads_Local.restype = ctypes.c_int
        # MKL's own memory pool keeps every freed buffer: without it the static square-pedestal
        # run peaks 2.6 MB lower, at no measured cost (PARDISO allocates a few buffers per call)
        lib.mkl_disable_fast_mm()
        lib.pardiso.argtypes = [
            ctypes.POINTER(ctypes.c_int64),
            _IP,
            _IP,
            _IP,
            _IP,
            _IP,
            _DP,
            _IP,
            _IP,
            _IP,
            _IP,
            _IP,
            _IP,
            _DP,
            _DP,
            _IP,
        ]
        lib.pardiso.restype = None
        lib.pardiso_getdiag.argtypes = [ctypes.POINTER(ctypes.c_int64), _DP, _DP, _IP, _IP]
        lib.pardiso_getdiag.restype = None
        _LIB = lib
        return lib
    _REASON = (
        "Intel MKL (libmkl_rt) not found: `pip install 'solidshell[mkl]'` (Linux x86-64), or set "
        "SOLIDSHELL_MKL_RT to the library's path"
    )
    return None


def available() -> bool:
    """True when MKL PARDISO can be loaded."""
    return _load() is not None


def unavailable_reason() -> str | None:
    """One line saying why PARDISO cannot be used (None when it can)."""
    _load()
    return _REASON if _LIB is None else None


class Pardiso(PatternFactor):
    """PARDISO Cholesky of symmetric matrices sharing a sparsity pattern: ``factor(A, shift)`` factors
    A + diag(shift) (A a sparse.LowerCSC) and returns True, or False when that matrix is not
    positive definite; ``solve(b)`` solves with the last successful factor."""

    _mtype = _MTYPE_SPD

    def __init__(self):
        lib = _load()
        if lib is None:
            raise RuntimeError(_REASON)
        self._lib = lib
        self._pt = np.zeros(64, dtype=np.int64)  # PARDISO's opaque handle
        self._iparm = np.zeros(64, dtype=np.int32)
        ip = self._iparm
        ip[0] = 1  # the settings below, not the defaults
        ip[1] = 0  # minimum-degree ordering: on the drapes' tangents 12 % less fill than
        # METIS, a 15 % faster factorisation and no 0.4 s METIS start-up
        # (docs/solvers.md, section 5)
        ip[7] = 0  # no iterative refinement (a plain solve, as CHOLMOD's)
        ip[34] = 1  # zero-based indices
        ip[55] = 1  # keep the factor's diagonal (pardiso_getdiag: the singular-pivot test)
        self._v = None
        self._n = 0
        self._threads = 1
        self.n_symbolic = 0

    # ------------------------------------------------------------------ the one routine
    def _call(self, phase, a, b=None, x=None):
        # every phase of a handle on the thread count of its analysis: MKL 2026.2 crashed
        # (segmentation fault) solving on one thread with a factor made on two
        old = self._lib.MKL_Set_Num_Threads_Local(self._threads)
        try:
            return self._pardiso(phase, a, b, x)
        finally:
            self._lib.MKL_Set_Num_Threads_Local(old)

    def _pardiso(self, phase, a, b, x):
        err = _INT(0)
        self._lib.pardiso(
            self._pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
            ctypes.byref(_INT(1)),
            ctypes.byref(_INT(1)),
            ctypes.byref(_INT(self._mtype)),
            ctypes.byref(_INT(phase)),
            ctypes.byref(_INT(self._n)),
            a.ctypes.data_as(_DP),
            self._indptr.ctypes.data_as(_IP),
            self._indices.ctypes.data_as(_IP),
            None,
            ctypes.byref(_INT(1)),
            self._iparm.ctypes.data_as(_IP),
            ctypes.byref(_INT(0)),
            None if b is None else b.ctypes.data_as(_DP),
            None if x is None else x.ctypes.data_as(_DP),
            ctypes.byref(err),
        )
        return err.value

    def _release(self):
        if self._indptr is not None and self._n:
            self._call(-1, self._v)
        self._key = self._indptr = self._indices = None
        self._ok = False

    def __del__(self):
        try:
            self._release()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass

    # ------------------------------------------------------------------ Cholesky's interface
    def _analyse(self, L):
        self._release()
        self._n = L.shape[0]
        self._indptr = np.ascontiguousarray(L.indptr, dtype=np.int32)
        self._indices = np.ascontiguousarray(L.indices, dtype=np.int32)
        self._v = np.array(L.data, dtype=float)
        self._threads, self._iparm[33], self._iparm[18] = 1, 0, -1  # [18] < 0: count the flops
        err = self._call(11, self._v)
        if err == 0 and self._iparm[18] >= THREADED_MFLOP:
            from numba import get_num_threads

            self._call(-1, self._v)
            self._threads, self._iparm[33] = get_num_threads(), _CNR
            err = self._call(11, self._v)
        if err != 0:
            raise RuntimeError(f"PARDISO analysis failed (MKL error {err})")
        self._key = L.key
        self.n_symbolic += 1

    def factor(self, A, shift=None) -> bool:
        """Factor A + diag(shift); False (and no factor kept) when it is not positive definite
        (PARDISO's Cholesky meets a non-positive pivot), not finite, or numerically singular (a
        pivot below sparse.SINGULAR_PIVOT of the largest: CHOLMOD's test, on L_ii^2)."""
        v = self._values(A, shift)
        if v is None:
            return False
        err = self._call(22, v)
        if err == -4:  # zero or negative pivot: not positive definite
            return False
        if err != 0:
            raise RuntimeError(f"PARDISO factorisation failed (MKL error {err})")
        piv = self._pivots()
        self._ok = bool(piv.size and piv.min() > 0.0 and piv.min() > SINGULAR_PIVOT * piv.max())
        return self._ok

    def _pivots(self):
        """The factor's pivots L_ii^2 (pardiso_getdiag), in the matrix's order."""
        df = np.empty(self._n)
        da = np.empty(self._n)
        err = _INT(0)
        self._lib.pardiso_getdiag(
            self._pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
            df.ctypes.data_as(_DP),
            da.ctypes.data_as(_DP),
            ctypes.byref(_INT(1)),
            ctypes.byref(err),
        )
        if err.value != 0:
            raise RuntimeError(f"PARDISO diagonal not available (MKL error {err.value})")
        return df

    def solve(self, b):
        """x with (A + diag(shift)) x = b for the last successful ``factor``."""
        if not self._ok:
            raise RuntimeError("no positive-definite factorisation to solve with")
        b = np.asarray(b, dtype=float)
        if b.ndim == 2:
            return np.column_stack([self.solve(c) for c in b.T])
        b = np.ascontiguousarray(b)
        x = np.empty_like(b)
        err = self._call(33, self._v, b, x)
        if err != 0:
            raise RuntimeError(f"PARDISO solve failed (MKL error {err})")
        return x


class PardisoLDL(Pardiso):
    """PARDISO's LDL^T of symmetric indefinite matrices (matrix type -2, Bunch-Kaufman 1x1 and 2x2
    pivots within supernodes) with its inertia, for the paper's scheme and the arc-length method
    (linear.ldl_inertia's job, ~2-3x faster than SuperLU there).  ``ldl(A)`` returns
    (self, number of negative eigenvalues), or None when PARDISO had to perturb a pivot (a pivot
    below 1e-8 of the matrix's scale: then neither the inertia nor the solve is exact, and the
    caller falls back to SuperLU, whose stricter singularity test decides)."""

    _mtype = _MTYPE_SYM_INDEFINITE

    def __init__(self):
        super().__init__()
        ip = self._iparm
        ip[9] = 8  # perturb pivots below 1e-8 (and report them: iparm[13])
        ip[10] = 1  # symmetric scaling and
        ip[12] = 1  # weighted matching: the 2x2 pivots chosen before the ordering
        ip[20] = 1  # Bunch-Kaufman pivoting
        ip[55] = 0  # no pardiso_getdiag here: 2x2 pivots make D's diagonal no test

    def factor(self, A, shift=None):
        raise TypeError("PardisoLDL factorises with ldl(A)")

    def ldl(self, A):
        """(self, n_negative) after factorising A, or None (perturbed pivots or non-finite A)."""
        v = self._values(A)
        if v is None:
            return None
        err = self._call(22, v)
        ip = self._iparm
        if err != 0 or ip[13] != 0 or ip[21] + ip[22] != self._n:
            return None
        self._ok = True
        return self, int(ip[22])
