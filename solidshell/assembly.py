"""Element arrays -> global vectors and sparse matrices.

The sparsity pattern of the global tangent and the position of every element entry in the CSR data
array are computed once per mesh; afterwards assembly is a compiled scatter-add (Model does it, a
chunk of elements at a time).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .elements.core import half_entries, half_slots


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
    """data[pos[e, a, b]] += Ke[e, a, b], skipping the entries with pos < 0 (a free lower-triangle
    pattern's fixed dofs and upper triangle; a full pattern has none)."""
    M, nd, _ = Ke.shape
    for e in range(M):
        for a in range(nd):
            for b in range(nd):
                k = pos[e, a, b]
                if k >= 0:
                    data[k] += Ke[e, a, b]


@njit(cache=True)
def scatter_add_half(pos, flat, Kh, data):
    """data[pos[e, k]] += Kh[e, flat[k]], skipping pos < 0 (fixed dofs): the half element matrices
    of core.force_tangent with ``half``, each flattened to (nd*nd,), at the entries ``flat`` = rows * nd +
    columns of core.half_entries, into a free lower-triangle pattern (``FreeLowerPattern.
    half_pos``).  Elements in order, so every entry sums its element terms in the same order as
    scatter_add_mat (an element adds to an entry once: its nodes are distinct)."""
    M = Kh.shape[0]
    n = flat.size
    for e in range(M):
        for k in range(n):
            p = pos[e, k]
            if p >= 0:
                data[p] += Kh[e, flat[k]]


@njit(cache=True)
def _half_positions(conn, pos, to_lower, rows, cols, out):
    """out[e, k] = to_lower[pos[e, a, b]] for the k-th entry (a, b) = (rows[k], cols[k]) of element
    e's half matrix (core.force_tangent with ``half``: nodes in decreasing global order); a, b are dofs in
    that order, ``pos`` (M, nd, nd) the full pattern's map in the local order."""
    M, nn = conn.shape
    nd = 6 * nn
    local = np.empty(nd, dtype=np.int64)  # dof in the half matrix's order -> local dof
    slot = np.empty(nn, dtype=np.int64)
    for e in range(M):
        half_slots(conn[e], slot)
        for i in range(nn):
            for c in range(6):
                local[6 * slot[i] + c] = 6 * i + c
        for k in range(rows.size):
            out[e, k] = to_lower[pos[e, local[rows[k]], local[cols[k]]]]


@njit(cache=True)
def _expand_node_pattern(nindptr, nindices):
    """Dof-level CSR (indptr, indices) of a node-level pattern with 6x6 blocks: row 6i+k holds the
    columns 6j..6j+5 of every neighbour j of node i, in increasing order."""
    N = nindptr.size - 1
    indptr = np.empty(6 * N + 1, dtype=np.int64)
    indptr[0] = 0
    for i in range(N):
        deg = nindptr[i + 1] - nindptr[i]
        for k in range(6):
            indptr[6 * i + k + 1] = indptr[6 * i + k] + 6 * deg
    indices = np.empty(indptr[-1], dtype=np.int32)
    for i in range(N):
        deg = nindptr[i + 1] - nindptr[i]
        for k in range(6):
            r0 = indptr[6 * i + k]
            for s in range(deg):
                j = nindices[nindptr[i] + s]
                for m in range(6):
                    indices[r0 + 6 * s + m] = 6 * j + m
    return indptr, indices


@njit(cache=True)
def _node_block_positions(conn, nindptr, nindices, indptr, pos):
    """Fill pos (M, 6nn, 6nn) (int32 or int64, allocated by the caller: int32 where the pattern
    allows, so no int64 map is ever formed) with the position of every element-matrix entry in
    the data array of the expanded pattern."""
    M, nn = conn.shape
    for e in range(M):
        for p in range(nn):
            i = conn[e, p]
            lo = nindptr[i]
            deg = nindptr[i + 1] - lo
            for q in range(nn):
                j = conn[e, q]
                s = np.searchsorted(nindices[lo : lo + deg], j)
                for ka in range(6):
                    base = indptr[6 * i + ka] + 6 * s
                    for kb in range(6):
                        pos[e, 6 * p + ka, 6 * q + kb] = base + kb


class SparsePattern:
    """CSR pattern of the union of element blocks; ``pos[k]`` maps block k's (M,nd,nd) entries.

    Built at the node level (node-pair graph, then 6x6 dof blocks) when the blocks' dofs are
    node-major (``element_dofs``), as all of solidshell's are: the element-entry-level construction
    (np.unique over every element entry) peaked at ~100 MB above the result on square-pedestal
    48x16x4; both give the same arrays."""

    def __init__(self, n_dofs: int, dof_blocks: list[np.ndarray]):
        self.n = n_dofs
        conns = [d[:, ::6] // 6 for d in dof_blocks]
        self.conns = None  # the blocks' connectivities when their dofs are node-major
        if n_dofs % 6 == 0 and all(
            d.shape[1] % 6 == 0 and np.array_equal(d, element_dofs(c)) for d, c in zip(dof_blocks, conns)
        ):
            self.conns = [np.ascontiguousarray(c, dtype=np.int64) for c in conns]
            self._from_nodes(n_dofs // 6, self.conns)
        else:
            self._from_entries(n_dofs, dof_blocks)

    def _from_nodes(self, N, conns):
        keys = [(c[:, :, None] * N + c[:, None, :]).ravel() for c in conns]
        uniq = np.unique(np.concatenate(keys)) if keys else np.zeros(0, np.int64)
        nindices = (uniq % N).astype(np.int64)
        nindptr = np.searchsorted(uniq // N, np.arange(N + 1)).astype(np.int64)
        indptr, self.indices = _expand_node_pattern(nindptr, nindices)
        self.nnz = int(indptr[-1])
        # int32 positions where they fit: half the memory of the (M, nd, nd) maps
        itype = np.int32 if self.nnz < 2**31 else np.int64
        self.pos = []
        for c in conns:
            nd = 6 * c.shape[1]
            pos = np.empty((c.shape[0], nd, nd), dtype=itype)
            _node_block_positions(c, nindptr, nindices, indptr, pos)
            self.pos.append(pos)
        self.indptr = indptr.astype(np.int32) if self.nnz < 2**31 else indptr

    def _from_entries(self, n_dofs, dof_blocks):
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
            self.pos.append(inv[start : start + len(k)].reshape(len(d), d.shape[1], d.shape[1]))
            start += len(k)
        self.nnz = len(uniq)


@njit(cache=True)
def _lower_free(indptr, indices, new, nf, to_lower):
    """The lower triangle of a symmetric CSR pattern restricted to the dofs with new[dof] >= 0,
    renumbered by ``new``, in CSC: (indptr, indices); ``to_lower`` (the full pattern's nnz, int32
    or int64, from the caller) gets the position in it of the full pattern's entry k, or -1.

    Column j of the lower triangle is filled from row j of the full matrix (its entries at and
    right of the diagonal), i.e. with K[j, i] at (i, j): the element matrices are symmetric only
    to round-off, and this is the triangle the solver factorised before (the free-dof CSR arrays
    read as CSC), so the factorisations, and the Newton paths, stay the same to the last bit.
    Rows come out sorted because the full rows are sorted and ``new`` is increasing."""
    n = indptr.size - 1
    count = np.zeros(nf + 1, dtype=np.int64)
    for r in range(n):
        nr = new[r]
        if nr < 0:
            continue
        for k in range(indptr[r], indptr[r + 1]):
            nc = new[indices[k]]
            if nc >= nr:
                count[nr + 1] += 1
    lptr = np.cumsum(count)
    lind = np.empty(lptr[-1], dtype=np.int32)
    to_lower[:] = -1
    for r in range(n):
        nr = new[r]
        if nr < 0:
            continue
        q = lptr[nr]
        for k in range(indptr[r], indptr[r + 1]):
            nc = new[indices[k]]
            if nc >= nr:
                lind[q] = nc
                to_lower[k] = q
                q += 1
    return lptr, lind


class FreeLowerPattern:
    """The lower triangle (CSC, diagonal included) of a :class:`SparsePattern` restricted to the
    free dofs.  The static solver assembles its tangent straight into this form, the one CHOLMOD
    factorises, instead of assembling all 6N x 6N entries and gathering the free lower part every
    iteration.  It holds the upper triangle of K_t transposed (``_lower_free`` says why): the
    entries whose global column dof is >= their global row dof.  Those are one triangle of each
    element matrix with its nodes in global order, so only that triangle is formed
    (core.force_tangent with ``half``: about 60 % of the material flops of the whole matrix).  ``half_pos``
    (one (M, nd(nd+1)/2) map per element block) gives the position in the data array of each
    entry of an element's half matrix listed in ``half_entries`` (flat indices row * nd + column of
    core.half_entries), -1 for a fixed dof.  Each entry sums the same element contributions in the
    same order as the full assembly, so the values are identical to the last bit.

    ``node_pos`` (N, 3, 3): the positions of the translational 3x3 block of every node (contact
    stiffness), -1 where not stored; ``diag_pos``: the diagonal entries; ``free``: the free dofs.
    """

    def __init__(self, pattern: SparsePattern, free: np.ndarray):
        n = pattern.n
        free = np.asarray(free, dtype=np.int64)
        nf = free.size
        new = np.full(n, -1, dtype=np.int64)
        new[free] = np.arange(nf)
        # int32 maps where they fit, gathered straight into int32 (an int64 gather of the
        # (M, nd, nd) maps was the peak of the static set-up: +39 MB on square-pedestal 48x16x4)
        to_lower = np.empty(pattern.indices.size, dtype=np.int32 if pattern.indices.size < 2**31 else np.int64)
        lptr, self.indices = _lower_free(pattern.indptr.astype(np.int64), pattern.indices, new, nf, to_lower)
        if pattern.conns is None:
            raise ValueError("FreeLowerPattern needs a node-major pattern (dofs from element_dofs)")
        self.half_pos = []
        self.half_entries = []
        for p, conn in zip(pattern.pos, pattern.conns):
            srt = np.sort(conn, axis=1)
            if np.any(srt[:, 1:] == srt[:, :-1]):
                raise ValueError("an element repeats a node: its half element matrix is not defined")
            rows, cols = half_entries(conn.shape[1])
            hp = np.empty((len(conn), rows.size), dtype=to_lower.dtype)
            _half_positions(conn, p, to_lower, rows, cols, hp)
            self.half_pos.append(hp)
            self.half_entries.append(rows * (6 * conn.shape[1]) + cols)
        del to_lower
        self.indptr = lptr.astype(np.int32)
        self.nnz = int(lptr[-1])
        self.n = nf
        self.free = free
        cols = np.repeat(np.arange(nf, dtype=np.int64), np.diff(lptr))
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
        keys = cols * nf + self.indices  # sorted: column-major order
        node_pos[ok] = np.searchsorted(keys, cc[ok] * nf + rr[ok])
        self.node_pos = node_pos
        self._new = new  # global dof -> free dof (-1: fixed)
        self._keys = None  # the keys above, kept once entry_positions needs them

    def entry_positions(self, rows, cols):
        """(data positions, mask) of entries (rows, cols) of the full 6N x 6N symmetric matrix given
        by global dofs: those on free dofs in the stored triangle (row >= column, free numbering),
        each once, and the mask of which they were (contact stiffness coupling an element's nodes:
        the pattern holds every pair of dofs of one element)."""
        if self._keys is None:
            self._keys = np.repeat(np.arange(self.n, dtype=np.int64), np.diff(self.indptr)) * self.n + self.indices
        r, c = self._new[rows], self._new[cols]
        ok = (r >= 0) & (c >= 0) & (r >= c)
        return np.searchsorted(self._keys, c[ok] * self.n + r[ok]), ok
