"""Hybrid macro-transition elements (paper Section 5.3, Fig. 16b; level i + 1/2).

A leaf quad whose neighbours across some of its edges are one level finer has the mid-edge nodes
of those edges active.  It is then meshed by a conforming patch of quadrilaterals and as few
triangles as possible, using those mid-edge nodes and, where needed, its (inactive as a leaf)
centre node.  A polygon with an odd number of boundary segments cannot be split into quads alone,
so one and three refined sides take exactly one triangle each; two adjacent, two opposite and four
refined sides take none.

Local node numbering of a leaf: 0-3 corners (counter-clockwise), 4+k the mid-edge node of edge k
(corner k -> corner k+1), 8 the centre.  Canonical patterns (refined edges listed), on the unit
square c0 = (0,0), c1 = (1,0), c2 = (1,1), c3 = (0,1):

====  ===========  =========================================================================
id    refined      elements
====  ===========  =========================================================================
1     {0}          quads [c0 m0 z c3], [m0 c1 c2 z]; triangle [z c2 c3]
2     {0, 1}       quads [c0 m0 z c3], [m0 c1 m1 z], [z m1 c2 c3]
3     {0, 2}       quads [c0 m0 m2 c3], [m0 c1 c2 m2]
4     {0, 1, 2}    quads [c0 m0 z c3], [m0 c1 m1 z], [z m1 c2 m2]; triangle [z m2 c3]
5     {0,1,2,3}    quads [c0 m0 z m3], [m0 c1 m1 z], [z m1 c2 m2], [m3 z m2 c3]
====  ===========  =========================================================================

Every other combination is one of these rotated by r quarter turns (local index k -> k + r), which
keeps the counter-clockwise order, so every element is counter-clockwise about the director as the
level-0 mesh is.  Patterns 1 and 4 have alternative variants with the triangle elsewhere (1: a
corner triangle [c0 m0 c3] or [m0 c1 c2] beside one quad, or [m0 c1 z] or [c0 m0 z] beside two;
4: the triangle at c0, at c1 or at c2);
each leaf takes the variant furthest from degenerate (angles nearest neither 0 nor 180 deg) on its own geometry, which on a square
is the one in the table and on distorted parents (the pedestal meshes' 45-degree trapezoids) keeps
the triangles away from the acute corners.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError

PATTERN_NAMES = {0: "plain", 1: "one side", 2: "two adjacent", 3: "two opposite", 4: "three", 5: "four"}

#: how a leaf picks among its pattern's variants (``adapt.transitions``): "quality" the variant
#: furthest from degenerate; "fewest_nodes" a variant without the centre node whenever one is
#: valid (patterns 1 and 4: one node and one element fewer), the best of those
TRANSITION_POLICIES = ("quality", "fewest_nodes")
#: fewer active nodes, and no loss in the drape coefficient, on the scenes measured (docs/adaptivity.md)
DEFAULT_TRANSITIONS = "fewest_nodes"
CENTRE = 8  # local index of the centre node


def check_policy(policy: str) -> str:
    """``policy`` when it is one of TRANSITION_POLICIES, else a one-line InputError."""
    if policy not in TRANSITION_POLICIES:
        raise InputError(f"adapt transitions must be one of {', '.join(TRANSITION_POLICIES)}, got {policy!r}")
    return policy


# variants of each canonical pattern: (quads, triangles); the first is the one drawn in the docs
# and the one chosen on a square parent, the others serve distorted parents (see choose_variant)
_CANON = {
    1: (
        0b0001,
        [
            ([[0, 4, 8, 3], [4, 1, 2, 8]], [[8, 2, 3]]),
            ([[4, 1, 2, 3]], [[0, 4, 3]]),
            ([[0, 4, 2, 3]], [[4, 1, 2]]),
            ([[8, 1, 2, 3], [0, 4, 8, 3]], [[4, 1, 8]]),
            ([[4, 1, 2, 8], [8, 2, 3, 0]], [[0, 4, 8]]),
        ],
    ),
    2: (0b0011, [([[0, 4, 8, 3], [4, 1, 5, 8], [8, 5, 2, 3]], [])]),
    3: (0b0101, [([[0, 4, 6, 3], [4, 1, 2, 6]], [])]),
    4: (
        0b0111,
        [
            ([[0, 4, 8, 3], [4, 1, 5, 8], [8, 5, 2, 6]], [[8, 6, 3]]),
            ([[0, 8, 6, 3], [4, 1, 5, 8], [8, 5, 2, 6]], [[0, 4, 8]]),
            ([[4, 5, 2, 6], [0, 4, 6, 3]], [[4, 1, 5]]),
            ([[4, 1, 5, 6], [0, 4, 6, 3]], [[5, 2, 6]]),
        ],
    ),
    5: (0b1111, [([[0, 4, 8, 7], [4, 1, 5, 8], [8, 5, 2, 6], [7, 8, 6, 3]], [])]),
}


def _rotate(local, r):
    a = np.asarray(local, dtype=np.int64).reshape(-1)
    out = a.copy()
    c = a < 4
    m = (a >= 4) & (a < 8)
    out[c] = (a[c] + r) % 4
    out[m] = 4 + (a[m] - 4 + r) % 4
    return out.reshape(np.shape(local))


def _rot_mask(mask, r):
    return ((mask << r) | (mask >> (4 - r))) & 0b1111


def _cells(c, k):
    return np.asarray(c, dtype=np.int64).reshape(-1, k)


def _build_table():
    """For each refined-edge mask 0..15: (pattern id, [(local quads (nq,4), local tris (nt,3)), ...])."""
    table = {0: (0, [(np.array([[0, 1, 2, 3]]), np.zeros((0, 3), np.int64))])}
    for pid, (mask, variants) in _CANON.items():
        for r in range(4):
            mr = _rot_mask(mask, r)
            if mr not in table:
                table[mr] = (pid, [(_rotate(_cells(q, 4), r), _rotate(_cells(t, 3), r)) for q, t in variants])
    assert sorted(table) == list(range(16))
    return table


#: mask (bit k = edge k refined) -> (pattern id, variants [(local quads, local triangles), ...])
TABLE = _build_table()
PATTERN_OF_MASK = np.array([TABLE[m][0] for m in range(16)], dtype=np.int64)


def angle_score(P: np.ndarray) -> np.ndarray:
    """min(smallest interior angle, 180 - largest interior angle) [deg] of convex polygons
    P (…,k,D), D = 2 or 3: small for a sliver and for a quad with a nearly straight corner."""
    P = np.asarray(P, dtype=float)
    nxt = np.roll(P, -1, axis=-2) - P
    prv = np.roll(P, 1, axis=-2) - P
    cosang = np.sum(nxt * prv, -1) / (np.linalg.norm(nxt, axis=-1) * np.linalg.norm(prv, axis=-1))
    ang = np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))
    return np.minimum(ang.min(-1), 180.0 - ang.max(-1))


def choose_variant(mask: int, pts: np.ndarray, policy: str = DEFAULT_TRANSITIONS) -> np.ndarray:
    """(n,) index of the variant of pattern ``mask`` that each leaf with local node positions pts
    (n,9,D) takes.  Policy "quality": the variant whose elements are furthest from degenerate, the
    largest min over its elements of :func:`angle_score` (no angle near 0 or 180 deg); ties (within
    1e-6 deg) go to the lower index, so a square parent always gets the first variant.  Policy
    "fewest_nodes": the same choice among the variants that leave the centre node out (patterns 1
    and 4 have them), and among all variants only where none of those is valid."""
    check_policy(policy)
    variants = TABLE[int(mask)][1]
    if len(variants) == 1:
        return np.zeros(len(pts), dtype=np.int64)
    P = np.asarray(pts, dtype=float)
    if P.shape[-1] == 2:
        P = np.concatenate([P, np.zeros(P.shape[:-1] + (1,))], axis=-1)
    normal = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])[:, None, None, :]
    score = np.empty((len(P), len(variants)))
    for v, (q, t) in enumerate(variants):
        a, ok = [], np.ones(len(P), dtype=bool)
        for c in (q, t):
            if len(c):
                E = P[:, c]
                a.append(angle_score(E).min(1))
                # every corner turns counter-clockwise about the leaf's normal (no reflex corner)
                cn = np.cross(np.roll(E, -1, axis=-2) - E, np.roll(E, 1, axis=-2) - E)
                ok &= (np.sum(cn * normal, -1) > 0).all(axis=(1, 2))
        score[:, v] = np.where(ok, np.min(a, axis=0) - 1e-6 * v, -np.inf)
    if policy == "fewest_nodes":
        lean = np.array([CENTRE not in np.ravel(q) and CENTRE not in np.ravel(t) for q, t in variants])
        # angle scores are <= 90 deg: a valid lean variant outranks every variant with the centre
        score = score + np.where(lean & np.isfinite(score), 180.0, 0.0)
    return np.argmax(score, axis=1)


def local_points(corners: np.ndarray) -> np.ndarray:
    """(…,9,D) local node positions of a straight-sided leaf with corners (…,4,D): corners, edge
    midpoints, centroid (the bilinear centre)."""
    c = np.asarray(corners, dtype=float)
    mids = 0.5 * (c + np.roll(c, -1, axis=-2))
    z = c.mean(axis=-2, keepdims=True)
    return np.concatenate([c, mids, z], axis=-2)


def element_quality(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(minimum interior angle [deg], aspect ratio = longest / shortest edge) of polygons P (…,k,2)."""
    P = np.asarray(P, dtype=float)
    nxt = np.roll(P, -1, axis=-2) - P
    prv = np.roll(P, 1, axis=-2) - P
    cosang = np.sum(nxt * prv, -1) / (np.linalg.norm(nxt, axis=-1) * np.linalg.norm(prv, axis=-1))
    ang = np.degrees(np.arccos(np.clip(cosang, -1.0, 1.0)))
    le = np.linalg.norm(nxt, axis=-1)
    return ang.min(-1), le.max(-1) / le.min(-1)


def pattern_quality(corners: np.ndarray, policy: str = DEFAULT_TRANSITIONS) -> dict[int, tuple[float, float]]:
    """{pattern id: (min angle [deg], max aspect ratio)} of each pattern on the parents with
    corners (…,4,2), worst over the parents and the four rotations, each leaf with the variant
    :func:`choose_variant` picks for it under ``policy``."""
    pts = local_points(np.asarray(corners, dtype=float).reshape(-1, 4, 2))
    out = {}
    for mask in range(16):
        pid, variants = TABLE[mask]
        pick = choose_variant(mask, pts, policy)
        amin, asp = np.inf, 0.0
        for v, (q, t) in enumerate(variants):
            sel = pts[pick == v]
            for cells in (q, t):
                if len(cells) and len(sel):
                    a, r = element_quality(sel[:, cells])
                    amin, asp = min(amin, a.min()), max(asp, r.max())
        prev = out.get(pid, (np.inf, 0.0))
        out[pid] = (min(prev[0], amin), max(prev[1], asp))
    return out
