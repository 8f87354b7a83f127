"""Critical time step of the central-difference scheme, Eq. (23).

Highest frequency
-----------------
omega_max^2 is the largest eigenvalue of M^-1 K on the free dofs (M lumped, K the tangent at the
current state).  We compute it on the symmetric form A = M^-1/2 K M^-1/2 by **Lanczos iteration**
(ARPACK ``eigsh``, the Krylov refinement of the power iteration), **matrix-free**: a product K v is
the central directional derivative of the internal force,

    K v ~ (F(U + e v) - F(U - e v)) / (2 e),

two internal-force evaluations, the same kernel the explicit loop runs; no tangent matrix is ever
assembled.  Why matrix-free rather than ``model.tangent`` once: it needs nothing but the hot-path
kernel (so it works for any model the loop can run, including the quasi-engineering thickness strain
whose tangent is only piecewise smooth), costs O(N) memory, and can be repeated at a deformed state
mid-run for the price of a few dozen force evaluations.  Why Lanczos rather than the plain power
iteration: in a solid-shell sheet the top of the spectrum is a dense cluster (one thickness-stretch
mode per node, all at nearly the same frequency), where the power iteration's Rayleigh quotient
creeps up from below for thousands of iterations -- and a low estimate of omega_max is an unsafe
(too long) step.  ``method="power"`` (plain power iteration) and ``method="tangent"`` (``eigsh`` on the
assembled ``model.tangent``) are kept for comparison and testing.

Stability limit
---------------
Undamped: dt_crit = 2 / omega_max.  For Eq. (23) -- mass-proportional damping with the *central*
velocity (D_n+1 - D_n-1)/(2 dt) -- a mode x'' + alpha x' + omega^2 x = 0 gives the recursion
(1 + c) x_n+1 - (2 - W^2) x_n + (1 - c) x_n-1 = 0, c = alpha dt/2, W = omega dt, whose roots lie in
the unit disc iff W <= 2: the damping does **not** shorten the critical step.  The textbook bound
dt_crit = (2/omega)(sqrt(1 + xi^2) - xi), xi = alpha/(2 omega) the damping ratio of the highest mode,
holds for schemes that lag the damping force by half a step (velocity v_n-1/2, e.g. Belytschko et
al., Nonlinear FE, Box 6.1).  We report and use that bound anyway: it is conservative for Eq. (23)
and at the highest mode xi is ~1e-5 (alpha = 5 1/s, omega ~ 1e5 1/s), so it costs nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit


@dataclass
class OmegaEstimate:
    """Result of :func:`estimate_omega_max`."""

    omega_max: float  # highest natural frequency [rad / time]
    method: str  # lanczos | power | tangent
    n_force_evals: int  # internal-force evaluations spent (0 for "tangent")
    converged: bool
    mode: np.ndarray | None = field(default=None, repr=False)  # (6N,) flat mode shape (M-normalised)

    @property
    def dt_undamped(self) -> float:
        return 2.0 / self.omega_max


def critical_time_step(omega_max: float, alpha: float = 0.0) -> float:
    """(2/omega)(sqrt(1 + xi^2) - xi) with xi = alpha / (2 omega): the critical step with
    mass-proportional damping alpha [1/time] (see the module docstring; = 2/omega for alpha = 0)."""
    w = float(omega_max)
    if not (w > 0.0 and math.isfinite(w)):
        raise ValueError(f"omega_max must be positive and finite, got {omega_max!r}")
    xi = max(float(alpha), 0.0) / (2.0 * w)
    return (2.0 / w) * (math.sqrt(1.0 + xi * xi) - xi)


_WARM_NOISE = 0.05
"""Weight of the random vector added to a given start vector (relative, both normalised)."""


@dataclass(frozen=True)
class Iteration:
    """How :func:`estimate_omega_max` iterates (defaults that no caller in the package changes).

    fd_step : the largest component of the perturbation e v in the directional derivative
              (in the dofs' own units; 1e-7 is far below the sheet's thickness and director length
              and, with a central difference, far above round-off in F)
    maxiter : iteration cap (None: 2000 Lanczos restarts, 5000 power steps, 10 n for "tangent")
    seed    : the start vector is drawn from this seed, so the estimate is reproducible
    """

    fd_step: float = 1e-7
    maxiter: int | None = None
    seed: int = 0


def estimate_omega_max(
    force,
    mass,
    free,
    U=None,
    *,
    method: str = "lanczos",
    tol: float = 1e-6,
    tangent=None,
    v0=None,
    difference: str = "central",
    iteration: Iteration = Iteration(),
) -> OmegaEstimate:
    """Highest natural frequency of M^-1 K on the free dofs.

    force   : callable U (N,6) -> internal force (N,6) (``model.internal_force``)
    mass    : (N,6) lumped masses (after any mass scaling)
    free    : (N,6) bool mask or flat indices of the free dofs
    U       : state at which K is taken (default zero)
    method  : "lanczos" (matrix-free ARPACK, default), "power" (matrix-free power iteration), or
              "tangent" (ARPACK on ``tangent(U)``, a callable returning the sparse (6N,6N) matrix)
    tol     : relative accuracy of the eigenvalue omega^2
    v0      : a start vector (6N,), e.g. the top mode of an earlier estimate (some of the seeded
              random vector is added to it)
    difference : "central" (K v from F(U + e v) - F(U - e v): two force evaluations per product,
              error O(e^2)) or "forward" (F(U + e v) - F(U), F(U) evaluated once: one evaluation
              per product, error O(e) -- ~1e-6 of omega^2 at fd_step 1e-7, far inside the step's
              safety factor; what an adaptive run's re-estimate after each remesh uses)
    iteration : the difference step, iteration cap and seed (:class:`Iteration`)
    """
    maxiter = iteration.maxiter
    M = np.asarray(mass, dtype=float)
    shape = M.shape
    Mf = M.ravel()
    if U is None:
        U = np.zeros(shape)
    U = np.asarray(U, dtype=float).reshape(shape)
    idx, mf, s = _free_dofs(Mf, free)
    start = _start_vector(idx, mf, iteration.seed, v0)
    if method == "tangent":
        lam, vec, conv = _tangent_top(tangent, U, idx, s, start, tol, maxiter)
        n_force_evals = 0
    else:
        product = _ForceProduct(force, U, idx, s, difference, iteration.fd_step)
        if method == "lanczos":
            lam, vec, conv = _lanczos_top(product, idx.size, start, tol, maxiter)
        elif method == "power":
            lam, vec, conv = _power_top(product, start, tol, maxiter)
        else:
            raise ValueError(f"unknown method {method!r}; use lanczos, power or tangent")
        n_force_evals = product.n_evals

    if not (lam > 0.0 and math.isfinite(lam)):
        raise ValueError(
            f"largest eigenvalue of M^-1 K is {lam!r}: the stiffness is not positive "
            "at this state or the force is not finite"
        )
    mode = np.zeros(Mf.size)
    mode[idx] = s * vec
    return OmegaEstimate(
        omega_max=math.sqrt(lam), method=method, n_force_evals=n_force_evals, converged=conv, mode=mode
    )


def _free_dofs(Mf, free):
    """(flat indices of the free dofs, their masses, 1 / sqrt of them); refuses none free or a massless one."""
    free = np.asarray(free)
    idx = np.flatnonzero(free.ravel()) if free.dtype == bool else np.asarray(free, dtype=np.int64)
    if idx.size == 0:
        raise ValueError("no free dof: nothing vibrates")
    mf = Mf[idx]
    if np.any(mf <= 0.0):
        raise ValueError(f"{int(np.sum(mf <= 0))} free dof(s) have no mass; the explicit scheme needs M > 0")
    return idx, mf, 1.0 / np.sqrt(mf)


def _start_vector(idx, mf, seed, v0):
    """The iteration's start vector on the free dofs (M^1/2-scaled): the seeded random vector, or the
    given mode ``v0`` with ``_WARM_NOISE`` of the random one added."""
    rng = np.random.default_rng(seed)
    start = rng.standard_normal(idx.size)
    if v0 is not None:
        # the given mode plus a little of the random vector: a mode carried from another mesh can
        # lack a new mode localised on refined elements entirely, which no Krylov space from it
        # would then contain (an adaptive FIRE run's estimate fell 12 % short that way with 20
        # Lanczos vectors; docs/adaptivity.md)
        w = np.asarray(v0, float)[idx] * np.sqrt(mf)
        nw = float(np.linalg.norm(w))
        if nw > 0.0:
            start = w / nw + _WARM_NOISE * start / float(np.linalg.norm(start))
    return start


def _tangent_top(tangent, U, idx, s, start, tol, maxiter):
    """(omega^2, eigenvector, converged) by ARPACK on the assembled M^-1/2 K M^-1/2 (method "tangent")."""
    from scipy.sparse import diags
    from scipy.sparse.linalg import eigsh

    if tangent is None:
        raise ValueError("method='tangent' needs the tangent callable")
    K = tangent(U).tocsr()[idx][:, idx]
    A = diags(s) @ K @ diags(s)
    lam, vec = eigsh(A, k=1, which="LA", tol=tol, v0=start, maxiter=maxiter or 10 * idx.size)
    return float(lam[0]), vec[:, 0], True


class _ForceProduct:
    """x -> M^-1/2 K M^-1/2 x on the free dofs, K x the directional derivative of the internal force
    at U by a central or forward difference (module docstring); ``n_evals`` counts the force
    evaluations spent (F(U) of the forward difference included)."""

    def __init__(self, force, U, idx, s, difference, fd_step):
        if difference not in ("central", "forward"):
            raise ValueError(f"unknown difference {difference!r}; use central or forward")
        self.force, self.shape, self.s, self.fd_step = force, U.shape, s, fd_step
        self.base = U.ravel().copy()
        self.idx = np.ascontiguousarray(idx, dtype=np.int64)
        self.n_evals = 0
        self.f0 = None
        if difference == "forward":
            self.f0 = np.array(force(self.base.reshape(self.shape)), dtype=float).ravel()[self.idx]
            self.n_evals += 1
        self.w = self.base.copy()  # the perturbed state, one buffer: only its ``idx`` entries change
        self.v = np.empty(idx.size)
        self.fp = np.empty(idx.size)

    def __call__(self, x):
        s, idx, base, w, v = self.s, self.idx, self.base, self.w, self.v
        x = np.ascontiguousarray(x, dtype=float).ravel()
        vmax = _scale_max(s, x, v)
        if vmax == 0.0:
            return np.zeros_like(x)
        e = self.fd_step / vmax
        _place(w, idx, base, e, v, 1.0)
        Fp = np.asarray(self.force(w.reshape(self.shape)), dtype=float).ravel()
        if self.f0 is not None:
            self.n_evals += 1
            return _forward_product(s, Fp, idx, self.f0, e)
        np.take(Fp, idx, out=self.fp)  # kept: force may reuse its buffer for the second evaluation
        _place(w, idx, base, e, v, -1.0)
        Fm = np.asarray(self.force(w.reshape(self.shape)), dtype=float).ravel()
        self.n_evals += 2
        return _central_product(s, self.fp, Fm, idx, e)


def _lanczos_top(product, n, start, tol, maxiter):
    """(omega^2, eigenvector, converged) by matrix-free ARPACK; without convergence the best Ritz pair."""
    from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

    op = LinearOperator((n, n), matvec=product, dtype=float)
    ncv = min(n, 40)
    try:
        lam, vec = eigsh(op, k=1, which="LA", tol=tol, v0=start, ncv=ncv, maxiter=maxiter or 2000)
        return float(lam[0]), vec[:, 0], True
    except ArpackNoConvergence as exc:  # keep the best Ritz value, say so
        ev, evec = exc.eigenvalues, exc.eigenvectors
        if ev is None or len(ev) == 0:
            raise
        return float(np.max(ev)), evec[:, int(np.argmax(ev))], False


def _power_top(product, start, tol, maxiter):
    """(omega^2, eigenvector, converged) by the plain power iteration (method "power")."""
    x = start / np.linalg.norm(start)
    lam, conv = 0.0, False
    for _ in range(maxiter or 5000):
        y = product(x)
        lam_new = float(x @ y)
        ny = np.linalg.norm(y)
        if ny == 0.0:
            break
        x = y / ny
        if abs(lam_new - lam) <= tol * abs(lam_new):
            lam, conv = lam_new, True
            break
        lam = lam_new
    return lam, x, conv


# The matrix-free product's vector work, one pass each (the numpy expressions they replace took
# ~0.13 ms per product on a 10^4-dof sheet, a quarter of a force evaluation).  No fastmath: each
# entry gets the operations of those expressions in their order, so the products, omega and the
# mode are bit for bit what they were (tests/test_explicit.py).


@njit(cache=True)
def _scale_max(s, x, v):
    """v = s * x; returns max |v| (NaN if any entry is)."""
    m = 0.0
    for k in range(x.size):
        v[k] = s[k] * x[k]
        a = abs(v[k])
        if a > m or a != a:  # a NaN propagates, as np.max's does
            m = a
    return m


@njit(cache=True)
def _place(w, idx, base, e, v, sign):
    """w[idx] = base[idx] + e v (sign 1) or base[idx] - e v (sign -1)."""
    for k in range(idx.size):
        ev = e * v[k]
        w[idx[k]] = base[idx[k]] + ev if sign > 0 else base[idx[k]] - ev


@njit(cache=True)
def _forward_product(s, F, idx, f0, e):
    """s * (F[idx] - f0) / e."""
    out = np.empty(idx.size)
    for k in range(idx.size):
        out[k] = s[k] * (F[idx[k]] - f0[k]) / e
    return out


@njit(cache=True)
def _central_product(s, fp, F, idx, e):
    """s * (fp - F[idx]) / (2 e)."""
    out = np.empty(idx.size)
    e2 = 2.0 * e
    for k in range(idx.size):
        out[k] = s[k] * (fp[k] - F[idx[k]]) / e2
    return out
