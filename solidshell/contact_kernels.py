"""Compiled contact: the bodies' signed distances, the penalty law and the Coulomb return map, one
node at a time (``contact.py`` describes the laws; its bodies and functions call these, and so does
the explicit solver's contact pass over its candidate nodes, ``contact_pass``).

A body is a code (SPHERE, PLANE, CYLINDER, BOX, CUSICK) and a parameter row of PARAMS floats:

* SPHERE   : centre (3), radius
* PLANE    : point (3), unit normal (3)
* CYLINDER : top centre (3), height, edge radius, radius        (a vertical pedestal)
* BOX      : top centre (3), height, edge radius, half widths a, b
* CUSICK   : top centre (3), height, edge radius, disc radius, disc thickness, stem radius  (a
  Cusick-type support: a disc on a narrower coaxial stem that reaches down to the base)
* MESH     : grid origin (3), spacing, blocks along x, y, z, start  (a body from a triangle mesh:
  its signed distance sampled on a narrow-band grid, ``contact_mesh.py``; the samples live in the
  shared float array ``grid`` from ``start`` on, see :func:`grid_distance`)

The kernels take that shared array as their last argument ``grid`` (None, the default, when no body
is a MESH: then numba compiles the functions without the MESH branch, and the analytic bodies run
the very code they ran before the MESH code existed).

Every function returns the same numbers the former numpy code did, to round-off: the sums of
three squares are taken left to right, the box distance follows ``_box`` below term by term.
Lengths in the scene's length unit, stiffnesses in force/length.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

SPHERE, PLANE, CYLINDER, BOX, CUSICK, MESH = 0, 1, 2, 3, 4, 5
PARAMS = 8
BLOCK = 8
"""Cells per block edge of a MESH body's grid: a block stores its (BLOCK + 1)^3 corner samples."""
FAR_OUT, FAR_IN = -1.0, -2.0  # a block's entry in the table when all its samples are +band / -band
MESH_LIPSCHITZ = math.sqrt(3.0)
"""Lipschitz bound of a MESH body's trilinear distance: each partial derivative is a convex
combination of the grid's finite differences along its axis, each at most 1 in size for samples of a
1-Lipschitz distance, so |grad g| <= sqrt(3) (contact_mesh.py)."""
_G0, _N0 = np.zeros(0), np.zeros((0, 3))  # "no given distances" (body_forces' g_in, n_in)


@njit(cache=True)
def _box(a0, a1, a2, h0, h1, h2, k):
    """Signed distance of the point a (its first k = 2 or 3 coordinates) to the box |a_j| <= h_j and
    its gradient: Euclidean outside (edges and corners rounded), minus the distance to the nearest
    face inside (the first face on a tie)."""
    s0 = 1.0 if a0 >= 0.0 else -1.0
    s1 = 1.0 if a1 >= 0.0 else -1.0
    s2 = 1.0 if a2 >= 0.0 else -1.0
    q0 = abs(a0) - h0
    q1 = abs(a1) - h1
    q2 = abs(a2) - h2 if k == 3 else -math.inf
    p0, p1, p2 = max(q0, 0.0), max(q1, 0.0), max(q2, 0.0)
    L = math.sqrt(p0 * p0 + p1 * p1 + p2 * p2) if k == 3 else math.sqrt(p0 * p0 + p1 * p1)
    m = max(q0, q1, q2)
    g = L + min(m, 0.0)
    if L > 0.0:
        return g, s0 * (p0 / L), s1 * (p1 / L), s2 * (p2 / L)
    if q0 >= q1 and q0 >= q2:
        return g, s0, 0.0, 0.0
    if q1 >= q2:
        return g, 0.0, s1, 0.0
    return g, 0.0, 0.0, s2


HEADER = 3
"""A MESH body's grid opens with the band, then the offsets (from its start) of its exact section
(0: none) and of its triangle records; the table of blocks follows (:func:`grid_distance`)."""
TRI = 30
"""Floats per triangle record of a MESH body's exact cells: corners a, b, c, the unit face normal,
the edges' pseudonormals (ab, bc, ca: the sums of their two faces' unit normals) and the corners'
(angle-weighted sums of their faces' unit normals)."""


@njit(cache=True, inline="always")
def grid_distance(p, grid, x0, x1, x2):
    """(g, grad g) of a MESH body at x (contact_mesh.py builds its grid).  ``grid[start]`` is the
    band b, ``grid[start + 1]`` the offset E of the exact section (0: none), ``grid[start + 2]`` the
    offset T of the triangle records; the table of blocks (nbx, nby, nbz, C order) follows, each entry a
    block number k >= 0, FAR_OUT (every sample of the block is +b), FAR_IN (-b) or -(3 + k) for a
    block k with exact cells; then the exact distances at the blocks' centres (same order,
    :func:`far_bound`); then block k's (BLOCK + 1)^3 samples (C order) at start + HEADER + 2 nbx nby
    nbz + k (BLOCK + 1)^3.  Samples are the exact distance clamped to [-b, b] (clamping keeps it
    1-Lipschitz); in a cell they are interpolated trilinearly, so the interpolant is continuous;
    outside the grid's box it is b.  The gradient is returned as it is, not normalised: the penalty
    force k p grad g is then exactly minus the gradient of the energy 1/2 k p^2 of this g (|grad g| =
    1 up to the interpolation error, O(spacing / curvature radius), near the surface).

    An *exact cell* (where the trilinear interpolant would round a sharp edge or a corner off:
    contact_mesh.build_grid) is evaluated from the triangles instead (:func:`exact_cell`): the
    exact signed distance, clamped to [-b, b], and its gradient."""
    inv = 1.0 / p[3]  # one division, not six
    nbx, nby, nbz, s = int(p[4]), int(p[5]), int(p[6]), int(p[7])
    band = grid[s]
    u = (x0 - p[0]) * inv
    v = (x1 - p[1]) * inv
    w = (x2 - p[2]) * inv
    nx, ny, nz = nbx * BLOCK, nby * BLOCK, nbz * BLOCK
    if not (0.0 <= u < nx and 0.0 <= v < ny and 0.0 <= w < nz):  # (NaN lands here too)
        return band, 0.0, 0.0, 0.0
    i, j, k = int(u), int(v), int(w)
    fu, fv, fw = u - i, v - j, w - k
    bi, bj, bk = i >> 3, j >> 3, k >> 3  # // BLOCK (8; i, j, k >= 0)
    kb = grid[s + HEADER + (bi * nby + bj) * nbz + bk]
    li, lj, lk = i - bi * BLOCK, j - bj * BLOCK, k - bk * BLOCK
    if kb < 0.0:
        if kb > -2.5:  # FAR_OUT or FAR_IN
            return (band if kb == FAR_OUT else -band), 0.0, 0.0, 0.0
        kb = -kb - 3.0  # a block with exact cells
        ct = s + int(grid[s + int(grid[s + 1]) + int(kb)])  # its cell table
        c = grid[ct + (li * BLOCK + lj) * BLOCK + lk]
        if c >= 0.0:
            return exact_cell(grid, s, s + int(c), x0, x1, x2, band)
    m = BLOCK + 1
    o = s + HEADER + 2 * nbx * nby * nbz + int(kb) * m * m * m + (li * m + lj) * m + lk
    c000, c001 = grid[o], grid[o + 1]
    c010, c011 = grid[o + m], grid[o + m + 1]
    c100, c101 = grid[o + m * m], grid[o + m * m + 1]
    c110, c111 = grid[o + m * m + m], grid[o + m * m + m + 1]
    # along w, then v, then u
    c00 = c000 + fw * (c001 - c000)
    c01 = c010 + fw * (c011 - c010)
    c10 = c100 + fw * (c101 - c100)
    c11 = c110 + fw * (c111 - c110)
    c0 = c00 + fv * (c01 - c00)
    c1 = c10 + fv * (c11 - c10)
    g = c0 + fu * (c1 - c0)
    gu = c1 - c0
    gv = (1.0 - fu) * (c01 - c00) + fu * (c11 - c10)
    d00, d01 = c001 - c000, c011 - c010
    d10, d11 = c101 - c100, c111 - c110
    gw = (1.0 - fu) * ((1.0 - fv) * d00 + fv * d01) + fu * ((1.0 - fv) * d10 + fv * d11)
    return g, gu * inv, gv * inv, gw * inv


@njit(cache=True)
def closest_on_triangle(r, x0, x1, x2):
    """(squared distance, closest point (3), feature) of the point x to the triangle whose record
    starts at r (TRI floats in the array r's owner: see :func:`exact_cell`); feature 0 the face, 1..3
    the edges ab, bc, ca, 4..6 the corners a, b, c.  Ericson, Real-Time Collision Detection (2005),
    Sec. 5.1.5, by the Voronoi regions of the corners and edges."""
    a0, a1, a2 = r[0], r[1], r[2]
    ab0, ab1, ab2 = r[3] - a0, r[4] - a1, r[5] - a2
    ac0, ac1, ac2 = r[6] - a0, r[7] - a1, r[8] - a2
    ap0, ap1, ap2 = x0 - a0, x1 - a1, x2 - a2
    d1 = ab0 * ap0 + ab1 * ap1 + ab2 * ap2
    d2 = ac0 * ap0 + ac1 * ap1 + ac2 * ap2
    if d1 <= 0.0 and d2 <= 0.0:
        c0, c1, c2, f = a0, a1, a2, 4
    else:
        bp0, bp1, bp2 = x0 - r[3], x1 - r[4], x2 - r[5]
        d3 = ab0 * bp0 + ab1 * bp1 + ab2 * bp2
        d4 = ac0 * bp0 + ac1 * bp1 + ac2 * bp2
        cp0, cp1, cp2 = x0 - r[6], x1 - r[7], x2 - r[8]
        d5 = ab0 * cp0 + ab1 * cp1 + ab2 * cp2
        d6 = ac0 * cp0 + ac1 * cp1 + ac2 * cp2
        vc = d1 * d4 - d3 * d2
        vb = d5 * d2 - d1 * d6
        va = d3 * d6 - d5 * d4
        if d3 >= 0.0 and d4 <= d3:
            c0, c1, c2, f = r[3], r[4], r[5], 5
        elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
            t = d1 / (d1 - d3)
            c0, c1, c2, f = a0 + t * ab0, a1 + t * ab1, a2 + t * ab2, 1
        elif d6 >= 0.0 and d5 <= d6:
            c0, c1, c2, f = r[6], r[7], r[8], 6
        elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
            t = d2 / (d2 - d6)
            c0, c1, c2, f = a0 + t * ac0, a1 + t * ac1, a2 + t * ac2, 3
        elif va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
            t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
            c0, c1, c2, f = r[3] + t * (r[6] - r[3]), r[4] + t * (r[7] - r[4]), r[5] + t * (r[8] - r[5]), 2
        else:
            den = 1.0 / (va + vb + vc)
            t, q = vb * den, vc * den
            c0, c1, c2, f = a0 + t * ab0 + q * ac0, a1 + t * ab1 + q * ac1, a2 + t * ab2 + q * ac2, 0
    e0, e1, e2 = x0 - c0, x1 - c1, x2 - c2
    return e0 * e0 + e1 * e1 + e2 * e2, c0, c1, c2, f


@njit(cache=True)
def exact_cell(grid, s, o, x0, x1, x2, band):
    """(g, grad g) of a MESH body at x in an exact cell whose list of triangles starts at o (a count,
    then the triangles' numbers; contact_mesh.build_grid lists every triangle that can hold the
    closest point of a point of the cell): the exact distance to the nearest of them, its sign by the
    pseudonormal of the nearest feature (Baerentzen & Aanaes, IEEE TVCG 11 (2005) 243-253: the face's
    normal, an edge's or a corner's pseudonormal; the sign libigl's signed_distance gives), the
    gradient the unit vector from the closest point (sign times), or the feature's unit pseudonormal
    on the surface itself; clamped to [-b, b] as the samples are (gradient 0 there)."""
    T = s + int(grid[s + 2])
    best = math.inf
    bt = 0
    bf = 0
    b0 = b1 = b2 = 0.0
    for t in range(int(grid[o])):
        r = T + TRI * int(grid[o + 1 + t])
        d2, c0, c1, c2, f = closest_on_triangle(grid[r : r + TRI], x0, x1, x2)
        if d2 < best:
            best, bt, bf, b0, b1, b2 = d2, r, f, c0, c1, c2
    # the nearest feature's pseudonormal, 9 + 3 f floats into its record (face 9, edges 12, 15, 18, corners 21, 24, 27)
    q = bt + 9 + 3 * bf
    e0, e1, e2 = x0 - b0, x1 - b1, x2 - b2
    sgn = 1.0 if e0 * grid[q] + e1 * grid[q + 1] + e2 * grid[q + 2] >= 0.0 else -1.0
    d = math.sqrt(best)
    g = sgn * d
    if g >= band:
        return band, 0.0, 0.0, 0.0
    if g <= -band:
        return -band, 0.0, 0.0, 0.0
    if d > 1e-12 * (1.0 + abs(x0) + abs(x1) + abs(x2)):
        return g, sgn * e0 / d, sgn * e1 / d, sgn * e2 / d
    n0, n1, n2 = grid[q], grid[q + 1], grid[q + 2]
    L = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    return g, n0 / L, n1 / L, n2 / L


@njit(cache=True)
def far_bound(p, grid, x0, x1, x2):
    """A lower bound of a MESH body's exact distance at x (for skipping what is far from it): the
    exact distance at the centre c of x's block less |x - c| (the distance is 1-Lipschitz), or,
    outside the grid's box, the band plus the distance to the box (its outer samples are all beyond
    the band)."""
    h = p[3]
    nbx, nby, nbz, s = int(p[4]), int(p[5]), int(p[6]), int(p[7])
    bh = BLOCK * h
    u, v, w = (x0 - p[0]) / bh, (x1 - p[1]) / bh, (x2 - p[2]) / bh
    if not (0.0 <= u < nbx and 0.0 <= v < nby and 0.0 <= w < nbz):
        d0 = max(-u, u - nbx, 0.0) * bh
        d1 = max(-v, v - nby, 0.0) * bh
        d2 = max(-w, w - nbz, 0.0) * bh
        return grid[s] + math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    bi, bj, bk = int(u), int(v), int(w)
    c0, c1, c2 = (bi + 0.5 - u) * bh, (bj + 0.5 - v) * bh, (bk + 0.5 - w) * bh
    return grid[s + HEADER + nbx * nby * nbz + (bi * nby + bj) * nbz + bk] - math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)


@njit(cache=True)
def signed_distance(code, p, x0, x1, x2, grid=None):
    """(g, n0, n1, n2): the signed distance of the point x to the body (positive outside) and its
    outward unit normal grad g (a MESH body's: see :func:`grid_distance`; ``grid`` its samples)."""
    if grid is not None:
        if code == MESH:
            return grid_distance(p, grid, x0, x1, x2)
    if code == SPHERE:
        d0, d1, d2 = x0 - p[0], x1 - p[1], x2 - p[2]
        r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if r > 0.0:
            return r - p[3], d0 / r, d1 / r, d2 / r
        return r - p[3], 0.0, 0.0, 1.0  # the centre itself: push up
    if code == PLANE:
        g = (x0 - p[0]) * p[3] + (x1 - p[1]) * p[4] + (x2 - p[2]) * p[5]
        return g, p[3], p[4], p[5]
    er = p[4]  # a pedestal: the edge radius
    d0, d1 = x0 - p[0], x1 - p[1]
    zc = (x2 - p[2]) + 0.5 * p[3]  # z about the pedestal's mid-height
    if code == CYLINDER:
        rho = math.hypot(d0, d1)
        g, ga0, ga1, _ = _box(rho, zc, 0.0, p[5] - er, 0.5 * p[3] - er, 0.0, 2)
        if rho > 0.0:
            e0, e1 = d0 / rho, d1 / rho
        else:
            e0, e1 = 1.0, 0.0
        return g - er, ga0 * e0, ga0 * e1, ga1
    if code == CUSICK:
        # the union of the disc (its top edge rounded by er) and the stem below it: the smaller of
        # the two cylinders' distances (exact outside the union, 1-Lipschitz inside; the disc's on a tie)
        rho = math.hypot(d0, d1)
        if rho > 0.0:
            e0, e1 = d0 / rho, d1 / rho
        else:
            e0, e1 = 1.0, 0.0
        t = p[6]
        g, ga0, ga1, _ = _box(rho, (x2 - p[2]) + 0.5 * t, 0.0, p[5] - er, 0.5 * t - er, 0.0, 2)
        g -= er
        hs = p[3] - t  # the stem: from the disc's underside down to the base
        gs, gs0, gs1, _ = _box(rho, (x2 - p[2]) + t + 0.5 * hs, 0.0, p[7], 0.5 * hs, 0.0, 2)
        if gs < g:
            return gs, gs0 * e0, gs0 * e1, gs1
        return g, ga0 * e0, ga0 * e1, ga1
    g, n0, n1, n2 = _box(d0, d1, zc, p[5] - er, p[6] - er, 0.5 * p[3] - er, 3)
    return g - er, n0, n1, n2


@njit(cache=True)
def distances(code, p, x, grid=None):
    """(g (N,), n (N,3)) of the points x (N,3)."""
    N = x.shape[0]
    g = np.empty(N)
    n = np.empty((N, 3))
    for i in range(N):
        g[i], n[i, 0], n[i, 1], n[i, 2] = signed_distance(code, p, x[i, 0], x[i, 1], x[i, 2], grid)
    return g, n


@njit(cache=True)
def _stick(mu, kp, kt, x0, x1, x2, n0, n1, n2, a0, a1, a2):
    """Coulomb friction of one node in contact (contact.py): the trial stick force -k_t (I - n n^T)(x - a)
    return-mapped onto |f_t| <= mu k p.  (f_t (3), slipped)."""
    if a0 != a0:  # first touch: the anchor is where the node is
        a0, a1, a2 = x0, x1, x2
    d0, d1, d2 = x0 - a0, x1 - a1, x2 - a2
    dn = d0 * n0 + d1 * n1 + d2 * n2
    f0, f1, f2 = -kt * (d0 - dn * n0), -kt * (d1 - dn * n1), -kt * (d2 - dn * n2)
    fmax = mu * kp
    mag = math.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
    if mag > fmax:
        c = fmax / mag
        return f0 * c, f1 * c, f2 * c, True
    return f0, f1, f2, False


@njit(cache=True)
def body_forces(code, p, offset, mu, x, k, kt, anchor, f, ft, new, g_in, n_in, grid=None):
    """One body on the points x (N,3), node stiffnesses k, kt (N,): the penalty force k p n plus,
    when mu > 0, the friction force into f (N,3) (added); friction forces ft (N,3) and the new
    anchors ``new`` (N,3; NaN off contact) written when mu > 0 (``anchor``: the previous ones, NaN
    where a node was not in contact).  A body of code < 0 (a user's own RigidBody) gives its signed
    distances and normals in g_in (N,), n_in (N,3).  Returns (penalty energy 1/2 sum k p^2, stick
    energy 1/2 sum |f_t|^2 / k_t, nodes in contact, slipping nodes, deepest |f_n| / k)."""
    return node_forces(code, p, offset, mu, x, k, kt, anchor, f, ft, new, g_in, n_in, _G0, _G0, grid)


@njit(cache=True)
def node_forces(code, p, offset, mu, x, k, kt, anchor, f, ft, new, g_in, n_in, fx, shift, grid=None):
    """:func:`body_forces` with ``fx`` (N,) the normal load the face points of the node's elements
    carry on it (contact_faces.face_pass; empty: none): it adds to the node's Coulomb limit, and a
    node with fx > 0 sticks or slips even when the node itself is just off the body (its face is on it);
    ``shift`` (N,): the nodes' augmented-Lagrangian shifts lambda / k (contact_augment.py; empty:
    none): the penetration counts from offset + shift."""
    en = 0.0
    et = 0.0
    nact = 0
    nslip = 0
    pen = 0.0
    extra = fx.size > 0
    shifted = shift.size > 0
    for i in range(x.shape[0]):
        if code < 0:
            g, n0, n1, n2 = g_in[i], n_in[i, 0], n_in[i, 1], n_in[i, 2]
        else:
            g, n0, n1, n2 = signed_distance(code, p, x[i, 0], x[i, 1], x[i, 2], grid)
        si = shift[i] if shifted else 0.0
        pi = max(-(g - offset) + si, 0.0)
        kp = k[i] * pi
        fn0, fn1, fn2 = kp * n0, kp * n1, kp * n2
        fxi = fx[i] if extra else 0.0
        if mu > 0.0:
            ft[i, 0] = ft[i, 1] = ft[i, 2] = 0.0
            new[i, 0] = new[i, 1] = new[i, 2] = np.nan
        if pi > 0.0:
            en += kp * pi
            nact += 1
            pen = max(pen, math.sqrt(fn0 * fn0 + fn1 * fn1 + fn2 * fn2) / k[i] - si)  # the depth, not the shifted one
        if mu > 0.0 and (pi > 0.0 or fxi > 0.0):
            t0, t1, t2, slip = _stick(
                mu, kp + fxi, kt[i], x[i, 0], x[i, 1], x[i, 2], n0, n1, n2, anchor[i, 0], anchor[i, 1], anchor[i, 2]
            )
            ft[i, 0], ft[i, 1], ft[i, 2] = t0, t1, t2
            new[i, 0], new[i, 1], new[i, 2] = x[i, 0] + t0 / kt[i], x[i, 1] + t1 / kt[i], x[i, 2] + t2 / kt[i]
            et += (t0 * t0 + t1 * t1 + t2 * t2) / kt[i]
            nslip += slip
            fn0, fn1, fn2 = fn0 + t0, fn1 + t1, fn2 + t2
        f[i, 0] += fn0
        f[i, 1] += fn1
        f[i, 2] += fn2
    return 0.5 * en, 0.5 * et, nact, nslip, pen


@njit(cache=True)
def contact_pass(codes, params, offsets, mus, X0, D, nodes, k, kt, anchors, new, C, FT, fx, Ff, shift, grid=None):
    """Every body (each of code >= 0) on the mid-surface nodes ``nodes`` (ascending) of the sheet at D (6N,): their
    contact forces plus the face points' Ff (N,3) (contact_faces.face_pass; empty: none) into C (6N,)
    (the nodes' translation dofs overwritten), the frictional bodies' forces into FT (n_fric,
    len(nodes), 3) and their new anchors into new (n_fric, N, 3) at the nodes (anchors: (n_fric, N,
    3), NaN off contact; fx (n_fric, N): the face points' normal load on the nodes, node_forces;
    shift (n_bodies, N): the augmented-Lagrangian shifts, node_forces; (0, 0): none; grid: the MESH
    bodies' samples, None without one).  Returns (contact energy, stick energy, nodes in contact counted per body, slipping nodes,
    deepest depth |f_n| / k - shift) -- node_forces summed in body order."""
    m = nodes.size
    x = np.empty((m, 3))
    kk = np.empty(m)
    kkt = np.empty(m)
    faces = Ff.shape[0] > 0
    fxj = np.zeros(m if faces else 0)
    shifted = shift.shape[0] > 0
    sj = np.zeros(m if shifted else 0)
    for j in range(m):
        i = nodes[j]
        x[j, 0], x[j, 1], x[j, 2] = X0[i, 0] + D[6 * i], X0[i, 1] + D[6 * i + 1], X0[i, 2] + D[6 * i + 2]
        kk[j] = k[i]
        kkt[j] = kt[i] if kt.size else 0.0
    f = np.zeros((m, 3))
    a = np.empty((m, 3))
    na = np.empty((m, 3))
    ec = et = pen = 0.0
    nact = nslip = 0
    jf = 0
    for b in range(codes.size):
        mu = mus[b]
        if shifted:
            for j in range(m):
                sj[j] = shift[b, nodes[j]]
        if mu > 0.0:
            for j in range(m):
                a[j, 0], a[j, 1], a[j, 2] = anchors[jf, nodes[j], 0], anchors[jf, nodes[j], 1], anchors[jf, nodes[j], 2]
            if faces:
                for j in range(m):
                    fxj[j] = fx[jf, nodes[j]]
            e1, e2, n1, n2, pb = node_forces(
                codes[b], params[b], offsets[b], mu, x, kk, kkt, a, f, FT[jf], na, _G0, _N0, fxj, sj, grid
            )
            for j in range(m):
                new[jf, nodes[j], 0], new[jf, nodes[j], 1], new[jf, nodes[j], 2] = na[j, 0], na[j, 1], na[j, 2]
            jf += 1
        else:
            e1, e2, n1, n2, pb = node_forces(
                codes[b], params[b], offsets[b], 0.0, x, kk, kkt, a, f, a, a, _G0, _N0, _G0, sj, grid
            )
        ec += e1
        et += e2
        nact += n1
        nslip += n2
        pen = max(pen, pb)
    for j in range(m):
        o = 6 * nodes[j]
        if faces:
            i = nodes[j]
            C[o], C[o + 1], C[o + 2] = f[j, 0] + Ff[i, 0], f[j, 1] + Ff[i, 1], f[j, 2] + Ff[i, 2]
        else:
            C[o], C[o + 1], C[o + 2] = f[j, 0], f[j, 1], f[j, 2]
    return ec, et, nact, nslip, pen


@njit(cache=True)
def friction_work(FT, nodes, Dn1, Dp):
    """sum over the frictional bodies and ``nodes`` of f_t . (x_n+1 - x_n-1): the scheme's central
    rule for the work of friction (times 2)."""
    s = 0.0
    for b in range(FT.shape[0]):
        for j in range(nodes.size):
            o = 6 * nodes[j]
            s += (
                FT[b, j, 0] * (Dn1[o] - Dp[o])
                + FT[b, j, 1] * (Dn1[o + 1] - Dp[o + 1])
                + FT[b, j, 2] * (Dn1[o + 2] - Dp[o + 2])
            )
    return s
