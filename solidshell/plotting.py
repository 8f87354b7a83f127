"""Pictures of a (deformed) sheet as PNG (matplotlib, Agg): ``top``, ``iso`` (isometric), ``side``
(x-z projection, looking along +y) and ``side_yz`` (y-z projection, looking along -x).

Faces are shaded by height z (colour bar in cm), axes are in cm with equal aspect, and the
scene's pedestal or sphere, when it has one, is drawn in grey.  Only :func:`render` is needed by
the runner; it writes atomically (solidshell.io.atomic_path).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

_CMAP = "viridis"
_BODY = "0.55"


def _mpl():
    import matplotlib

    if matplotlib.get_backend().lower() != "agg":
        try:
            matplotlib.use("Agg", force=True)
        except Exception:  # pragma: no cover - backend already fixed by the caller
            pass
    import matplotlib.pyplot as plt

    return plt


def _polys(mesh, X):
    """List of (k,3) arrays: element polygons at positions X, quads then triangles."""
    out = [X[c] for c in mesh.quads] if mesh.n_quads else []
    if mesh.n_tris:
        out += [X[c] for c in mesh.tris]
    return out


def _cells_z(mesh, X):
    parts = []
    if mesh.n_quads:
        parts.append(X[mesh.quads][:, :, 2].mean(axis=1))
    if mesh.n_tris:
        parts.append(X[mesh.tris][:, :, 2].mean(axis=1))
    return np.concatenate(parts)


def _norm(z):
    import matplotlib.colors as mcolors

    lo, hi = float(np.min(z)), float(np.max(z))
    if hi - lo < 1e-9 * max(1.0, abs(hi)):
        lo, hi = lo - 0.5, hi + 0.5
    return mcolors.Normalize(vmin=lo, vmax=hi)


def _light(mesh, X, facecolors):
    """Dim each face by the cosine of its normal with a light from above-front (keeps folds visible)."""
    parts = []
    for cells in (mesh.quads, mesh.tris):
        if len(cells):
            P = X[cells]
            if cells.shape[1] == 4:
                n = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])
            else:
                n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
            parts.append(n)
    n = np.concatenate(parts)
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    light = np.array([-0.4, -0.5, 1.0])
    light /= np.linalg.norm(light)
    shade = 0.55 + 0.45 * np.abs(n @ light)
    fc = facecolors.copy()
    fc[:, :3] *= shade[:, None]
    return fc


def _edge_width(mesh):
    return 0.15 if mesh.n_elements > 1500 else 0.3


# --------------------------------------------------------------------------- bodies
def _draw_body_top(ax, body):
    import matplotlib.patches as mpatches

    if body is None:
        return
    c = body.get("centre", (0.0, 0.0, 0.0))
    kw = dict(facecolor="0.85", edgecolor="0.3", lw=0.8, ls="--", zorder=0)
    if body["type"] == "sphere":
        ax.add_patch(mpatches.Circle((c[0], c[1]), body["radius"], **kw))
    elif body["type"] == "pedestal":
        if body.get("shape") == "disc":
            ax.add_patch(mpatches.Circle((c[0], c[1]), body["diameter"] / 2, **kw))
        else:
            a = body["size"]
            ax.add_patch(mpatches.Rectangle((c[0] - a / 2, c[1] - a / 2), a, a, **kw))


def _body_surfaces(body, zmin):
    """(X, Y, Z) grids of the body's visible surfaces down to zmin (for plot_surface)."""
    if body is None:
        return []
    c = np.asarray(body.get("centre", (0.0, 0.0, 0.0)), float)
    if body["type"] == "sphere":
        r = body["radius"]
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 48), np.linspace(0, np.pi, 24))
        return [(c[0] + r * np.cos(u) * np.sin(v), c[1] + r * np.sin(u) * np.sin(v), c[2] + r * np.cos(v))]
    if body["type"] != "pedestal":
        return []
    top = c[2]
    bottom = min(zmin, top - 0.5) if zmin < top else top - 0.5
    if body.get("shape") == "disc":
        r = body["diameter"] / 2
        t = np.linspace(0, 2 * np.pi, 64)
        zz = np.array([bottom, top])
        T, Z = np.meshgrid(t, zz)
        side = (c[0] + r * np.cos(T), c[1] + r * np.sin(T), Z)
        R, T2 = np.meshgrid(np.array([0.0, r]), t)
        cap = (c[0] + R * np.cos(T2), c[1] + R * np.sin(T2), np.full_like(R, top))
        return [side, cap]
    a = body["size"] / 2
    xs = np.array([-a, a, a, -a, -a]) + c[0]
    ys = np.array([-a, -a, a, a, -a]) + c[1]
    side = (np.vstack([xs, xs]), np.vstack([ys, ys]), np.vstack([np.full(5, bottom), np.full(5, top)]))
    gx, gy = np.meshgrid(np.array([-a, a]) + c[0], np.array([-a, a]) + c[1])
    cap = (gx, gy, np.full_like(gx, top))
    return [side, cap]


def _bodies(scene):
    if scene is None:
        return []
    out = [dict(c) for c in scene.contact if c["type"] in ("sphere", "pedestal")]
    if not any(c["type"] == "pedestal" for c in out):
        p = scene.pedestal()
        if p is not None:
            out.append(p)
    return out


# --------------------------------------------------------------------------- views
def _cax(ax):
    """A colour-bar axes exactly as tall as ``ax`` (which has equal aspect)."""
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    return make_axes_locatable(ax).append_axes("right", size="4%", pad=0.12)


def _top(ax, fig, mesh, X, norm, cmap, bodies):
    from matplotlib.collections import PolyCollection

    for b in bodies:
        _draw_body_top(ax, b)
    polys = [p[:, :2] for p in _polys(mesh, X)]
    z = _cells_z(mesh, X)
    pc = PolyCollection(polys, array=z, cmap=cmap, norm=norm, edgecolors="k",
                        linewidths=_edge_width(mesh), zorder=2)
    pc.set_alpha(0.95)
    ax.add_collection(pc)
    lo, hi = X[:, :2].min(0), X[:, :2].max(0)
    for b in bodies:
        if b["type"] == "sphere":
            c, r = np.asarray(b["centre"]), b["radius"]
            lo, hi = np.minimum(lo, c[:2] - r), np.maximum(hi, c[:2] + r)
    pad = 0.04 * max(hi - lo)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [cm]  (warp)")
    ax.set_ylabel("y [cm]  (weft)")
    ax.grid(True, lw=0.3, alpha=0.5)
    cb = fig.colorbar(pc, cax=_cax(ax))
    cb.set_label("height z [cm]")


def _side(ax, fig, mesh, X, norm, cmap, bodies, axis=0):
    """Projection on the x-z plane (axis 0, looking along +y) or the y-z plane (axis 1, looking
    along -x), faces coloured by height."""
    import matplotlib.patches as mpatches
    from matplotlib.collections import PolyCollection

    if axis == 1:       # rotate so that y plays the role of x below
        X = X[:, [1, 0, 2]]
        bodies = [dict(b, centre=tuple(np.asarray(b.get("centre", (0.0, 0.0, 0.0)))[[1, 0, 2]])) for b in bodies]
    lo, hi = X.min(0), X.max(0)
    for b in bodies:
        c = np.asarray(b.get("centre", (0.0, 0.0, 0.0)), float)
        kw = dict(facecolor="0.85", edgecolor="0.3", lw=0.8, ls="--", zorder=0)
        if b["type"] == "sphere":
            ax.add_patch(mpatches.Circle((c[0], c[2]), b["radius"], **kw))
            lo, hi = np.minimum(lo, c - b["radius"]), np.maximum(hi, c + b["radius"])
        elif b["type"] == "pedestal":
            half = b["size"] / 2 if b.get("shape") != "disc" else b["diameter"] / 2
            depth = max(c[2] - lo[2], 0.1 * (hi[0] - lo[0]))
            ax.add_patch(mpatches.Rectangle((c[0] - half, c[2] - depth), 2 * half, depth, **kw))
            lo[2] = min(lo[2], c[2] - depth)
            hi[2] = max(hi[2], c[2])
    polys = [p[:, [0, 2]] for p in _polys(mesh, X)]
    z = _cells_z(mesh, X)
    pc = PolyCollection(polys, array=z, cmap=cmap, norm=norm, edgecolors="face", linewidths=1.2, zorder=2)
    ax.add_collection(pc)
    ax.add_collection(PolyCollection(polys, facecolors="none", edgecolors="k",
                                     linewidths=_edge_width(mesh) * 0.7, zorder=3))
    span = max(hi[0] - lo[0], hi[2] - lo[2], 1e-9)
    pad = 0.04 * span
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[2] - pad, hi[2] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("y [cm]  (weft)" if axis == 1 else "x [cm]  (warp)")
    ax.set_ylabel("z [cm]")
    ax.grid(True, lw=0.3, alpha=0.5)
    cb = fig.colorbar(pc, cax=_cax(ax))
    cb.set_label("height z [cm]")


def _three_d(ax, fig, mesh, X, norm, cmap, bodies, elev, azim):
    import matplotlib.cm as mcm
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    z = _cells_z(mesh, X)
    sm = mcm.ScalarMappable(norm=norm, cmap=cmap)
    fc = _light(mesh, X, sm.to_rgba(z))
    lo, hi = X.min(0), X.max(0)
    for b in bodies:
        if b["type"] == "sphere":
            c, r = np.asarray(b["centre"]), b["radius"]
            lo, hi = np.minimum(lo, c - r), np.maximum(hi, c + r)
        elif b["type"] == "pedestal":
            hi[2] = max(hi[2], b.get("centre", (0, 0, 0))[2])
    sxy = float(max(hi[:2] - lo[:2]))
    if hi[2] - lo[2] < 0.25 * sxy:          # (nearly) flat: show some depth below the sheet
        lo[2] = hi[2] - 0.25 * sxy
    for b in bodies:
        for (bx, by, bz) in _body_surfaces(b, float(lo[2])):
            ax.plot_surface(bx, by, bz, color=_BODY, alpha=0.35, linewidth=0, shade=True)
    pc = Poly3DCollection(_polys(mesh, X), facecolors=fc, edgecolors=(0, 0, 0, 0.35),
                          linewidths=_edge_width(mesh) * 0.7)
    ax.add_collection3d(pc)
    span = np.maximum(hi - lo, 1e-3 * sxy)
    ax.set_xlim(lo[0], lo[0] + span[0])
    ax.set_ylim(lo[1], lo[1] + span[1])
    ax.set_zlim(lo[2], lo[2] + span[2])
    ax.set_box_aspect(tuple(span / span.max()))
    ax.view_init(elev=elev, azim=azim)
    ax.set_xlabel("x [cm]")
    ax.set_ylabel("y [cm]")
    ax.set_zlabel("z [cm]")
    ax.tick_params(labelsize=7)
    from matplotlib.ticker import MaxNLocator
    for a in (ax.xaxis, ax.yaxis, ax.zaxis):
        a.set_major_locator(MaxNLocator(5))
    sm.set_array(z)
    cb = fig.colorbar(sm, ax=ax, shrink=0.6, pad=0.14)
    cb.set_label("height z [cm]")


VIEWS = {"top": None, "iso": (30.0, -60.0), "side": None, "side_yz": None}
_VIEW_NAMES = {"top": "top view", "iso": "isometric view", "side": "side view (x-z projection)",
               "side_yz": "side view (y-z projection)"}


def render(path, mesh, U=None, view: str = "iso", title: str | None = None, scene=None,
           subtitle: str | None = None, dpi: int = 130) -> Path:
    """Draw the mesh at X_o + U_o (U (N,6) or None for the undeformed mesh) and write a PNG."""
    from .io import atomic_path

    if view not in VIEWS:
        raise ValueError(f"unknown view {view!r}; known: {', '.join(VIEWS)}")
    plt = _mpl()
    X = mesh.nodes.copy()
    if U is not None:
        X = X + np.asarray(U, float).reshape(-1, 6)[:, :3]
    bodies = _bodies(scene)
    norm = _norm(X[:, 2])
    fig = plt.figure(figsize=(7.0, 6.0))
    try:
        if view == "top":
            ax = fig.add_subplot(111)
            _top(ax, fig, mesh, X, norm, _CMAP, bodies)
        elif view in ("side", "side_yz"):
            ax = fig.add_subplot(111)
            _side(ax, fig, mesh, X, norm, _CMAP, bodies, axis=1 if view == "side_yz" else 0)
        else:
            elev, azim = VIEWS[view]
            ax = fig.add_subplot(111, projection="3d")
            _three_d(ax, fig, mesh, X, norm, _CMAP, bodies, elev, azim)
        head = title or "solidshell"
        sub = f"{_VIEW_NAMES[view]}" + (f" -- {subtitle}" if subtitle else "")
        ax.set_title(f"{head}\n{sub}", fontsize=9.5)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format="png", bbox_inches="tight", pad_inches=0.15)
    finally:
        plt.close(fig)
    return Path(path)
