"""Contact on element faces (solidshell/contact_faces.py, issue 36): the face points' forces are the
gradient of their energy, the explicit and static paths agree, and drapes keep every point of their
elements out of the bodies -- where contact on the nodes alone lets the bodies through.

"Out" is measured by solidshell.penetration (a 5 x 5 lattice per quad including the element's
edges, not the contact's own sub-cell centres) against contact.PENETRATION_TOL = 2 % of h."""

import math

import numpy as np
import pytest

from solidshell import Fabric
from solidshell.contact import PENETRATION_TOL, Pedestal, Sphere
from solidshell.contact_augment import DEFAULT_UPDATES
from solidshell.contact_faces import FacePoints, contact_terms, face_pass, reach, spacing
from solidshell.meshing import build_mesh
from solidshell.model import Model
from solidshell.penetration import check
from solidshell.problem import Problem
from solidshell.solvers import get

G0 = 980.665
H = Fabric.wool().thickness
TOL = PENETRATION_TOL * H


def _sheet(n, size, z=0.0):
    mesh = build_mesh("square", f"{n}x{n}", size=size)
    mesh.nodes[:, 2] += z
    return mesh


def test_face_points_partition_each_element():
    """Weights are a partition of unity, the points' areas sum to the element's, the stiffness per
    area is the nodes' (k_a / A_a), and the row sums (the critical step's share) are the nodes'
    own k on a uniform mesh with one point per sub-cell (sum_q N_a(xi_q) = n^2 / 4 per quad)."""
    mesh = _sheet(4, 4.0)
    A = np.ones(mesh.n_nodes)  # unit nodal areas: kappa = k
    fp = FacePoints(mesh, A, 3)
    assert len(fp) == 9 * 16 and np.all(fp.per_edge == 3)
    np.testing.assert_allclose(fp.w.sum(axis=1), 1.0, rtol=0, atol=1e-15)
    per_elem = np.bincount(fp.elem, weights=fp.area)
    np.testing.assert_allclose(per_elem, 1.0, rtol=1e-14)  # 16 unit squares
    kq = fp.stiffness(np.full(mesh.n_nodes, 2.0))
    np.testing.assert_allclose(kq, 2.0 / 9.0, rtol=1e-14)  # kappa 2 x area 1/9
    rows = fp.node_stiffness(kq)
    inner = np.flatnonzero((np.abs(mesh.nodes[:, :2]) < 1.9).all(axis=1))
    np.testing.assert_allclose(rows[inner], 2.0, rtol=1e-14)  # 4 quads x 9 points x N_a / 9 ... = k


def test_spacing_from_the_bodies_curvature():
    """n_e grows where the body is curved: a flat patch between points dips s^2 / (8 rho) = tol / 2."""
    sph = Sphere((0, 0, -5.0), 5.0, offset=H / 2)
    s = spacing([sph], H)
    assert s**2 / (8 * (5.0 + H / 2)) == pytest.approx(0.5 * TOL, rel=1e-12)
    box = Pedestal((0, 0, 0), half_widths=(1.0, 1.0))
    assert spacing([box], H) == math.inf  # flat faces, sharp edges: the least n everywhere
    fp = FacePoints(_sheet(4, 4.0), np.ones(25), 3, s)
    assert np.all(fp.per_edge == min(8, math.ceil(1.0 / s)))


def _face_pass(mesh, fp, bodies, x, kq, shift):
    """The explicit solver's compiled face_pass on every element and node at node positions x:
    (energy, points in contact, deepest penetration, Ff (N, 3), fx (n_frictional, N)); fx starts as
    NaN, so that a load left unset shows."""
    D = np.zeros(6 * len(x))
    D.reshape(-1, 6)[:, :3] = x - mesh.nodes
    n_fric = sum(b.friction > 0.0 for b in bodies)
    Ff, fx = np.zeros((len(x), 3)), np.full((n_fric, len(x)), np.nan)
    ec, nact, pen = face_pass(
        np.array([b.code for b in bodies]),
        np.array([b.params for b in bodies]),
        np.array([b.offset for b in bodies]),
        np.array([b.friction for b in bodies]),
        np.ascontiguousarray(mesh.nodes),
        D,
        np.arange(len(fp.conn4)),
        fp.estart,
        fp.nodes,
        fp.w,
        kq,
        np.arange(len(x)),
        fx,
        Ff,
        shift,
        reach(bodies, shift),
    )
    return ec, nact, pen, Ff, fx


def test_forces_are_the_gradient_and_both_paths_agree():
    """contact_terms' F is dE/dx (central differences, 1e-6 relative: the FD error of a quadratic
    penalty is round-off), its tangent is symmetric, and the explicit solver's compiled face_pass
    gives the same energy and forces (1e-12 relative: the same sums in another order)."""
    mesh = _sheet(4, 4.0)
    rng = np.random.default_rng(7)
    x = mesh.nodes + 0.02 * rng.standard_normal(mesh.nodes.shape)
    body = Sphere((0.3, -0.2, -5.0), 5.05)
    fp = FacePoints(mesh, np.ones(mesh.n_nodes), 3)
    kq = fp.stiffness(np.full(mesh.n_nodes, 10.0))
    e, F, (r, c, v) = contact_terms(fp, [body], x, kq, tangent=True)
    assert e > 0.0
    G = np.zeros_like(F)
    eps = 1e-6
    for i in range(len(x)):
        for j in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, j] += eps
            xm[i, j] -= eps
            G[i, j] = (contact_terms(fp, [body], xp, kq)[0] - contact_terms(fp, [body], xm, kq)[0]) / (2 * eps)
    assert np.abs(G - F).max() < 1e-6 * np.abs(F).max()
    import scipy.sparse as sp

    K = sp.coo_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=(6 * len(x),) * 2).toarray()
    assert np.abs(K - K.T).max() < 1e-14 * np.abs(K).max()
    ec, nact, pen, Ff, _ = _face_pass(mesh, fp, [body], x, kq, np.zeros((0, 0)))
    assert ec == pytest.approx(e, rel=1e-12) and nact > 0
    np.testing.assert_allclose(Ff, -F, rtol=0, atol=1e-12 * np.abs(F).max())
    assert pen == pytest.approx(-np.min(body.penetration(fp.positions(x))[0]), rel=1e-12)


def test_the_compiled_pass_skips_far_elements_exactly():
    """face_pass skips an element whose points are all beyond a body's reach (the bound g(c) - r of
    contact_faces.face_pass); the sums must stay those over every point.  Two bodies, one
    frictional, and augmented-Lagrangian shifts (which widen the reach): energy, point count, depth,
    forces and normal loads against the numpy contact_terms on every point (1e-12 relative: the same
    terms in another order) -- on a sheet with most elements far from both bodies."""
    mesh = _sheet(10, 10.0)
    rng = np.random.default_rng(3)
    x = mesh.nodes + 0.02 * rng.standard_normal(mesh.nodes.shape)
    fp = FacePoints(mesh, np.ones(mesh.n_nodes), 3)
    # a small ball under one point next to an element's corner: its element's centre is ~0.4 cm off
    # the ball, but the corner point is in: only the full bound g(c) - r keeps the element
    q = int(np.argmin(np.linalg.norm(fp.positions(x)[:, :2] - (0.1, 0.1), axis=1)))
    ball = fp.positions(x)[q] - (0.0, 0.0, 0.09)
    bodies = [
        Sphere((3.0, 3.0, -2.0), 2.03, offset=0.02, friction=0.3),
        Sphere((-4.0, -4.0, -1.0), 1.01),
        Sphere(ball, 0.1),
    ]
    kq = fp.stiffness(np.full(mesh.n_nodes, 10.0))
    shift = np.zeros((3, len(fp)))
    shift[:, ::7] = 0.05  # some points feel a body 0.05 beyond its offset
    e, F = 0.0, np.zeros_like(x)
    for j, b in enumerate(bodies):
        ej, Fj, _ = contact_terms(fp, [b], x, kq, shift=shift[j : j + 1])
        e, F = e + ej, F + Fj
    xq = fp.positions(x)
    gaps = np.array([b.penetration(xq)[0] - s for b, s in zip(bodies, shift)])
    fx_ref = np.zeros(len(x))  # the frictional body's normal loads sum_q N_a k_q p_q
    np.add.at(fx_ref, fp.nodes.ravel(), (fp.w * (kq * np.maximum(-gaps[0], 0.0))[:, None]).ravel())
    ec, nact, pen, Ff, fx = _face_pass(mesh, fp, bodies, x, kq, shift)
    assert nact == np.count_nonzero(gaps < 0.0) > 0
    assert np.count_nonzero((gaps < 1.0).any(axis=0)) < len(fp) / 2  # most points far: the skip is exercised
    assert ec == pytest.approx(e, rel=1e-12)
    np.testing.assert_allclose(Ff, -F, rtol=0, atol=1e-12 * np.abs(F).max())
    np.testing.assert_allclose(fx[0], fx_ref, rtol=1e-12, atol=1e-12 * fx_ref.max())
    raw = np.array([b.penetration(xq)[0] for b in bodies])
    assert pen == pytest.approx(np.max(np.where(gaps < 0.0, -raw, 0.0)), rel=1e-12)


def test_static_terms_skip_far_elements_bit_for_bit():
    """contact_terms (the static solver's) evaluates only the points of elements that may reach a
    body (FacePoints.near: the bound g(c) - L r with the body's Lipschitz constant, widened by the
    largest shift).  Energy, forces and tangent entries must be the same bits as over every point (the
    same body without a Lipschitz bound): the skipped points are all out of contact, so the same
    active points are summed in the same order.  The ball under one corner point makes the full
    bound necessary; the shifts on every 3rd point widen the reach (1 cm: points 0.5-1 cm off
    a body are in contact only through them)."""
    import copy

    mesh = _sheet(10, 10.0)
    rng = np.random.default_rng(5)
    x = mesh.nodes + 0.02 * rng.standard_normal(mesh.nodes.shape)
    fp = FacePoints(mesh, np.ones(mesh.n_nodes), 3)
    q = int(np.argmin(np.linalg.norm(fp.positions(x)[:, :2] - (0.1, 0.1), axis=1)))
    bodies = [
        Sphere((3.0, 3.0, -2.0), 2.03, offset=0.02),
        Pedestal((-4.0, -4.0, -0.01), radius=2.0, height=3.0),
        Sphere(fp.positions(x)[q] - (0.0, 0.0, 0.09), 0.1),
    ]
    unbounded = [copy.copy(b) for b in bodies]
    for b in unbounded:
        b.lipschitz = None
    kq = fp.stiffness(np.full(mesh.n_nodes, 10.0))
    shift = np.zeros((3, len(fp)))
    shift[:, ::3] = 1.0
    gaps = np.array([b.penetration(fp.positions(x))[0] for b in bodies])
    assert np.any((gaps > 0.5) & (gaps < shift))  # points only a shift brings into contact
    assert len(fp.near(x, bodies[0], 1.0)) < len(fp) / 2  # the skip is exercised
    for sh in (None, shift):
        e, F, (r, c, v) = contact_terms(fp, bodies, x, kq, tangent=True, shift=sh)
        e0, F0, (r0, c0, v0) = contact_terms(fp, unbounded, x, kq, tangent=True, shift=sh)
        assert e == e0 > 0.0
        assert np.array_equal(F, F0)
        for a, a0 in zip((r, c, v), (r0, c0, v0)):
            assert len(a) == len(a0) == 3 and all(np.array_equal(u, u0) for u, u0 in zip(a, a0))


@pytest.mark.parametrize("body", ["rim", "sphere"])
def test_static_contact_tangent_is_the_hessian(body, monkeypatch):
    """The static solver's contact tangent (nodes and face points) is the Hessian of its penalty
    energy: k (n n^T - p grad n) per point, grad n by central differences of the normals
    (contact.normal_gradient).  Against central differences of the contact gradient on a sheet
    pressed over a sharp pedestal rim (grad n = (I - n n^T - t t^T) / d at distance d ~ h / 2 from
    the edge) and into a sphere: within 1e-6 of the largest entry (measured 2e-11 and 9e-11: the
    difference quotients' round-off and truncation).  The Gauss-Newton tangent k n n^T it replaced is
    off by 5e-3 and 1.3e-2 of it there (asserted > 1e-4, so that the check tells the two apart)."""
    from solidshell.solvers.static.system import System

    mesh = _sheet(5, 3.0)
    x0 = mesh.nodes.copy()
    if body == "rim":
        x0[:, 0] += 1.8  # the sheet's middle over the edge of an r = 2 cm cylinder, sloping down past it
        x0[:, 2] += 0.025 - 0.1 * np.maximum(x0[:, 0] - 2.0, 0.0)
        b = Pedestal((0.0, 0.0, 0.0), radius=2.0, height=3.0, offset=H / 2)
    else:
        b = Sphere((0.0, 0.0, -2.0), 2.0 + H / 2 + 0.01, offset=H / 2)
    model = Model(mesh, Fabric.wool())
    prob = Problem(model, np.zeros((mesh.n_nodes, 6), bool), np.zeros((mesh.n_nodes, 6)), contact=[b])
    sys_ = System(prob.model, prob.fixed, prob.loads, prob.prescribed, prob.contact, 1.0, "cholmod")
    D = np.zeros(6 * mesh.n_nodes)
    D.reshape(-1, 6)[:, :3] = x0 - mesh.nodes
    _, _, blocks, entries = sys_._contact(D, want_tangent=True)
    assert blocks and entries[0]  # nodes and face points in contact
    K = sys_._contact_matrix(blocks, entries).toarray()
    t = np.flatnonzero(np.arange(6 * mesh.n_nodes) % 6 < 3)  # the translations
    G = np.zeros((len(t), len(t)))
    eps = 1e-6
    for j, d in enumerate(t):
        Dp, Dm = D.copy(), D.copy()
        Dp[d] += eps
        Dm[d] -= eps
        G[:, j] = (sys_._contact(Dp)[1][t] - sys_._contact(Dm)[1][t]) / (2 * eps)
    scale = np.abs(G).max()
    assert np.abs(K[np.ix_(t, t)] - G).max() < 1e-6 * scale
    assert np.abs(K - K.T).max() < 1e-12 * scale
    # the Gauss-Newton tangent (grad n taken as 0) is measurably not the Hessian here
    import solidshell.contact_faces as cf
    import solidshell.solvers.static.system as ss

    flat = lambda body, x: np.zeros((len(np.reshape(x, (-1, 3))), 3, 3))  # noqa: E731
    monkeypatch.setattr(cf, "normal_gradient", flat)
    monkeypatch.setattr(ss, "normal_gradient", flat)
    _, _, blocks, entries = sys_._contact(D, want_tangent=True)
    K_gn = sys_._contact_matrix(blocks, entries).toarray()
    assert np.abs(K_gn[np.ix_(t, t)] - G).max() > 1e-4 * scale


def test_normal_gradient_curvature_and_jumps():
    """contact.normal_gradient: on a sphere of radius R at distance g its eigenvalues are 0 (along n)
    and 1 / (R + g) twice (1e-8 relative: central differences); on a box's medial plane, where the
    normal jumps from one face's to another's, it is 0, not a quotient of order 1 / eps."""
    from solidshell.contact import normal_gradient

    sph = Sphere((0.1, -0.2, 0.3), 2.0)
    x = np.array([[0.1, -0.2, 2.8], [1.5, 1.2, 0.3], [-1.0, 0.5, -1.4]])
    r = np.linalg.norm(x - sph.center, axis=1)
    for J, ri in zip(normal_gradient(sph, x), r):
        np.testing.assert_allclose(np.linalg.eigvalsh(J), [0.0, 1 / ri, 1 / ri], atol=1e-8 / ri)
    box = Pedestal((0.0, 0.0, 0.0), half_widths=(1.0, 2.0), height=3.0)
    J = normal_gradient(box, [[0.5, 1.5, -0.5], [0.5, 0.3, -0.2]])  # on the x = y - 1 medial plane; inside
    assert np.all(J == 0.0)


def _drop_on_sphere(n_face, n=8, size=8.0):
    """An n x n wool sheet lying on the top of a R = 2 cm sphere (its lower face touching), relaxed
    under its weight with friction 0.3: it drapes round the sphere."""
    mesh = _sheet(n, size)
    model = Model(mesh, Fabric.wool())
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -model.lumped_mass()[:, 0] * G0
    sph = Sphere((0.0, 0.0, -2.0 - H / 2), 2.0, offset=H / 2, friction=0.3)
    prob = Problem(model, np.zeros((mesh.n_nodes, 6), bool), loads, contact=[sph])
    res = get("relax")(prob, {"contact_face_points": n_face, "mass_scaling": 100.0, "mass_scaling_mode": "director"})
    assert res.converged, res.message
    return check(mesh, res.U, [sph], H)[0], res


def test_coarse_sheet_on_a_sphere_keeps_its_faces_out_further():
    """1 cm elements relaxed onto a 2 cm sphere: contact on the nodes leaves the element faces ~L^2 /
    (8 R) = 0.06 cm (100 % of h) inside; the face points cut that by far more than 5 and keep every
    node out.  Measured with the default augmented-Lagrangian updates (contact_augment.py): 2.9 % of h
    after 1 update (11.8 % with the plain penalty) -- 1 cm faces over R = 2 cm are coarser than any
    paper scene's (docs/contact.md, "What is not met yet"), so asserted is the factor 5 and 5 % of h."""
    nodes_only, _ = _drop_on_sphere(0)
    assert nodes_only["deepest_face_point_cm"] > 10 * TOL  # what contact on the nodes lets through
    faces, res = _drop_on_sphere(3)
    assert faces["nodes_beyond"] == 0, faces
    assert faces["deepest_face_point_cm"] < nodes_only["deepest_face_point_cm"] / 5, (faces, nodes_only)
    assert faces["deepest_face_point_cm"] < 2.5 * TOL, faces
    assert res.info["max_contact_nodes"] > 0


@pytest.mark.parametrize("shape", ["box", "cylinder"])
@pytest.mark.parametrize("edge_radius", [0.0, 0.2])
def test_sheet_over_a_pedestal_edge_face_points_cut_the_edge_through(shape, edge_radius):
    """A 6 x 6 cm sheet (0.5 cm elements) held at its centre on a 2 cm wide pedestal top (its lower
    face on it), solved statically: the overhang folds down over the edge (sharp or rounded).  With
    contact on the nodes only the edge cuts through the elements lying over it; the face points
    keep them out to a fraction of that.  Measured deepest face point in units of h (nodes only ->
    face points with the default augmented-Lagrangian updates): box sharp 1.68 -> 0.179, cylinder
    sharp 1.16 -> 0, box rounded 1.85 -> 0.039, cylinder rounded 1.15 -> 0.077.  The contract's 2 %
    of h is NOT met over an edge on these 0.5 cm elements (a line load on a bilinear face between its
    points; docs/contact.md, "What is not met yet"): asserted is a third of the nodes-only depth and
    0.4 h, above what was measured."""

    from solidshell.solvers.static import solve_static

    mesh = _sheet(12, 6.0, z=H / 2)
    model = Model(mesh, Fabric.wool())
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[np.linalg.norm(mesh.nodes[:, :2], axis=1) < 1e-9] = True
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -model.lumped_mass()[:, 0] * G0
    size = {"half_widths": (1.0, 1.0)} if shape == "box" else {"radius": 1.0}
    ped = Pedestal((0, 0, 0), **size, edge_radius=edge_radius, offset=H / 2, height=3.0)
    deep = {}
    for n in (0, 3):
        res = solve_static(model, fixed, loads, contact=[ped], contact_face_points=n)
        assert res.converged, res.message
        assert (mesh.nodes + res.U[:, :3])[:, 2].min() < -0.5  # it draped over the edge
        deep[n] = check(mesh, res.U, [ped], H)[0]["deepest_face_point_cm"]
    assert deep[3] < deep[0] / 3 and deep[3] < 0.4 * H, deep


def _sheet_on_sphere():
    """The 8 x 8 cm sheet (1 cm quads) on a 2 cm sphere, held as the sphere scene's static run holds
    it ([supports.static]): the mesh's ``centre`` node in-plane and its ``centre_east`` node in y (a
    frictionless drape may turn about the vertical axis, a zero mode of the tangent otherwise).
    Returns (mesh, model, fixed, loads, sphere)."""
    mesh = _sheet(8, 8.0)
    model = Model(mesh, Fabric.wool())
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[mesh.node_sets["centre"], :2] = True
    fixed[mesh.node_sets["centre_east"], 1] = True
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -model.lumped_mass()[:, 0] * G0
    return mesh, model, fixed, loads, Sphere((0.0, 0.0, -2.0 - H / 2), 2.0, offset=H / 2)


def test_a_sheet_resting_on_a_sphere_is_not_predicted_through_it():
    """The flat sheet on the top of a sphere, its centre node held in-plane only: nothing holds it
    vertically but the contact, which is not pressed yet (gap 0: no stiffness), so the tangent at the
    start is singular in the vertical translation.  A linearised load predictor from that tangent
    (shifted to factorise) dropped the whole sheet 1821 cm, through the sphere to where the penalty
    sees no penetration, and each of five attempts then fell for 1000 iterations before a cut-back
    (5908 iterations in all).  No prediction is made from a tangent that is not positive definite:
    the trust region holds the first steps and the sheet lands on the sphere in one load step
    (measured 153 iterations, the same state: smallest tangent eigenvalue 4.2646e-3 before and after).
    Asserted: no cut-back, one load step, fewer than 500 iterations (3x the measured count: the
    trust-region path moves with round-off across BLAS builds), nodes outside the sphere."""
    from solidshell.solvers.static import solve_static

    mesh, model, fixed, loads, sph = _sheet_on_sphere()
    r = solve_static(model, fixed, loads, contact=[sph], contact_face_points=0, contact_augment=0)
    assert r.converged, r.message
    assert r.info["cutbacks"] == 0 and r.info["load_steps"] == 1, r.info
    assert r.info["iterations"] < 500, r.info["iterations"]
    assert r.info["positive_definite"]
    assert check(mesh, r.U, [sph], H)[0]["nodes_beyond"] == 0
    assert (mesh.nodes + r.U[:, :3])[:, 2].min() > -4.0  # hangs on the sphere (R = 2 cm), not below it


def test_static_drape_on_a_sphere_stable_and_faces_out_further():
    """Static solve of a sheet on a sphere, held as the sphere scene holds it (``_sheet_on_sphere``;
    frictionless: a centred drape slides off or turns otherwise): a converged stable minimum
    (positive-definite tangent) with contact on the nodes only, on the face points with the plain
    penalty, and with the augmented-Lagrangian updates (the default).  Measured deepest face point
    (5 x 5 lattice) in units of h: 1.75 (nodes only; chord sag L^2 / (8 R) of the 1 cm elements) ->
    0.055 (face points, penalty k = 1e4 K_sheet) -> 0.027 (4 updates).  Asserted: faces a third as
    deep as nodes only, the updates 1.5 x shallower again and within 2 x the contract (1 cm faces
    over R = 2 cm; the drape above)."""
    from solidshell.solvers.static import solve_static

    mesh, model, fixed, loads, sph = _sheet_on_sphere()
    deep = {}
    for n, updates in ((0, 0), (3, 0), (3, DEFAULT_UPDATES)):
        r = solve_static(model, fixed, loads, contact=[sph], contact_face_points=n, contact_augment=updates)
        assert r.converged, r.message
        assert r.info["positive_definite"]
        deep[n, updates] = check(mesh, r.U, [sph], H)[0]["deepest_face_point_cm"]
    assert r.info["contact_augment_updates"] >= 1
    assert deep[3, 0] < deep[0, 0] / 3, deep
    assert deep[3, DEFAULT_UPDATES] < min(deep[3, 0] / 1.5, 2 * TOL), deep
