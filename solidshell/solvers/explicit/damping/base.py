"""The damper base class: the hooks' defaults (solidshell.interfaces.Damper is the interface)."""

from __future__ import annotations

from ....interfaces import DampingView


class Damper:
    """Viscous damping with the ``alpha`` setting and nothing to do per step; a mode overrides what
    it changes.  The flags are False unless a mode sets them (damping/__init__.py)."""

    name = "damper"
    rewrites_step = False
    wants_power = False
    varies_alpha = False

    def alpha0(self, settings) -> float:
        """The ``alpha`` setting [1/s]."""
        return float(settings.alpha)

    def correct(self, view: DampingView, n, D, Dp, Dn1, R, vMv):
        return vMv, True

    def after(self, view: DampingView, n, D, Dn1, R, vMv) -> None:
        return None
