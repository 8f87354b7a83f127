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

Each is a :class:`Damper` (``base.py``: the hooks' defaults; the interface is
``solidshell.interfaces.Damper``).  Its hooks get a ``view`` of the run
(``solidshell.interfaces.DampingView``: the settings, the dof arrays, the state, the critical step,
and the operations a damper performs on the scheme -- change the step, change alpha, redo the step,
the stiffness), not the integrator:

``alpha0(settings)``                viscous alpha [1/s] of Eq. (23)'s coefficients at the start;
``correct(view, n, D, Dp, Dn1, R, vMv) -> (vMv, finite)``
                                    right after the step D_n -> D_n+1 is computed and before its
                                    books (energies, steady-state test): may rewrite Dn1; returns
                                    the v_n.M.v_n the books are to use and whether Dn1 is finite;
``after(view, n, D, Dn1, R, vMv)``  after the books, before the state advances (kinetic damping's
                                    restart, as it always ran).
``rewrites_step`` (flag)            True when correct() computes Dn1 from R alone whenever n > 0
                                    or the run is not fresh: the fused step then leaves Dn1 to it
                                    and its vMv argument is 0;
``wants_power`` (flag)              correct() reads view.step_power (formed by the fused step);
``varies_alpha`` (flag)             alpha changes during the run (kept in state.damper_alpha).

Everything a damper changes during a run lives in the integrator's State (``state.py``: fire_a,
fire_n, damper_alpha), so a checkpointed run continues bit for bit.
"""

from __future__ import annotations

from .base import Damper
from .fire import Fire
from .kinetic import Kinetic
from .modal import Modal
from .rayleigh import Rayleigh

DAMPERS = {"rayleigh": Rayleigh, "kinetic": Kinetic, "fire": Fire, "modal": Modal}
"""damping setting -> damper class."""


def make(name: str) -> Damper:
    """The damper of the ``damping`` setting ``name`` (a key of DAMPERS)."""
    return DAMPERS[name]()
