"""The sheet against itself in explicit dynamics and relaxation (contact_self_penalty.py): the closest
points against the IPC Toolkit's, the forces against the energy's gradient, the candidate search
against brute force, the Verlet list against a fresh search bit for bit, and drapes whose layers
meet -- two sheets dropped on each other, random drops, a sheet over a thin blade, an undamped
collision's energy balance -- checked by the library's intersection test (layers.py), which shares
no code with the penalty."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from solidshell import Fabric, Model
from solidshell import contact_self_kernels as sk
from solidshell.boundary import gravity_loads
from solidshell.contact import Plane
from solidshell.contact_self_penalty import REST_MIN, SelfPenalty, edges_of, ownership
from solidshell.layers import LAYER_TOL, report, self_intersections, triangles
from solidshell.mesh import ShellMesh
from solidshell.meshing import square, strip
from solidshell.problem import Problem
from solidshell.solvers.explicit import run, run_relax

WOOL = Fabric.wool()
H = WOOL.thickness

coord = st.floats(-2.0, 2.0, allow_nan=False)
point = st.tuples(coord, coord, coord)


# ------------------------------------------------------------------ kernels
@settings(max_examples=300, deadline=None)
@given(p=point, a=point, b=point, c=point)
def test_closest_point_on_a_triangle_matches_ipctk(p, a, b, c):
    """The distance from the closest point's weights equals ipctk's point-triangle distance (an
    independent implementation); 1e-9 relative: both are exact to round-off, and a nearly
    degenerate triangle loses a few digits in either."""
    import ipctk

    P, A, B, C = (np.array(v, dtype=float) for v in (p, a, b, c))
    area = np.linalg.norm(np.cross(B - A, C - A))
    if area < 1e-3:  # a degenerate triangle has no unique closest point
        return
    wa, wb, wc = sk.point_triangle(tuple(P), tuple(A), tuple(B), tuple(C))
    assert min(wa, wb, wc) >= 0.0 and wa + wb + wc == pytest.approx(1.0, abs=1e-12)
    d = np.linalg.norm(P - (wa * A + wb * B + wc * C))
    ref = math.sqrt(ipctk.point_triangle_distance(P, A, B, C))
    assert d == pytest.approx(ref, rel=1e-9, abs=1e-12)


def _two_layers(n=8, gap=0.8 * H, turn=20.0):
    """Two n x n sheets (6 cm and 4 cm) at a gap, the upper turned by ``turn`` degrees: their flat
    reference states 1 cm apart (so that no pair is a neighbour), U puts them ``gap`` apart."""
    a, b = square((n, n), size=6.0), square((n, n), size=4.0)
    th = math.radians(turn)
    R = np.array([[math.cos(th), -math.sin(th), 0], [math.sin(th), math.cos(th), 0], [0, 0, 1]])
    XB = b.nodes @ R.T + [0.3, 0.2, 1.0]
    mesh = ShellMesh(np.vstack([a.nodes, XB]), np.vstack([a.quads, b.quads + a.n_nodes]))
    U = np.zeros((mesh.n_nodes, 6))
    U[a.n_nodes :, 2] = gap - 1.0
    return mesh, U, a.n_nodes


def test_forces_are_minus_the_gradient_of_the_energy():
    """Central differences of the penalty energy against the forces at a crumpled two-layer state;
    tolerance 1e-6 of the largest force: the energy is C1 (its gradient kinks where a pair enters a
    new Voronoi region of its triangle, which random perturbations of 1e-7 rarely straddle)."""
    mesh, U, _ = _two_layers()
    rng = np.random.default_rng(3)
    U[:, :3] += rng.normal(scale=0.2 * H, size=(mesh.n_nodes, 3))
    k = rng.uniform(0.5, 2.0, mesh.n_nodes)
    sp = SelfPenalty(mesh, H, k)
    D = U.ravel().copy()
    C = np.zeros_like(D)
    E, n = sp.add_forces(D, C)
    assert n > 50 and E > 0.0
    eps = 1e-7
    for i in rng.choice(np.flatnonzero(np.any(C.reshape(-1, 6)[:, :3] != 0, axis=1)), 25, replace=False):
        for j in range(3):
            Dp, Dm = D.copy(), D.copy()
            Dp[6 * i + j] += eps
            Dm[6 * i + j] -= eps
            Ep = sp.add_forces(Dp, np.zeros_like(D))[0]
            Em = sp.add_forces(Dm, np.zeros_like(D))[0]
            assert -(Ep - Em) / (2 * eps) == pytest.approx(C[6 * i + j], abs=1e-6 * np.abs(C).max())
    # action and reaction: no net force, no net moment about the origin
    f = C.reshape(-1, 6)[:, :3]
    x = mesh.nodes + U[:, :3]
    assert np.abs(f.sum(axis=0)).max() < 1e-12 * np.abs(f).sum()
    assert np.abs(np.cross(x, f).sum(axis=0)).max() < 1e-10 * np.abs(f).sum()


def test_every_edge_and_corner_has_one_owner():
    mesh = square((5, 7), size=3.0)
    tri = triangles(mesh).astype(np.int64)
    own = ownership(tri, mesh.n_nodes)
    edges: dict = {}
    corners: dict = {}
    for t, (a, b, c) in enumerate(tri):
        for bit, e in enumerate(((a, b), (b, c), (c, a))):
            edges.setdefault(tuple(sorted(e)), []).append(bool(own[t] >> bit & 1))
        for bit, v in enumerate((a, b, c)):
            corners.setdefault(int(v), []).append(bool(own[t] >> (3 + bit) & 1))
    assert all(sum(o) == 1 for o in edges.values()) and all(sum(o) == 1 for o in corners.values())


def _brute_pairs(x, X0, tri, r, rest_min):
    out = set()
    for t, (a, b, c) in enumerate(tri):
        for v in range(len(x)):
            if v in (a, b, c):
                continue
            d = _dist(x, v, a, b, c)
            if d < r and _dist(X0, v, a, b, c) >= rest_min:
                out.add((v, t))
    return out


def _brute_edge_pairs(x, X0, edges, r, rest_min):
    out = set()
    for e in range(len(edges)):
        for f in range(e + 1, len(edges)):
            if set(edges[e]) & set(edges[f]):
                continue
            if _box_gap(x, edges[e], edges[f]) >= r:  # the segments' boxes already r apart
                continue
            if _seg(x, edges[e], edges[f]) < r and _seg(X0, edges[e], edges[f]) >= rest_min:
                out.add((e, f))
    return out


def _box_gap(x, e, f):
    lo1, hi1 = x[e].min(axis=0), x[e].max(axis=0)
    lo2, hi2 = x[f].min(axis=0), x[f].max(axis=0)
    return float(np.linalg.norm(np.maximum(0.0, np.maximum(lo1 - hi2, lo2 - hi1))))


def _seg(x, e, f):
    """Segment distance as the minimum of the convex quadratic |p(s) - q(t)|^2 over the unit square:
    the smallest of its interior stationary point (when it lies inside) and its minima along the
    square's four sides (each a clamped 1-D projection) -- an enumeration of the candidates,
    independent of the kernel's closed form (checked against scipy's bounded minimiser in
    test_the_reference_segment_distance_is_the_minimisers)."""
    p0, p1, q0, q1 = x[e[0]], x[e[1]], x[f[0]], x[f[1]]
    u, v, w = p1 - p0, q1 - q0, p0 - q0

    def d2(s_, t_):
        return float(np.sum((w + s_ * u - t_ * v) ** 2))

    uu, vv, uv, uw, vw = float(u @ u), float(v @ v), float(u @ v), float(u @ w), float(v @ w)
    best = math.inf
    det = uu * vv - uv * uv
    if det > 1e-14 * uu * vv:  # the interior stationary point: uu s - uv t = -uw, uv s - vv t = -vw
        s_, t_ = (uv * vw - vv * uw) / det, (uu * vw - uv * uw) / det
        if 0.0 <= s_ <= 1.0 and 0.0 <= t_ <= 1.0:
            best = d2(s_, t_)
    for t_ in (0.0, 1.0):  # sides t = 0, 1: s minimises |w + s u - t v|^2
        s_ = min(max((t_ * uv - uw) / uu, 0.0), 1.0) if uu > 0.0 else 0.0
        best = min(best, d2(s_, t_))
    for s_ in (0.0, 1.0):  # sides s = 0, 1
        t_ = min(max((vw + s_ * uv) / vv, 0.0), 1.0) if vv > 0.0 else 0.0
        best = min(best, d2(s_, t_))
    return math.sqrt(best)


def test_the_reference_segment_distance_is_the_minimisers():
    """_seg (the brute-force reference of the edge-pair search) on random segment pairs, parallel ones
    and touching ones: never above a 401 x 401 sampling of the unit square nor scipy's bounded
    minimiser (1e-12: _seg's value is attained, so it is never below the true minimum either), and
    within the sampling's bound (|u| + |v|) spacing / 2 of the sampled minimum.  (scipy's L-BFGS-B,
    the reference before from an 11 x 11 sampling, stops up to 3.9e-4 above the minimum on these
    pairs, 2.1e-2 from the square's centre.)"""
    from scipy.optimize import minimize

    rng = np.random.default_rng(11)
    pts = rng.normal(size=(200, 4, 3))
    pts[::7, 3] = pts[::7, 2] + (pts[::7, 1] - pts[::7, 0])  # parallel pairs
    pts[::11, 2] = pts[::11, 0] + 0.5 * (pts[::11, 1] - pts[::11, 0])  # one end on the other segment
    g = np.linspace(0.0, 1.0, 401)
    S, T = np.meshgrid(g, g, indexing="ij")
    for P in pts:
        u, v, w = P[1] - P[0], P[3] - P[2], P[0] - P[2]
        grid = np.sqrt(np.min(np.sum((w + S[..., None] * u - T[..., None] * v) ** 2, axis=-1)))

        def d2(st_, u=u, v=v, w=w):
            s_, t_ = np.clip(st_, 0.0, 1.0)
            return float(np.sum((w + s_ * u - t_ * v) ** 2))

        res = minimize(
            d2, [0.5, 0.5], bounds=[(0, 1), (0, 1)], method="L-BFGS-B", options={"ftol": 1e-15, "gtol": 1e-12}
        )
        d = _seg(P, (0, 1), (2, 3))
        assert d <= min(grid, math.sqrt(res.fun)) + 1e-12
        assert d >= grid - 0.5 * (g[1] - g[0]) * (np.linalg.norm(u) + np.linalg.norm(v))


def _dist(x, v, a, b, c):
    w = sk.point_triangle(tuple(x[v]), tuple(x[a]), tuple(x[b]), tuple(x[c]))
    return float(np.linalg.norm(x[v] - (w[0] * x[a] + w[1] * x[b] + w[2] * x[c])))


@settings(max_examples=10, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), fold=st.floats(0.2, 3.0), noise=st.floats(0.0, 0.5))
def test_the_grid_search_finds_every_pair_brute_force_does(seed, fold, noise):
    """The compiled grids' candidates are exactly the pairs within h + margin (and not neighbours)
    of a brute-force loop over every vertex and triangle and every two edges (their distance by an
    enumeration of the minimiser's candidates, _seg, not the kernel's closed form), on a sheet folded
    over at random."""
    mesh = square((6, 6), size=2.0)
    X0 = np.ascontiguousarray(mesh.nodes)
    rng = np.random.default_rng(seed)
    x = X0.copy()
    right = x[:, 0] > 0.0
    x[right, 0] = -x[right, 0] * math.cos(fold)  # the right half turned about the y axis
    x[right, 2] = X0[right, 0] * math.sin(fold) + 0.1
    x += rng.normal(scale=noise * 0.1, size=x.shape)
    tri = triangles(mesh).astype(np.int64)
    h = 0.1
    r = 3.0 * h
    got = {tuple(p) for p in sk.vf_candidates(np.ascontiguousarray(x), X0, tri, r, REST_MIN * h).tolist()}
    assert got == _brute_pairs(x, X0, tri, r, REST_MIN * h)
    edges = edges_of(tri).astype(np.int64)
    got_ee = {tuple(p) for p in sk.ee_candidates(np.ascontiguousarray(x), X0, edges, r, REST_MIN * h).tolist()}
    assert got_ee == _brute_edge_pairs(x, X0, edges, r, REST_MIN * h)


def test_a_stale_candidate_list_gives_the_forces_of_a_fresh_search_bit_for_bit():
    """The Verlet list: after moves below margin / 2 (about their common part) the forces equal those
    after a new search exactly (the pairs in contact are summed in the same order)."""
    mesh, U, _ = _two_layers()
    rng = np.random.default_rng(5)
    sp = SelfPenalty(mesh, H, 1.0)
    D0 = U.ravel().copy()
    sp.add_forces(D0, np.zeros_like(D0))
    searches = sp.searches
    move = rng.normal(size=(mesh.n_nodes, 3))
    move *= 0.24 * sp.margin / np.linalg.norm(move, axis=1).max()  # within 0.48 margin of any mean
    move += [0.3, -2.0, 5.0]  # and the whole moved far: the common part does not count
    U1 = U.copy()
    U1[:, :3] += move
    D1 = U1.ravel().copy()
    stale, fresh = np.zeros_like(D1), np.zeros_like(D1)
    Es, ns = sp.add_forces(D1, stale)
    assert sp.searches == searches  # no search: nothing moved margin / 2
    sp.search(mesh.nodes + U1[:, :3])
    Ef, nf = sp.add_forces(D1, fresh)
    assert ns == nf > 0 and Es == Ef and np.array_equal(stale, fresh)


# ------------------------------------------------------------------ drapes
def _stack(n=10, drop=1.0, turn=20.0, shift=(0.5, 0.3), self_contact=True):
    """The lower 10 cm sheet resting on a floor, the upper 6 cm sheet ``drop`` cm above it."""
    a, b = square((n, n), size=10.0), square((n, n), size=6.0)
    th = math.radians(turn)
    R = np.array([[math.cos(th), -math.sin(th), 0], [math.sin(th), math.cos(th), 0], [0, 0, 1]])
    XB = b.nodes @ R.T + [shift[0], shift[1], drop]
    mesh = ShellMesh(np.vstack([a.nodes, XB]), np.vstack([a.quads, b.quads + a.n_nodes]))
    model = Model(mesh, WOOL)
    N = mesh.n_nodes
    return Problem(
        model, np.zeros((N, 6), bool), gravity_loads(model), contact=[Plane((0, 0, 0))], self_contact=self_contact
    )


def test_two_sheets_dropped_on_each_other_never_pass_through():
    """Relaxation (FIRE) of a sheet dropped 1 cm onto another on a floor: with self-contact no two
    triangles intersect and the layers rest h apart (within LAYER_TOL h, the contract layers.py
    reports); without it the upper sheet falls through the lower one to the floor, where the two lie
    in one plane (coplanar triangles do not cross: layers.py sees them as layers 0 apart)."""
    on = _stack()
    res = run_relax(on, {"t_max": 1.5})
    rep = report(on.model.mesh, res.U, H)
    assert rep["self_intersections"] == 0
    assert rep["min_layer_gap"] >= (1.0 - LAYER_TOL) * H
    upper = (on.model.mesh.nodes + res.U[:, :3])[11 * 11 :, 2]
    assert upper.min() > (1.0 - LAYER_TOL) * H  # resting on the lower sheet, not on the floor
    assert res.info["self_contact_max_pairs"] > 0 and res.info["self_contact"] == "penalty"
    off = _stack(self_contact=False)
    res_off = run_relax(off, {"t_max": 1.5})
    rep_off = report(off.model.mesh, res_off.U, H)
    assert rep_off["layer_pairs_close"] > 100  # the layers within 0.9 h of each other ...
    assert (off.model.mesh.nodes + res_off.U[:, :3])[11 * 11 :, 2].min() < 0.1 * H  # ... on the floor


@settings(max_examples=4, deadline=None)
@given(drop=st.floats(0.2, 2.0), turn=st.floats(0.0, 90.0), sx=st.floats(-1.5, 1.5), sy=st.floats(-1.5, 1.5))
def test_random_drops_never_end_through_each_other(drop, turn, sx, sy):
    """Property: whatever the height, angle and place of the drop, the relaxed stack has no
    intersecting triangle pair (the penalty's failure rate on drapes: measured 0 in these and in
    the 20 drops of benchmarks/self_contact_cost.py)."""
    prob = _stack(n=8, drop=drop, turn=turn, shift=(sx, sy))
    res = run_relax(prob, {"t_max": 1.0})
    assert len(self_intersections(prob.model.mesh, res.U)) == 0


def _folded(self_contact):
    """A 20 x 3 cm strip on a floor, its right half wrapped 170 degrees round a 1 cm radius and laid
    back over its left half (a smooth start: positions and directors of the wrap): gravity folds it
    onto itself."""
    m = strip((60, 4), length=20.0, width=3.0)
    X = m.nodes.copy()
    X[:, 0] -= 10.0
    mesh = ShellMesh(X, m.quads)
    model = Model(mesh, WOOL)
    th, R0 = math.radians(170), 1.0
    s = np.maximum(X[:, 0], 0.0)  # arc length from the hinge
    phi = np.minimum(s / R0, th)
    rest = s - phi * R0  # beyond the wrap: straight
    U0 = np.zeros((mesh.n_nodes, 6))
    U0[:, 0] = R0 * np.sin(phi) + rest * np.cos(phi) - s
    U0[:, 2] = R0 * (1 - np.cos(phi)) + rest * np.sin(phi)
    U0[:, 3], U0[:, 5] = -np.sin(phi), np.cos(phi) - 1.0  # the director turned with the wrap
    N = mesh.n_nodes
    prob = Problem(
        model, np.zeros((N, 6), bool), gravity_loads(model), contact=[Plane((0, 0, 0))], self_contact=self_contact
    )
    res = run_relax(prob, {"t_max": 2.5, "U0": U0})
    return report(mesh, res.U, H)


def test_a_sheet_folded_onto_itself_by_gravity_keeps_its_layers_apart():
    """The upper half falls onto the lower: with self-contact no triangles cross and the layers rest
    a thickness apart (within LAYER_TOL h); without it the upper half passes into the lower
    (intersecting pairs; measured 130)."""
    on = _folded(True)
    assert on["self_intersections"] == 0 and on["min_layer_gap"] >= (1.0 - LAYER_TOL) * H
    off = _folded(False)
    assert off["self_intersections"] > 0


def test_an_undamped_frictionless_collision_keeps_its_energy():
    """Two sheets in free flight (no gravity) meet at 20 cm/s, undamped explicit dynamics: the
    energy balance (ledger.py: kinetic + strain + contact = initial) holds to 1 %, the solver's
    own measure, and the sheets part again (the penalty is elastic)."""
    mesh, U, na = _two_layers(n=8, gap=1.5 * H)
    model = Model(mesh, WOOL)
    N = mesh.n_nodes
    V0 = np.zeros((N, 6))
    V0[:na, 2], V0[na:, 2] = 10.0, -10.0
    prob = Problem(model, np.zeros((N, 6), bool), np.zeros((N, 6)), self_contact=True)
    res = run(prob, {"t_end": 0.01, "alpha": 0.0, "V0": V0, "U0": U})
    assert res.info["self_contact_max_pairs"] > 0
    assert res.info["energy_balance_error"] < 0.01
    x = mesh.nodes + res.U[:, :3]
    assert x[na:, 2].min() > x[:na, 2].max()  # still apart, upper above lower
    assert len(self_intersections(mesh, res.U)) == 0
