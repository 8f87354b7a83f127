"""A run's pictures as PNG: ``top``, ``iso`` (isometric), ``side`` (looking along +y: x-z) and
``side_yz`` (looking along -x: y-z), all orthographic.

The sheet is shaded with light and coloured by height z (colour bar in cm), with its mesh lines;
the scene's pedestal or sphere is drawn solid; axes are in cm with equal aspect and name the warp
and weft where they lie along x or y.  Rendering (solidshell.render): VTK through PyVista
off-screen when it can render here, else a matplotlib painter that sorts all polygons (sheet and
bodies together) by depth.  Each view has one fixed camera, so the same figure looks the same in
every run.  Only :func:`render` is needed by the runner; it writes atomically
(solidshell.io.atomic_path).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .render.geometry import CAMERAS, bodies_of
from .render.panel import ViewStyle, colorbar, draw_view, height_norm, scene_warp_deg

VIEWS = ("top", "iso", "side", "side_yz")
_VIEW_NAMES = {
    "top": "top view",
    "iso": "isometric view",
    "side": "side view (x-z projection)",
    "side_yz": "side view (y-z projection)",
}


def _figure(figsize):
    """A matplotlib Figure on the Agg canvas, made without pyplot: writing a PNG needs neither
    pyplot nor a change of the process's backend (a notebook that calls render keeps its own)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def render(
    path,
    mesh,
    U=None,
    view: str = "iso",
    title: str | None = None,
    scene=None,
    subtitle: str | None = None,
    dpi: int = 130,
    mesh_lines: bool = True,
) -> Path:
    """Draw the mesh at X_o + U_o (U (N,6) or None for the undeformed mesh) and write a PNG."""
    from .io import atomic_path

    if view not in VIEWS:
        raise ValueError(f"unknown view {view!r}; known: {', '.join(VIEWS)}")
    assert view in CAMERAS
    X = mesh.nodes.copy()
    if U is not None:
        X = X + np.asarray(U, float).reshape(-1, 6)[:, :3]
    fig = _figure((7.0, 6.0))
    ax = fig.add_subplot(111)
    sm = draw_view(
        ax,
        mesh,
        X,
        view,
        bodies=bodies_of(scene),
        norm=height_norm(X),
        warp_deg=scene_warp_deg(scene),
        style=ViewStyle(mesh_lines=mesh_lines),
    )
    colorbar(fig, ax, sm)
    head = title or "solidshell"
    sub = _VIEW_NAMES[view] + (f" -- {subtitle}" if subtitle else "")
    ax.set_title(f"{head}\n{sub}", fontsize=9.5)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png", bbox_inches="tight", pad_inches=0.15)
    return Path(path)
