"""Mass-proportional (Rayleigh) damping C = alpha M, Eq. (20): the paper's relaxation (Section 4.2,
alpha = 5 1/s with all masses x100).  Nothing to do per step: alpha enters Eq. (23)'s coefficients."""

from __future__ import annotations

from .base import Damper


class Rayleigh(Damper):
    name = "rayleigh"
