"""Compiled kernels of the sheet's penalty self-contact (contact_self_penalty.py): the closest points
of a triangle to a vertex and of two edges, the candidate searches, and the force pass.

Plain functions on plain arrays (positions (N,3) or the flat dof vector (6N,) of Eq. (1), index
arrays of triangles (T,3), edges (E,2) and candidate pairs); lengths in the mesh's unit, forces in
the model's force unit.  Closest points after Ericson, "Real-Time Collision Detection" (2005),
Sec. 5.1.5 (point-triangle, by Voronoi regions: the barycentric weights of the closest point are
exact zeros off the triangle's interior) and Sec. 5.1.9 (segment-segment).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _d3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True, inline="always")
def _comb3(wa, a, wb, b, wc, c):
    return (wa * a[0] + wb * b[0] + wc * c[0], wa * a[1] + wb * b[1] + wc * c[1], wa * a[2] + wb * b[2] + wc * c[2])


@njit(cache=True, inline="always")
def _pt(x, i):
    return (x[i, 0], x[i, 1], x[i, 2])


@njit(cache=True, inline="always")
def _ptd(X0, D, i):
    """The mid-surface position X0[i] + D[6i:6i+3] as a tuple."""
    return (X0[i, 0] + D[6 * i], X0[i, 1] + D[6 * i + 1], X0[i, 2] + D[6 * i + 2])


@njit(cache=True)
def point_triangle(p, a, b, c):
    """Barycentric weights (wa, wb, wc) of the point of triangle abc closest to p (3-tuples;
    Ericson 5.1.5)."""
    ab, ac, ap = _sub(b, a), _sub(c, a), _sub(p, a)
    d1, d2 = _d3(ab, ap), _d3(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0
    bp = _sub(p, b)
    d3, d4 = _d3(ab, bp), _d3(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return 1.0 - v, v, 0.0
    cp = _sub(p, c)
    d5, d6 = _d3(ab, cp), _d3(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return 1.0 - w, 0.0, w
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - w, w
    den = 1.0 / (va + vb + vc)
    v, w = vb * den, vc * den
    return 1.0 - v - w, v, w


@njit(cache=True)
def segment_segment(p1, q1, p2, q2):
    """Parameters (s, t) in [0,1] of the closest points p1 + s (q1-p1) and p2 + t (q2-p2) of two
    segments (3-tuples; Ericson 5.1.9; parallel segments: s = 0)."""
    d1, d2, r = _sub(q1, p1), _sub(q2, p2), _sub(p1, p2)
    a, e, f = _d3(d1, d1), _d3(d2, d2), _d3(d2, r)
    c, b = _d3(d1, r), _d3(d1, d2)
    den = a * e - b * b
    s = min(max((b * f - c * e) / den, 0.0), 1.0) if den > 1e-14 * a * e else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = min(max(-c / a, 0.0), 1.0)
    elif t > 1.0:
        t = 1.0
        s = min(max((b - c) / a, 0.0), 1.0)
    return s, t


@njit(cache=True)
def _vf_owned(own, wa, wb, wc):
    """Whether this triangle counts the vertex-triangle pair whose closest point has weights
    (wa, wb, wc): always in the interior; on an edge or a corner only if the triangle owns that
    feature (bits 0-2: edges ab, bc, ca; bits 3-5: corners a, b, c), so that a vertex near an
    edge or a corner shared by several triangles meets it once (IPC's vertex-edge and
    vertex-vertex pairs)."""
    za, zb, zc = wa == 0.0, wb == 0.0, wc == 0.0
    nz = int(za) + int(zb) + int(zc)
    if nz == 0:
        return True
    if nz == 1:
        bit = 0 if zc else (1 if za else 2)
    else:
        bit = 3 if not za else (4 if not zb else 5)
    return (own >> bit) & 1 == 1


@njit(cache=True, inline="always")
def _push(C, node, w, f, n):
    C[6 * node] += w * f * n[0]
    C[6 * node + 1] += w * f * n[1]
    C[6 * node + 2] += w * f * n[2]


@njit(cache=True)
def self_pass(X0, D, tri, own, vf, edges, ee, k, h, C):
    """Add the penalty forces of the candidate vertex-triangle pairs vf (P,2) and edge-edge pairs ee
    (Q,2) of ``edges`` (E,2) to C (6N,) at the state D (6N,): a pair at distance d < h with unit
    direction n (from the triangle's or second edge's closest point to the vertex or the first
    edge's) carries the energy k/2 (h - d)^2 and pushes its two closest points apart with k (h - d),
    spread on their nodes by the closest points' weights (the exact gradient: the weights are those
    of the closest point, Sec. 5.1 of Ericson).  k (N,) per node; a pair takes the smallest k of its
    four nodes; a triangle counts only the vertex pairs it owns (_vf_owned), an edge pair counts
    only with both closest points inside the edges (at an end point it is a vertex pair).  Returns
    (energy, pairs in contact, the smallest distance of those (inf: none))."""
    E, n_act, dmin = 0.0, 0, np.inf
    for i in range(len(vf)):
        v, t = vf[i, 0], vf[i, 1]
        a, b, c = tri[t, 0], tri[t, 1], tri[t, 2]
        p, xa, xb, xc = _ptd(X0, D, v), _ptd(X0, D, a), _ptd(X0, D, b), _ptd(X0, D, c)
        wa, wb, wc = point_triangle(p, xa, xb, xc)
        if not _vf_owned(own[t], wa, wb, wc):
            continue
        r = _sub(p, _comb3(wa, xa, wb, xb, wc, xc))
        d = math.sqrt(_d3(r, r))
        if d >= h or d == 0.0:
            continue
        dmin = min(dmin, d)
        kk = min(min(k[v], k[a]), min(k[b], k[c]))
        f = kk * (h - d)
        E += 0.5 * f * (h - d)
        n_act += 1
        n = (r[0] / d, r[1] / d, r[2] / d)
        _push(C, v, 1.0, f, n)
        _push(C, a, -wa, f, n)
        _push(C, b, -wb, f, n)
        _push(C, c, -wc, f, n)
    for i in range(len(ee)):
        e1, e2 = ee[i, 0], ee[i, 1]
        a, b, c, dd = edges[e1, 0], edges[e1, 1], edges[e2, 0], edges[e2, 1]
        xa, xb, xc, xd = _ptd(X0, D, a), _ptd(X0, D, b), _ptd(X0, D, c), _ptd(X0, D, dd)
        s, u = segment_segment(xa, xb, xc, xd)
        if not (0.0 < s < 1.0 and 0.0 < u < 1.0):
            continue
        r = _sub(_comb3(1.0 - s, xa, s, xb, 0.0, xb), _comb3(1.0 - u, xc, u, xd, 0.0, xd))
        d = math.sqrt(_d3(r, r))
        if d >= h or d == 0.0:
            continue
        dmin = min(dmin, d)
        kk = min(min(k[a], k[b]), min(k[c], k[dd]))
        f = kk * (h - d)
        E += 0.5 * f * (h - d)
        n_act += 1
        n = (r[0] / d, r[1] / d, r[2] / d)
        _push(C, a, 1.0 - s, f, n)
        _push(C, b, s, f, n)
        _push(C, c, -(1.0 - u), f, n)
        _push(C, dd, -u, f, n)
    return E, n_act, dmin


@njit(cache=True)
def relative_move(X0, D, Xb):
    """max_i |dx_i - c|, dx_i = X0[i] + D[6i:6i+3] - Xb[i] a node's move since the last candidate
    search (Xb its position then) and c the midpoint of the moves' bounding box: a pair's distance
    changes by at most twice this (its two closest points are convex combinations of nodes), so a
    sheet falling or sliding as a whole needs no new search.  NaN if a position is not finite."""
    N = len(X0)
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for i in range(N):
        for j in range(3):
            d = X0[i, j] + D[6 * i + j] - Xb[i, j]
            if not math.isfinite(d):
                return np.nan
            lo[j] = min(lo[j], d)
            hi[j] = max(hi[j], d)
    c0, c1, c2 = 0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])
    m = 0.0
    for i in range(N):
        r0 = X0[i, 0] + D[6 * i] - Xb[i, 0] - c0
        r1 = X0[i, 1] + D[6 * i + 1] - Xb[i, 1] - c1
        r2 = X0[i, 2] + D[6 * i + 2] - Xb[i, 2] - c2
        m = max(m, r0 * r0 + r1 * r1 + r2 * r2)
    return math.sqrt(m)


# ---------------------------------------------------------------------- the candidate search
@njit(cache=True)
def _cell(p, lo, c, n):
    """Integer cell (ix, iy, iz) of the point p in a grid of cell size c from lo, n cells per axis."""
    ix = min(max(int((p[0] - lo[0]) / c), 0), n[0] - 1)
    iy = min(max(int((p[1] - lo[1]) / c), 0), n[1] - 1)
    iz = min(max(int((p[2] - lo[2]) / c), 0), n[2] - 1)
    return ix, iy, iz


@njit(cache=True)
def _grid(p, c):
    """A uniform grid of cell size c over the points p (M,3): (lo, cells per axis, the points' keys
    sorted, the points in that order)."""
    lo = np.empty(3)
    hi = np.empty(3)
    n = np.empty(3, dtype=np.int64)
    for j in range(3):
        lo[j] = p[:, j].min() - c
        hi[j] = p[:, j].max() + c
        n[j] = max(1, int((hi[j] - lo[j]) / c) + 1)
    keys = np.empty(len(p), dtype=np.int64)
    for i in range(len(p)):
        ix, iy, iz = _cell(p[i], lo, c, n)
        keys[i] = (ix * n[1] + iy) * n[2] + iz
    order = np.argsort(keys, kind="mergesort")
    return lo, n, keys[order], order


@njit(cache=True)
def _pt_dist(x, v, a, b, c):
    """Distance of the point x[v] from the triangle x[a] x[b] x[c]."""
    p, xa, xb, xc = _pt(x, v), _pt(x, a), _pt(x, b), _pt(x, c)
    wa, wb, wc = point_triangle(p, xa, xb, xc)
    r = _sub(p, _comb3(wa, xa, wb, xb, wc, xc))
    return math.sqrt(_d3(r, r))


@njit(cache=True)
def _seg_dist(x, a, b, c, d):
    """Distance of the segments x[a] x[b] and x[c] x[d]."""
    xa, xb, xc, xd = _pt(x, a), _pt(x, b), _pt(x, c), _pt(x, d)
    s, t = segment_segment(xa, xb, xc, xd)
    r = _sub(_comb3(1.0 - s, xa, s, xb, 0.0, xb), _comb3(1.0 - t, xc, t, xd, 0.0, xd))
    return math.sqrt(_d3(r, r))


@njit(cache=True)
def vf_candidates(x, X0, tri, r, rest_min):
    """(P,2) the pairs (vertex, triangle) sharing no node whose distance at x (N,3) is below r and
    whose distance in the flat reference X0 is at least rest_min: a uniform grid over the vertices
    (cell: the largest triangle's box + 2r), each triangle's box grown by r looked up in it."""
    T = len(tri)
    ext = 0.0
    for t in range(T):
        for j in range(3):
            a, b, c = x[tri[t, 0], j], x[tri[t, 1], j], x[tri[t, 2], j]
            ext = max(ext, max(a, max(b, c)) - min(a, min(b, c)))
    cs = ext + 2.0 * r
    lo, n, skeys, order = _grid(x, cs)
    out = np.empty((max(1024, len(x)), 2), dtype=np.int64)
    m = 0
    bmin, bmax = np.empty(3), np.empty(3)
    for t in range(T):
        ia, ib, ic = tri[t, 0], tri[t, 1], tri[t, 2]
        for j in range(3):
            bmin[j] = min(x[ia, j], min(x[ib, j], x[ic, j])) - r
            bmax[j] = max(x[ia, j], max(x[ib, j], x[ic, j])) + r
        i0, j0, k0 = _cell(bmin, lo, cs, n)
        i1, j1, k1 = _cell(bmax, lo, cs, n)
        for ix in range(i0, i1 + 1):
            for iy in range(j0, j1 + 1):
                for iz in range(k0, k1 + 1):
                    key = (ix * n[1] + iy) * n[2] + iz
                    s0 = np.searchsorted(skeys, key)
                    s1 = np.searchsorted(skeys, key, side="right")
                    for s in range(s0, s1):
                        v = order[s]
                        if v == ia or v == ib or v == ic:
                            continue
                        if not (
                            bmin[0] <= x[v, 0] <= bmax[0]
                            and bmin[1] <= x[v, 1] <= bmax[1]
                            and bmin[2] <= x[v, 2] <= bmax[2]
                        ):
                            continue
                        if _pt_dist(x, v, ia, ib, ic) >= r or _pt_dist(X0, v, ia, ib, ic) < rest_min:
                            continue
                        if m == len(out):  # full: twice the room
                            grown = np.empty((2 * m, 2), dtype=np.int64)
                            grown[:m] = out
                            out = grown
                        out[m, 0] = v
                        out[m, 1] = t
                        m += 1
    return out[:m].copy()


@njit(cache=True)
def ee_candidates(x, X0, edges, r, rest_min):
    """(Q,2) the pairs (i < j) of edges sharing no node whose distance at x (N,3) is below r and in
    the flat reference X0 at least rest_min: a uniform grid over the edges' midpoints (cell: the
    longest edge + r, so that two edges within r have their midpoints in neighbouring cells), each
    pair's boxes grown by r compared before its distance."""
    E = len(edges)
    mid = np.empty((E, 3))
    lo_e = np.empty((E, 3))
    hi_e = np.empty((E, 3))
    ext = 0.0
    for e in range(E):
        a, b = edges[e, 0], edges[e, 1]
        for j in range(3):
            mid[e, j] = 0.5 * (x[a, j] + x[b, j])
            lo_e[e, j] = min(x[a, j], x[b, j])
            hi_e[e, j] = max(x[a, j], x[b, j])
        r_ab = _sub(_pt(x, a), _pt(x, b))
        ext = max(ext, math.sqrt(_d3(r_ab, r_ab)))
    cs = ext + r
    lo, n, skeys, order = _grid(mid, cs)
    out = np.empty((max(1024, E), 2), dtype=np.int64)
    m = 0
    for e in range(E):
        a, b = edges[e, 0], edges[e, 1]
        ci, cj, ck = _cell(mid[e], lo, cs, n)
        for ix in range(max(ci - 1, 0), min(ci + 2, n[0])):
            for iy in range(max(cj - 1, 0), min(cj + 2, n[1])):
                for iz in range(max(ck - 1, 0), min(ck + 2, n[2])):
                    key = (ix * n[1] + iy) * n[2] + iz
                    s0 = np.searchsorted(skeys, key)
                    s1 = np.searchsorted(skeys, key, side="right")
                    for s in range(s0, s1):
                        f = order[s]
                        if f <= e:
                            continue
                        if (
                            lo_e[f, 0] > hi_e[e, 0] + r
                            or lo_e[e, 0] > hi_e[f, 0] + r
                            or lo_e[f, 1] > hi_e[e, 1] + r
                            or lo_e[e, 1] > hi_e[f, 1] + r
                            or lo_e[f, 2] > hi_e[e, 2] + r
                            or lo_e[e, 2] > hi_e[f, 2] + r
                        ):
                            continue
                        c, d = edges[f, 0], edges[f, 1]
                        if c == a or c == b or d == a or d == b:
                            continue
                        if _seg_dist(x, a, b, c, d) >= r or _seg_dist(X0, a, b, c, d) < rest_min:
                            continue
                        if m == len(out):
                            grown = np.empty((2 * m, 2), dtype=np.int64)
                            grown[:m] = out
                            out = grown
                        out[m, 0] = e
                        out[m, 1] = f
                        m += 1
    return out[:m].copy()


@njit(cache=True)
def nearest_rest_pair(X0, tri, edges, r, rest_min):
    """The smallest flat-reference distance >= rest_min of a vertex-triangle or edge-edge pair
    sharing no node (inf: none within r): how far the candidates' reach may go before a flat
    sheet's neighbours become candidates (contact_self_penalty.SelfPenalty)."""
    pairs = vf_candidates(X0, X0, tri, r, rest_min)
    best = np.inf
    for i in range(len(pairs)):
        t = pairs[i, 1]
        best = min(best, _pt_dist(X0, pairs[i, 0], tri[t, 0], tri[t, 1], tri[t, 2]))
    pairs = ee_candidates(X0, X0, edges, r, rest_min)
    for i in range(len(pairs)):
        e, f = pairs[i, 0], pairs[i, 1]
        best = min(best, _seg_dist(X0, edges[e, 0], edges[e, 1], edges[f, 0], edges[f, 1]))
    return best
