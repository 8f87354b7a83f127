"""Rayleigh damping tuned to the slowest drape mode: alpha = 2 zeta omega_min (zeta = 1: the slowest
mode critically damped), omega_min^2 the smallest positive eigenvalue of M^-1 K at the current state.

Why: with mass-proportional damping a mode of frequency omega decays at the rate alpha/2 when
omega > alpha/2 and at omega^2/alpha (overdamped) below; the slowest mode sets the relaxation time,
which is shortest, omega_min, at alpha = 2 omega_min.  The paper's alpha = 5 1/s with masses x100 is,
by the time-stretch identity (tests/test_explicit.py), alpha = 50 1/s on the unscaled masses; the
slowest pedestal mode is ~11 rad/s there, so the paper's path is ~2.2x overdamped.

K = the model tangent (``model.tangent``) plus the contact and friction springs, whose 3x3 nodal
blocks come from central differences of the nodal contact forces (each node's contact force depends
on its own position only, so three perturbed evaluations give every block); omega_min from ARPACK
in shift-invert mode on K x = lambda M x (the tangent is sparse; one sparse LU per estimate).
Eigenvalues below 1e-10 of the largest diagonal ratio K_ii / M_ii are zero modes (a sheet free to
slide) and are skipped: they carry no out-of-balance force.  The estimate is taken at the start
and every ``modal_every`` steps; between estimates alpha is constant.  An estimate that fails
(ARPACK does not converge, no positive eigenvalue) keeps the previous alpha.
"""

from __future__ import annotations

import math

import numpy as np


def contact_blocks(integ, D, eps: float = 1e-7):
    """(rows, cols, vals) of the contact stiffness -dC/dx on the translation dofs at D (anchors held:
    stick springs count, slipping nodes only through their normal spring)."""
    N = integ.N
    if not integ.bodies:
        return None
    D = D.copy()
    cols = []
    for j in range(3):
        Dp_, Dm_ = D.copy(), D.copy()
        Dp_[j::6] += eps
        Dm_[j::6] -= eps
        if integ.n_fric:
            Cp = integ.forces.contact_friction(Dp_, integ.state.anchors)[0]
            Cm = integ.forces.contact_friction(Dm_, integ.state.anchors)[0]
        else:
            Cp = integ.forces.contact(Dp_)[0]
            Cm = integ.forces.contact(Dm_)[0]
        cols.append(-(np.asarray(Cp) - np.asarray(Cm)).reshape(N, 6)[:, :3] / (2 * eps))
    B = np.stack(cols, axis=2)                    # (N, 3 rows i, 3 cols j): d(-C_i)/dx_j
    nodes = np.flatnonzero(np.any(B != 0.0, axis=(1, 2)))
    ii, jj = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    rows = (6 * nodes[:, None, None] + ii[None]).ravel()
    colz = (6 * nodes[:, None, None] + jj[None]).ravel()
    return rows, colz, B[nodes].ravel()


def omega_min(integ, D) -> float | None:
    """Smallest positive omega [rad/s] of M^-1 K at D (None when the estimate fails)."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import eigsh

    K = integ.model.tangent(D.reshape(integ.shape)).tocsr()
    cb = contact_blocks(integ, D)
    if cb is not None:
        K = K + sp.csr_matrix((cb[2], (cb[0], cb[1])), shape=K.shape)
    idx = integ.free_idx
    K = K[idx][:, idx].tocsc()
    K = 0.5 * (K + K.T)
    m = integ.Mf[idx]
    zero = 1e-10 * float(np.max(K.diagonal() / m))
    try:
        lam = eigsh(K, k=6, M=sp.diags(m).tocsc(), sigma=-zero, which="LM", return_eigenvectors=False)
    except Exception:   # ArpackNoConvergence, a singular shift: keep the previous alpha
        return None
    pos = np.sort(lam[lam > zero])
    return float(math.sqrt(pos[0])) if pos.size else None


class Modal:
    name = "modal"
    varies_alpha = True

    def alpha0(self, integ) -> float:
        return float(integ.s.alpha)   # until the first estimate (at step 0 of a new run)

    def correct(self, integ, n, D, Dp, Dn1, R, vMv):
        if n % integ.s.modal_every == 0:
            w = omega_min(integ, D)
            if w is not None:
                integ.alpha = 2.0 * integ.s.modal_zeta * w
                integ.state.damper_alpha = integ.alpha
                # the step D_n -> D_n+1 already taken is redone with the new alpha
                integ._set_step(integ.state.dt)
                from ..kernels import central_step
                vMv, finite = central_step(Dn1, D, Dp, R, integ.cF, integ.cD, integ.cDp, integ.fixed_idx,
                                           integ.presc, integ.Mf, 0.5 / integ.state.dt)
                return vMv, finite
        return vMv, True

    def after(self, integ, n, D, Dn1, R, vMv) -> None:
        return None
