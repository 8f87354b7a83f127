"""Pictures of draped sheets: geometry (surfaces, cameras), two renderers (VTK through PyVista,
off-screen; a depth-sorting matplotlib painter as the fallback) and the panel that draws one view
into a matplotlib axes.  solidshell.plotting.render writes a run's pictures with it;
paper_figures/ composes the paper's figures from panels."""

from .geometry import CAMERAS, Camera, Surface, bodies_of, scene_surfaces
from .panel import ViewStyle, axis_labels, colorbar, draw_view, height_norm, renderer, scene_warp_deg

__all__ = [
    "CAMERAS",
    "Camera",
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
