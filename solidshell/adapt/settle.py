"""Quasi-static directors after a remesh: the director dofs U_n put at equilibrium with the positions.

Why.  In the solid-shell a node's director dofs U_n (Eq. 1) carry the thickness stretch and the
transverse shear, the stiffest and lightest dofs of the sheet: they set the top of the spectrum
(omega_max, the critical step of Eq. 23).  The DK transfer (Eqs. 30-34) gives an inserted node a
director that is kinematically sound but not in equilibrium with the new elements around it, and the
old nodes' directors were in equilibrium with the old, larger elements.  Each remesh therefore starts a
director oscillation at the top of the spectrum, which mass-proportional damping (Eq. 20) hardly
touches (damping ratio alpha / (2 omega_max) ~ 1e-4).  The Green thickness strain stiffens with the
director stretch, so a large enough oscillation passes the stability limit of Eq. (23): the cause of
the paper-path blow-up measured in docs/adaptivity.md.

What.  With the positions U_o held, the directors minimise the total potential Pi = U(D) - P.D; a
few Newton steps on the director block K_nn of the tangent (Eq. 9), each backtracked until Pi falls,
reach that minimum.  The driver settles D_n, and gives the settled dofs of D_n-1 the quasi-static rate
(:meth:`DirectorSettler.quasi_static_step`): the director velocity becomes the rate of the
quasi-static director, so the fast director oscillation is removed and the slow rotation with the
sheet is kept.  Positions and every translational dof are untouched (but the inserted nodes'
positions, when asked, whose velocity the driver keeps interpolated), so DK's placement of the new
nodes (§5.4) stands.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..solvers.linear import Cholesky, LowerCSC

_SHIFTS = (0.0, 1e-3, 1e-1, 10.0)  # Levenberg shifts, in units of the mean diagonal of K_nn


@dataclass
class SettleReport:
    """One director settling: Newton iterations, free-director residual norms before and after
    [force], and whether the residual fell by ``rtol`` (else the best state found is kept)."""

    iterations: int
    residual_before: float
    residual_after: float
    converged: bool


def director_dofs(fixed: np.ndarray, nodes=None, region=None) -> np.ndarray:
    """Flat indices of the free director dofs U_n (columns 3-5 of the (N, 6) dof table) of the nodes
    ``region`` (default: all), and of every free dof of ``nodes`` (the nodes a remesh inserted,
    when their positions settle too)."""
    sel = np.zeros(fixed.shape, dtype=bool)
    if region is None:
        sel[:, 3:] = True
    else:
        sel[np.asarray(region, dtype=np.int64), 3:] = True
    if nodes is not None:
        sel[np.asarray(nodes, dtype=np.int64)] = True
    return np.flatnonzero((sel & ~fixed).ravel())


class DirectorSettler:
    """Settles the directors of states on one problem (``model``, ``loads`` (N,6) [force], ``fixed``
    (N,6) bool), and the positions of ``nodes`` too when given (the inserted nodes), by Newton steps
    on that block K_nn of the tangent, each backtracked until Pi falls, with Levenberg shifts where
    K_nn is not convex there (the Newton step is then not a descent direction).  K_nn is refreshed
    every step: the Green thickness strain makes the block strongly nonlinear.  ``region`` (node
    indices): only those nodes' directors settle (and ``nodes``' positions), the rest is held, and
    only the elements touching them are evaluated (Model.around)."""

    def __init__(self, model, loads, fixed, nodes=None, region=None):
        self.fixed = np.asarray(fixed, dtype=bool)
        self.P = np.asarray(loads, dtype=float).ravel()
        self.idx = director_dofs(self.fixed, nodes, region)
        if region is not None:
            moved = np.union1d(region, [] if nodes is None else nodes).astype(np.int64)
            model = model.around(moved)
        self.model = model
        self._chol = Cholesky()  # CHOLMOD; one symbolic analysis for all steps (one pattern)
        self._lower = None  # K_nn's lower-triangle pattern, built at the first step
        self._K = None
        self._factored = False  # the last factorisation succeeded (quasi_static_step reuses it)
        self._shift = 0.0  # and its Levenberg shift

    def _step(self, U, r, shift):
        """K_nn^-1 r at U, or (K_nn + shift mean|diag K_nn| I)^-1 r; None where that matrix is not
        positive definite (then Newton's step need not descend: the next shift is tried).  K_nn is
        assembled straight into its lower-triangle pattern, as the static solver assembles its
        free-dof tangent (Model.force_and_free_tangent), not cut from a 6N x 6N matrix."""
        if shift == 0.0:
            if self._lower is None:
                self._lower = self.model.free_lower_pattern(self.idx)
            lw = self._lower
            _, data = self.model.force_and_free_tangent(U, lw)
            self._K = LowerCSC(lw.indptr, lw.indices, data, lw.diag_pos, lw)
        K = self._K
        s = shift * float(np.mean(np.abs(K.data[K.diag_pos]))) if shift else None
        self._factored = self._chol.factor(K, s)
        self._shift = shift
        if not self._factored:
            return None
        x = self._chol.solve(r)
        return x if np.all(np.isfinite(x)) else None

    def _descend(self, U, flat, r, pi):
        """One backtracked step; (Pi, force) after it, or None (flat restored) if none lowers Pi."""
        base = flat[self.idx].copy()
        for shift in _SHIFTS:
            got = self._backtrack(U, flat, base, self._step(U, r, shift), r, pi)
            if got is not None:
                return got
        return None

    def _backtrack(self, U, flat, base, step, r, pi):
        """(Pi, force) at the first of base + step, base + step/2, ... that lowers Pi, or None."""
        if step is None or not np.all(np.isfinite(step)) or not float(r @ step) > 0.0:
            return None
        idx, P, s = self.idx, self.P, 1.0
        for _ in range(8):  # a full step may overshoot
            flat[idx] = base + s * step
            E_t, F_t = self.model.energy_and_force(U)
            pi_t = float(E_t) - float(P @ flat)
            if np.isfinite(pi_t) and pi_t < pi:
                return pi_t, F_t
            s *= 0.5
        flat[idx] = base
        return None

    def __call__(self, D, *, max_iter: int = 8, rtol: float = 1e-3):
        """(D with its free directors at equilibrium (flat, 6N), report).  ``D`` flat (6N,) or (N,6),
        not modified.  Stops when the director residual is below ``rtol`` times that of D (three
        digits: the rest is then far below the translational out-of-balance force the transfer
        leaves), after ``max_iter`` steps, or when no step lowers Pi."""
        idx, P = self.idx, self.P
        U = np.array(D, dtype=float).reshape(self.fixed.shape)
        flat = U.ravel()
        E, F = self.model.energy_and_force(U)
        pi = float(E) - float(P @ flat)
        r = (P - np.asarray(F).ravel())[idx]
        r0 = rn = float(np.linalg.norm(r))
        it = 0
        while it < max_iter and rn > rtol * r0 and r0 > 0.0:
            got = self._descend(U, flat, r, pi)
            if got is None:
                break
            pi, F = got
            it += 1
            r = (P - np.asarray(F).ravel())[idx]
            rn = float(np.linalg.norm(r))
        return flat.copy(), SettleReport(it, r0, rn, bool(rn <= rtol * r0))

    def quasi_static_step(self, D, step):
        """``step`` (flat 6N: D_n - D_n-1 as transferred) with its settled entries replaced by the
        quasi-static rate at the settled state D: w = -K_SS^-1 K_SH v for the held dofs' step v, so
        that r_S stays zero to first order as the held dofs move (S: the settled dofs).  K_SH v is the
        central difference of the force over +-v (one time step each way: the secant of the motion
        the integrator makes); K_SS is the last factor of the settling (the state one Newton step
        before D, or D itself when none was taken).  Settling D_n-1 on its own instead leaves the
        difference of two settlings' residual errors in the velocity: ~1e-3 cm in D_n - D_n-1 is
        ~10 cm/s at dt ~ 1e-4 s (docs/adaptivity.md)."""
        idx = self.idx
        U = np.array(D, dtype=float).reshape(self.fixed.shape)
        v = np.array(step, dtype=float).ravel()
        v[idx] = 0.0
        v[self.fixed.ravel()] = 0.0
        if not (self._factored and self._shift == 0.0):
            if self._step(U, np.zeros(len(idx)), 0.0) is None:  # not convex: keep the step
                return np.array(step, dtype=float).ravel()
        flat = U.ravel()
        base = flat.copy()
        flat[:] = base + v
        Fp = np.asarray(self.model.internal_force(U)).ravel()[idx]
        flat[:] = base - v
        Fm = np.asarray(self.model.internal_force(U)).ravel()[idx]
        w = -self._chol.solve(0.5 * (Fp - Fm))
        out = np.array(step, dtype=float).ravel()
        if np.all(np.isfinite(w)):
            out[idx] = w
        return out


def settle_directors(model, loads, fixed, D, **kw):
    """One state's directors settled (:class:`DirectorSettler`): (flat D, SettleReport)."""
    return DirectorSettler(model, loads, fixed)(D, **kw)
