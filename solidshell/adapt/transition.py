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
level-0 mesh is.
"""

from __future__ import annotations

import numpy as np

PATTERN_NAMES = {0: "plain", 1: "one side", 2: "two adjacent", 3: "two opposite", 4: "three", 5: "four"}

_CANON = {
    1: (0b0001, [[0, 4, 8, 3], [4, 1, 2, 8]], [[8, 2, 3]]),
    2: (0b0011, [[0, 4, 8, 3], [4, 1, 5, 8], [8, 5, 2, 3]], []),
    3: (0b0101, [[0, 4, 6, 3], [4, 1, 2, 6]], []),
    4: (0b0111, [[0, 4, 8, 3], [4, 1, 5, 8], [8, 5, 2, 6]], [[8, 6, 3]]),
    5: (0b1111, [[0, 4, 8, 7], [4, 1, 5, 8], [8, 5, 2, 6], [7, 8, 6, 3]], []),
}


def _rotate(local, r):
    a = np.asarray(local, dtype=np.int64).reshape(-1)
    out = a.copy()
    c = a < 4
    m = (a >= 4) & (a < 8)
    out[c] = (a[c] + r) % 4
    out[m] = 4 + (a[m] - 4 + r) % 4
    return out.reshape(np.shape(local)) if len(a) else np.zeros((0,) + np.shape(local)[1:], np.int64)


def _rot_mask(mask, r):
    return ((mask << r) | (mask >> (4 - r))) & 0b1111


def _build_table():
    """For each refined-edge mask 0..15: (pattern id, local quads (nq,4), local triangles (nt,3))."""
    table = {0: (0, np.array([[0, 1, 2, 3]]), np.zeros((0, 3), np.int64))}
    for pid, (mask, q, t) in _CANON.items():
        for r in range(4):
            mr = _rot_mask(mask, r)
            if mr not in table:
                table[mr] = (pid, _rotate(np.array(q), r),
                             _rotate(np.array(t), r) if t else np.zeros((0, 3), np.int64))
    assert sorted(table) == list(range(16))
    return table


#: mask (bit k = edge k refined) -> (pattern id, local quads, local triangles)
TABLE = _build_table()
PATTERN_OF_MASK = np.array([TABLE[m][0] for m in range(16)], dtype=np.int64)


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


def pattern_quality(corners: np.ndarray) -> dict[int, tuple[float, float]]:
    """{pattern id: (min angle [deg], max aspect ratio)} over all four rotations of each pattern on
    the parents with corners (…,4,2) (worst over the parents)."""
    pts = local_points(np.asarray(corners, dtype=float).reshape(-1, 4, 2))
    out = {}
    for mask in range(16):
        pid, q, t = TABLE[mask]
        amin, asp = [], []
        for cells in (q, t):
            if len(cells):
                a, r = element_quality(pts[:, cells])
                amin.append(a.min())
                asp.append(r.max())
        prev = out.get(pid, (np.inf, 0.0))
        out[pid] = (min(prev[0], min(amin)), max(prev[1], max(asp)))
    return out
