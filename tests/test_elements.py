"""Element kernels (Eqs. 1-15): consistency of energy, force and tangent, objectivity, zero-energy
modes, mass and loads.  Physics the kernels must satisfy exactly, whatever the mesh."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from solidshell import Fabric, IsotropicShell, ShellMesh
from solidshell.boundary import gravity_loads, line_load, point_load, surface_load
from solidshell.errors import InputError
from solidshell.model import Model
from verification.checks.elements import mixed_curved_mesh  # two quads + two triangles, doubly curved

ISO = IsotropicShell(E=1.0e4, nu=0.3, h=0.1, density=2.0)
WOOL30 = Fabric.wool(warp_angle=30.0)


def flat_grid(n, tri=False, distort=0.3, seed=1):
    x = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(x, x)
    P = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    inner = (P[:, 0] > 0) & (P[:, 0] < 1) & (P[:, 1] > 0) & (P[:, 1] < 1)
    P[inner, :2] += distort / n * np.random.default_rng(seed).uniform(-1, 1, (inner.sum(), 2))
    a = (np.arange(n)[None, :] + (n + 1) * np.arange(n)[:, None]).ravel()
    q = np.column_stack([a, a + 1, a + n + 2, a + n + 1])
    if tri:
        return ShellMesh(P, tris=np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]))
    return ShellMesh(P, quads=q)


def large_motion(mesh, seed=0, scale=0.3):
    """A large, non-rigid displacement: a big rotation plus random stretches of positions/directors."""
    rng = np.random.default_rng(seed)
    R = Rotation.from_rotvec([0.7, -1.1, 0.5]).as_matrix()
    U = np.zeros((mesh.n_nodes, 6))
    U[:, :3] = mesh.nodes @ R.T - mesh.nodes + scale * rng.standard_normal((mesh.n_nodes, 3))
    U[:, 3:] = mesh.directors @ R.T - mesh.directors + scale * rng.standard_normal((mesh.n_nodes, 3))
    return U


def fd_gradient(f, U, eps):
    u = U.ravel()
    out = []
    for k in range(u.size):
        up, um = u.copy(), u.copy()
        up[k] += eps
        um[k] -= eps
        out.append((f(up.reshape(U.shape)) - f(um.reshape(U.shape))) / (2 * eps))
    return np.array(out)


@pytest.mark.parametrize("material", [ISO, WOOL30], ids=["isotropic", "wool-warp30"])
@pytest.mark.parametrize("thickness_strain", ["green", "quasi"])
@pytest.mark.parametrize("membrane", ["full", "ans"])
def test_force_and_tangent_are_derivatives(material, thickness_strain, membrane):
    mesh = mixed_curved_mesh()
    model = Model(mesh, material, thickness_strain=thickness_strain, membrane=membrane)
    U = large_motion(mesh)
    W, F = model.energy_and_force(U)
    F2, K = model.force_and_tangent(U)
    K = K.toarray()
    # The energy is a polynomial (quartic; piecewise smooth for Eq. 24) in U of size O(1): central
    # differences with eps = 1e-6 have truncation O(eps^2) ~ 1e-12 and round-off ~ 1e-16/eps ~ 1e-10
    # relative, so 1e-6 (the bound) leaves four orders of margin and still catches any wrong
    # term (a wrong term is O(1) relative).
    Ffd = fd_gradient(model.energy, U, 1e-6)
    assert np.abs(F.ravel() - Ffd).max() <= 1e-6 * np.abs(F).max()
    Kfd = fd_gradient(lambda V: model.internal_force(V).ravel(), U, 1e-6)
    assert np.abs(K - Kfd.T).max() <= 1e-6 * np.abs(K).max()
    np.testing.assert_array_equal(F, F2)
    # symmetric up to summation-order round-off of the entries
    assert np.abs(K - K.T).max() <= 1e-13 * np.abs(K).max()


ROTATIONS = {
    "90deg-z": Rotation.from_rotvec([0, 0, np.pi / 2]),
    "180deg-x": Rotation.from_rotvec([np.pi, 0, 0]),
    "180deg-diag": Rotation.from_rotvec(np.pi * np.array([1.0, 1.0, 1.0]) / np.sqrt(3)),
    "general": Rotation.from_rotvec([2.1, -0.4, 1.3]),
}


@pytest.mark.parametrize("rot", list(ROTATIONS), ids=list(ROTATIONS))
@pytest.mark.parametrize("thickness_strain", ["green", "quasi"])
@pytest.mark.parametrize("membrane", ["full", "ans"])
def test_objectivity(rot, thickness_strain, membrane):
    mesh = mixed_curved_mesh()
    model = Model(mesh, WOOL30, thickness_strain=thickness_strain, membrane=membrane)
    R = ROTATIONS[rot].as_matrix()
    c = np.array([3.0, -2.0, 5.0])

    def moved(U):
        xo = (mesh.nodes + U[:, :3]) @ R.T + c
        xn = (mesh.directors + U[:, 3:]) @ R.T
        return np.column_stack([xo - mesh.nodes, xn - mesh.directors])

    # a rigid motion of the undeformed sheet stores no energy: strains are differences of squared
    # lengths of O(1) vectors, so they vanish to ~1e-15 and the energy to ~C*(1e-15)^2*area
    scale = np.abs(WOOL30.C_m).max() * mesh.area()
    assert model.energy(moved(np.zeros((mesh.n_nodes, 6)))) <= 1e-24 * scale
    # and a rigid motion of a deformed state changes no energy (relative round-off)
    U = large_motion(mesh, seed=3, scale=0.1)
    W = model.energy(U)
    assert abs(model.energy(moved(U)) - W) <= 1e-12 * W
    # nor the bending strain measure of Eq. (25)
    np.testing.assert_allclose(model.bending_strain(moved(U)), model.bending_strain(U), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("n", [1, 2, 4])
@pytest.mark.parametrize("tri", [False, True], ids=["quads", "tris"])
@pytest.mark.parametrize("membrane", ["full", "ans"])
def test_exactly_six_zero_energy_modes_flat(n, tri, membrane):
    mesh = flat_grid(n, tri=tri)
    K = Model(mesh, ISO, membrane=membrane).tangent(np.zeros((mesh.n_nodes, 6))).toarray()
    ev = np.linalg.eigvalsh(K)
    # the zero eigenvalues are round-off (~1e-16 * max); the smallest physical one is the softest
    # bending mode, (h/L)^2 ~ 1e-2 below the membrane ones and >1e-6 of the largest here
    tol = 1e-10 * ev.max()
    assert np.sum(np.abs(ev) < tol) == 6
    assert ev[6] > 1e-6 * ev.max()


@pytest.mark.parametrize("membrane", ["full", "ans"])
def test_six_zero_modes_curved_mixed(membrane):
    mesh = mixed_curved_mesh()
    K = Model(mesh, ISO, membrane=membrane).tangent(np.zeros((mesh.n_nodes, 6))).toarray()
    ev = np.linalg.eigvalsh(K)
    assert np.sum(np.abs(ev) < 1e-10 * ev.max()) == 6
    assert ev[6] > 1e-7 * ev.max()


def test_uniaxial_green_strain_energy_follows_the_warp():
    # A flat sheet stretched along global X by stretch lam: Green strain E_xx = (lam^2-1)/2 exactly
    # (bilinear/linear interpolation reproduces a homogeneous deformation); the energy is
    # 1/2 C_m[xx] E_xx^2 * area with C_m[xx] the warp rigidity when the warp is along X and the weft
    # rigidity when the fabric is turned 90 degrees (weft-cut).
    for tri in (False, True):
        mesh = flat_grid(3, tri=tri)
        lam = 1.1
        U = np.zeros((mesh.n_nodes, 6))
        U[:, 0] = (lam - 1.0) * mesh.nodes[:, 0]
        E = 0.5 * (lam**2 - 1.0)
        for fab, T in ((Fabric.wool(), 1118.2), (Fabric.wool(warp_angle=90.0), 759.5)):
            W = Model(mesh, fab).energy(U)
            assert W == pytest.approx(0.5 * T * E**2 * mesh.area(), rel=1e-12)


def test_lumped_mass_and_loads_totals():
    mesh = mixed_curved_mesh()
    model = Model(mesh, WOOL30)
    Mass = model.lumped_mass()
    # J_o at the nodes integrates the area exactly for flat parallelograms; on this curved mixed
    # patch the nodal (trapezoidal) rule approximates the surface area to O(h^2 * curvature)
    A = model.nodal_areas().sum()
    assert A == pytest.approx(mesh.area(), rel=2e-2)
    mu, h = WOOL30.mass_per_area, WOOL30.thickness
    np.testing.assert_allclose(Mass[:, :3].sum(0), mu * A, rtol=1e-13)
    np.testing.assert_allclose(Mass[:, 3:].sum(0), mu * h * h / 4 * A, rtol=1e-13)
    P = gravity_loads(model)
    assert P[:, 2].sum() == pytest.approx(-WOOL30.weight * A, rel=1e-13)
    assert np.all(P[:, [0, 1, 3, 4, 5]] == 0)
    Ps = surface_load(model, 2.0, direction=(1, 0, 0))
    assert Ps[:, 0].sum() == pytest.approx(2.0 * A, rel=1e-13)
    Pp = point_load(mesh.n_nodes, [2, 5], [0, 0, -1.5])
    assert Pp[:, 2].sum() == pytest.approx(-3.0)


def test_flat_mesh_mass_is_exact_area():
    mesh = flat_grid(4)
    model = Model(mesh, Fabric.wool())
    # flat bilinear quads: J_o is linear in (xi, eta), so the nodal rule integrates the area exactly
    assert model.nodal_areas().sum() == pytest.approx(1.0, rel=1e-13)
    edge = np.flatnonzero(mesh.nodes[:, 0] == 1.0)
    Pl = line_load(mesh, edge, [0.0, 0.0, -2.0])
    assert Pl[:, 2].sum() == pytest.approx(-2.0, rel=1e-13)


def test_interpenetration_indicator():
    mesh = flat_grid(2)
    model = Model(mesh, Fabric.wool())
    U = np.zeros((mesh.n_nodes, 6))
    assert not model.interpenetrated_nodes(U).any()
    U[4, 3:] = -2.0 * mesh.directors[4]  # reverse the centre node's director
    flags = model.interpenetrated_nodes(U)
    assert flags[4] and flags.sum() == 1


def _alignment_numpy(mesh, U):
    """n_p . d_p by its NumPy definition (rolled corners, np.cross, np.linalg.norm), per block."""
    xo = mesh.nodes + U[:, :3]
    xn = mesh.directors + U[:, 3:]
    out = []
    for conn in (mesh.quads, mesh.tris):
        P = xo[conn]
        n = np.cross(np.roll(P, -1, axis=1) - P, np.roll(P, 1, axis=1) - P)
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        d = xn[conn] / np.linalg.norm(xn[conn], axis=-1, keepdims=True)
        out.append(np.sum(n * d, -1))
    return out


@pytest.mark.parametrize("scale", [1e-3, 0.3, 3.0])
def test_interpenetration_kernel_is_the_numpy_definition_bit_for_bit(scale):
    """The compiled corner pass (elements/corners.py) forms each n_p . d_p with the operations of
    the NumPy form in their order, so the values are equal bit for bit (np.array_equal, no
    tolerance) on quads and triangles, from small to large random displacements (where many
    corners flip)."""
    rng = np.random.default_rng(7)
    q = flat_grid(6)
    X = q.nodes + np.column_stack([rng.normal(0, 0.02, (q.n_nodes, 2)), rng.normal(0, 0.05, q.n_nodes)])
    top = q.quads[18:]  # rows 3-5 of the 6x6 grid as triangles
    mesh = ShellMesh(X, quads=q.quads[:18], tris=np.concatenate([top[:, [0, 1, 2]], top[:, [0, 2, 3]]]))
    U = rng.normal(0.0, scale, (mesh.n_nodes, 6))
    got = Model(mesh, Fabric.wool()).interpenetration(U)
    want = [w for w, c in zip(_alignment_numpy(mesh, U), (mesh.quads, mesh.tris)) if len(c)]
    assert len(got) == len(want) == 2
    for g, w in zip(got, want):
        assert np.array_equal(g, w)


def test_quasi_thickness_strain_penalises_reversed_director():
    # Eq. (24): a reversed director (n.d < -mu) costs the strain -|x_n| - 1 = -2 instead of Green's 0
    mesh = flat_grid(1)
    U = np.zeros((mesh.n_nodes, 6))
    U[0, 3:] = -2.0 * mesh.directors[0]
    Wg = Model(mesh, ISO, thickness_strain="green").energy(U)
    Wq = Model(mesh, ISO, thickness_strain="quasi").energy(U)
    assert Wg < 1e-6 * Wq
    assert Wq > 0


@pytest.mark.parametrize("shape", ["square", "rectangle", "distorted"])
def test_assumed_membrane_sees_no_stretch_where_the_edges_keep_their_lengths(shape):
    """A quad folded along a diagonal (two rigid triangles) keeps its four edge lengths; only the
    other diagonal shortens, which is in-plane shear.  With a section that has tensile but no shear
    rigidity the membrane energy must vanish on a rectangle (natural and Cartesian axes agree):
    membrane="ans" (quad4.py: the twist correction c/3 cancels the -|h|^2/3 mean stretch of the
    Gauss points) gives round-off (1e-18 of the compatible value); on a distorted quad, where the
    shear leaks into the Cartesian normal strains, < 1/10 of it (measured 1/17 .. 1/12).  The
    paper's 2x2 membrane ("full") stores the parasitic stretch."""
    from types import SimpleNamespace

    sec = SimpleNamespace(
        C_m=np.diag([1.0, 1.0, 0.0]),
        C_b=np.zeros((3, 3)),
        C_t=np.zeros((2, 2)),
        E_z=0.0,
        warp_angle_rad=0.0,
        thickness=0.01,
        mass_per_area=1.0,
    )
    X = {
        "square": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
        "rectangle": [[-2, -1, 0], [2, -1, 0], [2, 1, 0], [-2, 1, 0]],
        "distorted": [[-1.2, -0.9, 0], [1.1, -1, 0], [0.8, 1.3, 0], [-0.9, 1, 0]],
    }[shape]
    X = np.array(X, dtype=float)
    mesh = ShellMesh(X, quads=[[0, 1, 2, 3]])
    axis = (X[2] - X[0]) / np.linalg.norm(X[2] - X[0])
    for angle in (0.1, 1.0):
        x = X.copy()
        x[1] = X[0] + Rotation.from_rotvec(angle * axis).apply(X[1] - X[0])
        x[3] = X[0] + Rotation.from_rotvec(-angle * axis).apply(X[3] - X[0])
        U = np.zeros((4, 6))
        U[:, :3] = x - X
        full = Model(mesh, sec, membrane="full").energy(U)
        ans = Model(mesh, sec, membrane="ans").energy(U)
        assert full > 1e-6
        assert ans <= (1e-12 if shape != "distorted" else 0.1) * full


def test_membrane_per_quadrilateral():
    """A per-quad membrane choice (the adaptive mesh's coarse quads "ans", its finest "full") is
    each element's own formulation: the mixed model's element energies are the single-choice
    models' element by element (1e-13 relative: the same kernels on other block boundaries) in
    the mesh's element order; one choice for every quad is the plain model bit for bit."""
    mesh = mixed_curved_mesh()
    rng = np.random.default_rng(3)
    U = 0.05 * rng.standard_normal((mesh.n_nodes, 6))
    full, ans = Model(mesh, WOOL30, membrane="full"), Model(mesh, WOOL30, membrane="ans")
    choice = ["ans", "full"][: len(mesh.quads)]
    mixed = Model(mesh, WOOL30, membrane=choice)
    assert [len(b.conn) for b in mixed.blocks] == [1, 1, len(mesh.tris)]
    nq = len(mesh.quads)
    want = np.concatenate([ans.element_energies(U)[:1], full.element_energies(U)[1:nq], full.element_energies(U)[nq:]])
    np.testing.assert_allclose(mixed.element_energies(U), want, rtol=1e-13)
    same = Model(mesh, WOOL30, membrane=["full"] * nq)
    assert np.array_equal(same.internal_force(U), full.internal_force(U))  # one block: bitwise
    with pytest.raises(InputError, match="needs 2 values"):
        Model(mesh, WOOL30, membrane=["ans"])
    with pytest.raises(InputError, match="'sri'"):
        Model(mesh, WOOL30, membrane=["ans", "sri"])


@pytest.mark.parametrize("kind", ["quad4", "tri3"])
def test_bending_raw_strains_are_raw_strains_bending_part_bit_for_bit(kind):
    """Model.bending_strain (the adaptivity criterion, Eq. 25) forms only the bending columns of the
    raw strains; they must be raw_strains' columns 3-5 exactly (same operations), so the criterion
    did not change when it stopped forming the membrane, shear and thickness parts."""
    from solidshell.elements import quad4, tri3

    mod = {"quad4": quad4, "tri3": tri3}[kind]
    nn = 4 if kind == "quad4" else 3
    rng = np.random.default_rng(7)
    xo, xn = rng.normal(size=(2, 30, nn, 3))
    mb, _, _ = mod.raw_strains(xo, xn)
    assert np.array_equal(mod.bending_raw_strains(xo, xn), mb[..., 3:])
