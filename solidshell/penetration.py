"""How deep the sheet lies inside its rigid contact bodies: the contact contract, measured.

The contract (docs: DESIGN "Contact"): no node and no point of an element's contact face lies
inside a body deeper than ``contact.PENETRATION_TOL * h`` (h: the sheet's thickness).  A body's
``penetration(x)`` gives gap = g(x) - offset (g: signed distance, positive outside; offset: how far
the sheet's lower face lies below its mid-surface), so the penetration of a mid-surface point x is
p = -gap = offset - g(x).

Face points (the mid-surface x = X + U_o, interpolated by each element's shape functions):

* quad: an ``grid`` x ``grid`` lattice xi, eta in linspace(-1, 1, grid) (bilinear N_a);
* triangle: the barycentric lattice of order ``grid - 1`` ((grid (grid + 1)) / 2 points: 15 for 5).

Both include the element's corners (the nodes) and its edges, so a face-point count is never
smaller than what the nodes of that element show.  Everything is numpy over all elements at once
(chunked to bound memory); :func:`check` is what ``summary.json``'s ``"penetration"`` reports and
``verification/penetration_check.py`` recomputes from the written files with its own geometry.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .contact import PENETRATION_TOL
from .contact_faces import shapes
from .errors import InputError

DEFAULT_GRID = 5
"""Face points per element edge (5: a 5 x 5 grid per quad, 15 points per triangle)."""

_CHUNK = 1 << 18  # face points evaluated per body call (~6 MB of coordinates)


def _grid(grid) -> int:
    if isinstance(grid, bool) or not isinstance(grid, (int, np.integer)) or int(grid) < 2:
        raise InputError(f"face-point grid must be an integer >= 2 (points per element edge), got {grid!r}")
    return int(grid)


def quad_shape(grid: int = DEFAULT_GRID) -> np.ndarray:
    """(grid^2, 4) bilinear shape functions at xi, eta in linspace(-1, 1, grid), corners
    (-1,-1), (1,-1), (1,1), (-1,1) (the mesh's counter-clockwise order)."""
    s = np.linspace(-1.0, 1.0, _grid(grid))
    return shapes(False, np.column_stack([a.ravel() for a in np.meshgrid(s, s, indexing="ij")]))


def tri_shape(grid: int = DEFAULT_GRID) -> np.ndarray:
    """(grid (grid + 1) / 2, 3) barycentric coordinates of the order-(grid - 1) lattice."""
    m = _grid(grid) - 1
    i, j = np.meshgrid(np.arange(m + 1), np.arange(m + 1), indexing="ij")
    keep = (i + j) <= m
    return shapes(True, np.column_stack([i[keep], j[keep]]) / m)[:, :3]


def face_points(mesh, U=None, grid: int = DEFAULT_GRID) -> np.ndarray:
    """(n_quads * grid^2 + n_tris * grid (grid + 1) / 2, 3) the face points of every element on the
    deformed mid-surface X + U[:, :3] (quads first, element by element)."""
    x = np.asarray(mesh.nodes, float)
    if U is not None:
        x = x + np.asarray(U, float).reshape(len(x), 6)[:, :3]
    out = []
    if len(mesh.quads):
        out.append(np.einsum("qa,eak->eqk", quad_shape(grid), x[mesh.quads]).reshape(-1, 3))
    if len(mesh.tris):
        out.append(np.einsum("qa,eak->eqk", tri_shape(grid), x[mesh.tris]).reshape(-1, 3))
    return np.concatenate(out) if out else np.zeros((0, 3))


def _depths(body, x: np.ndarray) -> np.ndarray:
    """p = offset - g(x) of the points x (chunked); a mesh body's g is its exact distance to its
    triangles (contact_mesh.MeshBody.exact_distance), not the grid the solvers interpolate: the
    contract is about the body itself, so the grid's error counts."""
    if len(x) == 0:
        return np.zeros(0)
    exact = getattr(body, "exact_distance", None)
    if exact is not None:
        return np.concatenate([body.offset - exact(x[i : i + _CHUNK])[0] for i in range(0, len(x), _CHUNK)])
    return np.concatenate([-body.penetration(x[i : i + _CHUNK])[0] for i in range(0, len(x), _CHUNK)])


def check(mesh, U, bodies: Sequence, h: float, grid: int = DEFAULT_GRID, tol: float | None = None) -> list[dict]:
    """Per body: {"deepest_node_cm", "nodes_beyond", "deepest_face_point_cm", "face_points_beyond"}.

    mesh : ShellMesh;  U : (N,6) state;  bodies : solidshell.contact bodies (anything with
    ``penetration(x) -> (gap, normal)``);  h : the sheet's thickness [length];  tol : the depth
    [length] still allowed (default ``PENETRATION_TOL * h``).  A point is *beyond* when its
    penetration p = offset - g(x) exceeds tol.  The deepest values are max(0, max p): 0 when
    nothing touches.  Lengths in the mesh's unit (cm for the scenes)."""
    h = float(h)
    if not np.isfinite(h) or h <= 0.0:
        raise InputError(f"sheet thickness h must be a positive number, got {h!r}")
    tol = PENETRATION_TOL * h if tol is None else float(tol)
    U = np.asarray(U, float).reshape(mesh.n_nodes, 6)
    x_nodes = np.asarray(mesh.nodes, float) + U[:, :3]
    x_faces = face_points(mesh, U, grid)
    out = []
    for b in bodies:
        pn, pf = _depths(b, x_nodes), _depths(b, x_faces)
        out.append(
            {
                "deepest_node_cm": float(max(0.0, pn.max(initial=0.0))),
                "nodes_beyond": int(np.count_nonzero(pn > tol)),
                "deepest_face_point_cm": float(max(0.0, pf.max(initial=0.0))),
                "face_points_beyond": int(np.count_nonzero(pf > tol)),
            }
        )
    return out


def report(mesh, U, bodies: Sequence, tables: Sequence[dict], h: float, grid: int = DEFAULT_GRID) -> dict:
    """summary.json's ``"penetration"`` entry: {"tolerance_cm", "tolerance_fraction_of_h",
    "thickness_cm", "grid", "bodies": [table + :func:`check`'s numbers, ...]}; ``tables`` are the
    scene's contact tables, one per body, in the same order."""
    if len(tables) != len(bodies):
        raise InputError(f"{len(tables)} contact table(s) for {len(bodies)} contact body(ies)")
    tol = PENETRATION_TOL * float(h)
    rows = check(mesh, U, bodies, h, grid, tol)
    return {
        "tolerance_cm": tol,
        "tolerance_fraction_of_h": PENETRATION_TOL,
        "thickness_cm": float(h),
        "grid": int(grid),
        "bodies": [{**dict(t), **r} for t, r in zip(tables, rows)],
    }


def warnings(entry: dict) -> list[str]:
    """One line per body with points beyond the tolerance (empty: the contract holds)."""
    out = []
    tol, h = entry["tolerance_cm"], entry["thickness_cm"]
    for i, b in enumerate(entry["bodies"]):
        if b["nodes_beyond"] or b["face_points_beyond"]:
            deep = max(b["deepest_node_cm"], b["deepest_face_point_cm"])
            out.append(
                f"contact[{i}] ({b.get('type', '?')}): {b['nodes_beyond']} node(s) and "
                f"{b['face_points_beyond']} face point(s) lie deeper than the contact tolerance "
                f"{tol:.3g} cm ({100 * tol / h:.3g} % of h) inside the body; deepest {deep:.3g} cm "
                f"({100 * deep / h:.3g} % of h)"
            )
    return out
