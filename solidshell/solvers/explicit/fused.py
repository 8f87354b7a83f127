"""Internal force and the central-difference update of Eq. (23) with preallocated buffers.

One step is two compiled passes and no allocation:

1. the element pass: every element's force and energy into preallocated buffers -- quadrilaterals with
   the compatible membrane by the lane kernel (``elements/lanes.py``, elements in SIMD lanes),
   with the assumed membrane by ``elements/lanes_ans.py``, triangles by ``elements/lanes_tri.py``
   (same layout), each block's forces scattered into the dofs right after it (while they are
   in L1: a chunk reuses one block's rows of scratch and forces, FusedForces.element_pass), in
   parallel over CHUNKS fixed chunks of blocks (see CHUNKS: the sums of ``assembly.scatter_add_vec``'s order
   but at chunk boundaries); any other block by ``elements/core.energy_force``;
2. assembly and update, serial: the chunks' slots and the other blocks' forces are summed into the
   dofs (elements in mesh order, block by block); then R = P - F (+ C), D_n+1 of Eq. (23)
   with the operation order of ``kernels.central_step``, the prescribed values, finiteness and
   v_n.M.v_n in one pass.  (Why scatter inside the element pass and not gather by node afterwards:
   the measurements are in docs/elements.md, section 8.)

Nothing here depends on the thread count: elements are evaluated block by block by the same
instructions and every sum is serial in a fixed order.
"""

from __future__ import annotations

import numpy as np
from numba import get_num_threads, njit, prange

from ...assembly import scatter_add_vec
from ...elements import core, lanes, lanes_ans, lanes_tri, quad4, tri3
from ...elements.core import _FM
from .kernels import Coefficients, Dofs, dof_power

CHUNKS = 4
"""The lane blocks are cut into this many contiguous chunks, a fixed number whatever the thread
count (so the sums are too): each chunk scatters its blocks' forces as it computes them, while
they are in L1, into the dofs of the nodes it owns (the nodes whose first element is in it) and
into slots of its own for the nodes an earlier chunk owns; the slots are added afterwards, chunk
by chunk.  A dof thus sums its elements in mesh order within each chunk, then the chunks in order:
scatter_add_vec's sum bit for bit except at the few nodes on a chunk boundary (round-off there)."""


@njit(forceinline=True, error_model="numpy")
def _scatter_block(b, s, dest, fe, F, nn):
    """Block b's element forces (row s of fe; nn nodes each: a literal, so that the node loop is
    unrolled as for a fixed size) into F at ``dest`` (elements in order, node by node, dof by dof;
    a negative dest is a padded lane).  No fast-math: every += stays one rounded addition in
    order."""
    L = dest.shape[2]
    for k in range(L):
        for i in range(nn):
            o = dest[b, i, k]
            if o < 0:
                continue
            for c in range(6):
                F[o + c] += fe[s, (6 * i + c) * L + k]


@njit(cache=True, parallel=True, fastmath=_FM, error_model="numpy")
def lanes_scatter(X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we, bounds, dest, F, keep):
    """lanes.quad_forces and the scatter of each block right after it, chunk by chunk (CHUNKS):
    F (zero on entry) gets the owned dofs, its tail the slots (chunk_plan).  xs and fe are the
    scratch and the element forces (lanes._block): with ``keep`` one row per block (B rows: the
    forces are kept), else one row per chunk (CHUNKS rows), reused block after block while in
    L1."""
    for ch in prange(bounds.size - 1):
        for b in range(bounds[ch], bounds[ch + 1]):
            s = b if keep else np.int64(ch)  # (the parallel index is unsigned)
            lanes._block(b, s, X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we)
            _scatter_block(b, s, dest, fe, F, 4)


@njit(cache=True, parallel=True, fastmath=_FM, error_model="numpy")
def lanes_ans_scatter(X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we, bounds, dest, F, keep):
    """lanes_scatter for assumed-membrane quads (lanes_ans._block, the same layout and contract)."""
    for ch in prange(bounds.size - 1):
        for b in range(bounds[ch], bounds[ch + 1]):
            s = b if keep else np.int64(ch)  # (the parallel index is unsigned)
            lanes_ans._block(b, s, X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we)
            _scatter_block(b, s, dest, fe, F, 4)


@njit(cache=True, parallel=True, fastmath=_FM, error_model="numpy")
def lanes_tri_scatter(X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we, bounds, dest, F, keep):
    """lanes_scatter for triangles (lanes_tri._block: the same layout, 3 nodes, fe rows of 18 LANES)."""
    for ch in prange(bounds.size - 1):
        for b in range(bounds[ch], bounds[ch + 1]):
            s = b if keep else np.int64(ch)  # (the parallel index is unsigned)
            lanes_tri._block(b, s, X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we)
            _scatter_block(b, s, dest, fe, F, 3)


@njit(cache=True)
def add_slots(F_all, slot0, slot_node):
    """F_all[6 p + c] += slot s (F_all[slot0 + 6 s + c]) for the slots in order (chunk, node)."""
    for s in range(slot_node.size):
        o = 6 * slot_node[s]
        for c in range(6):
            F_all[o + c] += F_all[slot0 + 6 * s + c]


def chunk_plan(conn, M, N, chunks=CHUNKS):
    """(bounds (chunks+1,) block ranges, dest (B, nn, LANES) dof offsets, slot_node (S,)) for the
    lane layout conn (B, nn, LANES) of M elements on N nodes: see CHUNKS.  dest is 6 p for an owned
    node, 6 N + 6 s for slot s, -1 for a padded lane."""
    B, _, L = conn.shape
    bounds = np.round(np.linspace(0, B, chunks + 1)).astype(np.int64)
    chunk_of_block = np.searchsorted(bounds, np.arange(B), side="right") - 1
    e = np.arange(B * L).reshape(B, L)  # element number of (b, k)
    real = e < M
    ch = np.broadcast_to(chunk_of_block[:, None, None], conn.shape)
    mask = np.broadcast_to(real[:, None, :], conn.shape)
    owner = np.full(N, chunks, dtype=np.int64)
    np.minimum.at(owner, conn[mask], ch[mask])
    foreign = mask & (owner[conn] != ch)
    pairs = np.unique(ch[foreign] * N + conn[foreign])  # (chunk, node) in order
    slot_node = pairs % N
    dest = np.where(mask, 6 * conn, -1).astype(np.int64)
    dest[foreign] = 6 * N + 6 * np.searchsorted(pairs, ch[foreign] * N + conn[foreign])
    return bounds, dest, slot_node


@njit(cache=True)
def update(F, P, C, has_C, R, Dn1, D, Dp, cF, cD, cDp, fixed, presc, Mf, inv2dt):
    """R = P - F (+ C when has_C); D_n+1 = cF R + cD D + cDp Dp (kernels.central_step's operation
    order, no fast-math), prescribed values where ``fixed``; returns (v_n.M.v_n, finite)."""
    vMv = 0.0
    finite = True
    for i in range(F.size):
        r = P[i] - F[i]
        if has_C:
            r += C[i]
        R[i] = r
        x = cF[i] * r + cD * D[i] + cDp * Dp[i]
        if fixed[i]:
            x = presc[i]
        Dn1[i] = x
        if x - x != 0.0:  # inf - inf and nan - nan are nan
            finite = False
        w = (x - Dp[i]) * inv2dt
        vMv += Mf[i] * w * w
    return vMv, finite


@njit(cache=True)
def residual(F, P, C, has_C, R):
    """R = P - F (+ C when has_C), update's operations, for a damper that rewrites the step."""
    for i in range(F.size):
        r = P[i] - F[i]
        if has_C:
            r += C[i]
        R[i] = r


@njit(cache=True)
def residual_power(F, P, C, has_C, R, D, Dp, invM, Mf, fixed, inv_dt, half_dt):
    """residual's R and, in the same pass, FIRE's power sums over the free dofs (P = R.v, v.M.v,
    R.M^-1.R; kernels.dof_power, damping/fire.power's terms in its order, so the same sums bit for
    bit): one pass over the dofs fewer per FIRE step."""
    Pw = 0.0
    vMv = 0.0
    fMf = 0.0
    for i in range(F.size):
        r = P[i] - F[i]
        if has_C:
            r += C[i]
        R[i] = r
        if fixed[i]:
            continue
        p, w, f = dof_power(r, D[i], Dp[i], invM[i], Mf[i], inv_dt, half_dt)
        Pw += p
        vMv += w
        fMf += f
    return Pw, vMv, fMf


def _uses_lanes(b) -> bool:
    """The lane kernel covers the quadrilateral with the compatible membrane and 4 shear ties."""
    return b.module is quad4 and b.gp_membrane and b.alpha.shape[0] == 4 and np.array_equal(b.alpha, quad4.ALPHA)


class FusedForces:
    """Internal force of a ``solidshell.model.Model`` into preallocated buffers, and the fused step.
    ``use_lanes=False`` evaluates every block by core.energy_force (for comparisons).  ``parts``:
    (kind, block, packed lanes or None, offset, size) per block, kind "lanes" (pk["kernel"] one of
    lanes_scatter, lanes_ans_scatter, lanes_tri_scatter; pk["nn"] nodes per element) or "core"."""

    def __init__(self, model, use_lanes: bool = True):
        self.model = model
        self.N = N = model.n_nodes
        self.X = np.ascontiguousarray(model.mesh.nodes, dtype=float)
        self.Xn = np.ascontiguousarray(model.mesh.directors, dtype=float)
        self.quasi, self.mu = bool(model.quasi), float(model.mu)
        self.parts = []  # (kind, block, packed lanes or None, offset, size) in block order
        base = 0
        for b in model.blocks:
            M, nn = b.conn.shape
            kernel = None
            if not use_lanes:
                pass
            elif b.module is quad4 and lanes_ans.covers(b.c):  # the assumed-membrane quad
                mod, kernel = lanes_ans, lanes_ans_scatter
            elif _uses_lanes(b):
                mod, kernel = lanes, lanes_scatter
            elif b.module is tri3 and lanes_tri.covers(b.c):
                mod, kernel = lanes_tri, lanes_tri_scatter
            if kernel is not None:
                pk = mod.pack(b.conn, b.c, b.c["r_zq"])
                pk["kernel"] = kernel
                pk["nn"] = nn
                size = pk["B"] * 6 * nn * lanes.LANES
                self.parts.append(("lanes", b, pk, base, size))
            else:
                size = M * nn * 6
                self.parts.append(("core", b, None, base, size))
            base += size
        self.fe = np.zeros(base)
        slots = 0
        for kind, b, pk, o, size in self.parts:
            if kind == "lanes":
                pk["bounds"], dest, slot_node = chunk_plan(pk["conn"], pk["M"], N)
                pk["dest"] = np.where(dest >= 6 * N, dest + 6 * slots, dest)  # this part's slots after earlier parts'
                pk["slot_node"] = slot_node
                pk["slot0"] = 6 * N + 6 * slots
                slots += slot_node.size
        self.views = []
        for kind, b, pk, o, size in self.parts:
            if kind == "lanes":
                self.views.append(
                    (
                        self.fe[o : o + size].reshape(pk["B"], 6 * pk["nn"] * lanes.LANES),
                        np.zeros((pk["B"], lanes.LANES)),
                    )
                )
                # the stepping pass's scratch and element forces: one block's per chunk, reused
                # block after block while in L1 (one per block streamed ~1150 B per element
                # through memory every step); internal() keeps every block's forces (views)
                nch = pk["bounds"].size - 1
                pk["xs"] = np.zeros((nch, 12 * pk["nn"] * lanes.LANES))
                pk["fe"] = np.zeros((nch, 6 * pk["nn"] * lanes.LANES))
                pk["xs_blocks"] = None  # internal()'s scratch, made at its first call
            else:
                M, nn = b.conn.shape
                self.views.append((self.fe[o : o + size].reshape(M, nn, 6), np.zeros(M)))
        self.needs_current = any(kind == "core" for kind, *_ in self.parts)
        self.F_all = np.zeros(6 * N + 6 * slots)  # the dofs, then the chunks' slots
        self.F = self.F_all[: 6 * N]
        self._zero = np.zeros(0)

    # ------------------------------------------------------------ element pass
    def element_pass(self, D6, keep=False):
        """Element forces and energies at the displacements D6 (N, 6) into the buffers; the lane
        blocks' forces are also scattered (into F and the slots, lanes_scatter).  The lane parts'
        element forces stay in ``views`` only with ``keep`` (else each chunk reuses one block's
        rows); energies always do."""
        if self.needs_current:
            xo, xn, Uc = self.model._current(D6)
        nth = get_num_threads()
        self.F_all[:] = 0.0
        for (kind, b, pk, _, _), (fe, we) in zip(self.parts, self.views):
            if kind == "lanes":
                if keep and pk["xs_blocks"] is None:
                    pk["xs_blocks"] = np.zeros((pk["B"], pk["xs"].shape[1]))
                xs, fk = (pk["xs_blocks"], fe) if keep else (pk["xs"], pk["fe"])
                pk["kernel"](
                    self.X,
                    self.Xn,
                    D6,
                    pk["conn"],
                    pk["Cmb"],
                    pk["Cs"],
                    pk["Cz"],
                    pk["r_z"],
                    self.quasi,
                    self.mu,
                    xs,
                    fk,
                    we,
                    pk["bounds"],
                    pk["dest"],
                    self.F_all,
                    keep,
                )
            else:
                core.energy_force(*b.args(xo, xn, Uc, self.quasi, self.mu), fe, we, nth)

    def energy(self) -> float:
        """Strain energy of the last element pass, summed as Model.energy_and_force sums it."""
        W = 0.0
        for (kind, b, pk, _, _), (_, we) in zip(self.parts, self.views):
            W += (we.ravel()[: pk["M"]] if kind == "lanes" else we).sum()
        return float(W)

    # ------------------------------------------------------------ public
    def assemble(self):
        """F = the element forces of the last element pass summed into the dofs (self.F): the lane
        parts' slots added to what their chunks scattered, then the other blocks, block by block."""
        F = self.F
        for (kind, b, pk, _, _), (fe, _) in zip(self.parts, self.views):
            if kind == "lanes":
                add_slots(self.F_all, pk["slot0"], pk["slot_node"])
            else:
                scatter_add_vec(b.dofs, fe.reshape(len(fe), -1), F)

    def internal(self, D, want_energy):
        """(F(D) flat, a new array; strain energy or None) -- Forces.internal's contract; every
        element's forces are left in ``views``."""
        self.element_pass(np.ascontiguousarray(D, dtype=float).reshape(self.N, 6), keep=True)
        self.assemble()
        return self.F.copy(), (self.energy() if want_energy else None)

    def step(self, D, Dp, Dn1, R, C, dofs: Dofs, co: Coefficients, want_energy, residual_only=False, power=False):
        """One step of Eq. (23) from D_n: F into self.F, R = P - F (+ C unless None), D_n+1 into Dn1
        (prescribed on ``dofs.fixed_mask`` with the values ``dofs.presc_full``; coefficients ``co``).
        Returns (v_n.M.v_n, finite, strain energy or None).  ``residual_only``: F and R only, Dn1
        untouched, (0, True, energy) -- for a damper that computes D_n+1 itself (FIRE): one pass over
        the dofs fewer; with ``power`` also FIRE's power sums at v_n into self.last_power
        (residual_power), else self.last_power is None."""
        self.element_pass(D.reshape(self.N, 6))
        self.assemble()
        has_C = C is not None
        Cv = C if has_C else self._zero
        self.last_power = None
        if residual_only:
            if not power:
                residual(self.F, dofs.P, Cv, has_C, R)
            else:
                dt = co.dt
                self.last_power = residual_power(
                    self.F, dofs.P, Cv, has_C, R, D, Dp, dofs.invM, dofs.Mf, dofs.fixed_mask, 1.0 / dt, 0.5 * dt
                )
            return 0.0, True, (self.energy() if want_energy else None)
        vMv, finite = update(
            self.F,
            dofs.P,
            Cv,
            has_C,
            R,
            Dn1,
            D,
            Dp,
            co.cF,
            co.cD,
            co.cDp,
            dofs.fixed_mask,
            dofs.presc_full,
            dofs.Mf,
            0.5 / co.dt,
        )
        return vMv, finite, (self.energy() if want_energy else None)
