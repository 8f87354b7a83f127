"""One view of a draped sheet drawn into a matplotlib axes: the renderer's picture in true screen
coordinates [cm], equal axes, labels that follow the warp direction, the rigid bodies solid.

    sm = draw_view(ax, mesh, X, "top", bodies=bodies_of(scene), norm=norm, warp_deg=0.0)
    fig.colorbar(sm, ...)

The renderer is VTK (off-screen) when it can render here, else the depth-sorting
matplotlib painter (one log line says so, once per process).  ``SOLIDSHELL_RENDERER=matplotlib``
forces the painter.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass

import numpy as np

from ..material import Fabric
from . import mpl_backend, vtk_backend
from .geometry import CAMERAS, MARK_COLOR, Camera, bodies_of, scene_surfaces, screen_extent

log = logging.getLogger("solidshell")
CMAP = "viridis"
_SAID: dict = {}


def renderer() -> str:
    """ "vtk" or "matplotlib": the one pictures are drawn with in this process."""
    want = os.environ.get("SOLIDSHELL_RENDERER", "auto").strip().lower()
    if want in ("matplotlib", "mpl"):
        return "matplotlib"
    ok, why = vtk_backend.available()
    if ok:
        return "vtk"
    if not _SAID.get("fallback"):
        _SAID["fallback"] = True
        log.warning(f"pictures drawn with the depth-sorting matplotlib renderer: {why}")
    return "matplotlib"


def axis_labels(warp_deg: float | None) -> dict:
    """Axis labels [cm] naming the yarn directions when they lie along the axes: a warp at 0° (mod
    180°) puts the warp along x, at 90° along y; any other angle names neither (the warp's angle
    goes in the note).  ``warp_deg`` None: an isotropic sheet, no yarn names."""
    lab = {"x": "x [cm]", "y": "y [cm]", "z": "z [cm]", "note": ""}
    if warp_deg is None:
        return lab
    a = float(warp_deg) % 180.0
    if min(a, 180.0 - a) < 1e-6:
        lab["x"], lab["y"] = "x [cm]  (warp)", "y [cm]  (weft)"
    elif abs(a - 90.0) < 1e-6:
        lab["x"], lab["y"] = "x [cm]  (weft)", "y [cm]  (warp)"
    else:
        lab["note"] = f"warp at {float(warp_deg):g}° from x"
    return lab


def scene_warp_deg(scene) -> float | None:
    """The warp angle [deg] of a scene's fabric; None for an isotropic section (or no scene)."""
    if scene is None:
        return None
    m = scene.material_object()
    if not isinstance(m, Fabric):
        return None
    return float(np.degrees(m.warp_angle_rad))


@dataclass(frozen=True)
class SceneLook:
    """What a picture takes from its scene: the rigid bodies it draws (geometry.bodies_of's dicts)
    and the fabric's warp angle [deg] (None: isotropic).  Plain data: the pictures' process draws
    from it without importing the scenes' module (pydantic, ~0.4 s) or reading a body's mesh file."""

    bodies: tuple = ()
    warp_deg: float | None = None

    @classmethod
    def of(cls, scene) -> SceneLook:
        """The look of a Scene (None: no bodies, isotropic; a SceneLook: itself)."""
        if isinstance(scene, SceneLook):
            return scene
        if scene is None:
            return cls()
        return cls(tuple(bodies_of(scene)), scene_warp_deg(scene))


def height_norm(*Xs, pad: float = 0.0):
    """One colour scale (matplotlib Normalize) for the heights z of all position arrays given."""
    import matplotlib.colors as mcolors

    z = np.concatenate([np.asarray(X, float)[:, 2] for X in Xs])
    z = z[np.isfinite(z)]
    lo, hi = (float(z.min()), float(z.max())) if len(z) else (0.0, 1.0)
    if hi - lo < 1e-9 * max(1.0, abs(hi)):
        lo, hi = lo - 0.5, hi + 0.5
    return mcolors.Normalize(vmin=lo - pad, vmax=hi + pad)


def _edge_width(n_elements: int, vtk: bool) -> float:
    if vtk:
        return 1.0 if n_elements <= 2000 else 0.6
    return 0.35 if n_elements <= 1500 else 0.15


@dataclass(frozen=True)
class ViewStyle:
    """How :func:`draw_view` draws: the colour map of the heights, the mesh lines, axis labels (or
    the orientation triad of an oblique view), the VTK image height [px], and whether a pedestal's
    top is drawn over the sheet's clamped part."""

    cmap: str = CMAP
    mesh_lines: bool = True
    labels: bool = True
    height_px: int = 900
    cover_pedestal: bool = True


def draw_view(
    ax,
    mesh,
    X,
    view="iso",
    bodies=(),
    norm=None,
    warp_deg=None,
    zoom=None,
    extent=None,
    style: ViewStyle = ViewStyle(),
    marks=None,
):
    """Draw the sheet at positions X (N,3) [cm] with the bodies into ``ax``; returns a
    ScalarMappable for a colour bar of height z [cm].

    view   : a name of solidshell.render.geometry.CAMERAS or a Camera
    warp_deg : the fabric's warp angle [deg] (axis labels name the yarns); None: isotropic
    zoom   : (xmin, xmax, ymin, ymax) of the screen [cm] to show (Fig. 12c); None: everything
    extent : a fixed screen rectangle instead of the fitted one (the same frame across panels)
    style  : colour map, mesh lines, labels, image height, pedestal cover (:class:`ViewStyle`)
    marks  : {"cells": 0/1 per element, drawn red; "points": node indices, red rings drawn over
             the picture (seen through the sheet: a warning, not a shape)} or None
    """
    import matplotlib.cm as mcm

    cmap, labels = style.cmap, style.labels
    cam = CAMERAS[view] if isinstance(view, str) else view
    X = np.asarray(X, float)
    norm = norm or height_norm(X)
    marks = marks or {}
    surfaces = scene_surfaces(
        mesh,
        X,
        list(bodies),
        mesh_lines=style.mesh_lines,
        cover_pedestal=style.cover_pedestal,
        marked=marks.get("cells"),
    )
    ext = zoom or extent or screen_extent(surfaces, cam)
    use_vtk = renderer() == "vtk"
    ew = _edge_width(mesh.n_elements, use_vtk)
    if use_vtk:
        img = vtk_backend.render_image(surfaces, cam, ext, norm, cmap, height_px=style.height_px, edge_width=ew)
        ax.imshow(_opaque_rgba(img), extent=ext, origin="upper", interpolation="antialiased", zorder=1)
    else:
        mpl_backend.draw(ax, surfaces, cam, norm, cmap, edge_width=ew)
    pts = np.asarray(marks.get("points", ()), dtype=np.int64)
    if len(pts):
        sx, sy, _ = cam.project(X[pts])
        ax.scatter(sx, sy, s=22, facecolors="none", edgecolors=[MARK_COLOR], linewidths=1.2, zorder=6)
    ax.set_xlim(ext[0], ext[1])
    ax.set_ylim(ext[2], ext[3])
    ax.set_aspect("equal")
    name = view if isinstance(view, str) else None
    lab = axis_labels(warp_deg)
    if name in ("iso", None):
        ax.set_xticks([])
        ax.set_yticks([])
        for sp in ax.spines.values():
            sp.set_visible(False)
        if labels:
            triad(ax, cam, lab)
    elif labels:
        xl, yl = {
            "top": (lab["x"], lab["y"]),
            "bottom": (lab["x"], lab["y"]),
            "side": (lab["x"], lab["z"]),
            "side_yz": (lab["y"], lab["z"]),
        }[name]
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.tick_params(labelsize=8)
    if labels and lab["note"]:
        ax.text(0.99, 0.01, lab["note"], transform=ax.transAxes, ha="right", va="bottom", fontsize=7)
    sm = mcm.ScalarMappable(norm=norm, cmap=cmap)
    sm.set_array(np.asarray([norm.vmin, norm.vmax]))
    return sm


def _opaque_rgba(rgb) -> np.ndarray:
    """An RGB uint8 picture as opaque float32 RGBA, the form matplotlib resamples: handed uint8 RGB,
    matplotlib converts it to float and appends an alpha channel at each draw (0.05 s for
    1500x900 px)."""
    out = np.ones(rgb.shape[:2] + (4,), np.float32)
    np.multiply(rgb, np.float32(1.0 / 255.0), out=out[..., :3], casting="unsafe")
    return out


def triad(ax, cam: Camera, lab: dict, at=(0.1, 0.12), size=0.08):
    """Small x/y/z arrows (axes fraction) showing the orientation of an oblique view; their labels
    have a white halo, so that one lying over the dark part of a sheet still reads."""
    from matplotlib import patheffects

    halo = [patheffects.withStroke(linewidth=2.0, foreground="white")]
    r, u, _ = cam.frame()
    names = {"x": lab["x"].replace(" [cm]", ""), "y": lab["y"].replace(" [cm]", ""), "z": "z"}
    for k, e in zip("xyz", np.eye(3)):
        v = np.array([e @ r, e @ u]) * size
        ax.annotate(
            "",
            xy=(at[0] + v[0], at[1] + v[1]),
            xytext=at,
            xycoords="axes fraction",
            arrowprops=dict(arrowstyle="-|>", lw=0.9, color="0.15", shrinkA=0, shrinkB=0),
        )
        t = v / max(np.linalg.norm(v), 1e-12)
        ha = "left" if t[0] > 0.4 else "right" if t[0] < -0.4 else "center"
        va = "bottom" if t[1] > 0.4 else "top" if t[1] < -0.4 else "center"
        ax.text(
            at[0] + v[0] + 0.01 * t[0],
            at[1] + v[1] + 0.01 * t[1],
            " ".join(names[k].split()),
            transform=ax.transAxes,
            fontsize=7,
            ha=ha,
            va=va,
            color="0.15",
            path_effects=halo,
        )


def colorbar(fig, ax, sm, label="height z [cm]"):
    """A colour bar as tall as ``ax`` (which has equal aspect)."""
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    cax = make_axes_locatable(ax).append_axes("right", size="4%", pad=0.1)
    cb = fig.colorbar(sm, cax=cax)
    cb.set_label(label, fontsize=8)
    cb.ax.tick_params(labelsize=7)
    return cb
