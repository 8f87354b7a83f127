"""Quasi-static directors after a remesh: the director dofs U_n put at equilibrium with the positions.

Why.  In the solid-shell a node's director dofs U_n (Eq. 1) carry the thickness stretch and the
transverse shear, the stiffest and lightest dofs of the sheet: they set the top of the spectrum
(omega_max, the critical step of Eq. 23).  The DK transfer (Eqs. 30-34) gives an inserted node a
director that is kinematically sound but not in equilibrium with the new elements around it, and the
old nodes' directors were in equilibrium with the old, larger elements.  Each remesh therefore starts a
director oscillation at the top of the spectrum, which mass-proportional damping (Eq. 20) hardly
touches (damping ratio alpha / (2 omega_max) ~ 1e-4).  On the paper's relaxation path (alpha 5 1/s,
masses x100) the remeshes of one square-pedestal run raised the directors' step-to-step oscillation
from 1e-8 to 3e-2 in eight remeshes; the Green thickness strain stiffens as (1 + v)^2 with the
stretch v, so near v ~ 0.1 the top mode passes the stability limit and the run went non-finite
(docs/adaptivity.md).  The uniform mesh's directors oscillate at 1e-7 throughout.

What.  With the positions U_o held, the directors minimise the total potential Pi = U(D) - P.D; a
few Newton steps on the director block K_nn of the tangent (Eq. 9), each backtracked until Pi falls,
reach that minimum.  Applied to both time levels D_n and D_n-1 of the central-difference state, the
director velocity becomes the rate of the quasi-static director, so the fast director oscillation is
removed and the slow rotation with the sheet is kept.  Positions, the translational velocities and
every translational dof are untouched, so DK's placement of the new nodes (§5.4) stands.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import diags
from scipy.sparse.linalg import splu


_SHIFTS = (0.0, 1e-3, 1e-1, 10.0)   # Levenberg shifts, in units of the mean diagonal of K_nn


def _solve(K, r, shift):
    """K_nn^-1 r, or (K_nn + shift mean(diag K_nn) I)^-1 r; None if singular or not finite."""
    if shift:
        d = K.diagonal()
        K = K + diags(np.full(d.size, shift * float(np.mean(np.abs(d)))), format="csc")
    try:
        x = splu(K.tocsc()).solve(r)
    except RuntimeError:
        return None
    return x if np.all(np.isfinite(x)) else None


@dataclass
class SettleReport:
    """One director settling: Newton iterations, free-director residual norms before and after
    [force], and whether the residual fell by ``rtol`` (else the best state found is kept)."""

    iterations: int
    residual_before: float
    residual_after: float
    converged: bool


def director_dofs(fixed: np.ndarray) -> np.ndarray:
    """Flat indices of the free director dofs U_n (columns 3-5 of the (N, 6) dof table)."""
    sel = np.zeros(fixed.shape, dtype=bool)
    sel[:, 3:] = True
    return np.flatnonzero((sel & ~fixed).ravel())


def settle_directors(model, loads: np.ndarray, fixed: np.ndarray, D: np.ndarray, *, max_iter: int = 8,
                     rtol: float = 1e-6, settled: float = 1e-3) -> tuple[np.ndarray, SettleReport]:
    """(D with its free directors at equilibrium, report).  ``D`` flat (6N,) or (N, 6), not modified;
    ``loads`` (N, 6) [force], ``fixed`` (N, 6) bool.  Stops when the director residual is below
    ``rtol`` times its start value, after ``max_iter`` Newton steps, or when a step cannot lower Pi;
    the report calls it converged when the residual fell by ``settled`` (three digits: the rest of the
    imbalance is then far below the translational out-of-balance force the transfer leaves)."""
    shape = fixed.shape
    U = np.array(D, dtype=float).reshape(shape)
    flat = U.ravel()
    P = np.asarray(loads, dtype=float).ravel()
    idx = director_dofs(np.asarray(fixed, dtype=bool))
    E, F = model.energy_and_force(U)
    pi = float(E) - float(P @ flat)
    r = (P - np.asarray(F).ravel())[idx]
    r0 = float(np.linalg.norm(r))
    rn, it = r0, 0
    while it < max_iter and rn > rtol * r0 and r0 > 0.0:
        K = model.tangent(U).tocsr()[idx][:, idx].tocsc()
        base = flat[idx].copy()
        accepted = False
        for shift in _SHIFTS:           # Newton, then Levenberg-shifted where K_nn is not convex
            step = _solve(K, r, shift)
            if step is None or not float(r @ step) > 0.0:
                continue
            s = 1.0
            for _ in range(8):          # backtrack on Pi: a full step may overshoot
                flat[idx] = base + s * step
                E_t, F_t = model.energy_and_force(U)
                pi_t = float(E_t) - float(P @ flat)
                if np.isfinite(pi_t) and pi_t < pi:
                    accepted = True
                    break
                s *= 0.5
            if accepted:
                break
        if not accepted:
            flat[idx] = base
            break
        pi, it = pi_t, it + 1
        r = (P - np.asarray(F_t).ravel())[idx]
        rn = float(np.linalg.norm(r))
    return flat.copy(), SettleReport(it, r0, rn, bool(rn <= settled * r0))
