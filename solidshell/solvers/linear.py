"""Sparse symmetric factorisations for the static solvers.

Two factorisations, for two jobs:

``Cholesky``  CHOLMOD's supernodal Cholesky (SuiteSparse, through cvxopt) of a symmetric matrix
    that should be positive definite; failure *is* the answer "not positive definite".  The energy
    Newton needs exactly this: it factors K_t + sigma diag|K_t| with the smallest sigma that works.
    The tangents of one solve share a sparsity pattern, so the symbolic analysis (fill-reducing
    ordering, supernodes) is done once and reused; only the lower triangle is handed over.
    Measured on the 18 432 free dofs of square-pedestal 48x16x4 (0.95 M nonzeros): numeric
    factorisation 36-55 ms against 150-240 ms for SuperLU (below), symbolic analysis 17-28 ms once.

``ldl_inertia``  SuperLU with diagonal pivoting in symmetric mode: an LDL^T-type factorisation of
    any symmetric non-singular matrix, with its inertia (the number of negative pivots equals the
    number of negative eigenvalues, Sylvester's law).  The paper's scheme (Eq. 17 solves with an
    indefinite K_t as well) and the arc-length method (which counts negative eigenvalues along the
    path) need it.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

import cvxopt
import cvxopt.cholmod as _cholmod

__all__ = ["Cholesky", "SuperLUDefinite", "ldl_inertia", "SINGULAR_PIVOT", "FACTORIZATIONS"]

FACTORIZATIONS = ("cholmod", "superlu")

SINGULAR_PIVOT = 1e-14
"""A pivot smaller than this fraction of the largest marks a matrix as numerically singular (a free
rigid-body mode or mechanism); legitimate fabric tangents stay above ~1e-10."""


def ldl_inertia(A):
    """SuperLU of a symmetric CSC ``A`` with diagonal pivoting in symmetric mode.

    Returns (lu, n_negative): n_negative is the number of negative eigenvalues of A (with a
    symmetric permutation and diagonal pivots the U diagonal is the D of an LDL^T), or None when the
    pivoting was not symmetric.  Raises RuntimeError when A is singular.
    """
    lu = splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
              options=dict(SymmetricMode=True))
    d = lu.U.diagonal()
    ad = np.abs(d)
    if not np.all(np.isfinite(d)) or ad.min(initial=np.inf) <= SINGULAR_PIVOT * ad.max(initial=0.0):
        raise RuntimeError("singular matrix (a pivot below %.0e of the largest)" % SINGULAR_PIVOT)
    neg = int(np.count_nonzero(d < 0.0)) if np.array_equal(lu.perm_r, lu.perm_c) else None
    return lu, neg


class Cholesky:
    """Supernodal Cholesky of symmetric CSC matrices sharing a sparsity pattern (CHOLMOD).

    ``factor(A, shift)`` factors A + diag(shift) and returns True, or False when that matrix is not
    (numerically) positive definite; ``solve(b)`` then solves with the last successful factor.  A
    new pattern triggers a new symbolic analysis, so any sequence of matrices is accepted.
    """

    def __init__(self):
        self._indptr = None
        self._indices = None
        self._F = None
        self._ok = False
        self.n_symbolic = 0

    def _analyse(self, A):
        n = A.shape[0]
        col = np.repeat(np.arange(n), np.diff(A.indptr))
        row = A.indices
        self._lower = np.flatnonzero(row >= col)
        self._diag = np.flatnonzero(row == col)
        if self._diag.size != n:
            raise RuntimeError("the matrix pattern lacks diagonal entries")
        # position of each diagonal entry inside the lower-triangle value array
        self._diag_in_lower = np.searchsorted(self._lower, self._diag)
        self._I = cvxopt.matrix(row[self._lower].astype(np.int64))
        self._J = cvxopt.matrix(col[self._lower].astype(np.int64))
        self._n = n
        self._indptr = A.indptr.copy()
        self._indices = A.indices.copy()
        M = cvxopt.spmatrix(cvxopt.matrix(np.ones(self._lower.size)), self._I, self._J, (n, n))
        _cholmod.options["supernodal"] = 2
        self._F = _cholmod.symbolic(M, uplo="L")
        self.n_symbolic += 1

    def factor(self, A, shift=None) -> bool:
        """Factor A + diag(shift) (A: symmetric CSC, both triangles stored, sorted indices).

        Returns False (and keeps no factor) when it is not positive definite, or when its smallest
        pivot is below ``SINGULAR_PIVOT`` of the largest (singular for practical purposes)."""
        A = A.tocsc()
        if not A.has_sorted_indices:
            A = A.sorted_indices()
        if (self._F is None or A.shape[0] != self._n or not np.array_equal(A.indptr, self._indptr)
                or not np.array_equal(A.indices, self._indices)):
            self._analyse(A)
        v = A.data[self._lower]
        if shift is not None:
            v[self._diag_in_lower] += shift
        if not np.all(np.isfinite(v)):
            self._ok = False
            return False
        M = cvxopt.spmatrix(cvxopt.matrix(v), self._I, self._J, (self._n, self._n))
        try:
            _cholmod.numeric(M, self._F)
        except ArithmeticError:
            self._ok = False
            return False
        d = np.asarray(_cholmod.diag(self._F)).ravel()    # diagonal of L
        self._ok = bool(d.size and d.min() > 0.0 and d.min() ** 2 > SINGULAR_PIVOT * d.max() ** 2)
        return self._ok

    def solve(self, b):
        """x with (A + diag(shift)) x = b for the last successful ``factor``."""
        if not self._ok:
            raise RuntimeError("no positive-definite factorisation to solve with")
        x = cvxopt.matrix(np.asarray(b, dtype=float).reshape(-1, 1))
        _cholmod.solve(self._F, x)
        return np.asarray(x).ravel()


class SuperLUDefinite:
    """The :class:`Cholesky` interface on SuperLU's LDL^T (``ldl_inertia``): ``factor`` is True when
    the matrix has no negative pivot.  Slower (measured 150-240 ms against 36-55 ms for CHOLMOD at
    18 432 dofs) and kept for comparison: ``solve_static(..., factorization="superlu")`` runs the
    solvers exactly as they ran before CHOLMOD was added."""

    def __init__(self):
        self._lu = None
        self.n_symbolic = 0

    def factor(self, A, shift=None) -> bool:
        M = A if shift is None else (A + sp.diags(shift)).tocsc()
        self._lu = None
        try:
            lu, neg = ldl_inertia(M.tocsc())
        except RuntimeError:
            return False
        if neg != 0:
            return False
        self._lu = lu
        return True

    def solve(self, b):
        if self._lu is None:
            raise RuntimeError("no positive-definite factorisation to solve with")
        return self._lu.solve(np.asarray(b, dtype=float))

