"""The compiled and vectorised pieces of one central-difference step, Eq. (23).

Vector reductions on the hot path avoid BLAS (np.dot, np.linalg.norm of 1-D arrays): a threaded
OpenBLAS on a busy machine was measured at 3-15 ms for one 10^4-long dot product, against 25 us
for the plain pairwise sum below.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit


@dataclass(frozen=True)
class Dofs:
    """The flat (6N,) dof arrays of one explicit problem that a step reads (built once per problem)."""

    Mf: np.ndarray  # lumped (scaled) masses
    invM: np.ndarray  # 1 / Mf on the free dofs, 0 on the fixed ones
    P: np.ndarray  # dead loads [force]
    fixed_idx: np.ndarray  # indices of the fixed dofs
    presc: np.ndarray  # their prescribed values [length], in fixed_idx's order
    fixed_mask: np.ndarray  # (6N,) bool, True on the fixed dofs
    presc_full: np.ndarray  # the prescribed values on all dofs (0 on the free ones)
    free_idx: np.ndarray  # indices of the free dofs


@dataclass(frozen=True)
class Coefficients:
    """Eq. (23)'s coefficients for the step dt [s] and alpha [1/s] (:func:`coefficients`)."""

    dt: float
    cF: np.ndarray  # (6N,) multiplies (P - F + C)
    cD: float  # multiplies D_n
    cDp: float  # multiplies D_n-1

    @classmethod
    def of(cls, invM, dt: float, alpha: float) -> Coefficients:
        return cls(dt, *coefficients(invM, dt, alpha))


def dot(a, b) -> float:
    """a.b by numpy's pairwise sum (no BLAS)."""
    return float(np.add.reduce(a * b))


def norm(a) -> float:
    """|a| by numpy's pairwise sum (no BLAS)."""
    return math.sqrt(float(np.add.reduce(a * a)))


@njit(cache=True)
def central_step(Dn1, D, Dp, R, cF, cD, cDp, fixed_idx, presc, Mf, inv2dt):
    """Eq. (23) for every dof, D_n+1 = cF R + cD D_n + cDp D_n-1 (the same operation order as the
    numpy expression), the prescribed values, and in the same pass the finiteness of D_n+1 and
    v_n.M.v_n with v_n = (D_n+1 - D_n-1) / (2 dt).  Fusing these saves ~8 passes over 6N doubles
    per step (25 % of a 1600-quad step once the force kernel got fast)."""
    n = D.size
    for i in range(n):
        Dn1[i] = cF[i] * R[i] + cD * D[i] + cDp * Dp[i]
    for k in range(fixed_idx.size):
        Dn1[fixed_idx[k]] = presc[k]
    vMv = 0.0
    finite = True
    for i in range(n):
        x = Dn1[i]
        if x - x != 0.0:  # inf - inf and nan - nan are nan
            finite = False
        w = (x - Dp[i]) * inv2dt
        vMv += Mf[i] * w * w
    return vMv, finite


@njit(forceinline=True)
def dof_power(r, d, dp, invm, m, inv_dt, half_dt):
    """One free dof's terms of FIRE's power sums (damping/fire.py): (r v, m v v, r r / m) with the
    velocity at D_n of the velocity-Verlet form, v = (d - dp) / dt + dt/2 r / m.  One definition for
    the damper's own pass and the fused residual pass (fused.residual_power), so both sum the same
    rounded terms in the same order."""
    v = (d - dp) * inv_dt + half_dt * invm * r
    return r * v, m * v * v, invm * r * r


def coefficients(invM, dt: float, alpha: float):
    """(cF, cD, cDp) of Eq. (23) with lumped inverse mass invM (zero on fixed dofs), step dt [s] and
    Rayleigh alpha [1/s]: D_n+1 = cF (P - F + C) + cD D_n + cDp D_n-1."""
    lhs = 1.0 / dt**2 + alpha / (2.0 * dt)
    return (
        invM / lhs,  # multiplies (P - F + C)
        (2.0 / dt**2) / lhs,  # multiplies D_n
        (alpha / (2.0 * dt) - 1.0 / dt**2) / lhs,
    )  # multiplies D_n-1


def step(Dn1, D, Dp, R, dofs: Dofs, co: Coefficients):
    """:func:`central_step` with a problem's dof arrays and the current coefficients:
    (v_n.M.v_n, D_n+1 finite)."""
    return central_step(Dn1, D, Dp, R, co.cF, co.cD, co.cDp, dofs.fixed_idx, dofs.presc, dofs.Mf, 0.5 / co.dt)
