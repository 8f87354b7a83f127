"""Rigid bodies from triangle meshes: ``[[contact]] type = "mesh"`` (a scanned or CAD body from an
STL/OBJ/PLY file, or one built from primitives with gmsh).

What a mesh body is
-------------------
A closed, consistently oriented triangle surface (every edge shared by exactly two triangles, which
run along it in opposite directions), the boundary of a solid; several such shells are one body
(a table's top and legs).  An inward-oriented surface (negative enclosed volume) is turned outward.
An open surface (a boundary edge), an edge with three or more triangles, or two triangles that
disagree on the orientation is refused with one line naming the file and what is wrong: a signed
distance needs an inside, and a one-sided or thickened open sheet would silently change which side
the cloth may be on.  Close the surface (or give the open shell a thickness in the CAD tool) first.

Distance
--------
The exact signed distance, closest point and normal come from libigl (``igl.signed_distance``: an
AABB tree, the sign from the angle-weighted pseudonormal of the closest feature).  Chosen by a measured
comparison on a 81 920-triangle sphere and 2 x 10^5 points near it (one thread, load ~0.1;
benchmarks/mesh_sdf_libraries.py): libigl pseudonormal 0.34 M points/s, libigl fast winding number
0.22 M/s, trimesh's signed_distance (rtree) 0.010 M/s; the IPC Toolkit (already a dependency) has
point-triangle distances and a broad phase but no closest-point query on a whole mesh.

The solvers do not call libigl per node: a body's signed distance is sampled once, when it is built,
on a regular grid of spacing ``spacing`` in a band |g| <= ``band`` around its surface (outside the
band the samples are clamped to +-band, which keeps the function 1-Lipschitz), and the compiled
kernels interpolate it trilinearly (contact_kernels.grid_distance).  The grid is stored in blocks of
BLOCK^3 cells; a block wholly beyond the band (|g| at its centre minus its half diagonal >= band)
stores nothing.  One function then serves every solver: the explicit loop's kernels, the static
solver, the candidate selection and the start-up checks see the same g, so the static and explicit
solutions are of the same problem.  Its error against the exact distance is at most the interpolation
error, <= spacing^2 / (4 rho) near a smooth face of radius rho (the sphere R = 5 cm at spacing 0.1 cm:
5 um); on a flat face it is exact.

Sharp edges and corners: the trilinear interpolant would round them off by up to ~spacing / 4 (a
sheet pressed on a table's rim sank 0.034 cm, 58 % of the wool's h, into the exact table).  A cell
near the surface where the corners' directions to their closest points spread by more than
SHARP_DEG is therefore an *exact cell* (:func:`exact_cells`): it lists every triangle that can hold
the closest point of a point in it, and the kernels take the exact distance to them there
(contact_kernels.exact_cell).  g is then exact near sharp features, trilinear elsewhere; at the
faces between the two kinds of cells it jumps by at most the trilinear cell's own error (<= ~spacing
x SHARP_DEG / 8).  :meth:`MeshBody.exact_distance` gives libigl's value for checks.

The trilinear interpolant is sqrt(3)-Lipschitz, not 1 (contact_kernels.MESH_LIPSCHITZ): the face
points' skip bound and the explicit solver's candidate selection use that bound (the exact cells'
distance is 1-Lipschitz).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numba import njit

from . import contact_kernels as ck
from .contact import RigidBody, _pos, _vec3, friction_coefficient
from .errors import InputError

UNITS = {"mm": 0.1, "cm": 1.0, "m": 100.0, "in": 2.54}
"""A mesh file's length unit -> the scenes' length unit (cm)."""

MAX_SAMPLES = 40_000_000
"""The most grid samples a body may store (320 MB): a finer spacing is refused with the count."""


def read_surface(path, key: str = "file"):
    """(V (n,3) float, F (m,3) int64) of the triangle surface in ``path`` (anything meshio reads:
    STL, OBJ, PLY, ...; quads are split in two).  InputError naming the file for a missing or
    unreadable file or one without triangles."""
    import meshio

    p = Path(path)
    if not p.is_file():
        raise InputError(f"{key}: mesh file {str(p)!r} not found")
    try:
        m = meshio.read(p)
    except Exception as exc:  # meshio raises many kinds (ReadError, ValueError, KeyError, ...)
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"{key}: cannot read mesh file {str(p)!r}: {msg}") from None
    tris = []
    for block in m.cells:
        c = np.asarray(block.data, dtype=np.int64)
        if block.type == "triangle":
            tris.append(c)
        elif block.type == "quad":
            tris += [c[:, [0, 1, 2]], c[:, [0, 2, 3]]]
    if not tris:
        raise InputError(f"{key}: mesh file {str(p)!r} has no triangles or quads")
    return np.asarray(m.points, dtype=float)[:, :3], np.concatenate(tris)


def merge_vertices(V, F, tol: float):
    """Vertices closer than ``tol`` merged (an STL stores each triangle's corners apart), unused ones
    dropped, triangles that collapse removed: (V, F)."""
    key = np.round(np.asarray(V, float) / tol).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    F = inv.ravel()[F]
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])]
    used, Fc = np.unique(F, return_inverse=True)
    return np.asarray(V, float)[first][used], Fc.reshape(-1, 3).astype(np.int64)


def check_closed(F, where: str) -> None:
    """InputError unless every edge of F is shared by exactly two triangles running along it in
    opposite directions (closed, edge-manifold, consistently oriented)."""
    F = np.asarray(F, dtype=np.int64)
    d = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])  # directed edges
    u = np.sort(d, axis=1)
    _, cnt = np.unique(u, axis=0, return_counts=True)
    if np.any(cnt > 2):
        raise InputError(
            f"{where}: the body is not manifold: {int(np.sum(cnt > 2))} edge(s) shared by 3 or more triangles"
        )
    if np.any(cnt == 1):
        raise InputError(
            f"{where}: the body's surface is open ({int(np.sum(cnt == 1))} boundary edge(s)); a mesh body must "
            "be closed (the boundary of a solid)"
        )
    _, dcnt = np.unique(d, axis=0, return_counts=True)
    if np.any(dcnt > 1):
        raise InputError(
            f"{where}: the body's triangles are not consistently oriented ({int(np.sum(dcnt > 1))} edge(s) "
            "run the same way in both of their triangles)"
        )


def volume(V, F) -> float:
    """The signed volume the closed surface encloses (positive when its normals point outward)."""
    a, b, c = (np.asarray(V, float)[F[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def transform(V, scale: float = 1.0, rotate=(0.0, 0.0, 0.0), translate=(0.0, 0.0, 0.0)):
    """V scaled about the origin, turned by the angles ``rotate`` [degrees] about the fixed x, y and
    z axes in that order, then moved by ``translate``."""
    from scipy.spatial.transform import Rotation

    R = Rotation.from_euler("xyz", np.asarray(rotate, float), degrees=True).as_matrix()
    return (float(scale) * np.asarray(V, float)) @ R.T + np.asarray(translate, float)


def curvature_radius(V, F, sharp_deg: float = 30.0) -> float | None:
    """An estimate of the radius of the surface's most curved smooth part [length]: over the edges
    whose triangles turn by less than ``sharp_deg`` (sharper edges are edges, not curvature), the
    distance between the two triangles' centroids over the turn angle; the 10th percentile (the
    estimate scatters by ~10 % on a gmsh sphere, and a few badly shaped triangles must not set it).  None when the surface is flat between its sharp edges."""
    F = np.asarray(F, np.int64)
    a, b, c = (np.asarray(V, float)[F[:, i]] for i in range(3))
    nrm = np.cross(b - a, c - a)
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1), 1e-300)[:, None]
    cen = (a + b + c) / 3.0
    d = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    tri = np.tile(np.arange(len(F)), 3)
    order = np.lexsort((d[:, 1], d[:, 0]))
    d, tri = d[order], tri[order]
    pair = np.flatnonzero(np.all(d[1:] == d[:-1], axis=1))
    t0, t1 = tri[pair], tri[pair + 1]
    ang = np.arccos(np.clip(np.einsum("ij,ij->i", nrm[t0], nrm[t1]), -1.0, 1.0))
    smooth = (ang > 1e-6) & (ang < math.radians(sharp_deg))
    if not np.any(smooth):
        return None
    rho = np.linalg.norm(cen[t0] - cen[t1], axis=1)[smooth] / ang[smooth]
    return float(np.percentile(rho, 10.0))


def exact_signed_distance(V, F, x):
    """(g (N,), closest points (N,3), outward unit normals (N,3)) of the points x from libigl (the
    sign by the pseudonormal; the normal (x - c)/|x - c| times the sign, the closest face's normal
    on the surface itself)."""
    import igl

    x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
    g, _, c, n = igl.signed_distance(
        x, np.ascontiguousarray(V, float), np.ascontiguousarray(F, np.int64), igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL
    )[:4]
    d = (x - c) * np.where(g < 0.0, -1.0, 1.0)[:, None]  # outward from the closest point
    L = np.linalg.norm(d, axis=1)
    on = L <= 1e-12 * (1.0 + np.abs(x).max(axis=1))  # on the surface: the pseudonormal
    nn = np.where(on[:, None], n, d / np.where(on, 1.0, L)[:, None])
    return np.asarray(g, float), np.asarray(c, float), nn


SHARP_DEG = 5.0
"""A grid cell near the surface whose corners' directions to their closest points spread by more than
this angle (over the cell's diagonal) is an exact cell (:func:`build_grid`): the trilinear interpolant
there would round an edge or a corner off by up to ~spacing / 4; below it its error is at most
~spacing x angle / 8 (spacing 0.2 cm: 2e-3 cm), as on a smooth face of radius spacing / angle."""


def pseudonormals(V, F):
    """(face unit normals (m,3), edge pseudonormals (m,3,3) of the edges ab, bc, ca, corner
    pseudonormals (m,3,3) of a, b, c) of the closed surface (V, F): an edge's the sum of its two faces'
    unit normals, a vertex's the sum of its faces' unit normals weighted by their angles there
    (Baerentzen & Aanaes 2005; the sign of x - closest point against the closest feature's
    pseudonormal is the sign of the distance)."""
    F = np.asarray(F, np.int64)
    P = np.asarray(V, float)[F]  # (m, 3 corners, 3)
    nf = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    nf /= np.maximum(np.linalg.norm(nf, axis=1), 1e-300)[:, None]
    e = np.sort(np.stack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1).reshape(-1, 2), axis=1)
    _, inv = np.unique(e, axis=0, return_inverse=True)
    inv = inv.ravel()
    es = np.zeros((inv.max() + 1, 3))
    np.add.at(es, inv, np.repeat(nf, 3, axis=0))
    vn = np.zeros((len(V), 3))
    for i in range(3):  # the angle at corner i
        u, w = P[:, (i + 1) % 3] - P[:, i], P[:, (i + 2) % 3] - P[:, i]
        cos = np.einsum("ij,ij->i", u, w) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1), 1e-300)
        np.add.at(vn, F[:, i], np.arccos(np.clip(cos, -1.0, 1.0))[:, None] * nf)
    return nf, es[inv].reshape(-1, 3, 3), vn[F]


@njit(cache=True)
def _pair_distances(rec, tri, pts, which):
    """Distances of the points pts[which[j]] to the triangles tri[j] (records ``rec`` (m, TRI))."""
    out = np.empty(tri.size)
    for j in range(tri.size):
        x = pts[which[j]]
        out[j] = math.sqrt(ck.closest_on_triangle(rec[tri[j]], x[0], x[1], x[2])[0])
    return out


def exact_cells(V, F, lo, h, ib_kept, S, N, band):
    """The exact section of the grid (contact_kernels.grid_distance, exact_cell) for the kept
    blocks ``ib_kept`` (n, 3) with samples S (n, 9, 9, 9) and directions to their closest points N
    (n, 9, 9, 9, 3): (the blocks that hold exact cells, the section as a float array whose offsets
    count from the grid's start: a function of where it will start, ``section(base)`` -> (floats,
    offset of the triangle records); number of exact cells).

    A cell is exact when it comes near the surface (its smallest |corner sample| below (1 + sqrt 3)
    spacing: every point of it within one spacing of the surface is in such a cell) and its corners'
    directions spread by more than SHARP_DEG.  Its triangles: every triangle within d(c) + 2 r of the
    cell's centre c (r its half diagonal, d(c) the exact distance there) -- the closest point of any
    point x of the cell lies within d(x) + r <= d(c) + 2 r of c, so its triangle is among them."""
    B = ck.BLOCK
    n = len(ib_kept)
    sl = [
        (slice(None), slice(a, a + B), slice(b, b + B), slice(c, c + B)) for a in (0, 1) for b in (0, 1) for c in (0, 1)
    ]
    amin = np.min([np.abs(S[t]) for t in sl], axis=0)  # (n, 8, 8, 8)
    m = np.sum([N[t] for t in sl], axis=0)
    m /= np.maximum(np.linalg.norm(m, axis=-1), 1e-300)[..., None]
    cmin = np.min([np.einsum("...i,...i->...", N[t], m) for t in sl], axis=0)
    flag = (amin < (1.0 + math.sqrt(3.0)) * h) & (cmin < math.cos(math.radians(0.5 * SHARP_DEG)))
    kk, li, lj, lk = np.nonzero(flag)
    if not len(kk):
        return np.zeros(0, np.int64), None, 0
    loc = np.column_stack([li, lj, lk])
    centres = lo + (ib_kept[kk] * B + loc + 0.5) * h
    dc = np.abs(exact_signed_distance(V, F, centres)[0])
    R = dc + math.sqrt(3.0) * h  # d(c) + 2 r
    nf, ne, nv = pseudonormals(V, F)
    P = V[F]
    rec = np.ascontiguousarray(np.concatenate([P.reshape(-1, 9), nf, ne.reshape(-1, 9), nv.reshape(-1, 9)], axis=1))
    cen = P.mean(axis=1)
    rmax = float(np.max(np.linalg.norm(P - cen[:, None], axis=-1)))
    from scipy.spatial import cKDTree

    hits = cKDTree(cen).query_ball_point(centres, R + rmax, return_sorted=True)
    cnt = np.fromiter((len(x) for x in hits), np.int64, len(hits))
    tri = np.fromiter((t for x in hits for t in x), np.int64, int(cnt.sum()))
    which = np.repeat(np.arange(len(hits)), cnt)
    keep = _pair_distances(rec, tri, centres, which) <= R[which] * (1.0 + 1e-12) + 1e-12
    tri, which = tri[keep], which[keep]
    cnt = np.bincount(which, minlength=len(hits))
    used, tri_local = np.unique(tri, return_inverse=True)
    blocks = np.unique(kk)
    bpos = np.full(n, -1, np.int64)
    bpos[blocks] = np.arange(len(blocks))
    ncell = B**3

    def section(base: int):
        """(the section's floats, where its triangle records start), offsets counted from the grid's
        start given that the section starts at ``base``."""
        ct0 = base + n  # the cell tables
        lists0 = ct0 + len(blocks) * ncell
        lstart = lists0 + np.concatenate([[0], np.cumsum(cnt + 1)[:-1]])
        per_block = np.where(bpos >= 0, ct0 + bpos * ncell, -1).astype(float)
        cells = np.full(len(blocks) * ncell, -1.0)
        cells[bpos[kk] * ncell + (li * B + lj) * B + lk] = lstart
        lists = np.empty(int(cnt.sum()) + len(cnt))
        heads = lstart - lists0
        lists[heads] = cnt
        body = np.ones(len(lists), bool)
        body[heads] = False
        lists[body] = tri_local  # (sorted by cell: which is)
        return np.concatenate([per_block, cells, lists, rec[used].ravel()]), lists0 + lists.size

    return blocks, section, len(kk)


def build_grid(V, F, spacing: float, band: float, where: str = "mesh body"):
    """The narrow-band grid of the body (V, F) as one float array in contact_kernels.grid_distance's
    layout (start 0), its parameter row (contact_kernels.PARAMS), the number of blocks kept, the
    exact distances at the blocks' centres (nbx, nby, nbz; MeshBody.signed_distance's far bound) and
    the number of exact cells (:func:`exact_cells`).  The box is the body's bounding box grown by
    band plus one block on every side (so that the grid's outer samples are all +band), rounded up to
    whole blocks about the same centre."""
    B = ck.BLOCK
    h = float(spacing)
    lo = V.min(axis=0) - band - B * h
    hi = V.max(axis=0) + band + B * h
    nb = np.ceil((hi - lo) / (B * h)).astype(np.int64)
    # centred on the body's box: a body symmetric about its centre (a mirror, a quarter turn when
    # the extents are equal) gets samples and an interpolant with the same symmetry
    lo = 0.5 * (lo + hi) - 0.5 * nb * B * h
    # the blocks' centres: a block is kept when its centre's |g| minus its half diagonal is below band
    ib = np.stack(np.meshgrid(*(np.arange(n) for n in nb), indexing="ij"), axis=-1).reshape(-1, 3)
    centres = lo + (ib + 0.5) * B * h
    gc = exact_signed_distance(V, F, centres)[0]
    half = 0.5 * math.sqrt(3.0) * B * h
    near = np.abs(gc) - half < band
    table = np.where(gc >= 0.0, ck.FAR_OUT, ck.FAR_IN)
    kept = np.flatnonzero(near)
    m = B + 1
    n_samples = len(kept) * m**3
    if n_samples > MAX_SAMPLES:
        raise InputError(
            f"{where}: the grid at spacing {h:g} would store {n_samples:.3g} samples (at most {MAX_SAMPLES:.0e}); "
            "give a larger spacing"
        )
    table[kept] = np.arange(len(kept))
    loc = np.stack(np.meshgrid(*(np.arange(m),) * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    pts = (lo + (ib[kept][:, None, :] * B + loc[None]) * h).reshape(-1, 3)
    if len(pts):
        g, _, nrm = exact_signed_distance(V, F, pts)
        samples = np.clip(g, -band, band)
        blocks, section, n_exact = exact_cells(
            V, F, lo, h, ib[kept], samples.reshape(-1, m, m, m), nrm.reshape(-1, m, m, m, 3), band
        )
    else:
        samples, blocks, section, n_exact = np.zeros(0), np.zeros(0, np.int64), None, 0
    table[kept[blocks]] = -3.0 - blocks  # blocks with exact cells (contact_kernels.grid_distance)
    head = ck.HEADER + 2 * table.size + samples.size
    grid = np.concatenate([[band, 0.0, 0.0], table.astype(float), gc, samples])
    if section is not None:
        extra, rec_at = section(head)
        grid[1], grid[2] = head, rec_at
        grid = np.concatenate([grid, extra])
    params = np.zeros(ck.PARAMS)
    params[:8] = (*lo, h, *nb, 0.0)
    return grid, params, len(kept), gc.reshape(*nb), n_exact


def _geometry(V, F, spacing, band, where: str) -> dict:
    """The checked, outward surface of a body and its distance grid (MeshBody's docstring)."""
    V = np.asarray(V, dtype=float).reshape(-1, 3)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    if not len(F) or not np.all(np.isfinite(V)):
        raise InputError(f"{where}: the body has no triangles or non-finite vertex coordinates")
    diag = float(np.linalg.norm(np.ptp(V, axis=0)))
    V, F = merge_vertices(V, F, 1e-9 * diag)
    check_closed(F, where)
    vol = volume(V, F)
    if vol == 0.0:
        raise InputError(f"{where}: the body encloses no volume")
    if vol < 0.0:
        F = F[:, ::-1].copy()  # turned inward: turn it outward
    if spacing is None:
        e = np.linalg.norm(V[F] - V[np.roll(F, -1, axis=1)], axis=-1)
        spacing = float(np.clip(np.median(e), diag / 400.0, diag / 50.0))
    spacing = _pos(spacing, f"{where}: spacing")
    band = _pos(band, f"{where}: band") if band is not None else 8.0 * spacing
    V, F = np.ascontiguousarray(V), np.ascontiguousarray(F)
    built = _cached_grid(V, F, spacing, band, where)
    grid, params, n_blocks, coarse, n_exact = built
    rho = curvature_radius(V, F)
    return dict(
        V=V,
        F=F,
        spacing=spacing,
        band=band,
        grid=grid,
        params=params,
        n_blocks=n_blocks,
        rho=rho,
        coarse=coarse,
        n_exact=n_exact,
    )


GRID_FORMAT = 2
"""The grid layout's version (contact_kernels.grid_distance; 2: with exact cells): part of the disk
cache's key, so a cached grid of another layout is never read."""


def grid_cache_dir() -> Path | None:
    """Where built grids are kept between runs: $SOLIDSHELL_GRID_CACHE, else
    $XDG_CACHE_HOME/solidshell/mesh_grids (~/.cache/...); None when $SOLIDSHELL_GRID_CACHE is "off"."""
    import os

    env = os.environ.get("SOLIDSHELL_GRID_CACHE")
    if env is not None:
        return None if env.strip().lower() in ("", "off", "0", "no") else Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "solidshell" / "mesh_grids"


def _cached_grid(V, F, spacing: float, band: float, where: str):
    """build_grid's result for the surface (V, F), from the disk cache when it holds one.  The key is
    the SHA-256 of the final (merged, outward) vertices and triangles and of spacing, band,
    SHARP_DEG and GRID_FORMAT, so a changed file, transform or parameter builds anew.  The cache is a
    convenience: an unreadable entry is rebuilt and a failed write is skipped (the run needs neither);
    entries are written to a temporary name and renamed, so concurrent runs never read half a file."""
    import hashlib
    import os

    where_dir = grid_cache_dir()
    if where_dir is None:
        return build_grid(V, F, spacing, band, where)
    h = hashlib.sha256()
    for a in (V, F, np.array([spacing, band, SHARP_DEG, GRID_FORMAT], float)):
        h.update(np.ascontiguousarray(a).tobytes())
    path = where_dir / f"{h.hexdigest()}.npz"
    try:
        with np.load(path) as z:
            return z["grid"], z["params"], int(z["n_blocks"]), z["coarse"], int(z["n_exact"])
    except (OSError, KeyError, ValueError):
        pass
    built = build_grid(V, F, spacing, band, where)
    try:
        where_dir.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.stem}.{os.getpid()}.npz")
        np.savez(tmp, grid=built[0], params=built[1], n_blocks=built[2], coarse=built[3], n_exact=built[4])
        os.replace(tmp, path)
    except OSError:
        pass
    return built


class MeshBody(RigidBody):
    """A rigid solid bounded by the closed triangle surface (V, F) (module docstring); scenes build
    theirs with :func:`mesh_body`.

    spacing : the distance grid's spacing [length] (default: the surface's median edge length, at
        least 1/400 and at most 1/50 of its bounding box's diagonal);
    band : how far from the surface the grid holds the distance [length] (default 8 spacings);
        it must exceed the contact offset (contact reaches no farther than the band);
    where : how errors name the body ("contact[0]: file 'x.stl'").
    """

    lipschitz = ck.MESH_LIPSCHITZ  # trilinear interpolation of a 1-Lipschitz function's samples

    def __init__(self, V, F, spacing=None, band=None, offset=0.0, friction=0.0, where="mesh body", source=""):
        self.where, self.source = where, source
        self.offset = _pos(offset, "contact offset", allow_zero=True)
        self.friction = friction_coefficient(friction)
        self.code = ck.MESH
        self._set_geometry(_geometry(V, F, spacing, band, where))
        if self.band <= self.offset:
            raise InputError(f"{where}: band ({self.band:g}) must exceed the contact offset ({self.offset:g})")

    def _set_geometry(self, geo: dict) -> None:
        self.V, self.F = geo["V"], geo["F"]
        self.spacing, self.band = geo["spacing"], geo["band"]
        self.grid, self._params, self.n_blocks, self._rho = geo["grid"], geo["params"], geo["n_blocks"], geo["rho"]
        self._coarse, self._lo, self._hi = geo["coarse"], self.V.min(axis=0), self.V.max(axis=0)
        self.n_exact = geo["n_exact"]  # grid cells evaluated from the triangles (build_grid)

    @property
    def params(self) -> np.ndarray:
        return self._params.copy()

    @property
    def curvature_radius(self) -> float | None:
        return self._rho

    @property
    def n_triangles(self) -> int:
        return len(self.F)

    def signed_distance(self, x: np.ndarray):
        """(g, n) as the kernels see them (contact_kernels.grid_distance) wherever they see the
        body (|g| < band); beyond the band, where the grid holds +band, max(band, LB - sqrt(3)
        spacing) instead, LB a lower bound of the exact distance: g(c) - |x - c| with c the centre of
        x's block (its exact distance is stored), or outside the grid the distance to the body's
        bounding box.  The kernels' g at any y is at least min(band, g_exact(y) - sqrt(3) spacing) (a
        cell's trilinear value is at least its smallest corner sample, each within sqrt(3) spacing
        of y), and g is sqrt(3)-Lipschitz, so this keeps the explicit solver's candidate selection (a
        node is left out while its gap exceeds the margin and it has moved less than margin /
        lipschitz) exact and lets it leave out the nodes far from the body instead of seeing them
        all at the band; no exact query per call (libigl builds its tree on every call)."""
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        g, n = ck.distances(self.code, self._params, x, self.grid)
        far = g >= self.band
        if np.any(far):
            xf = x[far]
            B, h = ck.BLOCK, self.spacing
            lo = self._params[:3]
            nb = np.array(self._coarse.shape)
            ib = np.floor((xf - lo) / (B * h)).astype(np.int64)
            inside = np.all((ib >= 0) & (ib < nb), axis=1)
            c = lo + (np.clip(ib, 0, nb - 1) + 0.5) * B * h
            gc = self._coarse[tuple(np.clip(ib, 0, nb - 1).T)]
            d = xf - c
            box = np.linalg.norm(np.maximum(np.maximum(self._lo - xf, xf - self._hi), 0.0), axis=1)
            lb = np.where(inside, gc - np.linalg.norm(d, axis=1), box)
            g[far] = np.maximum(self.band, lb - ck.MESH_LIPSCHITZ * h)
            L = np.linalg.norm(d, axis=1)
            n[far] = d / np.where(L > 0.0, L, 1.0)[:, None]  # (no force acts here: any unit vector)
        return g, n

    def exact_penetration(self, x):
        """(gap (N,), normal (N,3)) as :meth:`penetration`, with libigl's exact distance where the
        grid sees the body (|g| < band): the augmented-Lagrangian updates (contact_augment.py) measure
        the raw penetration with it, so that their shifts take up the grid's interpolation error too
        (~spacing^2 / (4 rho) on a face of radius rho, ~spacing / 4 at a sharp edge, where the
        trilinear distance rounds the edge off and a sheet pressed on it sinks in)."""
        x = np.ascontiguousarray(x, dtype=float).reshape(-1, 3)
        g, n = self.signed_distance(x)
        near = np.abs(g) < self.band
        if np.any(near):
            g[near], n[near] = self.exact_distance(x[near])
        return g - self.offset, n

    def exact_distance(self, x):
        """(g (N,), outward unit normals (N,3)) of the points x (N,3) from libigl, not the grid."""
        g, _, n = exact_signed_distance(self.V, self.F, x)
        return g, n

    def __repr__(self):
        return (
            f"MeshBody({self.source or self.where}, {len(self.F)} triangles, spacing={self.spacing:g}, "
            f"band={self.band:g}, offset={self.offset}, friction={self.friction})"
        )


def pack_grid(bodies, params) -> np.ndarray | None:
    """The shared grid array of the MESH bodies among ``bodies`` (their grids one after the other),
    their rows of ``params`` (n_bodies, PARAMS) pointed at their start in it (in place); None when no
    body is a MESH (the kernels then compile without the MESH branch)."""
    parts, start = [], 0
    for b, body in enumerate(bodies):
        if getattr(body, "code", -1) == ck.MESH:
            params[b, 7] = start
            parts.append(body.grid)
            start += body.grid.size
    return np.concatenate(parts) if parts else None


def mesh_body(
    file=None,
    primitives=None,
    units: str = "cm",
    scale: float = 1.0,
    rotate=(0.0, 0.0, 0.0),
    translate=(0.0, 0.0, 0.0),
    mesh_size=None,
    spacing=None,
    band=None,
    where: str = "mesh body",
    base_dir=None,
    **kw,
) -> MeshBody:
    """A MeshBody from a file (relative to ``base_dir``) or from gmsh primitives
    (contact_shapes.surface), in ``units`` times ``scale``, turned by ``rotate`` [degrees about x, y,
    z], moved by ``translate`` [cm]; ``spacing``, ``band``: the grid's (MeshBody); ``kw``: offset,
    friction.  Built geometries are kept (a few, by source and transform): a run builds its bodies
    more than once (checks, problem, pictures)."""
    if units not in UNITS:
        raise InputError(f"{where}.units: unknown unit {units!r}; known: {', '.join(UNITS)}")
    if (file is None) == (primitives is None):
        raise InputError(f"{where}: give a mesh body either file or primitives")
    if file is not None:
        p = Path(file)
        if base_dir is not None and not p.is_absolute():
            p = Path(base_dir) / p
        where = f"{where}.file ({str(p)!r})"
        stat = p.stat() if p.is_file() else None
        key: tuple = (str(p.resolve()), stat.st_mtime_ns if stat else None, stat.st_size if stat else None)
        source = str(file)
    else:
        key = (repr(primitives), mesh_size)
        where = f"{where}.primitives"
        source = f"{len(primitives)} primitive(s)"
    s = _pos(scale, f"{where}: scale") * UNITS[units]
    rot, tr = _vec3(rotate, "rotate"), _vec3(translate, "translate")
    key += (s, tuple(rot), tuple(tr), spacing, band)
    geo = _CACHE.get(key)
    if geo is None:
        if file is not None:
            V, F = read_surface(p, where)
        else:
            from .contact_shapes import surface

            V, F = surface(primitives, mesh_size, where)
        geo = _geometry(transform(V, s, rot, tr), F, spacing, band, where)
        if len(_CACHE) >= 8:  # a few bodies per process (a run builds its bodies more than once)
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = geo
    body = MeshBody.__new__(MeshBody)
    body.where, body.source = where, source
    body.offset = _pos(kw.get("offset", 0.0), "contact offset", allow_zero=True)
    body.friction = friction_coefficient(kw.get("friction", 0.0))
    body.code = ck.MESH
    body._set_geometry(geo)
    if body.band <= body.offset:
        raise InputError(f"{where}: band ({body.band:g}) must exceed the contact offset ({body.offset:g})")
    return body


_CACHE: dict = {}
"""Built geometries by (source, transform, spacing, band): the grid is the expensive part."""
