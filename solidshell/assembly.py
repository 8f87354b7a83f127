"""Element arrays -> global vectors and sparse matrices.

The sparsity pattern of the global tangent and the position of every element entry in the CSR data
array are computed once per mesh; afterwards assembly is a compiled scatter-add.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numba import njit


def element_dofs(conn: np.ndarray) -> np.ndarray:
    """(M, 6 nn) global dof indices, node-major: 6*node + k with k = U_o (0..2), U_n (3..5)."""
    return (6 * conn[:, :, None] + np.arange(6)).reshape(len(conn), 6 * conn.shape[1])


@njit(cache=True)
def scatter_add_vec(dofs, fe, out):
    M, nd = dofs.shape
    for e in range(M):
        for a in range(nd):
            out[dofs[e, a]] += fe[e, a]


@njit(cache=True)
def scatter_add_mat(pos, Ke, data):
    M, nd, _ = Ke.shape
    for e in range(M):
        for a in range(nd):
            for b in range(nd):
                data[pos[e, a, b]] += Ke[e, a, b]


class SparsePattern:
    """CSR pattern of the union of element blocks; ``pos[k]`` maps block k's (M,nd,nd) entries."""

    def __init__(self, n_dofs: int, dof_blocks: list[np.ndarray]):
        self.n = n_dofs
        keys = []
        for d in dof_blocks:
            r = np.broadcast_to(d[:, :, None], d.shape + (d.shape[1],))
            c = np.broadcast_to(d[:, None, :], d.shape + (d.shape[1],))
            keys.append((r.astype(np.int64) * n_dofs + c).ravel())
        allk = np.concatenate(keys) if keys else np.zeros(0, np.int64)
        uniq, inv = np.unique(allk, return_inverse=True)
        self.indices = (uniq % n_dofs).astype(np.int32)
        rows = uniq // n_dofs
        self.indptr = np.searchsorted(rows, np.arange(n_dofs + 1)).astype(np.int32)
        self.pos = []
        start = 0
        for d, k in zip(dof_blocks, keys):
            self.pos.append(inv[start:start + len(k)].reshape(len(d), d.shape[1], d.shape[1]))
            start += len(k)
        self.nnz = len(uniq)

    def assemble(self, K_blocks: list[np.ndarray]) -> sp.csr_matrix:
        data = np.zeros(self.nnz)
        for pos, Ke in zip(self.pos, K_blocks):
            if len(Ke):
                scatter_add_mat(pos, Ke, data)
        return sp.csr_matrix((data, self.indices.copy(), self.indptr.copy()), shape=(self.n, self.n))
