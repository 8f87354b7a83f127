"""Element kernels: quad4 (Eqs. 1-9) and tri3 (Eqs. 10-15) share the batched kernels of core.py."""

from . import quad4, tri3

TYPES = {"quad": quad4, "tri": tri3}
