"""The sparse format and the factorisation base that the static solvers' three factorisations share.

``LowerCSC`` is the lower triangle of a symmetric matrix (the form CHOLMOD and PARDISO take, with
the diagonal's positions for a shifted factorisation); ``PatternFactor`` holds one symbolic
analysis per sparsity pattern.  ``linear`` (CHOLMOD, SuperLU) and ``pardiso`` (MKL) both build on
this module, so neither imports the other at module level.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SINGULAR_PIVOT", "LowerCSC", "PatternFactor", "as_csc"]

SINGULAR_PIVOT = 1e-14
"""A pivot smaller than this fraction of the largest marks a matrix as numerically singular (a free
rigid-body mode or mechanism); legitimate fabric tangents stay above ~1e-10."""


class LowerCSC:
    """The lower triangle (diagonal included) of a symmetric matrix in CSC arrays: the form in which
    the static solver assembles its free-dof tangent (solidshell.assembly.FreeLowerPattern) and in
    which CHOLMOD takes it.  ``key`` identifies the sparsity pattern (the pattern object: two
    matrices with the same key share indptr/indices), ``diag_pos`` the diagonal entries in ``data``.
    ``csc()`` gives the full symmetric scipy matrix (both triangles) for the rarer uses that need
    it (SuperLU's inertia, eigsh, matrix-vector products)."""

    __slots__ = ("indptr", "indices", "data", "diag_pos", "key", "_full")

    def __init__(self, indptr, indices, data, diag_pos, key):
        self.indptr, self.indices, self.data, self.diag_pos, self.key = indptr, indices, data, diag_pos, key
        self._full = None

    @property
    def shape(self):
        n = self.indptr.size - 1
        return (n, n)

    def diagonal(self):
        return self.data[self.diag_pos]

    def csc(self):
        if self._full is None:
            import scipy.sparse as sp

            L = sp.csc_matrix((self.data, self.indices, self.indptr), shape=self.shape)
            self._full = (L + sp.tril(L, -1, format="csc").T).tocsc()
            self._full.sort_indices()
        return self._full

    def __matmul__(self, x):
        return self.csc() @ x

    def matvec(self):
        """x -> A x from the stored lower triangle alone (L x + L^T x - diag x): no full matrix is
        formed (``csc()`` would copy both triangles, ~8 MB and ~20 ms on square-pedestal 48x16x4;
        this costs ~1.3 ms a product there)."""
        import scipy.sparse as sp

        L = sp.csc_matrix((self.data, self.indices, self.indptr), shape=self.shape)
        Lt = L.T
        d = self.diagonal()
        return lambda x: L @ x + Lt @ x - d * x

    def toarray(self):
        """The full symmetric matrix as a dense array (numpy only: a small run's stability report
        need not import scipy.sparse, ~0.15-0.3 s of a 20-element run's start-up)."""
        n = self.shape[0]
        col = np.repeat(np.arange(n), np.diff(self.indptr))
        out = np.zeros((n, n))
        out[self.indices, col] = self.data
        out[col, self.indices] = self.data
        return out

    @classmethod
    def from_symmetric(cls, A):
        """The lower triangle of a symmetric scipy matrix (both triangles stored)."""
        import scipy.sparse as sp

        A = sp.csc_matrix(A)
        if not A.has_sorted_indices:
            A = A.sorted_indices()
        L = sp.tril(A, format="csc")
        L.sort_indices()
        n = A.shape[0]
        col = np.repeat(np.arange(n), np.diff(L.indptr))
        diag_pos = np.flatnonzero(L.indices == col)
        if diag_pos.size != n:
            raise RuntimeError("the matrix pattern lacks diagonal entries")
        out = cls(L.indptr, L.indices, L.data, diag_pos, None)
        out._full = A
        return out


def as_csc(A):
    """The full symmetric scipy CSC of ``A`` (a scipy matrix or a :class:`LowerCSC`)."""
    if isinstance(A, LowerCSC):
        return A.csc()
    import scipy.sparse as sp

    return sp.csc_matrix(A)


class PatternFactor:
    """What the factorisation classes share: one symbolic analysis per sparsity pattern (the
    subclass's ``_analyse(L)``, which sets ``_key``, ``_indptr``, ``_indices`` and the value buffer
    ``_v``) and the values of A + diag(shift) written into ``_v`` for each numeric factorisation."""

    _key = None
    _indptr = None
    _indices = None
    _ok = False

    def _same_pattern(self, L):
        if self._indptr is None:
            return False
        if L.key is not None:
            return L.key is self._key
        return (
            L.indptr.size == self._indptr.size
            and np.array_equal(L.indptr, self._indptr)
            and np.array_equal(L.indices, self._indices)
        )

    def _values(self, A, shift=None):
        """The buffer ``_v`` holding A + diag(shift) (A a LowerCSC or a symmetric scipy matrix; a
        new pattern analysed first), or None when those values are not all finite.  Any earlier
        factor is dropped (``_ok`` False) until the subclass's factorisation succeeds."""
        L = A if isinstance(A, LowerCSC) else LowerCSC.from_symmetric(A)
        if not self._same_pattern(L):
            self._analyse(L)
        v = self._v
        v[:] = L.data
        if shift is not None:
            v[L.diag_pos] += shift
        self._ok = False
        return v if np.isfinite(v).all() else None
