"""The sheet against itself: where its mid-surface passes through itself, and how close its layers come.

What is measured (issue 37's contract: two layers keep their mid-surfaces at least about a
thickness h apart; elements sharing a node are not self-contact)
------------------------------------------------------------------------------------------
The mid-surface as triangles: each quad split along its 0-2 diagonal, the triangles as they are
(:func:`triangles`).

* ``self_intersections``: the pairs of these triangles that share no node and intersect.  Two
  triangles intersect exactly when an edge of one crosses the other, so the pairs are found from
  the crossing edge-triangle pairs: the candidates of the IPC Toolkit's broad phase (``ipctk``,
  an LBVH over the edges' and triangles' boxes), each tested by its exact edge-triangle test.
* ``min_layer_gap``: the smallest distance [length] between two *layers*: vertex-triangle,
  vertex-edge, vertex-vertex and edge-edge pairs sharing no node (ipctk's collision set within
  SEARCH x h) whose distance is less than half their distance in the flat reference state -- sheet
  brought together by folding, not neighbours in the plane (membrane strains are a few per cent).
  None when no two layers come within SEARCH x h.
* ``layer_pairs_close``: how many such pairs lie closer than (1 - LAYER_TOL) h.

A report, not the contact: the numbers come from the library's broad phase and distances, so they
check a run independently of any contact code.  Cost: one LBVH build and query per measure (tens
of milliseconds on 10^4 triangles).
"""

from __future__ import annotations

import numpy as np

SEARCH = 2.0
"""Layers are looked for within SEARCH x h: min_layer_gap is None beyond."""

SELF_CONTACT_DEFAULT = True
"""A scene's ``[self_contact] enabled`` when it does not say (solidshell.scenes.schema): on, as in
every cloth code users compare with -- a drape whose sheet passes through itself is not a drape.
Cheap where no layers meet (docs/contact.md §16); a scene whose sheet cannot fold onto itself
(the paper's strips) says ``enabled = false``."""

LAYER_TOL = 0.1
"""Two layers closer than (1 - LAYER_TOL) h are reported (layer_pairs_close) and warned about:
10 % of the thickness, the order of a fabric's compression under its own weight."""


def triangles(mesh) -> np.ndarray:
    """(T, 3) int32 node indices of the mid-surface triangles: the quads split along their 0-2
    diagonal (two each, in quad order), then the mesh's triangles."""
    q = np.asarray(mesh.quads, dtype=np.int64).reshape(-1, 4)
    t = np.asarray(mesh.tris, dtype=np.int64).reshape(-1, 3)
    return np.ascontiguousarray(np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]], t]), dtype=np.int32)


def _positions(mesh, U) -> np.ndarray:
    x = np.asarray(mesh.nodes, dtype=float)
    if U is not None:
        x = x + np.asarray(U, dtype=float).reshape(len(x), -1)[:, :3]
    return np.asfortranarray(x)


def self_intersections(mesh, U=None) -> np.ndarray:
    """(K, 2) the intersecting pairs (i < j) of mid-surface triangles (:func:`triangles`) that share
    no node, at the state U (N, 6) (None: the reference state)."""
    import ipctk

    F = triangles(mesh)
    if not len(F):
        return np.zeros((0, 2), dtype=np.int64)
    x = _positions(mesh, U)
    E = ipctk.edges(F)
    if not ipctk.has_intersections(ipctk.CollisionMesh(x, E, F), x):
        return np.zeros((0, 2), dtype=np.int64)  # the library's compiled yes/no first: the pairs below loop in Python
    bp = ipctk.LBVH()
    bp.build(x, np.asfortranarray(E), np.asfortranarray(F), 0.0)
    ef = np.array([(c.edge_id, c.face_id) for c in bp.detect_edge_face_candidates()], dtype=np.int64).reshape(-1, 2)
    e, f = E[ef[:, 0]], F[ef[:, 1]]
    apart = ~(e[:, :, None] == f[:, None, :]).any(axis=(1, 2))  # an edge of a triangle's neighbour
    hits = [
        (i, j)
        for (i, j), a, b in zip(ef[apart], e[apart], f[apart])
        if ipctk.is_edge_intersecting_triangle(x[a[0]], x[a[1]], x[b[0]], x[b[1]], x[b[2]])
    ]
    if not hits:
        return np.zeros((0, 2), dtype=np.int64)
    # the triangles on each side of a crossing edge, paired with the triangle it crosses
    n = len(x)
    es = np.sort(np.stack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1), axis=2).astype(np.int64)
    key = es[..., 0] * n + es[..., 1]  # (T, 3): each triangle's edges
    Es = np.sort(E, axis=1).astype(np.int64)
    hit_key = {int(Es[i, 0] * n + Es[i, 1]) for i, _ in hits}
    sides: dict[int, list[int]] = {}
    for t, k in zip(*np.nonzero(np.isin(key, list(hit_key)))):
        sides.setdefault(int(key[t, k]), []).append(int(t))
    pairs = set()
    for i, j in hits:
        for t in sides[int(Es[i, 0] * n + Es[i, 1])]:
            if not np.intersect1d(F[t], F[j]).size:
                pairs.add((min(t, int(j)), max(t, int(j))))
    return np.array(sorted(pairs), dtype=np.int64).reshape(-1, 2)


def layer_gaps(mesh, U, h: float) -> np.ndarray:
    """The distances [length] of the pairs of layers within SEARCH x h at the state U (module
    docstring): one per vertex-triangle, vertex-edge, vertex-vertex or edge-edge pair of ipctk's
    collision set whose distance is less than half its flat reference distance."""
    return layer_pairs(mesh, U, h)[0]


def layer_pairs(mesh, U, h: float) -> tuple[np.ndarray, list]:
    """(distances, node tuples): :func:`layer_gaps`' pairs with the nodes of each pair's two point
    sets (the output fields flag them: solidshell/fields.py)."""
    import ipctk

    F = triangles(mesh)
    if not len(F) or not h > 0.0:
        return np.zeros(0), []
    X, x = _positions(mesh, None), _positions(mesh, U)
    E = ipctk.edges(F)
    cm = ipctk.CollisionMesh(X, E, F)
    col = ipctk.NormalCollisions()
    col.build(cm, x, SEARCH * float(h))
    kinds = (  # (the pair's two point sets, their squared distance)
        ([((c.vertex0_id,), (c.vertex1_id,)) for c in col.vv_collisions], ipctk.point_point_distance),
        ([((c.vertex_id,), tuple(E[c.edge_id])) for c in col.ev_collisions], ipctk.point_edge_distance),
        ([((c.vertex_id,), tuple(F[c.face_id])) for c in col.fv_collisions], ipctk.point_triangle_distance),
        ([(tuple(E[c.edge0_id]), tuple(E[c.edge1_id])) for c in col.ee_collisions], ipctk.edge_edge_distance),
    )
    out, nodes = [], []
    for pairs, dist in kinds:
        for a, b in pairs:
            now = dist(*(x[i] for i in a), *(x[i] for i in b))
            rest = dist(*(X[i] for i in a), *(X[i] for i in b))
            if now < 0.25 * rest:  # squared: closer than half the reference distance
                out.append(np.sqrt(now))
                nodes.append(tuple(int(i) for i in a + b))
    return np.array(out), nodes


def report(mesh, U, h: float) -> dict:
    """summary.json's measures of the sheet against itself at the state U: ``self_intersections``
    (the count of intersecting triangle pairs sharing no node), ``min_layer_gap`` (None: no two
    layers within SEARCH x h), ``layer_pairs_close`` (pairs of layers closer than (1 - LAYER_TOL)
    h), and the thresholds used."""
    gaps = layer_gaps(mesh, U, h)
    return {
        "self_intersections": int(len(self_intersections(mesh, U))),
        "min_layer_gap": float(gaps.min()) if gaps.size else None,
        "layer_pairs_close": int(np.count_nonzero(gaps < (1.0 - LAYER_TOL) * h)),
        "layer_gap_limit": (1.0 - LAYER_TOL) * float(h),
        "layer_search": SEARCH * float(h),
    }


def warnings(entry: dict) -> list[str]:
    """One line per finding of :func:`report` that shows the sheet through or into itself."""
    out = []
    n = entry.get("self_intersections")
    if n:
        out.append(f"{n} pair(s) of mid-surface triangles sharing no node intersect: the sheet passes through itself")
    k, g = entry.get("layer_pairs_close"), entry.get("min_layer_gap")
    if k:
        out.append(
            f"{k} pair(s) of layers closer than {entry['layer_gap_limit']:.3g} (the thickness less "
            f"{100 * LAYER_TOL:g} %); the closest {g:.3g} apart"
        )
    return out
