"""The assumed-membrane quadrilateral (membrane="ans", elements/quad4.py) in its factorised form and
its lane kernel (elements/lanes_ans.py).

quad4 folds the 22x22 rigidity of the assumed field on its raw tying products into a 6x6 one on the
six products of the centre tangents and the hourglass vector (rank 5: Cm = P^T C5 P, raw = R y).
That must be the same element: the compact form against the dense 26-tie form of the same field on
distorted, warped quads (energy, force and tangent to round-off).  The lane kernel must give
core.energy_force's forces and energies to round-off, zero in padded lanes."""

import numpy as np
import pytest

from solidshell import Fabric, ShellMesh
from solidshell.elements import core, lanes, lanes_ans, quad4
from solidshell.model import Model

WOOL30 = Fabric.wool(warp_angle=30.0)


def distorted_warped_mesh(nx=7, ny=5, seed=2):
    """35 quads (not a multiple of LANES: the last block is padded), interior nodes moved by up to
    0.35 of a cell in the plane, the sheet doubly curved and with random out-of-plane warp."""
    rng = np.random.default_rng(seed)
    x, y = np.linspace(0, 3.5, nx + 1), np.linspace(0, 2.5, ny + 1)
    X, Y = np.meshgrid(x, y)
    P = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    inner = (P[:, 0] > 0) & (P[:, 0] < 3.5) & (P[:, 1] > 0) & (P[:, 1] < 2.5)
    P[inner, :2] += 0.35 * 0.5 * rng.uniform(-1, 1, (inner.sum(), 2))
    P[:, 2] = 0.3 * np.sin(P[:, 0]) * P[:, 1] + 0.08 * rng.standard_normal(len(P))
    a = (np.arange(nx)[None, :] + (nx + 1) * np.arange(ny)[:, None]).ravel()
    return ShellMesh(P, quads=np.column_stack([a, a + 1, a + nx + 2, a + nx + 1]))


def random_motion(mesh, seed, scale=0.05):
    """Random displacements of positions and directors (5 % of the sheet: large rotations of the
    directors, both branches of Eq. 24)."""
    return scale * np.random.default_rng(seed).standard_normal((mesh.n_nodes, 6))


def test_membrane_products_are_combinations_of_six():
    """Every raw tying product of the assumed field is R_MEM times the six centre products, for any
    nodal vectors (an identity of the bilinear interpolation: exact up to round-off of O(1) sums)."""
    x = np.random.default_rng(0).standard_normal((20, 4, 3)) * 10.0
    raw = quad4.tying_raw(quad4.M_ALPHA, quad4.M_BETA, quad4.M_TIE, x, x)
    y = quad4.tying_raw(quad4.P_ALPHA, quad4.P_BETA, quad4.P_TIE, x, x)
    assert np.abs(raw - y @ quad4.R_MEM.T).max() <= 1e-13 * np.abs(raw).max()


@pytest.mark.parametrize("thickness", ["green", "quasi"])
def test_factorised_membrane_is_the_dense_one(thickness):
    """Rank 5 (the field's five parameters), and core's kernels on the compact 10-tie form give the
    dense 26-tie form's energy, force and tangent: the same sums regrouped, so ~1e-15 relative per
    element; 1e-12 of the largest entry leaves room for sums of ~100 terms of mixed sign."""
    mesh = distorted_warped_mesh()
    model = Model(mesh, WOOL30, thickness_strain=thickness, membrane="ans")
    b = model.blocks[0]
    assert b.alpha.shape[0] == 10 and not b.gp_membrane
    Cm = quad4.dense_membrane(mesh.nodes[mesh.quads], b.c, WOOL30.C_m)
    sv = np.linalg.svd(Cm, compute_uv=False)
    assert np.all(sv[:, 5] <= 1e-14 * sv[:, 0]) and np.all(sv[:, 4] > 1e-4 * sv[:, 0])
    np.testing.assert_allclose(
        b.c["Cs"][:, 4:, 4:], quad4.R_MEM.T @ Cm @ quad4.R_MEM, rtol=0, atol=1e-13 * np.abs(Cm).max()
    )

    M = len(mesh.quads)
    Cs = np.zeros((M, 26, 26))
    Cs[:, :4, :4] = b.c["Cs"][:, :4, :4]
    Cs[:, 4:, 4:] = Cm
    alpha = np.vstack([quad4.ALPHA, quad4.M_ALPHA])
    beta = np.vstack([quad4.BETA, quad4.M_BETA])
    tie = np.vstack([quad4.TIE, quad4.M_TIE])
    U = random_motion(mesh, 1)
    xo, xn, Uc = model._current(U)
    compact = b.args(xo, xn, Uc, model.quasi, model.mu)
    dense = compact[:5] + (alpha, beta, tie, compact[8], Cs) + compact[10:]
    out = []
    for args in (compact, dense):
        fe, we, Ke = np.empty((M, 4, 6)), np.empty(M), np.empty((M, 24, 24))
        core.force_tangent(*args, False, fe, we, Ke, 1)
        fe2, we2 = np.empty((M, 4, 6)), np.empty(M)
        core.energy_force(*args, fe2, we2, 1)
        np.testing.assert_array_equal(fe, fe2)
        out.append((we, fe, Ke))
    (w0, f0, K0), (w1, f1, K1) = out
    assert np.abs(w0 - w1).max() <= 1e-12 * np.abs(w1).max()
    assert np.abs(f0 - f1).max() <= 1e-12 * np.abs(f1).max()
    assert np.abs(K0 - K1).max() <= 1e-12 * np.abs(K1).max()


def _lane_forces(model, U):
    mesh, b = model.mesh, model.blocks[0]
    xo, xn, Uc = model._current(U)
    pk = lanes_ans.pack(b.conn, b.c, b.c["r_zq"])
    L = lanes.LANES
    fs = np.full((pk["B"], 24 * L), np.nan)
    ws = np.full((pk["B"], L), np.nan)
    lanes_ans.quad_forces(
        mesh.nodes,
        mesh.directors,
        Uc,
        pk["conn"],
        pk["Cmb"],
        pk["Cs"],
        pk["Cz"],
        pk["r_z"],
        model.quasi,
        model.mu,
        np.empty((pk["B"], 48 * L)),
        fs,
        ws,
    )
    return pk, fs, ws


@pytest.mark.parametrize("thickness", ["green", "quasi"])
@pytest.mark.parametrize("seed", [3, 4])
def test_lane_kernel_matches_core(thickness, seed):
    """Same operations as core.energy_force, grouped and contracted differently: agreement to a few
    units of round-off of the largest element force and energy (1e-13 relative allows ~500 ulps
    over sums of ~100 products; the observed difference is ~4e-16).  Padded lanes: zero force and
    energy."""
    mesh = distorted_warped_mesh(seed=seed)
    model = Model(mesh, WOOL30, thickness_strain=thickness, membrane="ans")
    b = model.blocks[0]
    M = len(b.conn)
    U = random_motion(mesh, seed)
    xo, xn, Uc = model._current(U)
    fe, we = np.empty((M, 4, 6)), np.empty(M)
    core.energy_force(*b.args(xo, xn, Uc, model.quasi, model.mu), fe, we, 1)
    pk, fs, ws = _lane_forces(model, U)
    L = lanes.LANES
    assert pk["B"] * L > M  # a padded block is exercised
    assert np.abs(lanes.unpack_forces(fs, M) - fe).max() <= 1e-13 * np.abs(fe).max()
    assert np.abs(ws.ravel()[:M] - we).max() <= 1e-13 * np.abs(we).max()
    assert np.all(fs.reshape(-1, 24, L).transpose(0, 2, 1).reshape(-1, 24)[M:] == 0.0)
    assert np.all(ws.ravel()[M:] == 0.0)


def test_lane_kernel_membrane_alone_matches_core():
    """A pure in-plane motion of a flat distorted sheet loads the membrane only (no bending, shear
    or thickness strain): the lane kernel's membrane stage alone against core, to round-off."""
    mesh = distorted_warped_mesh()
    flat = ShellMesh(mesh.nodes * [1.0, 1.0, 0.0], quads=mesh.quads)
    model = Model(flat, WOOL30, membrane="ans")
    b = model.blocks[0]
    M = len(b.conn)
    U = np.zeros((flat.n_nodes, 6))
    U[:, :2] = 0.05 * np.random.default_rng(7).standard_normal((flat.n_nodes, 2))
    xo, xn, Uc = model._current(U)
    fe, we = np.empty((M, 4, 6)), np.empty(M)
    core.energy_force(*b.args(xo, xn, Uc, model.quasi, model.mu), fe, we, 1)
    _, fs, ws = _lane_forces(model, U)
    assert np.abs(fe[:, :, 3:]).max() <= 1e-12 * np.abs(fe).max()  # no director force
    assert np.abs(lanes.unpack_forces(fs, M) - fe).max() <= 1e-12 * np.abs(fe).max()
    assert np.abs(ws.ravel()[:M] - we).max() <= 1e-12 * np.abs(we).max()


def test_pack_refuses_the_compatible_membrane():
    model = Model(distorted_warped_mesh(), WOOL30, membrane="full")
    b = model.blocks[0]
    assert not lanes_ans.covers(b.c)
    with pytest.raises(ValueError, match="membrane='ans'"):
        lanes_ans.pack(b.conn, b.c, b.c["r_zq"])


def test_fused_step_with_assumed_membrane_follows_the_previous_path():
    """The explicit solver's fused step on a mesh whose quads are "ans" and "full" in runs (three
    blocks, the adaptive mesh's coarse/fine split) plus triangles: the ans blocks go through the
    lane kernel (the triangles through lanes_tri's), and 60 steps of a sheet falling onto a plane
    follow Model.internal_force + central_step to round-off (1e-11 relative: per-step differences
    of 1e-16 grown by 60 steps of a stable scheme)."""
    from test_lanes import fused_follows_previous_path, fused_force_matches_model

    from solidshell.solvers.explicit.fused import FusedForces, lanes_ans_scatter, lanes_scatter, lanes_tri_scatter

    base = distorted_warped_mesh()
    q = base.quads
    t = q[25:]
    mesh = ShellMesh(base.nodes, quads=q[:25], tris=np.vstack([t[:, [0, 1, 2]], t[:, [0, 2, 3]]]))
    choice = ["ans"] * 12 + ["full"] * 6 + ["ans"] * 7
    model = Model(mesh, WOOL30, thickness_strain="quasi", membrane=choice)
    ff = FusedForces(model)
    assert [p[2]["kernel"] for p in ff.parts if p[0] == "lanes"] == [
        lanes_ans_scatter,
        lanes_scatter,
        lanes_ans_scatter,
        lanes_tri_scatter,
    ]
    fused_follows_previous_path(model, z_plane=mesh.nodes[:, 2].min() + 0.01)  # the lowest nodes start in contact
    # and the force itself at a deformed state, on one and two threads
    fused_force_matches_model(ff, model, random_motion(mesh, 8))
