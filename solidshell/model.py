"""Model: a mesh and a shell section -> energy, internal force, tangent, lumped mass (public face).

U is always an (N,6) array [U_o | U_n] per node (Eq. 1), in the mesh's length unit; forces are in
the section's force unit (gf for fabrics), energies in force x length, the tangent is a scipy CSR
matrix (6N, 6N) with dof index 6*node + k.
"""

from __future__ import annotations

import copy

import numpy as np
from numba import get_num_threads

from .assembly import FreeLowerPattern, SparsePattern, element_dofs, scatter_add_half, scatter_add_mat, scatter_add_vec
from .elements import THICKNESS_STRAINS, core, quad4, tri3
from .elements.corners import corner_alignment
from .errors import InputError
from .mesh import ShellMesh

TANGENT_CHUNK = 1024
"""Elements per kernel call when tangents are assembled (Model._force_and_tangent_into)."""

HALF_TANGENT_CHUNK = 256
"""The same for the half element matrices (Model.force_and_free_tangent): a chunk's matrices,
written by the kernel and read back by the scatter, stay in the cache (1.2 MB of quads)."""


def _force_tangent_half(*args):
    """core.force_tangent with ``half``: the static solver's half element matrices."""
    return core.force_tangent(*args, True)


_TYPE_CONSTANTS = ("alpha", "beta", "tie")
"""Entries of an element type's constants shared by all its elements (not per element)."""


def _precompute(module, Xo_e, Xn_e, section, membrane) -> dict:
    return module.precompute(
        Xo_e,
        Xn_e,
        section.C_m,
        section.C_b,
        section.C_t,
        float(section.E_z),
        float(section.warp_angle_rad),
        membrane=membrane,
    )


def _section_key(section) -> bytes:
    """What of a section the folded constants depend on, as bytes."""
    return b"".join(
        np.asarray(v, dtype=float).tobytes()
        for v in (section.C_m, section.C_b, section.C_t, section.E_z, section.warp_angle_rad)
    )


class ElementConstants:
    """Folded element constants (``module.precompute``) kept by element, for the models of meshes
    that share elements: the adaptive driver's successive meshes, where most elements survive a
    remesh.  An element's constants depend only on its nodes' X_o and X_n, the section and the
    membrane choice, and the precompute functions treat every element apart from the others (bit
    for bit: tests/test_adapt_settle.py), so a model built with this cache equals one built
    without it.  Elements are recognised by the bytes of their reference nodes; one instance serves
    one section (a model of another section is refused)."""

    def __init__(self):
        self._section = None
        self._tables = {}  # (module, membrane) -> _ConstantsTable

    def get(self, module, Xo_e, Xn_e, section, membrane) -> dict:
        """precompute's dict for the elements with nodal (M, nn, 3) Xo_e, Xn_e: the cached rows,
        and one precompute call for the elements not seen before."""
        key = _section_key(section)
        if self._section is None:
            self._section = key
        elif key != self._section:
            raise ValueError("ElementConstants serves one section; make another for this one")
        if not len(Xo_e):
            return _precompute(module, Xo_e, Xn_e, section, membrane)
        table = self._tables.setdefault((module.__name__, membrane), _ConstantsTable())
        rows = _element_rows(Xo_e, Xn_e)
        slot = table.find(rows)
        miss = np.flatnonzero(slot < 0)
        if miss.size:
            slot[miss] = table.add(rows[miss], _precompute(module, Xo_e[miss], Xn_e[miss], section, membrane))
        return table.gather(slot)


def _element_rows(Xo_e, Xn_e) -> np.ndarray:
    """(M, 6 nn) uint64: each element's reference node coordinates X_o, X_n as raw 64-bit words, its
    key in ElementConstants (equal rows <=> equal bytes, as the per-element bytes keys were)."""
    M = len(Xo_e)
    R = np.concatenate(
        [np.asarray(Xo_e, dtype=float).reshape(M, -1), np.asarray(Xn_e, dtype=float).reshape(M, -1)], axis=1
    )
    return np.ascontiguousarray(R).view(np.uint64)


_FNV_PRIME = np.uint64(0x100000001B3)


def _row_hash(rows: np.ndarray) -> np.ndarray:
    """(M,) uint64 FNV-1a-style hash over the 64-bit words of each row (vectorised over rows).  A
    collision costs only a recomputation: a hit is confirmed by comparing the rows themselves."""
    h = np.full(len(rows), np.uint64(0xCBF29CE484222325))
    with np.errstate(over="ignore"):
        for j in range(rows.shape[1]):
            h = (h ^ rows[:, j]) * _FNV_PRIME
            h ^= h >> np.uint64(29)
    return h


class _ConstantsTable:
    """The constants of one (element type, membrane) seen so far: one row per element in growing
    stores, found by a sorted array of row hashes (np.searchsorted; no Python loop over elements,
    which the per-element dictionary of bytes keys was: 0.45 s of the paper path's remeshing)."""

    def __init__(self):
        self.n = 0
        self.rows = None  # (cap, 6 nn) uint64 keys of the stored elements
        self.store = {}  # per-element constant -> (cap, ...) array
        self.shared = None  # the type constants (_TYPE_CONSTANTS) of the first precompute
        self.hashes = np.zeros(0, dtype=np.uint64)  # sorted hashes of the indexed rows
        self.slots = np.zeros(0, dtype=np.int64)  # their rows in the stores

    def find(self, rows) -> np.ndarray:
        """(M,) store row of each element (row of ``rows``), -1 where not stored."""
        out = np.full(len(rows), -1, dtype=np.int64)
        if not self.hashes.size:
            return out
        h = _row_hash(rows)
        pos = np.minimum(np.searchsorted(self.hashes, h), self.hashes.size - 1)
        cand = np.flatnonzero(self.hashes[pos] == h)
        slot = self.slots[pos[cand]]
        same = np.all(self.rows[slot] == rows[cand], axis=1)
        out[cand[same]] = slot[same]
        return out

    def add(self, rows, consts: dict) -> np.ndarray:
        """Store new elements' rows and precomputed constants; their store rows.  A row whose hash
        is already indexed (a collision, or a duplicate within ``rows``) is stored but not indexed:
        it is recomputed when asked for again, never confused with another."""
        k = len(rows)
        if self.shared is None:
            self.shared = {c: v for c, v in consts.items() if c in _TYPE_CONSTANTS}
        per = {c: v for c, v in consts.items() if c not in _TYPE_CONSTANTS}
        if self.n + k > (0 if self.rows is None else len(self.rows)):
            cap = max(2 * (self.n + k), 64)
            self.rows = _grown(self.rows, cap, rows)
            self.store = {c: _grown(self.store.get(c), cap, v) for c, v in per.items()}
        new = np.arange(self.n, self.n + k)
        self.rows[new] = rows
        for c, v in per.items():
            self.store[c][new] = v
        self.n += k
        h = _row_hash(rows)
        _, first = np.unique(h, return_index=True)
        fresh = first[~np.isin(h[first], self.hashes)]
        hashes = np.concatenate([self.hashes, h[fresh]])
        order = np.argsort(hashes, kind="stable")
        self.hashes, self.slots = hashes[order], np.concatenate([self.slots, new[fresh]])[order]
        return new

    def gather(self, slot) -> dict:
        """precompute's dict for the stored elements ``slot`` (in that order)."""
        out = dict(self.shared)
        out.update({c: v[slot] for c, v in self.store.items()})
        return out


def _grown(a, cap, like) -> np.ndarray:
    """``a``'s rows in a new (cap, ...) array shaped and typed like ``like``'s rows."""
    out = np.empty((cap,) + like.shape[1:], dtype=like.dtype)
    if a is not None:
        out[: len(a)] = a
    return out


class _Block:
    """One element type of the mesh with its folded constants (see elements/core.py)."""

    def __init__(self, module, conn, Xo, Xn, section, membrane, constants=None):
        self.module = module
        self.conn = np.ascontiguousarray(conn, dtype=np.int64)
        self.nn = conn.shape[1]
        self.dofs = element_dofs(self.conn)
        c = (constants.get if constants is not None else _precompute)(module, Xo[conn], Xn[conn], section, membrane)
        # Eq. (24) measures |x_n| - 1 against |X_n| (not |X_n|^2/2 as the Green strain does)
        c["r_zq"] = np.sqrt(2.0 * c["r_z"])
        self.c = c
        self.dN = np.ascontiguousarray(module.DN_GP)
        self.alpha = np.ascontiguousarray(c["alpha"], dtype=float)
        self.beta = np.ascontiguousarray(c["beta"], dtype=float)
        self.tie = np.ascontiguousarray(c["tie"], dtype=float)
        self.gp_membrane = bool(np.any(c["Cmb"][:, :, 0]))

    def take(self, sel) -> "_Block":
        """This block with only the elements ``sel`` (indices): the constants are sliced, not folded
        again."""
        b = copy.copy(self)
        b.conn = np.ascontiguousarray(self.conn[sel])
        b.dofs = np.ascontiguousarray(self.dofs[sel])
        b.c = {k: (v if k in _TYPE_CONSTANTS else np.ascontiguousarray(v[sel])) for k, v in self.c.items()}
        return b

    def args(self, xo, xn, U, quasi, mu, sl=slice(None)):
        """Kernel arguments: current positions/directors xo, xn (N,3) and the displacements U (N,6)
        from which the strains are formed (displacement form, elements/core.py); ``sl`` selects a
        range of elements (the per-element arrays are sliced, views)."""
        c = self.c
        return (
            xo,
            xn,
            U,
            self.conn[sl],
            self.dN,
            self.alpha,
            self.beta,
            self.tie,
            c["Cmb"][sl],
            c["Cs"][sl],
            c["Cz"][sl],
            c["r_zq"][sl],
            quasi,
            mu,
        )


def _membrane_runs(membrane, n_quads: int) -> list:
    """[(first, end, membrane)]: the quads' membrane choice as runs of equal values (one element
    block each); InputError for an unknown value or a per-quad sequence of the wrong length."""
    if isinstance(membrane, str):
        per = np.full(n_quads, membrane, dtype=object)
    else:
        per = np.asarray(membrane, dtype=object).ravel()
        if per.size != n_quads:
            raise InputError(f"membrane per quadrilateral needs {n_quads} values, got {per.size}")
    bad = sorted({str(m) for m in per} - set(quad4.MEMBRANES))
    if bad or (isinstance(membrane, str) and membrane not in quad4.MEMBRANES):
        raise InputError(f"membrane must be one of {quad4.MEMBRANES}, got {(bad or [membrane])[0]!r}")
    if not n_quads:
        return []
    cut = np.flatnonzero(per[1:] != per[:-1]) + 1
    starts = np.concatenate([[0], cut])
    ends = np.concatenate([cut, [n_quads]])
    return [(int(a), int(b), str(per[a])) for a, b in zip(starts, ends)]


class Model:
    """Total-Lagrangian solid-shell model of a :class:`ShellMesh` with a section (Fabric or
    IsotropicShell).

    Parameters
    ----------
    thickness_strain : "green" (Eq. 3, default) or "quasi" (the quasi-engineering strain, Eq. 24)
    mu : the threshold of Eq. (24), 0 < mu < 1 (only with thickness_strain="quasi")
    membrane : quadrilateral membrane strains, "full" (compatible, 2x2 Gauss: the paper's element)
        or "ans" (assumed strains from edge and centre tying values, free of membrane locking;
        see solidshell/elements/quad4.py); or one of those per quadrilateral (a sequence of
        ``mesh.quads``' length), e.g. the adaptive mesh's coarse elements "ans" and its finest
        "full".  Each run of equal values becomes one element block, so the element order (quads in
        mesh order, then triangles) is kept.
    constants : an :class:`ElementConstants` cache shared by the models of meshes with common
        elements (the adaptive driver's), or None
    """

    def __init__(
        self,
        mesh: ShellMesh,
        material,
        thickness_strain: str = "green",
        mu: float = 0.5,
        membrane: str = "full",
        constants: ElementConstants | None = None,
    ):
        if thickness_strain not in THICKNESS_STRAINS:
            raise InputError(f"thickness_strain must be one of {THICKNESS_STRAINS}, got {thickness_strain!r}")
        runs = _membrane_runs(membrane, len(mesh.quads))
        if not (0.0 < float(mu) < 1.0):
            raise InputError(f"mu of Eq. (24) must lie in (0, 1), got {mu!r}")
        self.mesh = mesh
        self.material = material
        self.quasi = thickness_strain == "quasi"
        self.mu = float(mu)
        self.membrane = membrane if isinstance(membrane, str) else tuple(membrane)
        Xo, Xn = mesh.nodes, mesh.directors
        self.blocks = [_Block(quad4, mesh.quads[a:b], Xo, Xn, material, m, constants) for a, b, m in runs]
        if len(mesh.tris):
            self.blocks.append(_Block(tri3, mesh.tris, Xo, Xn, material, "full", constants))
        self._pattern: SparsePattern | None = None
        self._mass: np.ndarray | None = None
        self._areas: np.ndarray | None = None

    def around(self, nodes) -> "Model":
        """This model with only the elements that touch ``nodes`` (indices): the same mesh, node
        numbering and masses.  Its energy differs from the whole model's by terms that do not depend
        on those nodes' dofs, so its force on them is the whole force, and its tangent block on them
        the whole block: a local solve (adapt/settle.py) at the cost of the elements it involves."""
        touch = np.zeros(self.n_nodes, dtype=bool)
        touch[np.asarray(nodes, dtype=np.int64)] = True
        sub = copy.copy(self)
        sub.blocks = [b.take(np.flatnonzero(touch[b.conn].any(axis=1))) for b in self.blocks]
        sub.blocks = [b for b in sub.blocks if len(b.conn)]
        sub._pattern = None
        sub._areas = None  # nodal_areas() of the sub-model: its own blocks' (the memo is the whole model's)
        return sub

    n_nodes = property(lambda self: self.mesh.n_nodes)
    n_dofs = property(lambda self: 6 * self.mesh.n_nodes)

    # ------------------------------------------------------------- kinematics
    def _current(self, U):
        """(x_o, x_n, U): current positions and directors (N,3) and U itself as a contiguous (N,6)."""
        U = np.ascontiguousarray(U, dtype=float)
        if U.shape != (self.n_nodes, 6):
            U = U.reshape(self.n_nodes, 6)
        xo = np.ascontiguousarray(self.mesh.nodes + U[:, :3])
        xn = np.ascontiguousarray(self.mesh.directors + U[:, 3:])
        return xo, xn, U

    # ------------------------------------------------------------- energy & force
    def _element_forces(self, U):
        """Yield (block, element forces (M,nn,6), element energies (M,)) for each element block."""
        xo, xn, Uc = self._current(U)
        for b in self.blocks:
            M = len(b.conn)
            fe = np.empty((M, b.nn, 6))
            we = np.empty(M)
            core.energy_force(*b.args(xo, xn, Uc, self.quasi, self.mu), fe, we, get_num_threads())
            yield b, fe, we

    def energy_and_force(self, U):
        """(strain energy [force*length], internal force (N,6) [force]) at U (N,6): Eqs. (7), (9)."""
        F = np.zeros(self.n_dofs)
        W = 0.0
        for b, fe, we in self._element_forces(U):
            scatter_add_vec(b.dofs, fe.reshape(len(fe), -1), F)
            W += we.sum()
        return float(W), F.reshape(-1, 6)

    def energy(self, U) -> float:
        """Strain energy U = sum of U^e of Eq. (7) [force*length]."""
        return self.energy_and_force(U)[0]

    def internal_force(self, U) -> np.ndarray:
        """Internal force F = dU/dD (Eq. 9), (N,6) [force]."""
        return self.energy_and_force(U)[1]

    def element_energies(self, U) -> np.ndarray:
        """Per-element strain energies, quads first then triangles."""
        return np.concatenate([we for _, _, we in self._element_forces(U)])

    # ------------------------------------------------------------- tangent
    @property
    def pattern(self) -> SparsePattern:
        if self._pattern is None:
            self._pattern = SparsePattern(self.n_dofs, [b.dofs for b in self.blocks])
        return self._pattern

    def _chunked_tangent(self, U, nnz, chunk, kernel, scatter):
        """(internal force (6N,), tangent data (nnz,)) at U: per block, ``kernel``
        (core.force_tangent, whole or half matrices) on ``chunk`` elements at a time, each
        chunk's element matrices added into the data by ``scatter(block index, slice, matrices,
        data)``.  Chunks follow the element order, so every entry sums the same terms in the same
        order as one whole-mesh call would; only a chunk's element matrices are held at a time
        (the whole mesh's were 14 MB on square-pedestal 48x16x4, alive next to the last
        factorisation)."""
        xo, xn, Uc = self._current(U)
        F = np.zeros(self.n_dofs)
        data = np.zeros(nnz)
        nth = get_num_threads()
        for k, b in enumerate(self.blocks):
            M = len(b.conn)
            nd = 6 * b.nn
            step = min(M, chunk)
            fe = np.empty((step, b.nn, 6))
            we = np.empty(step)
            Ke = np.empty((step, nd, nd))
            for s0 in range(0, M, step):
                sl = slice(s0, min(M, s0 + step))
                m = sl.stop - sl.start
                kernel(*b.args(xo, xn, Uc, self.quasi, self.mu, sl), b.gp_membrane, fe[:m], we[:m], Ke[:m], nth)
                scatter_add_vec(b.dofs[sl], fe[:m].reshape(m, -1), F)
                scatter(k, sl, Ke[:m], data)
        return F, data

    def _force_and_tangent_into(self, U, pos_maps, nnz):
        """_chunked_tangent with the whole element matrices, scattered through ``pos_maps`` (one
        (M, nd, nd) position map per block; negative positions are skipped)."""
        return self._chunked_tangent(
            U,
            nnz,
            TANGENT_CHUNK,
            core.force_tangent,
            lambda k, sl, Ke, data: scatter_add_mat(pos_maps[k][sl], Ke, data),
        )

    def force_and_tangent(self, U):
        """(internal force (N,6), tangent K_t (6N,6N) CSR) at U, Eq. (9)."""
        import scipy.sparse as sp  # here only: the static solver's path never forms this matrix

        p = self.pattern
        F, data = self._force_and_tangent_into(U, p.pos, p.nnz)
        return F.reshape(-1, 6), sp.csr_matrix((data, p.indices.copy(), p.indptr.copy()), shape=(p.n, p.n))

    def free_lower_pattern(self, free) -> FreeLowerPattern:
        """The lower triangle of the tangent's pattern on the dofs ``free`` (assembly.py).  The
        full pattern is built for it but not kept unless it already was: the static solver needs
        only this one, and the full one's maps are ~15 MB on square-pedestal 48x16x4."""
        pattern = (
            self._pattern if self._pattern is not None else SparsePattern(self.n_dofs, [b.dofs for b in self.blocks])
        )
        return FreeLowerPattern(pattern, free)

    def force_and_free_tangent(self, U, lower: FreeLowerPattern):
        """(internal force (N,6), data of K_t's lower triangle on the free dofs in the CSC pattern
        ``lower``) at U, Eq. (9): the static solver's form of the tangent (no 6N x 6N matrix).
        Only the triangle of each element matrix that lands in this triangle is formed
        (core.force_tangent with ``half``) and scattered (lower.half_pos); the same bits as the full
        assembly's entries."""

        def scatter(k, sl, Kh, data):
            scatter_add_half(lower.half_pos[k][sl], lower.half_entries[k], Kh.reshape(len(Kh), -1), data)

        F, data = self._chunked_tangent(U, lower.nnz, HALF_TANGENT_CHUNK, _force_tangent_half, scatter)
        return F.reshape(-1, 6), data

    def tangent(self, U):
        """Tangent stiffness K_t = d^2 U / dD^2 (Eq. 9): scipy CSR (6N, 6N) [force/length]."""
        return self.force_and_tangent(U)[1]

    # ------------------------------------------------------------- mass
    def nodal_areas(self) -> np.ndarray:
        """(N,) mid-surface area share of each node by the trapezoidal rule [length^2] (Section 4).
        Computed once per model (the gravity loads and the lumped mass both ask; every remesh of an
        adaptive run builds a new model)."""
        if self._areas is None:
            A = np.zeros(self.n_nodes)
            Xo, Xn = self.mesh.nodes, self.mesh.directors
            for b in self.blocks:
                np.add.at(A, b.conn.ravel(), b.module.nodal_areas(Xo[b.conn], Xn[b.conn]).ravel())
            self._areas = A
        return self._areas.copy()

    def lumped_mass(self) -> np.ndarray:
        """(N,6) diagonal mass by the trapezoidal rule in-plane and through the thickness (Section 4):
        mu*A_i on the U_o dofs and mu*h^2/4*A_i on the U_n dofs [mass]."""
        if self._mass is None:
            A = self.nodal_areas()
            mu = self.material.mass_per_area
            h = self.material.thickness
            self._mass = np.column_stack(
                [np.repeat(mu * A[:, None], 3, 1), np.repeat(mu * h * h / 4.0 * A[:, None], 3, 1)]
            )
        return self._mass.copy()

    # ------------------------------------------------------------- diagnostics
    def bending_strain(self, U) -> np.ndarray:
        """||eps_b|| per element (quads first, then triangles) [1/length], the curvature measure of
        the adaptivity criterion Eq. (25): the Euclidean norm of the local bending strain vector of
        Eq. (6), root-mean-square over the element's integration points."""
        xo, xn, _ = self._current(U)
        out = []
        for b in self.blocks:
            kb = b.module.bending_raw_strains(xo[b.conn], xn[b.conn]) - b.c["r_mb"][..., 3:]
            eb = np.einsum("mgab,mgb->mga", b.c["T"], kb)
            out.append(np.sqrt(np.mean(np.sum(eb * eb, -1), axis=1)))
        return np.concatenate(out)

    def interpenetration(self, U) -> list[np.ndarray]:
        """n_p . d_p per element corner (Section 4.3), one (M,nn) array per element block:
        n_p the unit normal of the deformed corner p (edges to its two neighbours), d_p the unit
        deformed director; negative where the top and bottom surfaces interpenetrate
        (elements/corners.py)."""
        U = np.ascontiguousarray(U, dtype=float).reshape(self.n_nodes, 6)
        X = np.ascontiguousarray(self.mesh.nodes, dtype=float)
        Xn = np.ascontiguousarray(self.mesh.directors, dtype=float)
        out = []
        for b in self.blocks:
            nd = np.empty(b.conn.shape)
            corner_alignment(X, Xn, U, b.conn, nd)
            out.append(nd)
        return out

    def interpenetrated_nodes(self, U) -> np.ndarray:
        """(N,) bool: nodes where n_p . d_p < 0 in any element (Section 4.3)."""
        flag = np.zeros(self.n_nodes, dtype=bool)
        for b, nd in zip(self.blocks, self.interpenetration(U)):
            flag[b.conn[nd < 0.0]] = True
        return flag
