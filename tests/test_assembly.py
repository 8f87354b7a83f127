"""Assembly patterns (solidshell/assembly.py): the node-level construction of the tangent's CSR
pattern, the free-dof lower-triangle pattern the static solver assembles into, and the CHOLMOD fast
path fed with it (solidshell/solvers/linear.py)."""

import numpy as np
import scipy.sparse as sp

from solidshell.assembly import SparsePattern
from solidshell.material import Fabric
from solidshell.mesh import ShellMesh
from solidshell.model import Model
from solidshell.solvers.linear import Cholesky, LowerCSC


def mixed_mesh():
    """A 4x3 grid of quads with the last row split into triangles, slightly warped (no symmetry
    that could hide a misplaced entry); nodes numbered out of grid order."""
    nx, ny = 5, 4
    x, y = np.meshgrid(np.linspace(0, 4, nx), np.linspace(0, 3, ny))
    X = np.column_stack([x.ravel(), y.ravel(), 0.0 * x.ravel()])
    X[:, :2] += 0.07 * np.sin(3.0 * X[:, ::-1][:, 1:])
    idx = np.arange(nx * ny).reshape(ny, nx)
    cells = [[idx[j, i], idx[j, i + 1], idx[j + 1, i + 1], idx[j + 1, i]] for j in range(ny - 1) for i in range(nx - 1)]
    quads = np.array(cells[:8])
    tris = np.concatenate([[[c[0], c[1], c[2]], [c[0], c[2], c[3]]] for c in cells[8:]])
    perm = np.random.default_rng(3).permutation(nx * ny)
    inv = np.argsort(perm)
    return ShellMesh(X[perm], quads=inv[quads], tris=inv[tris])


def test_node_level_pattern_equals_the_entry_level_one():
    m = Model(mixed_mesh(), Fabric.wool())
    blocks = [b.dofs for b in m.blocks]
    fast = SparsePattern(m.n_dofs, blocks)
    ref = SparsePattern.__new__(SparsePattern)
    ref.n = m.n_dofs
    ref._from_entries(m.n_dofs, blocks)
    # exact: both are integer index maps of the same set of (row, column) pairs
    assert fast.nnz == ref.nnz
    assert np.array_equal(fast.indptr, ref.indptr) and np.array_equal(fast.indices, ref.indices)
    for p, q in zip(fast.pos, ref.pos):
        assert np.array_equal(p, q)


def test_free_lower_assembly_is_the_restricted_lower_triangle_to_the_last_bit():
    mesh = mixed_mesh()
    m = Model(mesh, Fabric.wool())
    rng = np.random.default_rng(1)
    U = 0.05 * rng.standard_normal((mesh.n_nodes, 6))
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[:3] = True
    fixed[7, [0, 4]] = True  # a partly fixed node
    free = np.flatnonzero(~fixed.ravel())
    lower = m.free_lower_pattern(free)
    F, data = m.force_and_free_tangent(U, lower)
    F0, K = m.force_and_tangent(U)
    # the lower triangle holds K[j, i] at (i, j): the upper triangle transposed (the element
    # matrices are symmetric to round-off only; _lower_free says why this one)
    ref = sp.triu(K.tocsr()[free][:, free], format="csr").T.tocsc()
    ref.sort_indices()
    # the same element contributions summed in the same order: identical bits, not just close
    assert np.array_equal(F, F0)
    assert np.array_equal(lower.indptr, ref.indptr) and np.array_equal(lower.indices, ref.indices)
    assert np.array_equal(data, ref.data)
    assert np.array_equal(data[lower.diag_pos], ref.diagonal())
    # the node translational blocks (contact stiffness) point at their (row, column) entries
    L = LowerCSC(lower.indptr, lower.indices, np.arange(lower.nnz, dtype=float), lower.diag_pos, lower)
    dense = L.csc().toarray()
    new = -np.ones(6 * mesh.n_nodes, int)
    new[free] = np.arange(free.size)
    for i in (7, 11):
        for a in range(3):
            for b in range(3):
                r, c = new[6 * i + a], new[6 * i + b]
                p = lower.node_pos[i, a, b]
                if r < 0 or c < 0 or r < c:
                    assert p == -1
                else:
                    assert p >= 0 and dense[r, c] == p


def test_cholesky_fast_path_matches_the_scipy_path():
    mesh = mixed_mesh()
    m = Model(mesh, Fabric.wool())
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[:5] = True
    free = np.flatnonzero(~fixed.ravel())
    lower = m.free_lower_pattern(free)
    _, data = m.force_and_free_tangent(np.zeros((mesh.n_nodes, 6)), lower)
    A = LowerCSC(lower.indptr, lower.indices, data, lower.diag_pos, lower)
    b = np.random.default_rng(2).standard_normal(free.size)
    c1, c2 = Cholesky(), Cholesky()
    assert c1.factor(A) and c2.factor(A.csc())
    # the same matrix; the scipy path drops the pattern's explicit zeros (scipy's sum prunes them),
    # so its AMD ordering may differ: the solutions agree to round-off, cond(K) ~ 2e5 here, so a
    # backward-stable solve is good to ~1e-16 * 2e5 ~ 2e-11 relative; 1e-9 leaves a margin
    x1, x2 = c1.solve(b), c2.solve(b)
    assert np.abs(x1 - x2).max() <= 1e-9 * np.abs(x1).max()
    r = A.csc() @ x1 - b
    assert np.linalg.norm(r) <= 1e-9 * np.linalg.norm(b)
    # a second matrix with the same pattern object reuses the analysis
    assert c1.factor(A, np.full(free.size, 1.0)) and c1.n_symbolic == 1


def test_chunked_tangent_assembly_is_bit_identical(monkeypatch):
    """Model assembles tangents TANGENT_CHUNK elements at a time; chunks of 3 elements (16 quads
    and triangles in 6 chunks per block) must give the very same bits as one chunk per block."""
    import solidshell.model as model_mod

    mesh = mixed_mesh()
    m = Model(mesh, Fabric.wool())
    U = 0.05 * np.random.default_rng(7).standard_normal((mesh.n_nodes, 6))
    F1, K1 = m.force_and_tangent(U)
    monkeypatch.setattr(model_mod, "TANGENT_CHUNK", 3)
    F2, K2 = m.force_and_tangent(U)
    assert np.array_equal(F1, F2) and np.array_equal(K1.data, K2.data)
    assert np.array_equal(K1.indices, K2.indices) and np.array_equal(K1.indptr, K2.indptr)
