"""Sparse symmetric factorisations for the static solvers.

Two factorisations, for two jobs:

``Cholesky``  CHOLMOD's supernodal Cholesky (SuiteSparse, through cvxopt) of a symmetric matrix
    that should be positive definite; failure *is* the answer "not positive definite".  The energy
    Newton needs exactly this: it factors K_t + sigma diag|K_t| with the smallest sigma that works.
    The tangents of one solve share a sparsity pattern, so the symbolic analysis (fill-reducing
    ordering, supernodes) is done once and reused; only the lower triangle is handed over.
    Several times faster than SuperLU (below) on the drapes (timings: docs/solvers.md, section 5).
    ``pardiso.Pardiso`` is the same interface on Intel MKL PARDISO (MKL: the optional extra [mkl] on Linux
    x86-64): about twice as fast again; ``factorization="auto"`` (the default) takes it when MKL
    is installed and the system is not tiny (``resolve_factorization``).

``ldl_inertia``  SuperLU with diagonal pivoting in symmetric mode: an LDL^T-type factorisation of
    any symmetric non-singular matrix, with its inertia (the number of negative pivots equals the
    number of negative eigenvalues, Sylvester's law).  The paper's scheme (Eq. 17 solves with an
    indefinite K_t as well) and the arc-length method (which counts negative eigenvalues along the
    path) need it.  With PARDISO, ``static.system.System.ldl`` uses PARDISO's LDL^T
    (pardiso.PardisoLDL) instead wherever it needs no perturbed pivot.
"""

from __future__ import annotations

import platform

import cvxopt
import cvxopt.cholmod as _cholmod
import numpy as np

from .sparse import SINGULAR_PIVOT, LowerCSC, PatternFactor, as_csc

__all__ = [
    "Cholesky",
    "LowerCSC",
    "PatternFactor",
    "SuperLUDefinite",
    "as_csc",
    "ldl_inertia",
    "pcg",
    "SINGULAR_PIVOT",
    "FACTORIZATIONS",
    "CHOLESKY_KINDS",
    "PARDISO_MIN_DOFS",
    "resolve_factorization",
    "positive_definite_factor",
    "arpack_start",
]

FACTORIZATIONS = ("auto", "cholmod", "pardiso", "superlu")
"""The static solvers' ``factorization`` setting: "auto" is "pardiso" where MKL is installed (on
systems of at least PARDISO_MIN_DOFS free dofs), else "cholmod"."""

CHOLESKY_KINDS = ("cholmod", "pardiso")
"""Factorisations that are a Cholesky of a positive-definite matrix (failure = not definite)."""


PARDISO_MIN_DOFS = 1000
""""auto" takes PARDISO from this many free dofs.  Below, a factorisation takes well under a
millisecond either way, and loading MKL (~50 ms and 13.6 MB for its library and first call) would
not be repaid: the 20-element strip's start-up (issue 13) stays as it was.  Square-pedestal 12x4x4
(1 152 free dofs, 85 factorisations of 1.2 against 2.0 ms) already repays it."""


def arpack_start(n: int) -> np.ndarray:
    """ARPACK's start vector for an n x n problem: the same on every call and in every process.

    Without one, ``eigsh`` draws a random start in each process, and the eigenvector it returns
    (its sign, and its direction within a cluster of near-equal eigenvalues) differs from run to
    run: a saddle escape along it, or a modal damping set from it, would then leave the same drape
    in another state or on another path (issue 34: same answer on every machine and every run)."""
    return np.random.default_rng(20150101).standard_normal(n)


def resolve_factorization(kind: str, n_free: int | None = None) -> str:
    """The factorisation ``kind`` names for ``n_free`` free dofs (None: a large system): "auto" is
    "pardiso" where MKL is installed and n_free >= PARDISO_MIN_DOFS, else "cholmod".  InputError
    for an unknown kind or for "pardiso" without MKL (with the one-line reason)."""
    from ..errors import InputError
    from . import pardiso

    if kind not in FACTORIZATIONS:
        raise InputError(f"factorization must be one of {FACTORIZATIONS}, got {kind!r}")
    if kind == "auto":
        small = n_free is not None and n_free < PARDISO_MIN_DOFS
        if small:
            return "cholmod"
        if pardiso.available():
            return "pardiso"
        _hint_mkl()
        return "cholmod"
    if kind == "pardiso" and not pardiso.available():
        raise InputError(f"factorization 'pardiso': {pardiso.unavailable_reason()}")
    return kind


_HINTED: list = []


def _hint_mkl() -> None:
    """One log line per process when "auto" falls back to CHOLMOD for want of MKL (an optional
    extra since issue 40: the main job is 1.1-1.4x faster with it, README "Install")."""
    if _HINTED or platform.machine().lower() not in ("x86_64", "amd64"):
        return
    _HINTED.append(True)
    import logging

    logging.getLogger(__name__).warning(
        "static solves use CHOLMOD: MKL PARDISO is not installed "
        "(pip install 'solidshell[mkl]' makes the main job ~1.2x faster)"
    )


def positive_definite_factor(kind: str):
    """A new factorisation object of a resolved ``kind`` (``factor(A, shift) -> bool``, ``solve``)."""
    if kind == "pardiso":
        from .pardiso import Pardiso

        return Pardiso()
    return Cholesky() if kind == "cholmod" else SuperLUDefinite()


def ldl_inertia(A):
    """SuperLU of a symmetric CSC ``A`` (or a :class:`LowerCSC`) with diagonal pivoting in symmetric mode.

    Returns (lu, n_negative): n_negative is the number of negative eigenvalues of A (with a
    symmetric permutation and diagonal pivots the U diagonal is the D of an LDL^T), or None when the
    pivoting was not symmetric.  Raises RuntimeError when A is singular.
    """
    from scipy.sparse.linalg import splu  # only where a tangent is indefinite: a lazy import

    A = as_csc(A)
    lu = splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=dict(SymmetricMode=True))
    d = lu.U.diagonal()
    ad = np.abs(d)
    if not np.all(np.isfinite(d)) or ad.min(initial=np.inf) <= SINGULAR_PIVOT * ad.max(initial=0.0):
        raise RuntimeError("singular matrix (a pivot below %.0e of the largest)" % SINGULAR_PIVOT)
    neg = int(np.count_nonzero(d < 0.0)) if np.array_equal(lu.perm_r, lu.perm_c) else None
    return lu, neg


class Cholesky(PatternFactor):
    """Supernodal Cholesky of symmetric matrices sharing a sparsity pattern (CHOLMOD).

    ``factor(A, shift)`` factors A + diag(shift) and returns True, or False when that matrix is not
    (numerically) positive definite; ``solve(b)`` then solves with the last successful factor.  A
    is a :class:`LowerCSC` (the fast path: its values go straight into CHOLMOD's matrix) or a
    symmetric scipy matrix with both triangles stored.  A new pattern triggers a new symbolic
    analysis (AMD ordering, supernodes), so any sequence of matrices is accepted.

    The CHOLMOD matrix (a cvxopt spmatrix) is built once per pattern and only its values are
    replaced afterwards (``spmatrix.V``): rebuilding it from triplets every iteration cost up to a
    third of a numeric factorisation (docs/solvers.md, section 5).
    """

    def __init__(self):
        self._F = None
        self._M = None
        self.n_symbolic = 0

    def _analyse(self, L):
        n = L.shape[0]
        col = np.repeat(np.arange(n, dtype=np.int64), np.diff(L.indptr))
        self._vbuf = cvxopt.matrix(np.ones(L.indices.size))
        self._v = np.asarray(self._vbuf).reshape(-1)  # a view of the cvxopt buffer
        self._M = cvxopt.spmatrix(self._vbuf, cvxopt.matrix(L.indices.astype(np.int64)), cvxopt.matrix(col), (n, n))
        self._n = n
        self._key = L.key
        # a keyed pattern owns its arrays (they are never changed): no copy (2 MB on square-pedestal
        # 48x16x4, alive next to the factor at the static solver's memory peak)
        self._indptr = L.indptr if L.key is not None else L.indptr.copy()
        self._indices = L.indices if L.key is not None else L.indices.copy()
        if not np.array_equal(np.asarray(self._M.I).ravel(), L.indices):
            raise RuntimeError("the lower-triangle pattern must have sorted, unique row indices")
        _cholmod.options["supernodal"] = 2
        self._F = _cholmod.symbolic(self._M, uplo="L")
        self.n_symbolic += 1

    def factor(self, A, shift=None) -> bool:
        """Factor A + diag(shift).

        Returns False (and keeps no factor) when it is not positive definite, or when its smallest
        pivot is below ``SINGULAR_PIVOT`` of the largest (singular for practical purposes)."""
        if self._values(A, shift) is None:
            return False
        self._M.V = self._vbuf
        try:
            _cholmod.numeric(self._M, self._F)
        except ArithmeticError:
            return False
        d = np.asarray(_cholmod.diag(self._F)).ravel()  # diagonal of L
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
        import scipy.sparse as sp

        A = as_csc(A)
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


def pcg(matvec, b, precondition, eta, max_iter):
    """Preconditioned conjugate gradients for A x = b, A symmetric, to |b - A x| <= eta |b|.

    ``matvec`` applies A, ``precondition`` an approximation of A^-1 (symmetric positive definite: a
    Cholesky factor of a nearby matrix).  Returns (x, iterations, converged, x.A.x).  Stops,
    not converged, after ``max_iter`` iterations or on a direction of non-positive curvature (A is
    then not positive definite along the Krylov space).  Every iterate is a descent direction of
    the quadratic 1/2 x.A.x - b.x, started from x = 0 (Steihaug)."""
    x = np.zeros_like(b)
    Ax = np.zeros_like(b)
    r = b.copy()
    z = precondition(r)
    d = z.copy()
    rz = float(np.dot(r, z))
    nb = float(np.linalg.norm(b))
    for k in range(1, int(max_iter) + 1):
        Ad = matvec(d)
        dAd = float(np.dot(d, Ad))
        if not (dAd > 0.0 and np.isfinite(dAd)):
            return x, k, False, float(np.dot(x, Ax))
        a = rz / dAd
        x += a * d
        Ax += a * Ad
        r -= a * Ad
        if float(np.linalg.norm(r)) <= eta * nb:
            return x, k, True, float(np.dot(x, Ax))
        z = precondition(r)
        rz_new = float(np.dot(r, z))
        d = z + (rz_new / rz) * d
        rz = rz_new
    return x, int(max_iter), False, float(np.dot(x, Ax))
