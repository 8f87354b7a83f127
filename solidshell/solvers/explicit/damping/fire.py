"""FIRE, the fast inertial relaxation engine (Bitzek, Koskinen, Gaehler, Moseler & Gumbsch 2006,
Phys. Rev. Lett. 97, 170201), on the central-difference scheme of Eq. (23) without viscous damping.

Each step, with F = R_n = P - F_int(D_n) + C(D_n) the out-of-balance force at D_n, a = M^-1 F, and
the velocity at D_n of the velocity-Verlet form of Eq. (23) (FIRE's MD integrator), v = v_n =
v_n-1/2 + dt/2 a with v_n-1/2 = (D_n - D_n-1)/dt:

* power P = F.v; when P >= 0, mix the velocity towards the force, v <- (1 - a) v + a |v| F^ (F1-F2),
  and after ``fire_n_min`` steps with P >= 0 grow the step, dt <- min(f_inc dt, dt_max), and decay
  the mixing, a <- f_alpha a;
* when P < 0 (the motion climbs the energy): freeze, v = 0, shrink the step, dt <- f_dec dt, and
  restart the mixing at a_start (F3);
* then the MD step, v_n+1/2 = v + dt/2 a, D_n+1 = D_n + dt v_n+1/2.  Without mixing or a change of
  dt this is Eq. (23) with alpha = 0 exactly.

Why v_n and not v_n-1/2 (the semi-implicit Euler form of FIRE, e.g. ASE's): a freeze then restarts
from D_n at rest with D_n+1 = D_n + dt^2/2 a, which is stable up to omega dt = 2 like the scheme; a
freeze of v_n-1/2 gives D_n+1 = D_n + dt^2 a, steepest descent with step dt^2 M^-1, unstable above
omega dt = sqrt(2) -- measured on the wool strip at dt = 0.9 dt_crit: 16666 freezes in 200000 steps,
dt stuck at half its maximum, no steady state (the same reason as kinetic damping's half-step
restart, kinetic.py).

The mixing is taken in the mass metric (coordinates y = M^1/2 x, where every mass is 1, as in the
paper's MD): |v| = sqrt(v.M.v), F^ = M^-1 F / sqrt(F.M^-1 F), so translations [cm] and director
dofs mix in proportion to their inertia.  dt_max is the scheme's own stable step (safety x the
critical step, Section 4.1 -- FIRE's 10 x dt_MD would be unstable here), dt is never below
``fire_dt_min`` x dt_max.  The kinetic energy the mixing and the freezes take out is booked as
damping dissipation (half-step measure, as kinetic damping books its resets).

Cost: one pass over the 6N dofs per step (``update``), no allocation: the integrator's fused step
only forms R (``rewrites_step``) instead of a step that would be overwritten, and the power sums
with it (``wants_power``: fused.residual_power, the terms of ``power`` in its order); ``power``
is the damper's own pass where the step is not fused.
"""

from __future__ import annotations

import math

from numba import njit

from ....interfaces import DampingView
from ..kernels import dof_power
from .base import Damper


@njit(cache=True)
def power(D, Dp, R, invM, Mf, fixed, inv_dt, half_dt):
    """(P = R.v, v.M.v, R.M^-1.R) over the free dofs, v = (D - Dp) inv_dt + half_dt M^-1 R."""
    P = 0.0
    vMv = 0.0
    fMf = 0.0
    for i in range(D.size):
        if fixed[i]:
            continue
        p, w, f = dof_power(R[i], D[i], Dp[i], invM[i], Mf[i], inv_dt, half_dt)
        P += p
        vMv += w
        fMf += f
    return P, vMv, fMf


@njit(cache=True)
def update(Dn1, D, Dp, R, invM, Mf, fixed, presc, inv_dt_old, dt_new, c_v, c_f):
    """w = c_v v + c_f M^-1 R with v = v_n = (D - Dp) inv_dt_old + dt_old/2 M^-1 R; D_n+1 = D +
    dt_new (w + dt_new/2 M^-1 R), prescribed where ``fixed``.  Returns (w.M.w, finite): w is the velocity at D_n the step
    carries, the measure of the books and the steady-state test."""
    wMw = 0.0
    finite = True
    half_old = 0.5 / inv_dt_old
    half_new = 0.5 * dt_new
    for i in range(D.size):
        if fixed[i]:
            Dn1[i] = presc[i]
            continue
        a = invM[i] * R[i]
        v = (D[i] - Dp[i]) * inv_dt_old + half_old * a
        w = c_v * v + c_f * a
        x = D[i] + dt_new * (w + half_new * a)
        Dn1[i] = x
        if x - x != 0.0:  # inf - inf and nan - nan are nan
            finite = False
        wMw += Mf[i] * w * w
    return wMw, finite


class Fire(Damper):
    name = "fire"
    rewrites_step = True  # correct() computes D_n+1 from R alone (but on a fresh run's first step)
    wants_power = True  # correct() reads view.step_power (P, v.M.v, R.M^-1.R) when the step formed it

    def alpha0(self, settings) -> float:
        return 0.0  # no viscous damping: FIRE's mixing and freezes take the energy out

    def correct(self, view: DampingView, n, D, Dp, Dn1, R, vMv):
        """Rewrite the step into Dn1 (see the module docstring); (v_n.M.v_n of the step taken,
        D_n+1 finite)."""
        st, s, dofs = view.state, view.settings, view.dofs
        dt = st.dt
        dt_max = min(s.dt if s.dt is not None else s.safety * view.dt_crit, s.safety * st.dtc_min)
        pw = view.step_power  # formed with R by the fused residual pass, else one pass here
        P, vMv_old, fMf = (
            pw if pw is not None else power(D, Dp, R, dofs.invM, dofs.Mf, dofs.fixed_mask, 1.0 / dt, 0.5 * dt)
        )
        if n == 0 and view.fresh:
            # D_-1 is the start rule's Taylor point (v_-1/2 = V_0 - dt/2 A_0), not a velocity the
            # run had: the first step is the scheme's own
            return vMv, True
        if P >= 0.0:
            a = st.fire_a
            c_v, c_f = 1.0 - a, (a * math.sqrt(vMv_old / fMf) if fMf > 0.0 else 0.0)
            if st.fire_n > s.fire_n_min:
                dt_new = min(dt * s.fire_f_inc, dt_max)
                st.fire_a = a * s.fire_f_alpha
            else:
                dt_new = dt
            st.fire_n += 1
        else:
            c_v = c_f = 0.0
            dt_new = max(dt * s.fire_f_dec, s.fire_dt_min * dt_max)
            st.fire_a = s.fire_alpha_start
            st.fire_n = 0
            st.resets += 1
        wMw, finite = update(
            Dn1, D, Dp, R, dofs.invM, dofs.Mf, dofs.fixed_mask, dofs.presc_full, 1.0 / dt, dt_new, c_v, c_f
        )
        st.damp_sum += 0.5 * (vMv_old - wMw)  # >= 0: |(1 - a) v + a |v| F^| <= |v|
        if dt_new != dt:
            view.change_step(n, dt_new)  # t_n stays where it is; the step n -> n+1 (and on) is dt_new
        return wMw, finite
