"""The triangle's lane kernel (elements/lanes_tri.py) and its place in the explicit loop (fused.py).

lanes_tri must give core.energy_force's energies and forces for tri3's element to round-off (its
tangents, tying vectors and strains are core's bit for bit; only the stress sums and the force
accumulation are grouped and contracted differently), zero in padded lanes, the same bits on any
thread count; FusedForces must route triangle blocks to it and, on an adapted quad + triangle mesh,
give Model.energy_and_force's force and energy to round-off without computing Model._current."""

import numba
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from solidshell import Fabric, IsotropicShell, ShellMesh
from solidshell.elements import core, lanes, lanes_tri
from solidshell.model import Model
from solidshell.solvers.explicit.fused import FusedForces, lanes_ans_scatter, lanes_scatter, lanes_tri_scatter

L = lanes.LANES
WOOL30 = Fabric.wool(warp_angle=30.0)


def loose_triangles(M, seed, shape):
    """M separate triangles (3 nodes each) of random size (0.05..5), orientation and position:
    ``shape`` "regular" (near-equilateral), "obtuse" (one angle ~150 deg) or "slender" (aspect
    ~20); each slightly curved (its directors tilted from the normal by up to ~0.15 rad)."""
    rng = np.random.default_rng(seed)
    base = {
        "regular": [[0, 0], [1, 0], [0.5, 0.87]],
        "obtuse": [[0, 0], [1, 0], [0.9, 0.14]],
        "slender": [[0, 0], [1, 0], [0.5, 0.05]],
    }[shape]
    P = np.array(base, float)[None] + 0.01 * rng.uniform(-1, 1, (M, 3, 2))
    size = np.exp(rng.uniform(np.log(0.05), np.log(5.0), M))
    X = np.concatenate([P * size[:, None, None], np.zeros((M, 3, 1))], 2)
    R = Rotation.random(M, random_state=seed).as_matrix()
    X = np.einsum("mij,mpj->mpi", R, X) + 10.0 * rng.standard_normal((M, 1, 3))
    Dn = R[:, None, :, 2] + 0.1 * rng.standard_normal((M, 3, 3))
    return ShellMesh(X.reshape(-1, 3), tris=np.arange(3 * M).reshape(M, 3), directors=Dn.reshape(-1, 3))


def deformation(mesh, seed, scale):
    """Random nodal displacements of loose_triangles' mesh: U_o of ``scale`` times the element's
    size, U_n of ``scale`` (large director rotations and stretches: both branches of Eq. 24 at
    scale ~0.5)."""
    rng = np.random.default_rng(seed)
    h = np.linalg.norm(mesh.nodes[mesh.tris[:, 1]] - mesh.nodes[mesh.tris[:, 0]], axis=1)
    U = scale * rng.standard_normal((mesh.n_nodes, 6))
    U[:, :3] *= np.repeat(h, 3)[:, None]
    return U


def core_and_lanes(model, U, nth=None):
    """(core's (M,3,6) forces and (M,) energies; the lane kernel's (B, 18 L), (B, L) arrays)."""
    b = model.blocks[-1]
    M = len(b.conn)
    xo, xn, Uc = model._current(U)
    fe, we = np.empty((M, 3, 6)), np.empty(M)
    core.energy_force(*b.args(xo, xn, Uc, model.quasi, model.mu), fe, we, 1)
    pk = lanes_tri.pack(b.conn, b.c, b.c["r_zq"])
    fs, ws = np.full((pk["B"], 18 * L), np.nan), np.full((pk["B"], L), np.nan)
    old = numba.get_num_threads()
    try:
        numba.set_num_threads(nth or old)
        lanes_tri.tri_forces(
            model.mesh.nodes,
            model.mesh.directors,
            Uc,
            pk["conn"],
            pk["Cmb"],
            pk["Cs"],
            pk["Cz"],
            pk["r_z"],
            model.quasi,
            model.mu,
            np.empty((pk["B"], 36 * L)),
            fs,
            ws,
        )
    finally:
        numba.set_num_threads(old)
    return fe, we, fs, ws


def assert_matches_core(model, U):
    """Per element: force to 1e-12 of the element's largest force component and energy to 1e-12
    of its energy.  The strains are core's bit for bit, so what differs is the grouping of the
    3-term stress sums, of the 3-6-term force sums and of the energy's quadratic forms, each a few
    ulps of its largest term; the largest term is bounded by the element force times the
    rigidity's condition (observed: up to 3e-14 over 600 random cases of every shape, section,
    thickness strain and scale; typically ~1e-15).  Padded lanes: zero force and energy."""
    fe, we, fs, ws = core_and_lanes(model, U)
    M = len(fe)
    fl = lanes_tri.unpack_forces(fs, M)
    scale = np.abs(fe).reshape(M, -1).max(1)
    assert np.all(np.abs(fl - fe).reshape(M, -1).max(1) <= 1e-12 * scale)
    assert np.all(np.abs(ws.ravel()[:M] - we) <= 1e-12 * np.abs(we))
    assert np.all(fs.reshape(-1, 18, L).transpose(0, 2, 1).reshape(-1, 18)[M:] == 0.0)
    assert np.all(ws.ravel()[M:] == 0.0)
    return fe, we


@pytest.mark.parametrize("shape", ["regular", "obtuse", "slender"])
@pytest.mark.parametrize("thickness", ["green", "quasi"])
def test_lane_kernel_matches_core(shape, thickness):
    """37 triangles (two full blocks and a padded third) at moderate (5 %) and large (50 %)
    deformation: the second reaches Eq. (24)'s compressive branch at some nodes."""
    mesh = loose_triangles(37, 11, shape)
    model = Model(mesh, WOOL30, thickness_strain=thickness)
    assert lanes_tri.covers(model.blocks[-1].c)
    for seed, scale in ((1, 0.05), (2, 0.5)):
        fe, we = assert_matches_core(model, deformation(mesh, seed, scale))
        assert np.all(we > 0.0) and np.all(np.isfinite(fe))


@settings(max_examples=40, deadline=None)
@given(
    M=st.integers(1, 3 * L + 5),
    seed=st.integers(0, 2**31 - 1),
    shape=st.sampled_from(["regular", "obtuse", "slender"]),
    scale=st.sampled_from([1e-6, 1e-3, 0.05, 0.5]),
    quasi=st.booleans(),
    iso=st.booleans(),
)
def test_lane_kernel_matches_core_property(M, seed, shape, scale, quasi, iso):
    """Any number of elements (1 .. 3 blocks + 5, mostly padded), any deformation from 1e-6 (where
    a non-displacement form would lose ten digits) to 50 %, both thickness strains, an isotropic
    section or an anisotropic fabric at a warp angle."""
    mesh = loose_triangles(M, seed, shape)
    section = IsotropicShell(E=1e3, nu=0.3, h=0.1) if iso else WOOL30
    model = Model(mesh, section, thickness_strain="quasi" if quasi else "green")
    assert_matches_core(model, deformation(mesh, seed + 1, scale))


def test_threads_do_not_change_the_bits():
    """Blocks are the unit of work: 1 and 2 threads give the same bits."""
    mesh = loose_triangles(5 * L + 3, 4, "regular")
    model = Model(mesh, WOOL30, thickness_strain="quasi")
    U = deformation(mesh, 5, 0.3)
    _, _, f1, w1 = core_and_lanes(model, U, 1)
    _, _, f2, w2 = core_and_lanes(model, U, min(2, numba.config.NUMBA_NUM_THREADS))
    assert np.array_equal(f1, f2) and np.array_equal(w1, w2)


def test_pack_refuses_other_constants():
    """A quad block's constants are not the triangle's."""
    q = ShellMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], quads=[[0, 1, 2, 3]])
    b = Model(q, WOOL30).blocks[0]
    assert not lanes_tri.covers(b.c)
    with pytest.raises(ValueError, match="tri3.precompute"):
        lanes_tri.pack(b.conn, b.c, b.c["r_zq"])


def adapted_mesh():
    """test_adapt_mesh's adapted curved grid holding every transition pattern (quads and
    triangles, levels 0-2)."""
    from test_adapt_mesh import CURVED8, every_pattern_state

    return every_pattern_state(CURVED8)[1].mesh


@pytest.mark.parametrize("thickness", ["green", "quasi"])
def test_fused_forces_on_an_adapted_mesh_are_the_models(thickness):
    """Quads "ans" and "full" in runs and the transition triangles, all through lane kernels
    (no core part, so no Model._current per step): force and energy equal Model.energy_and_force's
    to round-off -- 1e-13 of the largest force and of the energy (the element forces agree to
    ~1e-15 and a node sums at most ~8 of them, in a different order at the triangles' nodes and at
    chunk boundaries; observed 2e-16); the same bits on 1 and 2 threads."""
    from test_lanes import fused_force_matches_model

    mesh = adapted_mesh()
    assert len(mesh.tris) > 0
    nq = len(mesh.quads)
    choice = ["ans"] * (nq // 3) + ["full"] * (nq // 3) + ["ans"] * (nq - 2 * (nq // 3))
    model = Model(mesh, WOOL30, thickness_strain=thickness, membrane=choice)
    ff = FusedForces(model)
    assert [p[2]["kernel"] for p in ff.parts] == [
        lanes_ans_scatter,
        lanes_scatter,
        lanes_ans_scatter,
        lanes_tri_scatter,
    ]
    assert not ff.needs_current
    ff.model = None  # element_pass must not reach for Model._current
    fused_force_matches_model(ff, model, 0.05 * np.random.default_rng(9).standard_normal((mesh.n_nodes, 6)))


def test_fused_step_with_triangles_follows_the_previous_path():
    """60 explicit steps of the adapted sheet (quads and triangles) falling onto a plane: the fused
    step with the triangle lanes follows Model.internal_force + central_step to round-off
    (test_lanes.fused_follows_previous_path: 1e-11 relative)."""
    from test_lanes import fused_follows_previous_path

    mesh = adapted_mesh()
    model = Model(mesh, WOOL30, thickness_strain="quasi")
    assert any(p[2] is not None and p[2]["kernel"] is lanes_tri_scatter for p in FusedForces(model).parts)
    fused_follows_previous_path(model, z_plane=mesh.nodes[:, 2].min() + 0.01)


@pytest.mark.parametrize("thickness", ["green", "quasi"])
def test_rigid_rotation_of_a_triangle_mesh_has_no_force(thickness):
    """A curved triangle mesh (the adapted grid's cells cut in two, 128 triangles) turned by 2 rad
    about a skew axis and moved: zero force and energy to round-off.  The strains of a rigid
    motion are round-off of O(|X|^2) products, ~1e-16 of a unit strain; bounds: force 1e-12 of
    the force of a unit strain (measured from a 1e-6 stretch: linear there to 1e-6) and energy
    1e-24 of its energy (observed 6e-15 and 3e-30) -- a non-objective term would give O(1)."""
    from test_adapt_mesh import CURVED8

    q = CURVED8.quads
    mesh = ShellMesh(CURVED8.nodes, tris=np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]))
    model = Model(mesh, WOOL30, thickness_strain=thickness)
    ff = FusedForces(model)
    assert [p[2]["kernel"] for p in ff.parts] == [lanes_tri_scatter]
    R = Rotation.from_rotvec([1.1, -1.5, 0.7]).as_matrix()
    U = np.column_stack([mesh.nodes @ R.T + [3.0, -2.0, 1.0] - mesh.nodes, mesh.directors @ R.T - mesh.directors])
    F, W = ff.internal(U.ravel(), True)
    stretch = np.zeros_like(U)
    stretch[:, :2] = 1e-6 * mesh.nodes[:, :2]
    Fu, Wu = ff.internal(stretch.ravel(), True)
    Fu, Wu = Fu / 1e-6, Wu / 1e-12  # per unit strain
    assert np.abs(F).max() <= 1e-12 * np.abs(Fu).max()
    assert abs(W) <= 1e-24 * Wu
