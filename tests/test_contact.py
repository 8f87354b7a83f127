"""Penalty contact bodies: forces are minus the gradient of the penalty energy, vanish outside the
body, respect symmetry, and the stiffness / time-step rules hold."""

import math

import numpy as np
import pytest

from solidshell.contact import (
    Pedestal,
    Plane,
    RigidBody,
    Sphere,
    combined_critical_time_step,
    contact_critical_time_step,
    contact_forces,
    penalty_stiffness,
)
from solidshell.errors import InputError

BODIES = {
    "sphere": Sphere((0.1, -0.2, 0.3), 2.0),
    "sphere_offset": Sphere((0.0, 0.0, 0.0), 2.0, offset=0.03),
    "plane": Plane((0.0, 0.0, -1.0), (0.2, 0.1, 1.0)),
    "cylinder": Pedestal((0.0, 0.0, 0.0), radius=1.5, height=3.0),
    "cylinder_round": Pedestal((0.0, 0.0, 0.0), radius=1.5, height=3.0, edge_radius=0.3),
    "box": Pedestal((0.0, 0.0, 0.0), half_widths=(1.0, 1.5), height=3.0),
    "box_round": Pedestal((0.0, 0.0, 0.0), half_widths=(1.0, 1.5), height=3.0, edge_radius=0.2),
}


def _points_near_surface(body, rng, n=200):
    """Random points within +-0.2 of the body's surface (so that about half penetrate)."""
    x = rng.uniform(-2.5, 2.5, size=(4 * n, 3))
    g, nrm = body.signed_distance(x)
    x = x - (g - body.offset)[:, None] * nrm + rng.uniform(-0.2, 0.2, size=(4 * n, 1)) * nrm
    return x[:n]


@pytest.mark.parametrize("name", sorted(BODIES))
def test_force_is_minus_gradient_of_energy(name):
    body = BODIES[name]
    rng = np.random.default_rng(1)
    x = _points_near_surface(body, rng)
    k = rng.uniform(50.0, 150.0, size=len(x))
    f, _ = body.forces(x, k)
    assert np.any(np.linalg.norm(f, axis=1) > 0), "no point in contact: test set-up is wrong"
    # central differences, one coordinate at a time, vectorised over the points (each point's
    # energy depends on that point only).  Step 1e-6: truncation O(h^2 * k) ~ 1e-10, round-off
    # ~ 1e-16 * E / h ~ 1e-9; tolerance 1e-5 relative to k*0.2 (the largest force) is far above both
    # and far below any real error.  Points within 1e-4 of a kink of the signed distance (medial
    # planes inside a box, the axis inside a cylinder) are skipped: there the force has a kink.
    h = 1e-6
    fd = np.zeros_like(x)
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        gp, _ = body.penetration(x + e)
        gm, _ = body.penetration(x - e)
        Ep = 0.5 * k * np.maximum(-gp, 0) ** 2
        Em = 0.5 * k * np.maximum(-gm, 0) ** 2
        fd[:, j] = -(Ep - Em) / (2 * h)
    ok = np.ones(len(x), bool)
    if isinstance(body, Pedestal):
        d = x - body.top_center
        if body.kind == "box":
            q = np.abs(np.column_stack([d[:, 0], d[:, 1], d[:, 2] + body.height / 2])) - np.array(
                [*body.half_widths, body.height / 2]
            )
        else:
            q = np.column_stack(
                [np.hypot(d[:, 0], d[:, 1]) - body.radius, np.abs(d[:, 2] + body.height / 2) - body.height / 2]
            )
        qs = np.sort(q, axis=1)
        ok = (qs[:, -1] - qs[:, -2] > 1e-4) | (qs[:, -1] > 0)
    scale = 150.0 * 0.2
    assert np.max(np.abs(f[ok] - fd[ok])) < 1e-5 * scale


@pytest.mark.parametrize("name", sorted(BODIES))
def test_zero_force_outside(name):
    body = BODIES[name]
    rng = np.random.default_rng(2)
    x = rng.uniform(-6, 6, size=(2000, 3))
    gap, _ = body.penetration(x)
    f, E = body.forces(x[gap > 0], 100.0)
    assert np.all(f == 0.0) and E == 0.0
    # and points inside are pushed outward: force along +normal, energy positive
    fi, Ei = body.forces(x[gap < 0], 100.0)
    _, n = body.penetration(x[gap < 0])
    if np.any(gap < 0):
        assert Ei > 0 and np.all(np.einsum("ij,ij->i", fi, n) > 0)


def test_symmetric_configuration_gives_symmetric_forces():
    # a grid symmetric about x=0 and y=0 over a sphere centred on the z axis: forces mirror exactly
    s = np.linspace(-1.5, 1.5, 7)
    X, Y = np.meshgrid(s, s, indexing="ij")
    x = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, 1.9)])
    for body in (
        Sphere((0, 0, 0), 2.0),
        Pedestal((0, 0, 2.0), radius=1.2),
        Pedestal((0, 0, 2.0), half_widths=(1.2, 1.2), edge_radius=0.1),
    ):
        f, _ = body.forces(x, 10.0)
        F = f.reshape(7, 7, 3)
        assert np.any(F != 0)
        np.testing.assert_allclose(F[::-1, :, 0], -F[:, :, 0], atol=1e-12)
        np.testing.assert_allclose(F[::-1, :, 1], F[:, :, 1], atol=1e-12)
        np.testing.assert_allclose(F[::-1, :, 2], F[:, :, 2], atol=1e-12)
        np.testing.assert_allclose(F[:, ::-1, 1], -F[:, :, 1], atol=1e-12)
        np.testing.assert_allclose(F[:, ::-1, 2], F[:, :, 2], atol=1e-12)
        # and the total lateral force vanishes
        assert abs(f[:, 0].sum()) < 1e-10 and abs(f[:, 1].sum()) < 1e-10


def test_known_values():
    sph = Sphere((0, 0, 0), 5.0)
    f, E = sph.forces(np.array([[0.0, 0.0, 4.9], [0.0, 3.0, 0.0]]), 10.0)
    np.testing.assert_allclose(f, [[0, 0, 1.0], [0, 20.0, 0]], atol=1e-12)
    assert E == pytest.approx(0.5 * 10 * (0.1**2 + 2.0**2))
    floor = Plane((0, 0, 0))
    f, E = floor.forces(np.array([[3.0, 1.0, -0.01], [0, 0, 0.5]]), 1000.0)
    np.testing.assert_allclose(f, [[0, 0, 10.0], [0, 0, 0]], atol=1e-12)
    ped = Pedestal((0, 0, 0), half_widths=(1.0, 1.0), height=2.0)
    g, n = ped.penetration(np.array([[0.0, 0.0, -0.1], [0.95, 0.0, -1.0], [2.0, 0.0, 1.0]]))
    np.testing.assert_allclose(g, [-0.1, -0.05, math.sqrt(2)], atol=1e-12)
    np.testing.assert_allclose(n[:2], [[0, 0, 1], [1, 0, 0]], atol=1e-12)
    np.testing.assert_allclose(n[2], [math.sqrt(0.5), 0, math.sqrt(0.5)], atol=1e-12)


def test_contact_forces_sum_and_stiffness_rules():
    x = np.array([[0, 0, 1.95], [5, 0, -0.05], [10, 10, 10]])
    bodies = [Sphere((0, 0, 0), 2.0), Plane((0, 0, 0))]
    f, E, n_act = contact_forces(bodies, x, 100.0)
    np.testing.assert_allclose(f, [[0, 0, 5.0], [0, 0, 5.0], [0, 0, 0]], atol=1e-9)
    assert n_act == 2 and E == pytest.approx(2 * 0.5 * 100 * 0.05**2)
    m = np.array([1.0, 2.0, 4.0])
    k = penalty_stiffness(m, omega_max=100.0, factor=0.1)
    np.testing.assert_allclose(k, 0.1 * m * 1e4)
    assert contact_critical_time_step(k, m) == pytest.approx(2.0 / math.sqrt(1e3))
    assert combined_critical_time_step(100.0, k, m) == pytest.approx(0.02 / math.sqrt(1.1))
    with pytest.raises(InputError, match=r"either radius \(cylinder\) or half_widths \(box\), not both"):
        Pedestal((0, 0, 0), radius=1.0, half_widths=(1, 1))
    with pytest.raises(InputError, match="sphere radius must be positive, got -1.0"):
        Sphere((0, 0, 0), -1.0)


# ------------------------------------------------------------------------------ Coulomb friction
def test_friction_coefficient_validated():
    assert Plane((0, 0, 0)).friction == 0.0  # default: frictionless
    assert Sphere((0, 0, 0), 1.0, friction=0.3).friction == 0.3
    for bad in (-0.1, float("nan"), float("inf"), "rough", None):
        with pytest.raises(InputError, match="friction"):
            Plane((0, 0, 0), friction=bad)
    with pytest.raises(InputError, match="friction"):
        Pedestal((0, 0, 0), radius=1.0, friction=-1.0)


def test_friction_return_map_stick_and_slip():
    """Floor, k = 100, mu = 0.5, every node 0.01 deep (|f_n| = 1, cone 0.5).  Stick: anchor 0.002
    away -> f_t = -k_t s = 0.2, anchor kept (in the plane of the node).  Slip: 0.02 away -> trial 2
    is scaled to 0.5 and the anchor follows, |f_t| / k_t = 0.005 behind the node.  First touch
    (NaN anchor): no tangential force.  The input anchors are not modified."""
    from solidshell.contact import frictional_contact

    floor = Plane((0, 0, 0), friction=0.5)
    x = np.array([[0.0, 0.0, -0.01], [1.0, 0.0, -0.01], [2.0, 0.0, -0.01], [3.0, 0.0, 0.5]])
    anchor = np.array([[-0.002, 0.0, 0.0], [1.0, -0.02, 0.3], [np.nan] * 3, [3.0, 0.0, 0.0]])
    keep = anchor.copy()
    f, e_n, idx, ft, e_t, new, n_slip = frictional_contact(floor, x, 100.0, 100.0, anchor)
    np.testing.assert_array_equal(anchor, keep)
    assert idx.tolist() == [0, 1, 2] and n_slip == 1
    np.testing.assert_allclose(f, [[-0.2, 0, 1.0], [0, -0.5, 1.0], [0, 0, 1.0], [0, 0, 0]], atol=1e-12)
    np.testing.assert_allclose(ft, f[:3] - [[0, 0, 1.0]] * 3, atol=1e-12)
    np.testing.assert_allclose(new[0], [-0.002, 0.0, -0.01], atol=1e-12)  # stick: anchor stays (tangentially)
    np.testing.assert_allclose(new[1], [1.0, -0.005, -0.01], atol=1e-12)  # slip: anchor follows
    np.testing.assert_allclose(new[2], x[2], atol=1e-12)  # first touch
    assert np.all(np.isnan(new[3]))  # out of contact: forgotten
    assert e_n == pytest.approx(3 * 0.5 * 100 * 0.01**2)
    assert e_t == pytest.approx(0.5 * (0.2**2 + 0.5**2) / 100.0)
    # the cone holds for any stretch and normal force (random check)
    rng = np.random.default_rng(3)
    x = rng.uniform(-1, 1, (500, 3)) * [1, 1, 0.02]
    anchor = x + rng.normal(size=(500, 3)) * 0.05
    f, _, idx, ft, _, new, _ = frictional_contact(floor, x, 100.0, 300.0, anchor)
    fn = f[idx, 2]
    assert np.all(np.linalg.norm(ft, axis=1) <= 0.5 * fn * (1 + 1e-12))
    assert np.all(np.abs(ft[:, 2]) < 1e-12)  # tangential
    np.testing.assert_allclose(-300.0 * (x[idx] - new[idx]), ft, atol=1e-12)


def _box_sdf_reference(a, half):
    """The box distance written with numpy (the form contact.py had before the compiled kernels):
    Euclidean outside, minus the nearest face's distance inside."""
    s = np.where(a >= 0.0, 1.0, -1.0)
    q = np.abs(a) - half
    qp = np.maximum(q, 0.0)
    L = np.linalg.norm(qp, axis=1)
    g = L + np.minimum(q.max(axis=1), 0.0)
    grad = np.zeros_like(a)
    out = L > 0.0
    grad[out] = qp[out] / L[out, None]
    inn = np.flatnonzero(~out)
    grad[inn, np.argmax(q[inn], axis=1)] = 1.0
    return g, grad * s


@pytest.mark.parametrize("name", ["sphere", "plane", "cylinder_round", "box_round"])
def test_compiled_distances_match_the_numpy_formulas(name):
    """contact_kernels.signed_distance against the bodies' formulas in numpy, on points around the
    surface, inside and outside (to 1e-13 relative of the body's size: the same formulas, the
    compiled sums of three squares taken left to right as numpy's)."""
    body, rng = BODIES[name], np.random.default_rng(11)
    x = _points_near_surface(body, rng, 400)
    x = np.vstack([x, rng.uniform(-4, 4, (200, 3))])
    g, n = body.signed_distance(x)
    if name == "sphere":
        d = x - body.center
        r = np.linalg.norm(d, axis=1)
        g0, n0 = r - body.radius, d / r[:, None]
    elif name == "plane":
        g0, n0 = (x - body.point) @ body.normal, np.broadcast_to(body.normal, x.shape)
    else:
        er, d = body.edge_radius, x - body.top_center
        zc = d[:, 2] + 0.5 * body.height
        if body.kind == "cylinder":
            rho = np.hypot(d[:, 0], d[:, 1])
            g0, ga = _box_sdf_reference(
                np.column_stack([rho, zc]), np.array([body.radius - er, 0.5 * body.height - er])
            )
            n0 = np.column_stack([ga[:, :1] * d[:, :2] / rho[:, None], ga[:, 1]])
        else:
            g0, n0 = _box_sdf_reference(
                np.column_stack([d[:, :2], zc]), np.array([*body.half_widths, 0.5 * body.height]) - er
            )
        g0 = g0 - er
    np.testing.assert_allclose(g, g0, rtol=0, atol=1e-13 * 4)
    np.testing.assert_allclose(n, n0, rtol=0, atol=1e-13)


class _Floor(RigidBody):
    """A user's own body (no kernel code): the floor z <= 0 by its signed distance alone."""

    lipschitz = 1.0

    def __init__(self, friction=0.0):
        self.friction = friction

    def signed_distance(self, x):
        x = np.asarray(x, float).reshape(-1, 3)
        return x[:, 2].copy(), np.tile([0.0, 0.0, 1.0], (len(x), 1))


def test_a_users_body_gets_the_same_laws():
    """A RigidBody subclass that only gives signed_distance (code -1) goes through the same penalty
    and friction laws as the built-in Plane: identical forces, energies and anchors."""
    from solidshell.contact import frictional_contact

    rng = np.random.default_rng(5)
    x = rng.uniform(-1, 1, (300, 3)) * [1, 1, 0.02]
    anchor = x + rng.normal(size=(300, 3)) * 0.05
    anchor[::7] = np.nan
    for a, b in ((_Floor(), Plane((0, 0, 0))), (_Floor(0.4), Plane((0, 0, 0), friction=0.4))):
        fa, ea = a.forces(x, 50.0)
        fb, eb = b.forces(x, 50.0)
        np.testing.assert_array_equal(fa, fb)
        assert ea == eb
        if a.friction:
            ra, rb = frictional_contact(a, x, 50.0, 80.0, anchor), frictional_contact(b, x, 50.0, 80.0, anchor)
            for u, v in zip(ra, rb):
                np.testing.assert_array_equal(u, v)


def test_a_body_changed_after_construction_is_seen():
    """The kernels' parameters are read from the body's attributes at each call, so a body a
    script moves or resizes is seen at its new place (exact: a distance along the axis)."""
    s = Sphere((0.0, 0.0, 0.0), 1.0)
    s.center, s.radius = np.array([0.0, 0.0, 1.0]), 2.0
    assert s.signed_distance(np.array([[0.0, 0.0, 4.0]]))[0][0] == 1.0
    p = Pedestal((0.0, 0.0, 0.0), half_widths=(1.0, 1.0), height=3.0)
    p.top_center = np.array([0.0, 0.0, -1.0])
    assert p.signed_distance(np.array([[0.0, 0.0, 0.5]]))[0][0] == 1.5
