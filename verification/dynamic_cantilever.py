"""Explicit dynamics (Eq. 23) against closed forms, and the critical-step estimate against the
observed stability limit.

1. First bending frequency of a cantilever strip vs the Euler-Bernoulli closed form
   omega_1 = 1.8751^2 sqrt(B / (mu L^4)) (B bending rigidity per width, mu mass per area): an
   isotropic strip (nu = 0, L/h = 50) on 10, 20, 40 elements and the wool warp strip of Section 3.1
   (5 x 1 cm) on 10 and 20.  The explicit run starts from the discrete first mode (from the linear
   eigenproblem K(0), lumped M, scipy) at an amplitude 1e-4 L and the period is measured from the
   zero crossings of the tip deflection; the error against the discrete eigenvalue isolates the time
   integration, the error against the closed form adds the spatial discretisation.  The wool strip
   is run unscaled on 10 elements, and with the director masses x100 (mass_scaling_mode="director")
   on 10 and 20: the director masses carry the rotary inertia, mu h^2/4 per area per unit director
   rate; scaled by s its radius of gyration is sqrt(s) h/2, which lowers omega_1 by roughly
   (1/2)(beta_1/L)^2 s h^2/4 ~ 0.6 % for s = 100 -- the price of director mass scaling in a dynamic
   (not a relaxation) run, measured here.
2. A free sheet falling under gravity with Rayleigh damping alpha vs z(t) = -(g/alpha)(t - (1 -
   exp(-alpha t))/alpha) (alpha = 0: -g t^2 / 2, which central differences integrate exactly).
3. The observed stability limit: the largest dt / dt_crit (dt_crit from the matrix-free Lanczos
   estimate) for which 3000 steps stay finite and energy-balanced, found by bisection, for three
   problems.  Eq. (23)'s limit is omega_max dt = 2 whatever alpha (timestep.py), so the ratio should
   be 1 up to the estimate's accuracy and the nonlinearity of the run.

    python -m verification.dynamic_cantilever      (about a minute; writes out/dynamic_cantilever.json)
"""

from __future__ import annotations

import math
import time

import numpy as np
import scipy.linalg

from solidshell import Fabric, IsotropicShell, ShellMesh
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers import explicit
from solidshell.units import G0

from . import rect_grid, write_json

BETA1 = 1.8751040687119611  # first root of 1 + cos(b) cosh(b) = 0


def strip_problem(material, nx, L, W, gravity=0.0, ny=1):
    nodes, quads = rect_grid(nx, ny, L, W)
    mesh = ShellMesh(nodes, quads=quads)
    model = Model(mesh, material)
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[np.isclose(nodes[:, 0], 0.0)] = True
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -gravity * model.lumped_mass()[:, 0] * G0
    return Problem(model, fixed, loads)


def crossings(t, w):
    out = []
    for sgn in (1, -1):
        s = np.flatnonzero((sgn * w[:-1] < 0) & (sgn * w[1:] >= 0))
        tc = t[s] - w[s] * (t[s + 1] - t[s]) / (w[s + 1] - w[s])
        out.append(np.diff(tc))
    return np.concatenate(out)


def frequency_case(name, material, nx, L, W, B, mu, settings):
    prob = strip_problem(material, nx, L, W)
    m = prob.model
    M = explicit.scaled_mass(m, settings.get("mass_scaling", 1.0), settings.get("mass_scaling_mode", "uniform")).ravel()
    K = m.tangent(np.zeros((m.n_nodes, 6))).toarray()
    fr = prob.free
    w2, phi = scipy.linalg.eigh(K[np.ix_(fr, fr)], np.diag(M[fr]), subset_by_index=[0, 0])
    w_disc = math.sqrt(w2[0])
    w_ref = BETA1**2 * math.sqrt(B / (mu * L**4))
    U0 = np.zeros(6 * m.n_nodes)
    U0[fr] = phi[:, 0]
    U0 *= 1e-4 * L / np.max(np.abs(U0.reshape(-1, 6)[:, :3]))
    T = 2 * math.pi / w_disc
    t0 = time.perf_counter()
    res = explicit.run(prob, {"t_end": 2.3 * T, "alpha": 0.0, "U0": U0.reshape(-1, 6), "frame_every": 1, **settings})
    wall = time.perf_counter() - t0
    tip = np.isclose(m.mesh.nodes[:, 0], L)
    t = np.array([f[0] for f in res.frames])
    w = np.array([f[1][tip, 2].mean() for f in res.frames])
    T_meas = crossings(t, w).mean()
    w_meas = 2 * math.pi / T_meas
    row = dict(case=name, elements=nx, steps=res.info["steps"], dt=res.info["dt"],
               omega_closed_form=w_ref, omega_discrete=w_disc, omega_explicit=w_meas,
               error_vs_discrete=w_meas / w_disc - 1, error_vs_closed_form=w_meas / w_ref - 1,
               discrete_vs_closed_form=w_disc / w_ref - 1, energy_balance_error=res.info["energy_balance_error"],
               wall_s=wall)
    print(f"{name:<26}{nx:>4}  omega {w_meas:10.5f}  vs discrete {row['error_vs_discrete']:+.2e}  vs closed form "
          f"{row['error_vs_closed_form']:+.2e}  ({res.info['steps']} steps, energy err {row['energy_balance_error']:.1e})")
    return row


def free_fall(alpha):
    nodes, quads = rect_grid(2, 2, 1.0, 1.0)
    mesh = ShellMesh(nodes, quads=quads)
    model = Model(mesh, Fabric.wool())
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -model.lumped_mass()[:, 0] * G0
    prob = Problem(model, np.zeros((mesh.n_nodes, 6), bool), loads)
    T = 0.05
    rows = []
    for ms in (1.0, 100.0):
        # masses x100 with the weight unchanged (Section 4.2) divide the acceleration by 100 and
        # lengthen dt by 10: the closed form uses g / ms, and the O(dt^2) error of the damped case grows
        r = explicit.run(prob, {"t_end": T, "alpha": alpha, "mass_scaling": ms})
        assert r.converged, r.message
        z = r.U[:, 2].mean()
        g = G0 / ms
        ref = -g * T**2 / 2 if alpha == 0 else -(g / alpha) * (T - (1 - math.exp(-alpha * T)) / alpha)
        rows.append(dict(alpha=alpha, mass_scaling=ms, dt=r.info["dt"], z=z, z_closed_form=ref, rel_error=z / ref - 1,
                         energy_balance_error=r.info["energy_balance_error"]))
        print(f"free fall alpha={alpha:<4g} masses x{ms:<4g} dt {r.info['dt']:.3e}: z(0.05 s) = {z:.10f}  closed form "
              f"{ref:.10f}  rel. error {z / ref - 1:+.2e}")
    return rows


def stable(prob, dtc, f, settings, steps=3000):
    r = explicit.run(prob, {"t_end": steps * f * dtc * (1 - 1e-12), "dt": f * dtc, "critical_time_step": dtc,
                            "allow_unstable": True, "sample_every": 10, **settings})
    return r.info["status"] == "done"


def stability_case(name, prob, settings):
    pre = explicit.run(prob, {"t_end": 1e-9, **settings})
    dtc = pre.info["critical_time_step"]
    lo, hi = 0.9, 1.2
    if not stable(prob, dtc, lo, settings):
        print(f"{name}: unstable already at 0.9 dt_crit")
        return dict(case=name, critical_time_step=dtc, observed_limit_over_estimate=None)
    while hi - lo > 2e-4:  # growth per step at 1 + 1e-4 is ~1.03: 3000 steps amplify round-off 1e36x
        mid = 0.5 * (lo + hi)
        if stable(prob, dtc, mid, settings):
            lo = mid
        else:
            hi = mid
    print(f"{name:<40} dt_crit (Lanczos) {dtc:.4e} s   observed limit {lo:.5f} .. {hi:.5f} x dt_crit")
    return dict(case=name, critical_time_step=dtc, observed_stable=lo, observed_unstable=hi,
                force_evals_for_estimate=pre.info["time_step_force_evals"])


def main():
    out = {}
    print("1. first bending frequency")
    iso = IsotropicShell(E=1e5, nu=0.0, h=0.2, density=1.0)
    B_iso = iso.E * iso.h**3 / 12
    rows = [frequency_case("isotropic L/h=50", iso, nx, 10.0, 1.0, B_iso, iso.density * iso.h, {}) for nx in (10, 20, 40)]
    wool = Fabric.wool()
    rows += [frequency_case("wool warp 5x1 cm", wool, 10, 5.0, 1.0, wool.bending_warp, wool.mass_per_area, {})]
    rows += [frequency_case("wool warp, director x100", wool, nx, 5.0, 1.0, wool.bending_warp, wool.mass_per_area,
                            {"mass_scaling": 100, "mass_scaling_mode": "director"}) for nx in (10, 20)]
    out["frequency"] = rows
    print("2. free fall")
    out["free_fall"] = free_fall(0.0) + free_fall(5.0)
    print("3. stability limit")
    out["stability"] = [
        stability_case("isotropic strip 8x2, 1% weight", strip_problem(IsotropicShell(E=1e5, nu=0.3, h=0.1, density=1.0),
                                                                      8, 2.0, 0.5, gravity=0.01, ny=2), {"alpha": 0.0}),
        stability_case("wool strip 10x1, weight, alpha=5", strip_problem(wool, 10, 5.0, 1.0, gravity=1.0), {"alpha": 5.0}),
        stability_case("wool strip 10x1, weight, director x100", strip_problem(wool, 10, 5.0, 1.0, gravity=1.0),
                       {"alpha": 5.0, "mass_scaling": 100, "mass_scaling_mode": "director"}),
    ]
    p = write_json("dynamic_cantilever", out)
    print(f"wrote {p}")


if __name__ == "__main__":
    main()
