"""The static solver's tangent assembly from half element matrices (core.force_tangent with ``half`` into
FreeLowerPattern, Model.force_and_free_tangent) against the whole-matrix path it replaced: the
assembled data must be the same to the last bit, because the static paths of some scenes are chaotic
(square-on-disc) and a last-bit change can pick another equilibrium.  The full-pattern tangent's
finite-difference consistency and symmetry are tested in tests/test_elements.py
(test_force_and_tangent_are_derivatives, mixed quad/triangle mesh, both membranes, Eq. 24)."""

import numpy as np
import pytest
from numba import get_num_threads
from test_assembly import mixed_mesh

import solidshell.model as model_mod
from solidshell.assembly import _lower_free, scatter_add_mat, scatter_add_vec
from solidshell.elements import core
from solidshell.material import Fabric
from solidshell.mesh import ShellMesh
from solidshell.model import Model


def warped_quads(nx=7, ny=5, seed=4):
    """A curved, distorted quad grid with its nodes numbered at random (so the elements' local and
    global node orders disagree in every way)."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.linspace(0, 3, nx), np.linspace(0, 2, ny))
    X = np.column_stack([x.ravel(), y.ravel(), 0.2 * np.sin(x.ravel()) * np.cos(y.ravel())])
    X[:, :2] += 0.05 * rng.uniform(-1, 1, (X.shape[0], 2))
    idx = np.arange(nx * ny).reshape(ny, nx)
    quads = np.array(
        [[idx[j, i], idx[j, i + 1], idx[j + 1, i + 1], idx[j + 1, i]] for j in range(ny - 1) for i in range(nx - 1)]
    )
    perm = rng.permutation(nx * ny)
    inv = np.argsort(perm)
    return ShellMesh(X[perm], quads=inv[quads])


def whole_matrix_assembly(m, U, free):
    """The assembly the static solver used before: the whole element matrices of core.force_tangent
    scattered through the dense (M, nd, nd) map of the free lower triangle (Model.
    _force_and_tangent_into with FreeLowerPattern's former ``pos``)."""
    p = m.pattern
    new = np.full(p.n, -1, dtype=np.int64)
    new[free] = np.arange(free.size)
    to_lower = np.empty(p.indices.size, dtype=np.int64)
    _, lind = _lower_free(p.indptr.astype(np.int64), p.indices, new, free.size, to_lower)
    xo, xn, Uc = m._current(U)
    F = np.zeros(m.n_dofs)
    data = np.zeros(lind.size)
    for b, pos in zip(m.blocks, p.pos):
        M, nd = len(b.conn), 6 * b.nn
        fe, we, Ke = np.empty((M, b.nn, 6)), np.empty(M), np.empty((M, nd, nd))
        core.force_tangent(*b.args(xo, xn, Uc, m.quasi, m.mu), b.gp_membrane, fe, we, Ke, get_num_threads())
        scatter_add_vec(b.dofs, fe.reshape(M, -1), F)
        scatter_add_mat(to_lower[pos], Ke, data)
    return F.reshape(-1, 6), data


def fixed_free(mesh):
    """Some whole nodes and one partly fixed node fixed: the free dofs."""
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[[0, 5, 11]] = True
    fixed[7, [1, 3, 5]] = True
    return np.flatnonzero(~fixed.ravel())


CASES = {
    "quads": (warped_quads, {}),
    "quads-ans-quasi": (warped_quads, dict(membrane="ans", thickness_strain="quasi")),
    "mixed": (mixed_mesh, {}),
    "mixed-quasi-per-quad-membrane": (mixed_mesh, dict(membrane=["ans", "full"] * 4, thickness_strain="quasi")),
}


@pytest.mark.parametrize("case", list(CASES))
def test_half_matrix_assembly_equals_the_whole_matrix_one_to_the_last_bit(case):
    make, kw = CASES[case]
    mesh = make()
    m = Model(mesh, Fabric.wool(warp_angle=20.0), **kw)
    U = 0.05 * np.random.default_rng(6).standard_normal((mesh.n_nodes, 6))
    free = fixed_free(mesh)
    F0, data0 = whole_matrix_assembly(m, U, free)
    F, data = m.force_and_free_tangent(U, m.free_lower_pattern(free))
    # every kept entry is the same expression summed in the same order: identical bits
    assert np.array_equal(F, F0)
    assert np.array_equal(data, data0)
    assert np.all(np.isfinite(data)) and np.count_nonzero(data) > data.size // 2


def test_half_element_matrices_are_entries_of_the_whole_ones():
    """core.force_tangent's half matrices: their formed entries (core.half_entries, nodes in decreasing global
    order) are bit for bit the corresponding entries of core.force_tangent's whole matrices."""
    mesh = mixed_mesh()
    m = Model(mesh, Fabric.wool(), membrane=["ans", "full"] * 4, thickness_strain="quasi")
    U = 0.05 * np.random.default_rng(8).standard_normal((mesh.n_nodes, 6))
    xo, xn, Uc = m._current(U)
    for b in m.blocks:
        M, nn, nd = len(b.conn), b.nn, 6 * b.nn
        args = b.args(xo, xn, Uc, m.quasi, m.mu)
        f1, w1, K1 = np.empty((M, nn, 6)), np.empty(M), np.empty((M, nd, nd))
        f2, w2, K2 = np.empty((M, nn, 6)), np.empty(M), np.empty((M, nd, nd))
        core.force_tangent(*args, b.gp_membrane, f1, w1, K1, 1)
        core.force_tangent(*args, b.gp_membrane, f2, w2, K2, 1, True)
        assert np.array_equal(f1, f2) and np.array_equal(w1, w2)
        rows, cols = core.half_entries(nn)
        assert rows.size == nd * (nd + 1) // 2
        slot = np.empty(nn, dtype=np.int64)
        for e in range(M):
            core.half_slots(b.conn[e], slot)
            local = np.empty(nd, dtype=np.int64)
            local[(6 * slot[:, None] + np.arange(6)).ravel()] = np.arange(nd)
            g = (6 * b.conn[e][:, None] + np.arange(6)).ravel()[local]  # global dof per half dof
            # the formed entries are exactly those with global column >= global row
            assert np.array_equal(
                np.sort(np.flatnonzero((g[:, None] <= g[None, :]).ravel())), np.sort(rows * nd + cols)
            )
            assert np.array_equal(K2[e][rows, cols], K1[e][local[rows], local[cols]])


def test_chunked_half_assembly_is_bit_identical(monkeypatch):
    """Chunks of 3 elements (6 chunks per block) give the very bits of one chunk per block."""
    mesh = mixed_mesh()
    m = Model(mesh, Fabric.wool())
    U = 0.05 * np.random.default_rng(9).standard_normal((mesh.n_nodes, 6))
    lower = m.free_lower_pattern(fixed_free(mesh))
    F1, d1 = m.force_and_free_tangent(U, lower)
    monkeypatch.setattr(model_mod, "HALF_TANGENT_CHUNK", 3)
    F2, d2 = m.force_and_free_tangent(U, lower)
    assert np.array_equal(F1, F2) and np.array_equal(d1, d2)
