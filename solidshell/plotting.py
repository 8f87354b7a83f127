"""A run's pictures as PNG: ``top``, ``iso`` (isometric), ``side`` (looking along +y: x-z) and
``side_yz`` (looking along -x: y-z), all orthographic.

The sheet is shaded with light and coloured by height z (colour bar in cm), with its mesh lines;
the scene's pedestal or sphere is drawn solid; axes are in cm with equal aspect and name the warp
and weft where they lie along x or y.  Rendering (solidshell.render): VTK
off-screen when it can render here, else a matplotlib painter that sorts all polygons (sheet and
bodies together) by depth.  Each view has one fixed camera, so the same figure looks the same in
every run.  Only :func:`render` is needed by the runner; it writes atomically
(solidshell.io.atomic_path).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .render.geometry import CAMERAS, MARK_COLOR
from .render.panel import SceneLook, ViewStyle, colorbar, draw_view, height_norm

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
    marks: dict | None = None,
) -> Path:
    """Draw the mesh at X_o + U_o (U (N,6) or None for the undeformed mesh) and write a PNG.

    reference : a clamped strip's reference centre line, {"x": [...], "z": [...], "label": str} [cm]
        from its clamp along the strip (solidshell.references.strip_elastica's ``curve``), drawn
        dashed in the side view from the mean of the mesh's ``clamped`` nodes.
    scene : the Scene (or its render.SceneLook) whose bodies are drawn and whose fabric's warp
        names the axes; None: the sheet alone, isotropic.
    marks : what the picture marks in red, with a legend line each (:func:`crossing_marks`):
        {"cells": 0/1 per element, "points": node indices, "pairs": crossing triangle pairs}.
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
    look = SceneLook.of(scene)
    sm = draw_view(
        ax,
        mesh,
        X,
        view,
        bodies=look.bodies,
        norm=height_norm(X),
        warp_deg=look.warp_deg,
        style=ViewStyle(mesh_lines=mesh_lines),
        marks=marks,
    )
    if _facing_fraction(mesh, X, CAMERAS[view]) >= 0.05:
        colorbar(fig, ax, sm)
    if reference is not None and view == "side":
        ax.legend(
            handles=_draw_reference(ax, mesh, reference, CAMERAS[view]), loc="lower left", fontsize=7.5, frameon=False
        )
    handles = _mark_handles(marks)
    if handles:  # a caption under the picture (below the x label of a labelled view): it hides nothing
        if ax.get_legend() is not None:
            ax.add_artist(ax.get_legend())  # the reference's legend stays beside this one
        below = -0.01 if view == "iso" else -0.12
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, below), fontsize=8, frameon=False)
    head = title or "solidshell"
    sub = _VIEW_NAMES[view] + (f" -- {subtitle}" if subtitle else "")
    ax.set_title(f"{head}\n{sub}", fontsize=9.5)
    with atomic_path(path) as tmp:
        _save_tight_png(fig, tmp, dpi, pad_inches=0.15)
    return Path(path)


PNG_COMPRESS_LEVEL = 3
"""zlib level of the pictures' PNGs: 3 encodes a run's pictures in 45-75 % of the time of PIL's
default 6, for files 8-17 % larger (the pixels are the same)."""


def _save_tight_png(fig, path, dpi: int, pad_inches: float) -> None:
    """Write the figure as ``savefig(path, dpi=dpi, bbox_inches="tight", pad_inches=pad_inches)``
    would -- the figure cut to its artists' box, padded -- from one draw instead of savefig's two
    (a "tight" savefig draws the figure once to measure it and once more to save it; the text and
    tick layout of a draw is 0.1-0.2 s of each picture, issue 41): the figure is drawn once at
    ``dpi`` and its pixels are cut to the padded box.  The picture differs from savefig's by the
    sub-pixel offset of that box (savefig shifts the drawing by it, the cut snaps to whole pixels)
    and is the same size +-1 px.  A box reaching outside the figure (a title wider than it) is
    saved by savefig, which widens the canvas to it."""
    from matplotlib import __version__ as mpl_version
    from PIL import Image, PngImagePlugin

    dpi0 = fig.dpi
    try:
        fig.dpi = dpi
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        box = fig.get_tightbbox(renderer).padded(pad_inches)
        rgba = np.asarray(fig.canvas.buffer_rgba())
    finally:
        fig.dpi = dpi0
    H, W = rgba.shape[:2]
    x0, y0 = int(np.floor(box.x0 * dpi)), int(np.floor(box.y0 * dpi))
    w, h = int(box.width * dpi), int(box.height * dpi)  # as savefig's canvas: Agg truncates
    if x0 < 0 or y0 < 0 or x0 + w > W or y0 + h > H:
        fig.savefig(path, dpi=dpi, format="png", bbox_inches="tight", pad_inches=pad_inches)
        return
    cut = rgba[H - (y0 + h) : H - y0, x0 : x0 + w]  # rows from the top: display y points up
    info = PngImagePlugin.PngInfo()
    info.add_text("Software", f"Matplotlib version{mpl_version}, https://matplotlib.org/")
    Image.fromarray(np.ascontiguousarray(cut)).save(
        path, format="png", pnginfo=info, dpi=(dpi, dpi), compress_level=PNG_COMPRESS_LEVEL
    )


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


def _draw_reference(ax, mesh, reference: dict, camera) -> list:
    """The reference centre line from the strip's clamp, along the undeformed strip's horizontal
    direction, dashed; returns its legend handles."""
    clamp = mesh.node_sets.get("clamped")
    if clamp is None or not len(clamp):
        return []
    X0 = np.asarray(mesh.nodes, float)
    origin = X0[clamp].mean(0)
    along = X0.mean(0) - origin
    along[2] = 0.0
    if not np.linalg.norm(along) > 0:
        return []
    along /= np.linalg.norm(along)
    P = origin + np.outer(reference["x"], along) + np.outer(reference["z"], [0.0, 0.0, 1.0])
    sx, sy, _ = camera.project(P)
    (line,) = ax.plot(sx, sy, "--", color="crimson", lw=1.4, zorder=5, label=reference.get("label", "reference"))
    from matplotlib.lines import Line2D

    sheet = Line2D([], [], color=(0.05, 0.05, 0.05), lw=1.6, label="this run")
    return [sheet, line]


def _mark_handles(marks: dict | None) -> list:
    """Legend handles saying what is marked red and how much of it there is."""
    if not marks:
        return []
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    out = []
    n_cells = int(np.count_nonzero(marks.get("cells", ())))
    if n_cells:
        pairs = marks.get("pairs")
        what = f" ({pairs} crossing triangle pair{'s' if pairs != 1 else ''})" if pairs else ""
        out.append(Patch(color=MARK_COLOR, label=f"{n_cells} element(s) through the sheet itself{what}"))
    n_pts = len(marks.get("points", ()))
    if n_pts:
        out.append(
            Line2D(
                [],
                [],
                ls="none",
                marker="o",
                mfc="none",
                mec=MARK_COLOR,
                label=f"{n_pts} interpenetrated node(s) (n$_p$·d$_p$ < 0)",
            )
        )
    return out


def crossing_marks(model, U, summary: dict) -> dict | None:
    """What a run's pictures mark red (on when there is any, docs/output.md): the elements whose
    mid-surface triangles cross another's sharing no node (solidshell/layers.py, summary.json
    ``self_intersections``) and the interpenetrated nodes (n_p . d_p < 0, Section 4.3, summary.json
    ``interpenetrated_nodes``), from solidshell.fields' flags of the state U (N,6).  None when the
    summary counts neither (nothing computed)."""
    pairs = int(summary.get("self_intersections") or 0)
    if not pairs and not summary.get("interpenetrated_nodes"):
        return None
    from .fields import flag_fields

    point, cell = flag_fields(model, U, self_intersection=bool(pairs))
    return {
        "cells": cell.get("self_intersecting", np.zeros(model.mesh.n_elements, np.int8)),
        "points": np.flatnonzero(point["interpenetrated"]),
        "pairs": pairs,
    }
