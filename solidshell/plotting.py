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
    reference: dict | None = None,
) -> Path:
    """Draw the mesh at X_o + U_o (U (N,6) or None for the undeformed mesh) and write a PNG.

    reference : a clamped strip's reference centre line, {"x": [...], "z": [...], "label": str} [cm]
        from its clamp along the strip (solidshell.references.strip_elastica's ``curve``), drawn
        dashed in the side view from the mean of the mesh's ``clamped`` nodes.
    The colour bar of height is left out of a view that sees the sheet edge-on (a strip from the
    side: less than 5 % of its area faces the camera), where it would colour nothing."""
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
    if _facing_fraction(mesh, X, CAMERAS[view]) >= 0.05:
        colorbar(fig, ax, sm)
    if reference is not None and view == "side":
        _draw_reference(ax, mesh, reference, CAMERAS[view])
    head = title or "solidshell"
    sub = _VIEW_NAMES[view] + (f" -- {subtitle}" if subtitle else "")
    ax.set_title(f"{head}\n{sub}", fontsize=9.5)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png", bbox_inches="tight", pad_inches=0.15)
    return Path(path)


def _facing_fraction(mesh, X, camera) -> float:
    """The share of the sheet's area that faces the camera: sum |n . d| A / sum A over the
    elements (quads by their diagonals' cross product) at positions X."""
    d = camera.frame()[2]
    a = []
    for cells in (np.asarray(mesh.quads), np.asarray(mesh.tris)):
        if len(cells):
            P = X[cells]
            n = np.cross(P[:, 2] - P[:, 0], P[:, -1] - P[:, 1]) if cells.shape[1] == 4 else None
            if n is None:
                n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
            a.append(n)
    n = np.concatenate(a)
    area = np.linalg.norm(n, axis=1).sum()
    return float(np.abs(n @ d).sum() / area) if area > 0 else 1.0


def _draw_reference(ax, mesh, reference: dict, camera) -> None:
    """The reference centre line from the strip's clamp, along the undeformed strip's horizontal
    direction, dashed, with a legend."""
    clamp = mesh.node_sets.get("clamped")
    if clamp is None or not len(clamp):
        return
    X0 = np.asarray(mesh.nodes, float)
    origin = X0[clamp].mean(0)
    along = X0.mean(0) - origin
    along[2] = 0.0
    if not np.linalg.norm(along) > 0:
        return
    along /= np.linalg.norm(along)
    P = origin + np.outer(reference["x"], along) + np.outer(reference["z"], [0.0, 0.0, 1.0])
    sx, sy, _ = camera.project(P)
    (line,) = ax.plot(sx, sy, "--", color="crimson", lw=1.4, zorder=5, label=reference.get("label", "reference"))
    from matplotlib.lines import Line2D

    sheet = Line2D([], [], color=(0.05, 0.05, 0.05), lw=1.6, label="this run")
    ax.legend(handles=[sheet, line], loc="lower left", fontsize=7.5, frameon=False)
