"""Mass-proportional (Rayleigh) damping C = alpha M, Eq. (20): the paper's relaxation (Section 4.2,
alpha = 5 1/s with all masses x100).  Nothing to do per step: alpha enters Eq. (23)'s coefficients."""

from __future__ import annotations


class Rayleigh:
    name = "rayleigh"

    def alpha0(self, integ) -> float:
        """The ``alpha`` setting [1/s]."""
        return float(integ.s.alpha)

    def correct(self, integ, n, D, Dp, Dn1, R, vMv):
        return vMv, True

    def after(self, integ, n, D, Dn1, R, vMv) -> None:
        return None
