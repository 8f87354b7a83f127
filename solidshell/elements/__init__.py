"""Element kernels: quad4 (Eqs. 1-9) and tri3 (Eqs. 10-15) share the batched kernels of core.py."""

from . import quad4, tri3

TYPES = {"quad": quad4, "tri": tri3}

THICKNESS_STRAINS = ("green", "quasi")
"""The thickness strain of the kernels (core.py, lanes*.py): Green (Eq. 3) or the quasi-engineering
strain of Eq. (24); ``Model(thickness_strain=...)`` and a scene's ``model.thickness_strain``."""
