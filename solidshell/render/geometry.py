"""What a picture shows, independent of the renderer: polygon surfaces in 3-D and an orthographic
camera.

A :class:`Surface` is the deformed sheet (coloured by height z, mesh lines optional) or a rigid
body (one solid colour, tessellated finely enough for a depth-sorting painter).  A
:class:`Camera` is a view direction and an up vector; every picture is an orthographic
(parallel) projection, so a top or side view has true lengths in cm on its axes.  Both
renderers (solidshell.render.vtk_backend, solidshell.render.mpl_backend) take the same surfaces
and camera and draw into the same 2-D screen coordinates ``(p . right, p . up)`` [cm].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Surface:
    """Polygons sharing a point array.

    points : (P,3) [cm];  quads : (M,4) int;  tris : (K,3) int
    scalars: (P,) values mapped through the colour map (the sheet's height), or None
    color  : RGB in [0,1] for a solid body (used when scalars is None)
    edges  : draw the polygon outlines (the mesh)
    solid  : a closed body seen from outside (its back faces may be culled); a sheet is two-sided
    """

    points: np.ndarray
    quads: np.ndarray
    tris: np.ndarray
    scalars: np.ndarray | None = None
    color: tuple = (0.72, 0.72, 0.74)
    edges: bool = False
    solid: bool = False

    def polygons(self):
        """(corner points (n,k,3), cell index into faces) for quads then triangles."""
        out = []
        if len(self.quads):
            out.append(self.points[self.quads])
        if len(self.tris):
            out.append(self.points[self.tris])
        return out


@dataclass(frozen=True)
class Camera:
    """Orthographic camera: ``direction`` from the eye into the scene, ``up`` the screen's up.
    Screen right = direction x up; depth = p . direction (larger is farther)."""

    direction: tuple
    up: tuple

    def frame(self):
        d = np.asarray(self.direction, float)
        d = d / np.linalg.norm(d)
        u = np.asarray(self.up, float)
        u = u - (u @ d) * d
        u = u / np.linalg.norm(u)
        r = np.cross(d, u)
        return r, u, d

    def project(self, P):
        """(screen x, screen y, depth) of points P (...,3) [cm]."""
        r, u, d = self.frame()
        P = np.asarray(P, float)
        return P @ r, P @ u, P @ d


def oblique(elev_deg: float, azim_deg: float) -> Camera:
    """matplotlib's (elev, azim) convention: the eye sits along (cos e cos a, cos e sin a, sin e)."""
    e, a = np.radians(elev_deg), np.radians(azim_deg)
    eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    return Camera(tuple(-eye), (0.0, 0.0, 1.0))


# One camera per view name: the same picture of a figure looks the same in every run.
CAMERAS = {
    "top": Camera((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),  # x right, y up
    "iso": oblique(30.0, -60.0),
    "side": Camera((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),  # looking along +y: x right, z up
    "side_yz": Camera((-1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),  # looking along -x: y right, z up
    "bottom": Camera((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
}


# --------------------------------------------------------------------------- the sheet
def cloth_surface(mesh, X, edges: bool = True) -> Surface:
    """The deformed mid-surface (X = nodal positions (N,3) [cm]) coloured by height z."""
    quads = np.asarray(mesh.quads, int).reshape(-1, 4)
    tris = np.asarray(mesh.tris, int).reshape(-1, 3)
    return Surface(np.asarray(X, float), quads, tris, scalars=np.asarray(X, float)[:, 2], edges=edges)


MARK_COLOR = (0.86, 0.08, 0.08)
"""The red of the elements a picture marks (solidshell.plotting: self-intersecting elements)."""


def split_marked(cloth: Surface, marked) -> list:
    """[cloth without the marked elements, the marked ones in :data:`MARK_COLOR`] -- ``marked`` a
    0/1 per element, quads then triangles (the mesh's element order) -- or [cloth] when none is
    marked.  Two surfaces on the same points and no shared cell: no depth fight between them."""
    m = np.asarray(marked, bool).ravel() if marked is not None else np.zeros(0, bool)
    if not m.any():
        return [cloth]
    nq = len(cloth.quads)
    mq, mt = m[:nq], m[nq : nq + len(cloth.tris)]
    rest = Surface(cloth.points, cloth.quads[~mq], cloth.tris[~mt], scalars=cloth.scalars, edges=cloth.edges)
    red = Surface(cloth.points, cloth.quads[mq], cloth.tris[mt], color=MARK_COLOR, edges=True)
    return [rest, red]


def _grid_quads(nu: int, nv: int, closed_u: bool = False) -> np.ndarray:
    """Quads of a (nv+1) x (nu+1) point grid (row-major, u fastest); closed_u wraps u."""
    i, j = np.meshgrid(np.arange(nv), np.arange(nu), indexing="ij")
    w = nu if closed_u else nu + 1
    a = i * w + j
    b = i * w + (j + 1) % w if closed_u else a + 1
    return np.stack([a, b, b + w, a + w], axis=-1).reshape(-1, 4)


def sphere_surface(centre, radius, n_around: int = 72, n_up: int = 36) -> Surface:
    """A UV sphere; quads outward (counter-clockwise seen from outside)."""
    c = np.asarray(centre, float)
    th = np.linspace(0.0, np.pi, n_up + 1)  # from the south pole up
    ph = np.linspace(0.0, 2 * np.pi, n_around, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing="ij")
    pts = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), -np.cos(T)], -1).reshape(-1, 3)
    q = _grid_quads(n_around, n_up, closed_u=True)
    return Surface(c + radius * pts, q, np.zeros((0, 3), int), solid=True)


def _outline(shape: str, size: float, n: int):
    """Closed outline (n,2) of the pedestal top, counter-clockwise."""
    if shape == "disc":
        t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
        return 0.5 * size * np.stack([np.cos(t), np.sin(t)], -1)
    a = 0.5 * size
    k = max(n // 4, 1)
    s = np.linspace(-a, a, k, endpoint=False)
    return np.concatenate(
        [
            np.stack([s, np.full(k, -a)], -1),
            np.stack([np.full(k, a), s], -1),
            np.stack([-s, np.full(k, a)], -1),
            np.stack([np.full(k, -a), -s], -1),
        ]
    )


def _cap(ring, c_xy, z: float, up: bool = True) -> Surface:
    """A flat face of outline ``ring`` (n,2) about ``c_xy`` at height z: concentric rings and a fan
    (works for a disc and a square), normals up (or down)."""
    n = len(ring)
    rings = [c_xy + f * ring for f in np.linspace(1.0, 0.0, 9)[:-1]]
    pts = np.concatenate([np.column_stack([r_, np.full(n, z)]) for r_ in rings] + [[[c_xy[0], c_xy[1], z]]])
    tq = _grid_quads(n, len(rings) - 1, closed_u=True)  # rings inwards: normals up
    centre_idx = len(pts) - 1
    inner = (len(rings) - 1) * n + np.arange(n)
    tt = np.stack([inner, (inner - inner[0] + 1) % n + inner[0], np.full(n, centre_idx)], -1)
    if not up:
        tq, tt = tq[:, ::-1], tt[:, ::-1]
    return Surface(pts, tq, tt, solid=True)


def _column(c_xy, shape: str, size: float, top: float, bottom: float, cap: bool = True, base: bool = False) -> list:
    """A vertical prism of outline ``shape`` (disc: diameter ``size``; square: side) from ``top``
    down to ``bottom`` [cm]: its side wall, then its top face (``cap``) and underside (``base``).
    Cells no larger than ~1/12 of the outline (the painter sorts polygons by their centroids, which
    needs polygons about the size of the sheet's)."""
    c_xy = np.asarray(c_xy, float)[:2]
    ring = _outline(shape, size, 96)
    n = len(ring)
    nz = max(4, int(np.ceil((top - bottom) / (size / 12.0))))
    zs = np.linspace(top, bottom, nz + 1)
    wall = np.concatenate([np.column_stack([ring + c_xy, np.full(n, z)]) for z in zs])
    out = [Surface(wall, _grid_quads(n, nz, closed_u=True)[:, ::-1], np.zeros((0, 3), int), solid=True)]  # outward
    if cap:
        out.append(_cap(ring, c_xy, top))
    if base:
        out.append(_cap(ring, c_xy, bottom, up=False))
    return out


def _extent(body: dict) -> float:
    return float(body["diameter"] if body.get("shape") == "disc" else body["size"])


def pedestal_surfaces(body: dict, bottom: float | None = None, cap_gap: float = 0.0, cap: bool = True) -> list:
    """The surfaces of a pedestal body dict (Scene.bodies) as it is: a solid column from its top
    face down to ``bottom`` (default: its base, ``height`` below the top), or a Cusick-type
    support's disc (side, top, underside) on its stem; a clamp is a short solid disc.  ``cap_gap``
    lowers the top of the side walls, ``cap`` False leaves the top face out (a sheet covers it)."""
    c = np.asarray(body.get("centre", (0.0, 0.0, 0.0)), float)
    size = _extent(body)
    top = float(c[2])
    if bottom is None:
        bottom = top - float(body.get("height", 10.0))
    if body.get("support") == "cusick":
        t = float(body["disc_thickness"])
        disc = _column(c, "disc", size, top - min(cap_gap, 0.25 * t), top - t, cap=cap, base=True)
        return disc + _column(c, "disc", float(body["stem_diameter"]), top - t, bottom, cap=False)
    return _column(c, body.get("shape", "square"), size, top - cap_gap, bottom, cap=cap)


def covered_top(body: dict, z: float) -> Surface:
    """The part of a sheet lying flat on a pedestal's top (the pedestal scenes mesh only the
    hanging part and clamp its edge there): a flat, cloth-coloured patch at height z."""
    c = np.asarray(body.get("centre", (0.0, 0.0, 0.0)), float)
    cap = _cap(_outline(body.get("shape", "square"), _extent(body), 96), c[:2], z)
    return Surface(cap.points, cap.quads, cap.tris, scalars=np.full(len(cap.points), z), edges=False)


def bodies_of(scene) -> list:
    """The rigid bodies a scene's pictures show: its spheres, pedestals (a Cusick support and
    its clamp included) and mesh bodies (with their ``triangles`` (V, F) added) out of
    ``scene.bodies()``, the same dicts the solvers build their contact bodies from (planes are not
    drawn)."""
    if scene is None:
        return []
    out = [b for b in scene.bodies() if b["type"] in ("sphere", "pedestal", "mesh")]
    for b in out:
        if b["type"] == "mesh":  # its triangles, as the solver's body holds them (contact_mesh)
            from ..scenes.build import contact_body

            body = contact_body(b, scene.base_dir)
            b["triangles"], b["curvature_radius"] = (body.V, body.F), body.curvature_radius
    return out


def scene_surfaces(mesh, X, bodies, mesh_lines: bool = True, cover_pedestal: bool = True, marked=None) -> list:
    """The sheet and the bodies of a picture: [cloth, (its marked elements), (flat cloth on the
    pedestal top), bodies...].  A pedestal is drawn as it is: from its top face down to its base
    (``height``).  ``marked``: 0/1 per element, drawn red (:func:`split_marked`)."""
    out = split_marked(cloth_surface(mesh, X, edges=mesh_lines), marked)
    for b in bodies:
        if b["type"] == "sphere":
            out.append(sphere_surface(b["centre"], b["radius"] - chord_sag(mesh, X, b["radius"])))
        elif b["type"] == "mesh":
            V, F = (np.asarray(a) for a in b["triangles"])
            rho = b.get("curvature_radius")
            if rho:  # drawn smaller by the chord sag, as the sphere is (chord_sag), but by no more
                # than the contact offset: a thin part (a table top) would turn inside out
                V = V - min(chord_sag(mesh, X, rho), float(b.get("offset", 0.0))) * _vertex_normals(V, F)
            out.append(Surface(V.astype(float), np.zeros((0, 4), int), F.astype(int), solid=True))
        elif b["type"] == "pedestal":
            # a pedestal scene meshes only the hanging part; the sheet lies flat on the top (its
            # mid-surface ``offset`` above it), which hides the pedestal's own top.  A clamp sits on
            # the sheet and is drawn whole.
            if cover_pedestal and b.get("role", "support") == "support" and _sheet_around(mesh, X, b):
                top = float(b.get("centre", (0, 0, 0))[2])
                out.append(covered_top(b, top + float(b.get("offset", 0.0))))
                out += pedestal_surfaces(b, cap_gap=0.01 * _extent(b), cap=False)
            else:
                out += pedestal_surfaces(b)
    return out


def _vertex_normals(V, F) -> np.ndarray:
    """(P,3) unit area-weighted vertex normals of a closed outward triangle surface."""
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    out = np.zeros_like(V, dtype=float)
    for k in range(3):
        np.add.at(out, F[:, k], n)
    return out / np.maximum(np.linalg.norm(out, axis=1), 1e-300)[:, None]


def chord_sag(mesh, X, radius: float) -> float:
    """How far a flat element lying on a sphere of ``radius`` dips below the sphere between its
    nodes [cm]: d^2 / (8 R) for its diagonal d (the 90th percentile over the sheet).  Contact acts
    at the nodes, so the drawn sphere is made this much smaller; else it would show through the
    middle of every element resting on it."""
    cells = np.asarray(mesh.quads, int).reshape(-1, 4)
    if not len(cells):
        cells = np.asarray(mesh.tris, int).reshape(-1, 3)[:, [0, 1, 2, 1]]
    if not len(cells):
        return 0.0
    P = np.asarray(X, float)[cells]
    d = np.maximum(np.linalg.norm(P[:, 2] - P[:, 0], axis=1), np.linalg.norm(P[:, 3] - P[:, 1], axis=1))
    return float(np.percentile(d, 90) ** 2 / (8.0 * radius))


def _sheet_around(mesh, X, body) -> bool:
    """True when the undeformed sheet has a hole over the pedestal's top (the pedestal recipes)."""
    c = np.asarray(body.get("centre", (0.0, 0.0, 0.0)), float)
    X0 = np.asarray(mesh.nodes, float)
    r = (
        np.linalg.norm(X0[:, :2] - c[:2], axis=1)
        if body.get("shape") == "disc"
        else np.max(np.abs(X0[:, :2] - c[:2]), axis=1)
    )
    half = 0.5 * (body["diameter"] if body.get("shape") == "disc" else body["size"])
    return bool(len(r)) and float(r.min()) >= half * (1.0 - 1e-6)


def screen_extent(surfaces, camera: Camera, pad: float = 0.04):
    """(xmin, xmax, ymin, ymax) of all surfaces on the screen [cm], padded by ``pad`` of the span."""
    xs, ys = [], []
    for s in surfaces:
        x, y, _ = camera.project(s.points)
        xs.append(x)
        ys.append(y)
    x, y = np.concatenate(xs), np.concatenate(ys)
    span = max(float(x.max() - x.min()), float(y.max() - y.min()), 1e-9)
    p = pad * span
    return float(x.min() - p), float(x.max() + p), float(y.min() - p), float(y.max() + p)
