"""Dampers of dynamic relaxation (Section 4.2): how the explicit scheme of Eq. (23) loses energy.

One small module per mode, each a class with the same three hooks (PyElastica-style: the
integrator knows the interface, not the modes):

* ``rayleigh`` (rayleigh.py): mass-proportional viscous damping alpha M v, Eq. (20) -- the paper's;
* ``kinetic``  (kinetic.py):  Cundall's kinetic damping, the state restarted at rest at each
                              kinetic-energy peak;
* ``fire``     (fire.py):     FIRE (Bitzek et al. 2006), velocity mixing towards the force with
                              an adaptive step, reset when the power P = F.v turns negative;
* ``modal``    (modal.py):    Rayleigh damping tuned to critically damp the slowest mode, alpha =
                              2 zeta omega_min with omega_min^2 the smallest eigenvalue of M^-1 K
                              (ARPACK, shift-invert), re-estimated as the drape settles.

Hooks (all optional but ``alpha``):

``alpha0(integ)``                   viscous alpha [1/s] of Eq. (23)'s coefficients at the start;
``correct(integ, n, D, Dp, Dn1, R, vMv) -> (vMv, finite)``
                                    right after the step D_n -> D_n+1 is computed and before its
                                    books (energies, steady-state test): may rewrite Dn1; returns
                                    the v_n.M.v_n the books are to use and whether Dn1 is finite;
``after(integ, n, D, Dn1, R, vMv)`` after the books, before the state advances (kinetic damping's
                                    restart, as it always ran).
``rewrites_step`` (attribute)       True when correct() computes Dn1 from R alone whenever n > 0
                                    or the run is not fresh: the fused step then leaves Dn1 to it
                                    and its vMv argument is 0.

Everything a damper changes during a run lives in the integrator's State (``state.py``: fire_a,
fire_n, damper_alpha), so a checkpointed run continues bit for bit.
"""

from __future__ import annotations

from .fire import Fire
from .kinetic import Kinetic
from .modal import Modal
from .rayleigh import Rayleigh

DAMPERS = {"rayleigh": Rayleigh, "kinetic": Kinetic, "fire": Fire, "modal": Modal}
"""damping setting -> damper class."""


def make(name: str):
    """The damper of the ``damping`` setting ``name`` (a key of DAMPERS)."""
    return DAMPERS[name]()
