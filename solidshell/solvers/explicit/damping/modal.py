"""Rayleigh damping tuned to the slowest drape mode: alpha = 2 zeta omega_min (zeta = 1: the slowest
mode critically damped), omega_min^2 the smallest positive eigenvalue of M^-1 K at the current state.

Why: with mass-proportional damping a mode of frequency omega decays at the rate alpha/2 when
omega > alpha/2 and at omega^2/alpha (overdamped) below; the slowest mode sets the relaxation time,
which is shortest, omega_min, at alpha = 2 omega_min.  The paper's alpha = 5 1/s with masses x100 is,
by the time-stretch identity (tests/test_explicit.py), alpha = 50 1/s on the unscaled masses; the
slowest pedestal mode is ~11 rad/s there, so the paper's path is ~2.2x overdamped.

K = the model tangent (``model.tangent``) plus the contact and friction springs, whose 3x3 nodal
blocks come from central differences of the nodal contact forces (each node's contact force depends
on its own position only, so three perturbed evaluations give every block; forces.Forces.
contact_stiffness), both from the run's ``view.stiffness``; omega_min from ARPACK
in shift-invert mode on K x = lambda M x (the tangent is sparse; one sparse LU per estimate).
Eigenvalues below 1e-10 of the largest diagonal ratio K_ii / M_ii are zero modes (a sheet free to
slide) and are skipped: they carry no out-of-balance force.  The estimate is taken at the start
and every ``modal_every`` steps; between estimates alpha is constant.  An estimate that fails
(ARPACK does not converge, no positive eigenvalue) keeps the previous alpha.
"""

from __future__ import annotations

import math

import numpy as np

from ....interfaces import DampingView
from .base import Damper


def omega_min(view: DampingView, D) -> float | None:
    """Smallest positive omega [rad/s] of M^-1 K at D (None when the estimate fails)."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import eigsh

    from ...linear import arpack_start

    K = view.stiffness(D)
    idx = view.dofs.free_idx
    K = K[idx][:, idx].tocsc()
    K = 0.5 * (K + K.T)
    m = view.dofs.Mf[idx]
    zero = 1e-10 * float(np.max(K.diagonal() / m))
    try:
        lam = eigsh(
            K,
            k=6,
            M=sp.diags(m).tocsc(),
            sigma=-zero,
            which="LM",
            return_eigenvectors=False,
            v0=arpack_start(K.shape[0]),
        )
    except Exception:  # ArpackNoConvergence, a singular shift: keep the previous alpha
        return None
    pos = np.sort(lam[lam > zero])
    return float(math.sqrt(pos[0])) if pos.size else None


class Modal(Damper):
    name = "modal"
    varies_alpha = True  # alpha0 (the alpha setting) until the first estimate, at step 0 of a new run

    def correct(self, view: DampingView, n, D, Dp, Dn1, R, vMv):
        s = view.settings
        if n % s.modal_every == 0:
            w = omega_min(view, D)
            if w is not None:
                view.set_alpha(2.0 * s.modal_zeta * w)
                # the step D_n -> D_n+1 already taken is redone with the new alpha
                return view.central_step(Dn1, D, Dp, R)
        return vMv, True
