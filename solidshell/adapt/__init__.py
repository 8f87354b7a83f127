"""Adaptive mesh subdivision (paper Section 5): background mesh and labels (background.py),
active leaves with 2:1 balance and the computational mesh (forest.py), hybrid macro-transition
patterns (transition.py).  A peer of the solvers: solidshell.solvers never imports this package."""

from .background import BackgroundMesh, boundary_area_report, circle_projector, estimate_background_bytes
from .forest import ActiveMesh, AdaptiveMesh
from .transition import PATTERN_NAMES

__all__ = [
    "BackgroundMesh",
    "AdaptiveMesh",
    "ActiveMesh",
    "PATTERN_NAMES",
    "boundary_area_report",
    "circle_projector",
    "estimate_background_bytes",
]
