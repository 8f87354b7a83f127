"""Contact on element faces: points inside each element that touch the rigid bodies like the nodes do.

Why
---
With contact on the nodes only, a body passes between them: a flat element of size L resting with
its nodes on a sphere of radius R has its centre L^2 / (8 R) inside (0.025 cm for L = 1 cm, R =
5 cm: 42 % of the wool's thickness; measured on the sphere scene 16x16: face points 0.18 cm deep).

Which points
------------
Every element carries n_e x n_e *face points*: on a quad the centres of its n_e x n_e sub-cells in
(xi, eta), on a triangle the centroids of the n_e^2 sub-triangles of its n_e-fold subdivision.  A
face point lies on the mid-surface, x_q = sum_a N_a(xi_q) x_a (the element's shape functions N_a at
the point, x_a = X_a + U_o,a), and meets the bodies exactly as a node does (``contact.py``):
penetration p_q = max(0, offset - g(x_q)), penalty energy 1/2 k_q p_q^2, force k_q p_q n on the
point, which acts on the element's nodes as N_a(xi_q) k_q p_q n (the virtual work of the point
force: exactly minus the gradient of the energy in the node positions).  The nodes keep their own
contact, so the free edges and the corners are covered too.  This is the "face quadrature points
with shape-function-distributed forces" scheme of the segment-based penalty contacts (LS-DYNA's
SOFT=2, Abaqus's surface-to-surface discretisation) with the rigid body as master.

How many: n_e = max(n, ceil(L_e / s)), at most MAX_FACE_POINTS, with n = ``contact_face_points``
(default 3), L_e the element's longest edge and s the spacing at which a flat patch between points
resting on the body's most curved smooth face (radius rho, the bodies' ``curvature_radius``) dips
at most half the tolerance into it: s^2 / (8 rho) = tol / 2 (:func:`spacing`).  Sharp edges are not
counted (rho = 0 would ask for infinitely many points): where a sheet lies over a sharp edge, the
edge can poke between points by up to ~(s / 2) sin(turn / 2); the default pedestal's sharp top edge
is under the clamped rim itself.  The choice (against nodes only, a fixed n, and a deepest-point
search that was tried and dropped: its nonsmooth energy stalled relaxations) is measured in
docs/contact.md.

Stiffness
---------
A face point stands for 1/n_e^2 of its element's area A_e; its stiffness is k_q = (A_e / n_e^2) *
kappa_e, kappa_e the mean over the element's nodes of k_a / A_a (the nodes' penalty stiffness per
unit of their lumped area).  With the explicit rule k_a = factor m_a omega^2 (m_a = mu A_a) that is
k_q = factor (mu A_e / n_e^2) omega^2: the point's own mass share times the same factor.  The
points' Hessian sum_q k_q N_q N_q^T n n^T has, by the row-sum (Gershgorin) bound with N >= 0, its
largest eigenvalue relative to the lumped mass at most max_a (sum_q k_q N_a(xi_q)) / m_a:
:func:`FacePoints.node_stiffness` gives these row sums, which the critical time step adds to the
nodes' own k (``stepcontrol``).  Friction stays on the nodes (their stick springs, ``contact.py``);
the normal force a face point carries adds N_a(xi_q) k_q p_q to node a's Coulomb limit, so the
friction capacity of a face is its whole normal load, and the stick springs take the normal
stiffness a node has when its faces lie flat on the body (its own plus its grid share), so that
normal and tangential springs ring in step.

Cost: one compiled pass over the elements near a body (the explicit solver's candidates): per
element and body one distance at its centre, which skips the element when it bounds all its points
off the body (:func:`face_pass`), else n_e^2 distances.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .contact import PENETRATION_TOL, normal_gradient
from .contact_kernels import MESH, MESH_LIPSCHITZ, far_bound, signed_distance
from .errors import InputError

DEFAULT_FACE_POINTS = 3
"""Face points per element edge (n: n^2 per element).  3 is what the measured comparison in
docs/contact.md chose; 0 switches face contact off (nodes only)."""

MAX_FACE_POINTS = 8


def spacing(bodies, h: float) -> float:
    """The face-point spacing s [length] at which a flat patch between points on the bodies' most
    curved smooth face (radius rho = curvature_radius + offset) dips at most half the contact
    tolerance (contact.PENETRATION_TOL h) into it: s = sqrt(4 rho tol); inf without curved faces."""
    rho = [b.curvature_radius + b.offset for b in bodies if b.curvature_radius is not None]
    if not rho:
        return math.inf
    return math.sqrt(4.0 * min(rho) * PENETRATION_TOL * float(h))


def face_points_count(v, name: str = "contact_face_points") -> int:
    """Check a face-point count: an integer in 0..MAX_FACE_POINTS (0: nodes only)."""
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 0 <= int(v) <= MAX_FACE_POINTS:
        raise InputError(f"{name} must be an integer from 0 (nodes only) to {MAX_FACE_POINTS}, got {v!r}")
    return int(v)


def quad_points(n: int) -> np.ndarray:
    """(n^2, 2) parameters (xi, eta) of the quad's face points: the centres of its n x n sub-cells."""
    c = -1.0 + (2.0 * np.arange(n) + 1.0) / n
    return np.column_stack([a.ravel() for a in np.meshgrid(c, c, indexing="ij")])


def tri_points(n: int) -> np.ndarray:
    """(n^2, 2) parameters (s, t) of the triangle's face points (barycentric (1 - s - t, s, t)): the
    centroids of the n^2 sub-triangles of its n-fold subdivision."""
    st = [((i + 1 / 3) / n, (j + 1 / 3) / n) for i in range(n) for j in range(n - i)]
    st += [((i + 2 / 3) / n, (j + 2 / 3) / n) for i in range(n) for j in range(n - 1 - i)]
    return np.array(st)


def shapes(tri: bool, uv) -> np.ndarray:
    """(m, 4) shape-function values at the parameters uv (m, 2): a quad's bilinear N_a(xi, eta), nodes
    counter-clockwise from (-1, -1), or a triangle's barycentric (1 - s - t, s, t) and 0."""
    u, v = np.asarray(uv, float).T
    if tri:
        return np.column_stack([1.0 - u - v, u, v, np.zeros_like(u)])
    return 0.25 * np.column_stack([(1 - u) * (1 - v), (1 + u) * (1 - v), (1 + u) * (1 + v), (1 - u) * (1 + v)])


class FacePoints:
    """The face points of a mesh, element by element (quads first, then triangles): ``nodes`` (P, 4)
    element node indices, ``w`` (P, 4) the shape functions at the points (a triangle's fourth column
    repeats its first node with weight 0), ``elem`` (P,) the element of each point, ``area`` (P,)
    the area each point stands for [length^2]; per element ``conn4`` (E, 4) and ``per_edge`` (E,)
    its n_e, ``longest_edge`` (E,) and ``elem_area`` (E,) [length, length^2] in the reference state.
    ``node_area``: the lumped nodal areas (Model.nodal_areas); ``n``: the least points per element
    edge (0: none at all); ``spacing``: the largest spacing between points [length] (:func:`spacing`;
    inf: n everywhere)."""

    def __init__(self, mesh, node_area, n: int = DEFAULT_FACE_POINTS, spacing: float = math.inf):
        self.n = face_points_count(n)
        X = np.asarray(mesh.nodes, dtype=float)
        blocks = []  # (conn4, tri, areas) of the quads and the triangles
        for conn, A_e, tri in zip((mesh.quads, mesh.tris), mesh.element_areas(), (False, True)):
            conn = np.asarray(conn, dtype=np.int64).reshape(-1, 3 if tri else 4)
            c4 = conn if not tri else np.column_stack([conn, conn[:, 0]])
            blocks.append((c4, np.full(len(c4), tri), np.asarray(A_e, float).reshape(-1)))
        self.conn4 = np.ascontiguousarray(np.concatenate([b[0] for b in blocks]))
        tri = np.concatenate([b[1] for b in blocks])
        A_e = np.concatenate([b[2] for b in blocks])
        xe = X[self.conn4]
        L = np.max(np.linalg.norm(xe - np.roll(xe, -1, axis=1), axis=-1), axis=1)  # the longest edge
        self.longest_edge, self.elem_area = L, A_e
        per = np.full(len(L), self.n, dtype=np.int64)
        if self.n and math.isfinite(spacing) and spacing > 0.0:
            per = np.clip(np.ceil(L / spacing), self.n, MAX_FACE_POINTS).astype(np.int64)
        self.per_edge = per if self.n else np.zeros(len(L), np.int64)
        parts = []  # (element, shape functions (k, 4)) per group of one (kind, n_e)
        for t in (False, True):
            for m in np.unique(self.per_edge[tri == t]):
                if m == 0:
                    continue
                es = np.flatnonzero((tri == t) & (self.per_edge == m))
                N = shapes(t, (tri_points if t else quad_points)(int(m)))
                parts.append((np.repeat(es, len(N)), np.tile(N, (len(es), 1))))
        elem = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, np.int64)
        w = np.concatenate([p[1] for p in parts]) if parts else np.zeros((0, 4))
        order = np.argsort(elem, kind="stable")  # element by element
        self.elem = elem[order]
        self.w = np.ascontiguousarray(w[order])
        self.nodes = np.ascontiguousarray(self.conn4[self.elem])
        k = self.per_edge[self.elem].astype(float) ** 2
        self.area = A_e[self.elem] / k if len(k) else np.zeros(0)
        self.estart = np.searchsorted(self.elem, np.arange(len(self.conn4) + 1)).astype(np.int64)
        self.node_area = np.asarray(node_area, dtype=float)
        self.n_nodes = len(self.node_area)

    def __len__(self) -> int:
        return len(self.w)

    def stiffness(self, k_node) -> np.ndarray:
        """(P,) penalty stiffness of the points from the nodes' (N,) k (module docstring)."""
        k = np.broadcast_to(np.asarray(k_node, dtype=float), (self.n_nodes,))
        A = self.node_area
        kappa = np.where(A > 0.0, k / np.where(A > 0.0, A, 1.0), 0.0)
        used = self.w > 0.0
        kap = np.sum(np.where(used, kappa[self.nodes], 0.0), axis=1) / np.maximum(used.sum(axis=1), 1)
        return np.ascontiguousarray(kap * self.area)

    def node_stiffness(self, k_points) -> np.ndarray:
        """(N,) row sums sum_q k_q N_a(xi_q) of the points' Hessian: its share of the critical step
        per node (module docstring), and what a node's normal stiffness grows by when its faces lie
        flat on a body."""
        out = np.zeros(self.n_nodes)
        np.add.at(out, self.nodes.ravel(), (np.asarray(k_points, float)[:, None] * self.w).ravel())
        return out

    def positions(self, x, points=None) -> np.ndarray:
        """(P, 3) mid-surface positions of the points (or of the points ``points``) for node positions
        x (N, 3)."""
        w, nodes = (self.w, self.nodes) if points is None else (self.w[points], self.nodes[points])
        return np.einsum("pa,pai->pi", w, np.asarray(x, dtype=float)[nodes])

    def near(self, x, body, reach: float):
        """Ascending indices of the points that may lie within ``reach`` of ``body``'s offset surface
        (gap = g - offset < reach) for node positions x (N, 3), or None when the body states no
        Lipschitz bound (then every point may).  The numpy form of :func:`face_pass`'s skip: an
        element's points are convex combinations of its nodes, so they lie within r = max_a |x_a - c|
        of any c, and an L-Lipschitz distance is at least g(c) - L r there; an element whose bound
        exceeds ``reach`` has none of its points in contact."""
        L = body.lipschitz
        if L is None:
            return None
        xe = np.asarray(x, dtype=float)[self.conn4]
        c = xe.mean(axis=1)
        r = np.sqrt(np.max(np.sum((xe - c[:, None]) ** 2, axis=-1), axis=1))
        els = np.flatnonzero(body.penetration(c)[0] - L * r <= reach)
        lo, hi = self.estart[els], self.estart[els + 1]
        counts = hi - lo
        start = np.cumsum(counts) - counts
        return np.repeat(lo - start, counts) + np.arange(int(counts.sum()))


# ---------------------------------------------------------------------- compiled pass (explicit solver)
@njit(cache=True)
def face_pass(codes, params, offsets, mus, X0, D, els, estart, pn, pw, kq, nodes, fx, Ff, shift, reach, grid=None):
    """The face points of the elements ``els`` (ascending; their points estart[e]..estart[e+1]) on
    every body (code >= 0): their forces N_a k p n added into Ff (N, 3) and, per frictional body,
    their normal loads N_a k p into fx (n_fric, N), both zeroed first at ``nodes`` (the nodes of the
    elements are among them).  ``shift`` (n_bodies, P): the points' augmented-Lagrangian shifts
    (contact_augment.py; p counts from offset + shift), (0, 0): none; ``reach`` (n_bodies,): the
    offset plus the body's largest shift (:func:`reach`); ``grid``: the MESH bodies' samples
    (contact_kernels.grid_distance; None without one).  Returns (penalty energy, points in
    contact, deepest penetration).

    An element whose points are all farther than ``reach`` from a body is skipped for it: its points
    are convex combinations of its nodes, so they lie within r = max_a |x_a - c| of the mean c of its
    nodes, and an L-Lipschitz distance is at least g(c) - L r there (L = 1 for the analytic bodies'
    exact distances, sqrt(3) for a MESH body's trilinear one: contact_kernels.MESH_LIPSCHITZ).  Skipped
    points would add nothing, so the sums are those over every point, term for term.  Bodies
    outermost: each body's parameter row is taken once (a row view per point costs more than the
    distance itself)."""
    shifted = shift.shape[0] > 0
    for j in range(nodes.size):
        i = nodes[j]
        Ff[i, 0] = Ff[i, 1] = Ff[i, 2] = 0.0
        for b in range(fx.shape[0]):
            fx[b, i] = 0.0
    en = 0.0
    nact = 0
    pen = 0.0
    xa = np.empty((4, 3))
    jf = 0
    for b in range(codes.size):
        code, p, off, fric, rb = codes[b], params[b], offsets[b], mus[b] > 0.0, reach[b]
        lip = MESH_LIPSCHITZ if code == MESH else 1.0  # x 1.0: the analytic bodies' bound as before, bit for bit
        for je in range(els.size):
            e = els[je]
            q0 = estart[e]
            c0 = c1 = c2 = 0.0
            for a in range(4):
                i = pn[q0, a]
                xa[a, 0] = X0[i, 0] + D[6 * i]
                xa[a, 1] = X0[i, 1] + D[6 * i + 1]
                xa[a, 2] = X0[i, 2] + D[6 * i + 2]
                c0 += 0.25 * xa[a, 0]
                c1 += 0.25 * xa[a, 1]
                c2 += 0.25 * xa[a, 2]
            r2 = 0.0
            for a in range(4):
                r2 = max(r2, (xa[a, 0] - c0) ** 2 + (xa[a, 1] - c1) ** 2 + (xa[a, 2] - c2) ** 2)
            gc = signed_distance(code, p, c0, c1, c2, grid)[0]
            if gc - lip * math.sqrt(r2) > rb:
                continue
            if grid is not None:
                # beyond a mesh body's band its grid holds the band, which bounds nothing: there the
                # kernels' g is at least min(band, g_exact - sqrt(3) spacing), and g_exact at least
                # far_bound(c) - r (contact_mesh.MeshBody.signed_distance)
                if code == MESH and gc >= grid[int(p[7])] > rb:
                    if far_bound(p, grid, c0, c1, c2) - MESH_LIPSCHITZ * p[3] - math.sqrt(r2) > rb:
                        continue
            for q in range(q0, estart[e + 1]):
                # the sum of N_a x_a in node order, as FacePoints.positions takes it
                x0 = x1 = x2 = 0.0
                for a in range(4):
                    wa = pw[q, a]
                    x0 += wa * xa[a, 0]
                    x1 += wa * xa[a, 1]
                    x2 += wa * xa[a, 2]
                g, n0, n1, n2 = signed_distance(code, p, x0, x1, x2, grid)
                sq = shift[b, q] if shifted else 0.0
                pq = off - g + sq
                if pq > 0.0:
                    kp = kq[q] * pq
                    en += kp * pq
                    nact += 1
                    pen = max(pen, pq - sq)  # the depth, not the shifted one
                    for a in range(4):
                        i = pn[q, a]
                        wa = pw[q, a]
                        Ff[i, 0] += wa * kp * n0
                        Ff[i, 1] += wa * kp * n1
                        Ff[i, 2] += wa * kp * n2
                        if fric:
                            fx[jf, i] += wa * kp
        if fric:
            jf += 1
    return 0.5 * en, nact, pen


def reach(bodies, shift) -> np.ndarray:
    """(n_bodies,) how far from each body a face point still feels it: its offset plus its largest
    augmented-Lagrangian shift (``shift`` (n_bodies, P) or empty: none) [length]."""
    off = np.array([b.offset for b in bodies], dtype=float)
    if np.size(shift):
        off = off + np.max(np.asarray(shift, float), axis=1, initial=0.0)
    return off


# ---------------------------------------------------------------------- numpy (static solver, reports)
def contact_terms(faces: FacePoints, bodies, x, k_points, tangent: bool = False, shift=None):
    """Energy, node forces and (optionally) the Hessian of the face points' energy for node positions
    x (N, 3): (energy, F (N, 3) = gradient of the energy [force], entries or None).  ``shift``
    (n_bodies, P): the points' augmented-Lagrangian shifts (contact_augment.py; None or empty: none).  ``entries``:
    (rows, cols, vals) over the translation dofs 6 a + i of the full 6N x 6N matrix, the blocks
    sum_q k_q N_a N_b (n n^T - p_q grad n) of the points in contact (grad n = grad^2 g by central
    differences, contact.normal_gradient: the force turning with the normal as a point slides round
    a curved face or a rim, which the Gauss-Newton tangent k n n^T left out; with it Newton converges
    quadratically to the end on square-on-disc, docs/contact.md section 8)."""
    F = np.zeros((faces.n_nodes, 3))
    entries: tuple = ([], [], [])
    if not len(faces) or not bodies:
        return 0.0, F, entries if tangent else None
    shifted = shift is not None and np.size(shift)
    e = 0.0
    for j, b in enumerate(bodies):
        # only the points of the elements that may reach the body (each point's shift may widen it)
        pts = faces.near(x, b, float(np.max(shift[j], initial=0.0)) if shifted else 0.0)
        xq = faces.positions(x, pts)
        gap, nrm = b.penetration(xq)
        if shifted:
            gap = gap - (shift[j] if pts is None else shift[j][pts])
        act = np.flatnonzero(gap < 0.0)
        if not act.size:
            continue
        p, nn, xp = -gap[act], nrm[act], xq[act]  # xp: the points in contact
        if pts is not None:
            act = pts[act]  # the points' own numbering
        kq, w, nd = np.asarray(k_points, float)[act], faces.w[act], faces.nodes[act]
        e += 0.5 * float(np.sum(kq * p * p))
        np.add.at(F, nd.ravel(), -(w[:, :, None] * ((kq * p)[:, None] * nn)[:, None, :]).reshape(-1, 3))
        if tangent:
            # k (n n^T - p grad n): the exact Hessian (contact.normal_gradient), (A,3,3)
            J = normal_gradient(b, xp)
            blk = kq[:, None, None] * (nn[:, :, None] * nn[:, None, :] - p[:, None, None] * J)
            v = w[:, :, None, None, None] * w[:, None, :, None, None] * blk[:, None, None]  # (A,4,4,3,3)
            ii = np.arange(3)
            r = 6 * nd[:, :, None, None, None] + ii[None, None, None, :, None]
            c = 6 * nd[:, None, :, None, None] + ii[None, None, None, None, :]
            r, c = np.broadcast_arrays(r, c, v)[:2]
            entries[0].append(r.ravel())
            entries[1].append(c.ravel())
            entries[2].append(v.ravel())
    return e, F, entries if tangent else None
