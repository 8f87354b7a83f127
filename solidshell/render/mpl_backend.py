"""Fallback renderer (matplotlib only): a painter's algorithm over ALL polygons of a picture.

The sheet and the rigid bodies go into one list, projected by the orthographic camera, and are
drawn farthest first as one 2-D PolyCollection; back faces of closed bodies are culled.  This is
what matplotlib's own 3-D axes cannot do: it sorts each collection on its own and then stacks
the collections, so a sphere drawn as a separate surface is painted over the cloth lying on it.
Sorting by centroid depth is exact for the non-intersecting, similarly sized polygons of a drape
picture (the bodies are tessellated to the sheet's element size by solidshell.render.geometry).
"""

from __future__ import annotations

import numpy as np

from .geometry import Camera


def _light_dir(camera: Camera):
    """A light above-left of the eye (unit vector towards the light)."""
    r, u, d = camera.frame()
    L = -d + 0.55 * u - 0.35 * r
    return L / np.linalg.norm(L)


def shade(normals, light, two_sided: bool, ambient: float = 0.38):
    """Lambert factor in [ambient, 1] per face (normals unit (n,3))."""
    c = normals @ light
    c = np.abs(c) if two_sided else np.clip(c, 0.0, None)
    return ambient + (1.0 - ambient) * c


def _normals(P):
    """Unit normals of polygons P (n,k,3): a quad's from its diagonals, a triangle's from its edges."""
    if P.shape[1] == 4:
        n = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])
    else:
        n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    return n / np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]


def draw(ax, surfaces, camera: Camera, norm, cmap, edge_width: float = 0.3, zorder: float = 2.0):
    """Draw ``surfaces`` (solidshell.render.geometry.Surface) into the 2-D axes ``ax`` in screen
    coordinates [cm]; returns the PolyCollection."""
    import matplotlib as mpl
    from matplotlib.collections import PolyCollection

    cmap = mpl.colormaps[cmap] if isinstance(cmap, str) else cmap
    r, u, d = camera.frame()
    light = _light_dir(camera)
    polys, depth, faces, edges, widths = [], [], [], [], []
    for s in surfaces:
        for cells in (s.quads, s.tris):
            if not len(cells):
                continue
            P = s.points[cells]
            n = _normals(P)
            keep = np.ones(len(P), bool)
            if s.solid:
                keep = (n @ d) < 1e-9  # outward normal towards the eye
            P, n, cells_k = P[keep], n[keep], cells[keep]
            if not len(P):
                continue
            f = shade(n, light, two_sided=not s.solid)
            if s.scalars is not None:
                rgba = cmap(norm(s.scalars[cells_k].mean(axis=1)))
            else:
                rgba = np.tile(np.r_[s.color, 1.0], (len(P), 1))
            rgba[:, :3] *= f[:, None]
            if s.edges:
                e = np.tile([0.0, 0.0, 0.0, 0.45], (len(P), 1))
                w = np.full(len(P), edge_width)
            else:  # seal the seams between neighbouring polygons
                e = rgba.copy()
                w = np.full(len(P), 0.25)
            polys.extend(np.stack([P @ r, P @ u], axis=-1))
            depth.append((P @ d).mean(axis=1))
            faces.append(rgba)
            edges.append(e)
            widths.append(w)
    if not polys:
        return None
    order = np.argsort(-np.concatenate(depth), kind="stable")  # farthest first
    fc = np.concatenate(faces)[order]
    ec = np.concatenate(edges)[order]
    lw = np.concatenate(widths)[order]
    pc = PolyCollection(
        [polys[i] for i in order], facecolors=fc, edgecolors=ec, linewidths=lw, zorder=zorder, antialiaseds=True
    )
    ax.add_collection(pc)
    return pc
