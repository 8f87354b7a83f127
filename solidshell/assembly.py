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


@njit(cache=True)
def scatter_add_mat_masked(pos, Ke, data):
    """``scatter_add_mat`` skipping the entries with pos < 0 (fixed dofs, upper triangle)."""
    M, nd, _ = Ke.shape
    for e in range(M):
        for a in range(nd):
            for b in range(nd):
                k = pos[e, a, b]
                if k >= 0:
                    data[k] += Ke[e, a, b]


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


class FreeLowerPattern:
    """The lower triangle (CSC, diagonal included) of a :class:`SparsePattern` restricted to the
    free dofs, with the position of every element-matrix entry in its data array (-1: a fixed dof
    or the upper triangle).  The static solver assembles its tangent straight into this form, the
    one CHOLMOD factorises, instead of assembling all 6N x 6N entries and gathering the free lower
    part every iteration.  Each entry sums the same element contributions in the same order as the
    full assembly, so the values are identical to the last bit.

    ``node_pos`` (N, 3, 3): the positions of the translational 3x3 block of every node (contact
    stiffness), -1 where not stored; ``diag_pos``: the diagonal entries; ``free``: the free dofs.
    """

    def __init__(self, pattern: SparsePattern, free: np.ndarray):
        n = pattern.n
        free = np.asarray(free, dtype=np.int64)
        nf = free.size
        new = np.full(n, -1, dtype=np.int64)
        new[free] = np.arange(nf)
        row = np.repeat(np.arange(n, dtype=np.int64), np.diff(pattern.indptr))
        r, c = new[row], new[pattern.indices.astype(np.int64)]
        keep = np.flatnonzero((r >= 0) & (c >= 0) & (r >= c))
        order = np.lexsort((r[keep], c[keep]))          # column-major: CSC of the lower triangle
        kept = keep[order]
        self.indices = r[kept].astype(np.int32)
        cols = c[kept]
        self.indptr = np.searchsorted(cols, np.arange(nf + 1)).astype(np.int32)
        to_lower = np.full(pattern.nnz, -1, dtype=np.int64)
        to_lower[kept] = np.arange(kept.size)
        self.pos = [to_lower[p] for p in pattern.pos]
        self.nnz = int(kept.size)
        self.n = nf
        self.free = free
        self.diag_pos = np.flatnonzero(self.indices == cols)
        if self.diag_pos.size != nf:
            raise RuntimeError("the tangent pattern lacks a diagonal entry of a free dof")
        # the translational block of each node: (row 6i+a, column 6i+b) with a >= b, free dofs
        N = n // 6
        a = np.arange(3)
        rr = new[(6 * np.arange(N))[:, None, None] + a[None, :, None]].repeat(3, axis=2)
        cc = new[(6 * np.arange(N))[:, None, None] + a[None, None, :]].repeat(3, axis=1)
        ok = (rr >= 0) & (cc >= 0) & (rr >= cc)
        node_pos = np.full((N, 3, 3), -1, dtype=np.int64)
        keys = cols * nf + self.indices              # sorted: column-major order
        node_pos[ok] = np.searchsorted(keys, cc[ok] * nf + rr[ok])
        self.node_pos = node_pos

    def assemble(self, K_blocks: list[np.ndarray]) -> np.ndarray:
        """The data array (lower triangle, free dofs) of the sum of the element matrices."""
        data = np.zeros(self.nnz)
        for pos, Ke in zip(self.pos, K_blocks):
            if len(Ke):
                scatter_add_mat_masked(pos, Ke, data)
        return data
