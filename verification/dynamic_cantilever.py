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

from solidshell import Fabric, IsotropicShell
from solidshell.solvers import explicit
from verification.checks.dynamics import BETA1, cantilever_problem, crossings, free_fall, frequency_case  # noqa: F401  (the computations live in the package)

from . import write_json

strip_problem = cantilever_problem


def stable(prob, dtc, f, settings, steps=3000):
    r = explicit.run(
        prob,
        {
            "t_end": steps * f * dtc * (1 - 1e-12),
            "dt": f * dtc,
            "critical_time_step": dtc,
            "allow_unstable": True,
            "sample_every": 10,
            **settings,
        },
    )
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
    return dict(
        case=name,
        critical_time_step=dtc,
        observed_stable=lo,
        observed_unstable=hi,
        force_evals_for_estimate=pre.info["time_step_force_evals"],
    )


def _freq(*args):
    row = frequency_case(*args)
    print(
        f"{row['case']:<26}{row['elements']:>4}  omega {row['omega_explicit']:10.5f}  vs discrete "
        f"{row['error_vs_discrete']:+.2e}  vs closed form {row['error_vs_closed_form']:+.2e}  ({row['steps']} steps, "
        f"energy err {row['energy_balance_error']:.1e})",
        flush=True,
    )
    return row


def _fall(alpha):
    rows = free_fall(alpha)
    for r in rows:
        print(
            f"free fall alpha={alpha:<4g} masses x{r['mass_scaling']:<4g} dt {r['dt']:.3e}: z(0.05 s) = {r['z']:.10f}  "
            f"closed form {r['z_closed_form']:.10f}  rel. error {r['rel_error']:+.2e}  ({r['status']})"
        )
    return rows


def main():
    out = {}
    print("1. first bending frequency")
    iso = IsotropicShell(E=1e5, nu=0.0, h=0.2, density=1.0)
    B_iso = iso.E * iso.h**3 / 12
    rows = [_freq("isotropic L/h=50", iso, nx, 10.0, 1.0, B_iso, iso.density * iso.h, {}) for nx in (10, 20, 40)]
    wool = Fabric.wool()
    rows += [_freq("wool warp 5x1 cm", wool, 10, 5.0, 1.0, wool.bending_warp, wool.mass_per_area, {})]
    rows += [
        _freq(
            "wool warp, director x100",
            wool,
            nx,
            5.0,
            1.0,
            wool.bending_warp,
            wool.mass_per_area,
            {"mass_scaling": 100, "mass_scaling_mode": "director"},
        )
        for nx in (10, 20)
    ]
    out["frequency"] = rows
    print("2. free fall")
    out["free_fall"] = _fall(0.0) + _fall(5.0)
    print("3. stability limit")
    out["stability"] = [
        stability_case(
            "isotropic strip 8x2, 1% weight",
            strip_problem(IsotropicShell(E=1e5, nu=0.3, h=0.1, density=1.0), 8, 2.0, 0.5, gravity=0.01, ny=2),
            {"alpha": 0.0},
        ),
        stability_case(
            "wool strip 10x1, weight, alpha=5", strip_problem(wool, 10, 5.0, 1.0, gravity=1.0), {"alpha": 5.0}
        ),
        stability_case(
            "wool strip 10x1, weight, director x100",
            strip_problem(wool, 10, 5.0, 1.0, gravity=1.0),
            {"alpha": 5.0, "mass_scaling": 100, "mass_scaling_mode": "director"},
        ),
    ]
    p = write_json("dynamic_cantilever", out)
    print(f"wrote {p}")


if __name__ == "__main__":
    main()
