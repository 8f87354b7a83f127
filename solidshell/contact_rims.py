"""Contact of the bodies' sharp edges with the sheet's faces (rim-to-face).

Why
---
Face points (contact_faces.py) keep a smooth body out of the element faces, but a *sharp* edge -- the
top rim of a pedestal, the rim of a Cusick support disc -- is a line, and a line pressing across a
flat bilinear face is felt only where a face point happens to lie.  Between the points it pokes into
the face's lower layer: on square-on-disc 30x240 relaxation a 33 x 33 checker lattice found the rim
25.7 % of h into the faces while the 5 x 5 lattice of the contract read 0.9 % (docs/contact.md
section 11).  No density of points on the sheet closes that; the rim's own points have to be tested
against the sheet's faces.

The law
-------
Each sharp convex edge of a body is sampled by *rim points* P_r, fixed in space, at spacing s_r
(:func:`rim_spacing`).  A rim point feels the sheet's mid-surface through the distances d to the
elements' faces (bilinear quad or flat triangle, the closest point x* with parameters clamped to the
element: :func:`closest_on_quad`, :func:`closest_on_tri`), to the sides between two elements and
to the nodes off the sheet's boundary.  With the body's contact offset o (h / 2: the sheet's face
layer) less a slack c = RIM_SLACK PENETRATION_TOL h, a term penetrates by p = o - c - d, and the
rim energy is, by inclusion-exclusion over the sheet's cells (:func:`owners`),

    E_r = sum_faces psi(p) - sum_interior sides psi(p) + sum_interior nodes psi(p),

    psi(p) = k_r p^3 / (6 c)  (0 < p < c),    k_r (p^2 / 2 - c p / 2 + c^2 / 6)  (p >= c),

the improved max approximation of [Li et al. 2023] (convergent IPC; the IPC Toolkit's
NormalCollisions set type IMPROVED_MAX_APPROX, ipctk 1.6): a rim point over a face's interior near
a side has its nearest point on the neighbour's face at that side, at the side's own distance: the
two cancel, and the point is counted once wherever its nearest points lie, continuously.  A plain
sum over the elements counts it twice over every side, a washboard for the sheet sliding over the
rim (measured: the relaxation of square-on-disc 30x240 never came to rest); the minimum over the
elements has forces that jump where the nearest element changes.  psi is C2: its second derivative
rises linearly from 0 to k_r over the slack, so no stiffness jumps where a term comes into contact.
A term's force on the sheet, sign psi'(p) n at x*, n = (x* - P_r) / d, goes to the element's nodes
as N_a(xi*) sign psi'(p) n: minus the gradient of E_r in the node positions (xi* is stationary, so
its variation drops out).  Every term acts whichever side of the body's face x* lies on: a term
left out there would leave its partners of the inclusion-exclusion unbalanced (the face points push
a mid-surface that went through the body's face back out along the body's normal).

The explicit solvers only, and opt-in (``solver.explicit.contact_rims`` / ``solver.relax.contact_rims``
= true).  Measured (docs/contact.md, "Sharp rims"): on square-on-disc 30x240 relaxation they take
the rim's depth in the faces, read on a 17 x 17 / 33 x 33 lattice per element, from 18.5 / 25.7 %
of h to 0.65 / 8.1 %, at 2.9 x the wall time (ten updates, each re-relaxed); on large-square-pedestal
relaxation the updates stall FIRE (its step halved on every uphill reset, down 50 x after five
updates, though the forces are the energy's gradient there; not understood yet), while the plain
rims (``contact_augment = 0``) converge but gain little (5.2 -> 4.8 % of h).  The static solver
does not take them: with the rims its Newton iterations converged linearly, at 0.995 per iteration,
where an element's side rests across a rim point -- a ridge balanced on a point, whose energy falls
as the ridge slides off it sideways (curvature -psi'/d, which a Gauss-Newton tangent leaves out and
an exact one makes indefinite).

Frictionless: friction acts on the nodes (contact_faces.py).

Augmented like the face points (contact_augment.py): a rim point carries a shift s_r >= 0 (a length,
its multiplier over k_r) that raises the offset of all its pairs, p_re = o - c + s_r - d_re, and an
update at a converged state sets s_r <- max(0, s_r + max_e (o - c - d_re)) (:func:`update`).  The
penalty k_r alone lets a rim point sink f / k_r into the faces under its share f of the load: on
square-on-disc 30x240 relaxation 21 % of h at the pedestal's rim with the explicit solver's k
(docs/contact.md, "Sharp rims"); the updates take that up at the same critical step.

Stiffness: a rim point stands for a strip s_r wide across the row of face points it competes with,
k_r = kappa_e s_e s_r, kappa_e the element's penalty stiffness per unit area and s_e its face-point
spacing (so k_r = k_q s_r / s_e, k_q one of its face points' stiffness), taken as one value for the
sheet, the median over its elements (:meth:`Rims.stiffness`).  The critical step adds
the rows of the rim Hessian: an element is crossed by at most (RIM_CROSSING L_e / s_r + 2) rim points
of one edge, each adding k_r N_a <= k_r to a row (:meth:`Rims.node_stiffness`).

Which edges (:func:`rim_points`): a Pedestal with a sharp edge (edge_radius 0) -- a cylinder's top and
base circles, a box's top and base rectangles and its four vertical edges; a CusickSupport -- the
disc's top and underside rims when sharp, the stem's base circle.  A rounded edge is a smooth face
and is the face points' (their spacing follows its radius).  Mesh bodies: their triangle edges are
not sampled (left to the face points; docs/contact.md).

Cost: one compiled pass over the elements near a body (the explicit solver's candidates); per
element the rim points of the hash cells its box (grown by the offset) overlaps
(:func:`rim_pass`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .contact import PENETRATION_TOL, CusickSupport, Pedestal

RIM_SLACK = 0.25
"""A rim point acts where the sheet is nearer it than the body's offset less RIM_SLACK PENETRATION_TOL h
(0.5 % of h): on a face the sheet rests on, the face points hold it shallower than that, and the rim
points along the face's edge stay out of contact instead of hovering at its threshold."""

RIM_CROSSING = 1.5
"""An element's rim points of one edge lie along the edge's chord through the element, at most its
diagonal (sqrt 2 L_e for a square) long: the critical step's bound counts 1.5 L_e / s_r + 2 of them."""


# ---------------------------------------------------------------------- geometry of the edges
def _circle(c, z, R, s) -> np.ndarray:
    n = max(8, math.ceil(2.0 * math.pi * R / s))
    t = 2.0 * math.pi * np.arange(n) / n
    return np.column_stack([c[0] + R * np.cos(t), c[1] + R * np.sin(t), np.full(n, z)])


def _segment(a, b, s, ends=True) -> np.ndarray:
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = max(1, math.ceil(np.linalg.norm(b - a) / s))
    t = np.arange(n + 1) / n if ends else np.arange(1, n) / n
    return a + t[:, None] * (b - a)


def _rectangle(c, z, a, b, s) -> np.ndarray:
    corners = [(c[0] - a, c[1] - b), (c[0] + a, c[1] - b), (c[0] + a, c[1] + b), (c[0] - a, c[1] + b)]
    pts = [_segment((*corners[i], z), (*corners[(i + 1) % 4], z), s)[:-1] for i in range(4)]
    return np.concatenate(pts)


def rim_points(body, s: float) -> np.ndarray:
    """(R, 3) points at spacing <= s along the body's sharp convex edges (module docstring); (0, 3)
    for a body without any (a sphere, a plane, a mesh body, rounded edges)."""
    out = []
    if isinstance(body, Pedestal):
        c, z0 = body.top_center, float(body.top_center[2])
        z1 = z0 - body.height
        if body.kind == "cylinder":
            if body.edge_radius == 0.0:
                out += [_circle(c, z0, body.radius, s), _circle(c, z1, body.radius, s)]
        elif body.edge_radius == 0.0:
            a, b = body.half_widths
            out += [_rectangle(c, z0, a, b, s), _rectangle(c, z1, a, b, s)]
            for dx, dy in ((-a, -b), (a, -b), (a, b), (-a, b)):
                out.append(_segment((c[0] + dx, c[1] + dy, z0), (c[0] + dx, c[1] + dy, z1), s, ends=False))
    elif isinstance(body, CusickSupport):
        c, z0 = body.top_center, float(body.top_center[2])
        if body.edge_radius == 0.0:
            out += [_circle(c, z0, body.radius, s), _circle(c, z0 - body.disc_thickness, body.radius, s)]
        out.append(_circle(c, z0 - body.height, body.stem_radius, s))
    return np.concatenate(out) if out else np.zeros((0, 3))


def rim_spacing(body, h: float, face_spacing: float) -> float:
    """s_r [length]: the face points' finest spacing, and on a circular edge of radius R no more than
    the chord whose sag s^2 / (8 R) is half the contact tolerance (contact_faces.spacing's rule)."""
    radii = []
    if isinstance(body, Pedestal) and body.kind == "cylinder":
        radii.append(body.radius)
    elif isinstance(body, CusickSupport):
        radii += [body.radius, body.stem_radius]
    s = float(face_spacing)
    for R in radii:
        s = min(s, math.sqrt(4.0 * R * PENETRATION_TOL * float(h)))
    return s


def owners(conn4: np.ndarray, tri: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(side_own, node_own), each (E, 4) bool, for the inclusion-exclusion of rim_pass (module
    docstring): side a of element e joins its nodes a and a + 1 (mod 4; a triangle's side 3 joins
    its first node to itself and is no side) and is e's when two elements share it and e is the
    lower-numbered; node a is e's when it is off the sheet's boundary (on no side of one element)
    and e is the lowest-numbered element holding it.  Around an interior node the faces, less the
    interior sides, plus the node count 1; around a boundary node the faces less the interior sides
    do: a rim point then feels the sheet once wherever its nearest points lie."""
    conn4 = np.asarray(conn4, np.int64)
    E = len(conn4)
    nxt = np.roll(conn4, -1, axis=1)
    valid = conn4 != nxt
    n_nodes = int(conn4.max(initial=-1)) + 1
    key = np.minimum(conn4, nxt) * n_nodes + np.maximum(conn4, nxt)
    elem = np.broadcast_to(np.arange(E)[:, None], (E, 4))
    uniq, inv, count = np.unique(key[valid], return_inverse=True, return_counts=True)
    first = np.full(len(uniq), E, np.int64)
    np.minimum.at(first, inv, elem[valid])
    side_own = np.zeros((E, 4), bool)
    side_own[valid] = (count[inv] >= 2) & (first[inv] == elem[valid])
    boundary = np.zeros(n_nodes, bool)
    edge_nodes = np.stack([conn4[valid], nxt[valid]], axis=1)[count[inv] == 1]
    boundary[edge_nodes.ravel()] = True
    holds = np.ones((E, 4), bool)
    holds[np.asarray(tri, bool), 3] = False  # a triangle's fourth node repeats its first
    lowest = np.full(n_nodes, E, np.int64)
    np.minimum.at(lowest, conn4[holds], elem[holds])
    node_own = holds & ~boundary[conn4] & (lowest[conn4] == elem)
    return np.ascontiguousarray(side_own), np.ascontiguousarray(node_own)


class Rims:
    """The rim points of ``bodies`` against the sheet of ``faces`` (contact_faces.FacePoints), h the
    thickness: ``points`` (R, 3), ``body`` (R,) their body, ``spacing`` (R,) their s_r, a hash grid of
    them (``keys``/``order``/``lo``/``cell``/``dims``), ``slack`` c and per body ``offsets`` (its
    contact offset less c), and per element ``conn4``/``tri``, ``side_own``/``node_own``
    (:func:`owners`) and ``s_e``, its face-point spacing."""

    def __init__(self, bodies, faces, h: float):
        per = np.maximum(faces.per_edge, 1).astype(float)
        self.s_e = np.sqrt(faces.elem_area) / per  # each element's face-point spacing
        face_spacing = float(np.min(self.s_e)) if len(self.s_e) else math.inf
        pts, owner, sp = [np.zeros((0, 3))], [np.zeros(0, np.int64)], [np.zeros(0)]
        for j, b in enumerate(bodies):
            s = rim_spacing(b, h, face_spacing)
            P = rim_points(b, s) if math.isfinite(s) else np.zeros((0, 3))
            pts.append(P)
            owner.append(np.full(len(P), j, np.int64))
            sp.append(np.full(len(P), s))
        self.slack = RIM_SLACK * PENETRATION_TOL * float(h)
        self.offsets = np.array([b.offset for b in bodies], dtype=float) - self.slack
        self.points = np.ascontiguousarray(np.concatenate(pts))
        self.body = np.concatenate(owner)
        self.spacing = np.concatenate(sp)
        self.conn4 = faces.conn4
        self.tri = np.ascontiguousarray(faces.conn4[:, 3] == faces.conn4[:, 0])
        self.side_own, self.node_own = owners(faces.conn4, self.tri)
        self.estart = faces.estart
        self.longest_edge = faces.longest_edge
        self.n_nodes = faces.n_nodes
        self._hash(float(np.max(faces.longest_edge)) if len(faces.longest_edge) else 1.0)

    def __len__(self) -> int:
        return len(self.points)

    def _hash(self, cell: float) -> None:
        """Sort the rim points into cells of the elements' largest reference edge (an element's box,
        grown by the offset, then overlaps a few cells; the sheet's elements stretch little)."""
        P = self.points
        self.cell = max(cell, float(np.max(self.spacing, initial=0.0)))
        self.lo = (P.min(axis=0) if len(P) else np.zeros(3)) - self.cell
        ijk = np.floor((P - self.lo) / self.cell).astype(np.int64)
        self.dims = (ijk.max(axis=0) if len(P) else np.zeros(3, np.int64)) + 2
        key = (ijk[:, 0] * self.dims[1] + ijk[:, 1]) * self.dims[2] + ijk[:, 2]
        self.order = np.argsort(key, kind="stable").astype(np.int64)
        self.keys = np.ascontiguousarray(key[self.order])

    def stiffness(self, kq) -> np.ndarray:
        """(E,) k_r of a rim point on each element, from the face points' stiffness kq (P,): one value
        for the whole sheet, the median over the elements of k_q s_r / s_e.  One value, because a rim
        point's nearest element changes as the sheet slides over the edge: a stiffness that changed
        with it would make the energy jump there."""
        s_r = float(np.min(self.spacing)) if len(self.spacing) else 0.0
        first = np.asarray(kq, float)[np.minimum(self.estart[:-1], max(len(kq) - 1, 0))] if len(kq) else 0.0
        k = float(np.median(first * s_r / self.s_e)) if len(self.s_e) else 0.0
        return np.full(len(self.conn4), k)

    def node_stiffness(self, k_elem) -> np.ndarray:
        """(N,) the critical step's row-sum bound of the rim Hessian per node (module docstring)."""
        out = np.zeros(self.n_nodes)
        if not len(self):
            return out
        per = np.asarray(k_elem, float) * (RIM_CROSSING * self.longest_edge / float(np.min(self.spacing)) + 2.0)
        for a in range(4):  # a triangle's fourth node repeats its first: counted once
            col = self.conn4[:, a]
            new = np.ones(len(col), bool) if a == 0 else ~np.any(self.conn4[:, :a] == col[:, None], axis=1)
            np.add.at(out, col[new], per[new])
        return out


# ---------------------------------------------------------------------- compiled pass
@njit(cache=True)
def _clamp01(t):
    return min(1.0, max(0.0, t))


@njit(cache=True)
def closest_on_quad(xa, p0, p1, p2):
    """(squared distance, N (4,)) of the point p to the bilinear quad with corners xa (4, 3),
    N_a(u, v) = (1-u)(1-v), u(1-v), uv, (1-u)v at the closest parameters in [0, 1]^2 (contact_faces's
    counter-clockwise nodes, xi = 2u - 1): the nearer of Gauss-Newton's point on |x(u, v) - p|^2 (the
    parameters clamped) and the exact closest points of the four sides."""
    u = v = 0.5
    for _ in range(30):
        N0, N1, N2, N3 = (1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v
        x0 = N0 * xa[0, 0] + N1 * xa[1, 0] + N2 * xa[2, 0] + N3 * xa[3, 0] - p0
        x1 = N0 * xa[0, 1] + N1 * xa[1, 1] + N2 * xa[2, 1] + N3 * xa[3, 1] - p1
        x2 = N0 * xa[0, 2] + N1 * xa[1, 2] + N2 * xa[2, 2] + N3 * xa[3, 2] - p2
        a = b = c = gu = gv = 0.0
        for k in range(3):
            xu = (1 - v) * (xa[1, k] - xa[0, k]) + v * (xa[2, k] - xa[3, k])
            xv = (1 - u) * (xa[3, k] - xa[0, k]) + u * (xa[2, k] - xa[1, k])
            rk = x0 if k == 0 else (x1 if k == 1 else x2)
            a += xu * xu
            b += xu * xv
            c += xv * xv
            gu += xu * rk
            gv += xv * rk
        det = a * c - b * b
        if det <= 1e-30 * (a * c + 1e-300):
            break
        un = _clamp01(u - (c * gu - b * gv) / det)
        vn = _clamp01(v - (a * gv - b * gu) / det)
        step = abs(un - u) + abs(vn - v)
        u, v = un, vn
        if step < 1e-13:
            break
    N = np.empty(4)
    N[0], N[1], N[2], N[3] = (1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v
    best = _dist2(xa, N, p0, p1, p2)
    # the four sides are segments: their exact closest points (where the minimum lies on the
    # boundary, or Gauss-Newton stopped at a clamped point that is not it)
    return _nearest_side(xa, 4, p0, p1, p2, N, best), N


@njit(cache=True)
def closest_on_tri(xa, p0, p1, p2):
    """(squared distance, N (4,)) of p to the triangle xa[0..2] (N_3 = 0): the plane's projection when
    it falls inside, else the nearest of the three sides."""
    e1 = xa[1] - xa[0]
    e2 = xa[2] - xa[0]
    w0, w1, w2 = p0 - xa[0, 0], p1 - xa[0, 1], p2 - xa[0, 2]
    a = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]
    b = e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]
    c = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]
    f1 = e1[0] * w0 + e1[1] * w1 + e1[2] * w2
    f2 = e2[0] * w0 + e2[1] * w1 + e2[2] * w2
    det = a * c - b * b
    N = np.zeros(4)
    if det > 0.0:
        s = (c * f1 - b * f2) / det
        t = (a * f2 - b * f1) / det
        if s >= 0.0 and t >= 0.0 and s + t <= 1.0:
            N[0], N[1], N[2] = 1.0 - s - t, s, t
            return _dist2(xa, N, p0, p1, p2), N
    return _nearest_side(xa, 3, p0, p1, p2, N, np.inf), N


@njit(cache=True)
def _nearest_side(xa, n, p0, p1, p2, N, best):
    """The squared distance of p to the nearest of the n sides (xa[i], xa[(i + 1) % n]) when below
    ``best``, N then set to its point's shape functions; else ``best``, N unchanged."""
    M = np.zeros(4)
    for i in range(n):
        j = (i + 1) % n
        t = _on_segment(xa, i, j, p0, p1, p2)
        M[:] = 0.0
        M[i], M[j] = 1.0 - t, t
        d2 = _dist2(xa, M, p0, p1, p2)
        if d2 < best:
            best = d2
            N[:] = M
    return best


@njit(cache=True)
def _on_segment(xa, i, j, p0, p1, p2):
    """The parameter t in [0, 1] of the closest point (1 - t) xa[i] + t xa[j] to p."""
    num = den = 0.0
    for k in range(3):
        B = xa[j, k] - xa[i, k]
        pk = p0 if k == 0 else (p1 if k == 1 else p2)
        num += (pk - xa[i, k]) * B
        den += B * B
    return _clamp01(num / den) if den > 0.0 else 0.0


@njit(cache=True)
def _dist2(xa, N, p0, p1, p2):
    d2 = 0.0
    for k in range(3):
        pk = p0 if k == 0 else (p1 if k == 1 else p2)
        d2 += (N[0] * xa[0, k] + N[1] * xa[1, k] + N[2] * xa[2, k] + N[3] * xa[3, k] - pk) ** 2
    return d2


@njit(cache=True)
def rim_pass(
    pts, pbody, keys, order, lo, cell, dims, offsets, X0, D, els, conn4, tri, side_own, node_own, kr, ramp, shift,
    deep, Ff,
):  # fmt: skip
    """The rim points (module docstring) against the elements ``els``: for each element and each rim
    point nearer than ``offsets`` (the bodies' offsets less the slack) to its face (+), to a side it
    owns (-, ``side_own`` (E, 4): side a joins its nodes a and a + 1) or to a node it owns (+,
    ``node_own`` (E, 4)), the term's force sign N_a psi'(p) n added into Ff (N, 3)
    (contact_faces.face_pass zeroed it at the elements' nodes); ``ramp`` is the slack c of the
    penalty psi (:func:`ramped`).  ``shift`` (R,): the rim points' augmented-Lagrangian shifts (size
    0: none), each raising its terms' offset; ``deep`` (R,) (size 0: not wanted): set to each rim
    point's deepest raw penetration o - c - d over the faces within reach (-inf where none is).
    Returns (penalty energy, terms in contact, deepest raw penetration o - c - d of a face)."""
    shifted = shift.size > 0
    reach = 0.0
    for b in range(offsets.size):
        reach = max(reach, offsets[b])
    if shifted:
        top = 0.0
        for r in range(shift.size):
            top = max(top, shift[r])
        reach += top
    if deep.size:
        deep[:] = -np.inf
    xa = np.empty((4, 3))
    i0 = np.empty(3, np.int64)
    i1 = np.empty(3, np.int64)
    mn = np.empty(3)
    mx = np.empty(3)
    M = np.zeros(4)
    en = 0.0
    na = 0
    pen = 0.0
    for je in range(els.size):
        e = els[je]
        for a in range(4):
            i = conn4[e, a]
            for k in range(3):
                xa[a, k] = X0[i, k] + D[6 * i + k]
        for k in range(3):
            mn[k] = min(min(xa[0, k], xa[1, k]), min(xa[2, k], xa[3, k]))
            mx[k] = max(max(xa[0, k], xa[1, k]), max(xa[2, k], xa[3, k]))
            i0[k] = max(0, int(math.floor((mn[k] - reach - lo[k]) / cell)))
            i1[k] = min(dims[k] - 1, int(math.floor((mx[k] + reach - lo[k]) / cell)))
        for ci in range(i0[0], i1[0] + 1):
            for cj in range(i0[1], i1[1] + 1):
                for ck_ in range(i0[2], i1[2] + 1):
                    key = (ci * dims[1] + cj) * dims[2] + ck_
                    q0 = np.searchsorted(keys, key)
                    q1 = np.searchsorted(keys, key, side="right")
                    for q in range(q0, q1):
                        r = order[q]
                        b = pbody[r]
                        off = offsets[b] + shift[r] if shifted else offsets[b]
                        gap2 = 0.0  # the box's distance bounds the element's from below
                        for k in range(3):
                            gk = max(mn[k] - pts[r, k], pts[r, k] - mx[k], 0.0)
                            gap2 += gk * gk
                        if gap2 >= off * off:
                            continue
                        if tri[e]:
                            d2, N = closest_on_tri(xa, pts[r, 0], pts[r, 1], pts[r, 2])
                        else:
                            d2, N = closest_on_quad(xa, pts[r, 0], pts[r, 1], pts[r, 2])
                        de, na, p = _term(1.0, d2, N, xa, pts, r, e, off, conn4, kr, ramp, Ff, na)
                        en += de
                        if p > 0.0:
                            pen = max(pen, p - off + offsets[b])  # the depth, not the shifted one
                        if deep.size and d2 < off * off:
                            deep[r] = max(deep[r], offsets[b] - math.sqrt(d2))
                        for sd in range(4):  # the sides this element owns: minus their terms
                            if not side_own[e, sd]:
                                continue
                            a1 = (sd + 1) % 4
                            t = _on_segment(xa, sd, a1, pts[r, 0], pts[r, 1], pts[r, 2])
                            M[:] = 0.0
                            M[sd], M[a1] = 1.0 - t, t
                            d2 = _dist2(xa, M, pts[r, 0], pts[r, 1], pts[r, 2])
                            de, na, _ = _term(-1.0, d2, M, xa, pts, r, e, off, conn4, kr,
                                              ramp, Ff, na)  # fmt: skip
                            en += de
                        for a in range(4):  # the nodes it owns: plus theirs
                            if not node_own[e, a]:
                                continue
                            M[:] = 0.0
                            M[a] = 1.0
                            d2 = _dist2(xa, M, pts[r, 0], pts[r, 1], pts[r, 2])
                            de, na, _ = _term(1.0, d2, M, xa, pts, r, e, off, conn4, kr,
                                              ramp, Ff, na)  # fmt: skip
                            en += de
    return en, na, pen


@njit(cache=True)
def _term(sign, d2, N, xa, pts, r, e, off, conn4, kr, ramp, Ff, na):
    """One term of rim_pass: the rim point r at squared distance d2 from the point N . xa of element e
    (its face, a side or a node): (energy sign psi(p), terms in contact, p; p = -1 out of contact)."""
    if d2 >= off * off:
        return 0.0, na, -1.0
    d = math.sqrt(d2)
    if d <= 1e-12 * off:
        return 0.0, na, -1.0  # on the mid-surface itself: no direction to push along
    x0 = N[0] * xa[0, 0] + N[1] * xa[1, 0] + N[2] * xa[2, 0] + N[3] * xa[3, 0]
    x1 = N[0] * xa[0, 1] + N[1] * xa[1, 1] + N[2] * xa[2, 1] + N[3] * xa[3, 1]
    x2 = N[0] * xa[0, 2] + N[1] * xa[1, 2] + N[2] * xa[2, 2] + N[3] * xa[3, 2]
    p = off - d
    n0, n1, n2 = (x0 - pts[r, 0]) / d, (x1 - pts[r, 1]) / d, (x2 - pts[r, 2]) / d
    f = ramped(kr[e], p, ramp)
    psi = f[0]
    f = sign * f[1]
    for a in range(4):
        if N[a] != 0.0:
            i = conn4[e, a]
            Ff[i, 0] += N[a] * f * n0
            Ff[i, 1] += N[a] * f * n1
            Ff[i, 2] += N[a] * f * n2
    return sign * psi, na + 1, p


@njit(cache=True)
def ramped(k, p, ramp):
    """(energy, force, stiffness) of the rim penalty at penetration p > 0: k p^3 / (6 ramp) up to
    p = ramp, then k (p^2 / 2 - ramp p / 2 + ramp^2 / 6) -- the plain 1/2 k p^2 shifted, its second
    derivative rising linearly from 0 to k over the ramp, so no stiffness jumps where a term comes
    into contact (module docstring)."""
    if p < ramp:
        return k * p * p * p / (6.0 * ramp), 0.5 * k * p * p / ramp, k * p / ramp
    return k * (0.5 * p * p - 0.5 * ramp * p + ramp * ramp / 6.0), k * (p - 0.5 * ramp), k


NONE = np.zeros(0)
"""No rim shifts (the plain penalty; contact_augment.NONE's counterpart)."""


def pass_args(rims: Rims, X0, D, kr, els=None) -> tuple:
    """rim_pass's arguments up to ``shift`` for the elements ``els`` (ascending; None: every one)."""
    if els is None:
        els = np.arange(len(rims.conn4), dtype=np.int64)
    return (
        rims.points, rims.body, rims.keys, rims.order, rims.lo, rims.cell, rims.dims, rims.offsets,
        np.ascontiguousarray(X0, dtype=float), np.ascontiguousarray(D, dtype=float),
        els, rims.conn4, rims.tri, rims.side_own, rims.node_own, kr, rims.slack,
    )  # fmt: skip


def rim_terms(rims: Rims, X0, D, kr, shift=NONE) -> tuple[float, np.ndarray]:
    """The rim contact at D (6N,) with the rim points' shifts ``shift`` (R,) or NONE: (energy,
    gradient (N, 3) [force]) -- rim_pass over every element, for numpy callers and the tests."""
    Ff = np.zeros((len(X0), 3))
    if not len(rims):
        return 0.0, Ff
    en, _, _ = rim_pass(*pass_args(rims, X0, D, kr), shift, NONE, Ff)
    return en, -Ff


def update(rims: Rims, X0, D, shift=NONE) -> tuple[float, np.ndarray]:
    """One Uzawa update of the rim points' shifts at D (contact_augment.update's rule s <- max(0,
    s + p) per rim point, p its deepest raw penetration o - c - d over its pairs; a point with no
    pair within reach has s + p < 0 and drops to 0): (deepest penetration of the faces' layer o - d
    [length], the new shifts (R,)).  Empty rims: (0, NONE)."""
    if not len(rims):
        return 0.0, NONE
    deep = np.empty(len(rims))
    kr = np.zeros(len(rims.conn4))  # the raw depths only: no forces wanted
    rim_pass(*pass_args(rims, X0, D, kr), shift, deep, np.zeros((len(X0), 3)))
    new = np.maximum(deep + (shift if shift.size else 0.0), 0.0)
    return max(float(deep.max(initial=-np.inf)) + rims.slack, 0.0), np.ascontiguousarray(new)
