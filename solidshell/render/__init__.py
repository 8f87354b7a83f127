"""Pictures of draped sheets: geometry (surfaces, cameras), two renderers (VTK, off-screen; a depth-sorting matplotlib painter as the fallback) and the panel that draws one view
into a matplotlib axes.  solidshell.plotting.render writes a run's pictures with it;
paper_figures/ composes the paper's figures from panels.

The names below are imported on first use: ``solidshell.render.server`` (a run's pictures'
process, started before the run's own imports) must not load NumPy and the geometry first."""

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .geometry import CAMERAS, Camera, Surface, bodies_of, scene_surfaces
    from .panel import SceneLook, ViewStyle, axis_labels, colorbar, draw_view, height_norm, renderer, scene_warp_deg

__all__ = [
    "CAMERAS",
    "Camera",
    "SceneLook",
    "Surface",
    "ViewStyle",
    "axis_labels",
    "bodies_of",
    "colorbar",
    "draw_view",
    "height_norm",
    "renderer",
    "scene_surfaces",
    "scene_warp_deg",
]

_GEOMETRY = {"CAMERAS", "Camera", "Surface", "bodies_of", "scene_surfaces"}


def __getattr__(name):
    if name in __all__:
        import importlib

        module = importlib.import_module(f".{'geometry' if name in _GEOMETRY else 'panel'}", __name__)
        return getattr(module, name)
    raise AttributeError(f"module 'solidshell.render' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
