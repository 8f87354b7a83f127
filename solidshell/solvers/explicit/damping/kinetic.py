"""Cundall's kinetic damping: no viscous damping; at each kinetic-energy peak the state restarts at
rest.  Measured against Rayleigh damping in docs/explicit.md and benchmarks/explicit_relaxation.py."""

from __future__ import annotations

import numpy as np

from ....interfaces import DampingView
from ..kernels import dot
from .base import Damper


class Kinetic(Damper):
    name = "kinetic"

    def alpha0(self, settings) -> float:
        # Cundall's kinetic damping replaces the viscous damping: a scene file's alpha is meant for
        # damping="rayleigh" (with both, the relaxation measured 4x more steps on the wool strip)
        return 0.0

    def after(self, view: DampingView, n, D, Dn1, R, vMv) -> None:
        """At a kinetic-energy peak (between v_n-1/2 and v_n+1/2, i.e. at D_n) restart from D_n at
        rest with the start rule, D_n+1 = D_n + dt^2/2 M^-1 R_n.  (Simply zeroing v_n+1/2 at D_n+1
        turns repeated resets near equilibrium into steepest descent with step dt^2 M^-1, unstable
        above omega dt = sqrt(2); the half-step restart is stable up to omega dt = 2 like the scheme
        itself.)"""
        st, dt, dofs = view.state, view.state.dt, view.dofs
        dh = Dn1 - D
        ek_half = 0.5 * dot(dofs.Mf * dh, dh) / dt**2
        if ek_half < st.ek_prev_half:
            st.damp_sum += 0.5 * vMv
            np.multiply(dofs.invM, R, out=Dn1)
            Dn1 *= 0.5 * dt * dt
            Dn1 += D
            Dn1[dofs.fixed_idx] = dofs.presc
            dh = Dn1 - D
            ek_half = 0.5 * dot(dofs.Mf * dh, dh) / dt**2
            st.resets += 1
        st.ek_prev_half = ek_half
