"""Static equilibrium: an energy-minimising trust-region Newton (the default), the paper's
lambda-scaled Newton-Raphson (Section 3, Eqs. 16-18) and Crisfield's arc-length method.

    from solidshell.solvers.static import solve_static
    res = solve_static(model, fixed, loads, load_factors=[0.5, 1.0], method="newton", tol=1e-9)
    res.U, res.converged, res.message, res.info, res.path

Modules:
  settings.py   StaticSettings: every option with its type, range and default (the one place)
  system.py     the discrete system (potential, gradient, free tangent, contact, factorisations),
                the convergence measures, the stability check and the saddle escape
  newton.py     the trust-region / Armijo / no-line-search Newton at one load level
  paper.py      the paper's scheme (Eqs. 16-18) at one load level
  arclength.py  Crisfield's arc-length method
  driver.py     solve_static, the registry entry run, load stepping and the report

Iteration counts of every method and what was tried and dropped: docs/solvers.md.
"""

from .settings import METHODS, StaticSettings

__all__ = ["METHODS", "StaticSettings", "run", "solve_static"]


def __getattr__(name):
    # the solver is loaded when it is asked for: a scene's settings check (StaticSettings) does
    # not load it
    if name in ("solve_static", "run"):
        from . import driver

        return getattr(driver, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
