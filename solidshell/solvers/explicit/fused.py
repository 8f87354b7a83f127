"""Internal force and the central-difference update of Eq. (23) with preallocated buffers.

One step is two compiled passes and no allocation:

1. the element pass: every element's force and energy into one flat buffer -- quadrilaterals with
   the compatible membrane by the lane kernel (``elements/lanes.py``, elements in SIMD lanes),
   other blocks (triangles, the assumed-membrane quadrilateral) by ``elements/core.energy_force``;
2. the node pass, parallel over nodes: each dof sums its elements' contributions in the order of
   ``assembly.scatter_add_vec`` (block by block, elements in mesh order), so the assembled force
   equals the model's whenever the element forces do, then R = P - F (+ C), D_n+1 of Eq. (23), the
   prescribed values, finiteness and the nodal parts of v_n.M.v_n.

Nothing here depends on the thread count: elements are evaluated block by block by the same
instructions, every sum has a fixed order, and the per-node parts of v.M.v are added serially.
"""

from __future__ import annotations

import numpy as np
from numba import get_num_threads, njit, prange

from ...elements import core, lanes, quad4


@njit(cache=True, parallel=True)
def node_pass(fe, ptr, off, stride, P, C, has_C, F, R, Dn1, D, Dp, cF, cD, cDp, fixed, presc, Mf, inv2dt,
              part, bad, step):
    """Assemble F from the element forces (no fastmath: the sums keep scatter_add_vec's order);
    R = P - F (+ C when has_C); when ``step``, D_n+1 = cF R + cD D + cDp Dp with prescribed values
    where ``fixed``, and per node n the part of v.M.v (part[n]) and a non-finite flag (bad[n])."""
    N = ptr.size - 1
    for n in prange(N):
        acc = 0.0
        nf = 0
        for c in range(6):
            s = 0.0
            for j in range(ptr[n], ptr[n + 1]):
                s += fe[off[j] + c * stride[j]]
            i = 6 * n + c
            F[i] = s
            r = P[i] - s
            if has_C:
                r += C[i]
            R[i] = r
            if step:
                x = cF[i] * r + cD * D[i] + cDp * Dp[i]
                if fixed[i]:
                    x = presc[i]
                Dn1[i] = x
                if x - x != 0.0:  # inf - inf and nan - nan are nan
                    nf = 1
                w = (x - Dp[i]) * inv2dt
                acc += Mf[i] * w * w
        part[n] = acc
        bad[n] = nf


@njit(cache=True)
def _serial_sum(a):
    s = 0.0
    for i in range(a.size):
        s += a[i]
    return s


def _uses_lanes(b) -> bool:
    """The lane kernel covers the quadrilateral with the compatible membrane and 4 shear ties."""
    return b.module is quad4 and b.gp_membrane and b.alpha.shape[0] == 4 and np.array_equal(b.alpha, quad4.ALPHA)


class FusedForces:
    """Internal force of a ``solidshell.model.Model`` into preallocated buffers, and the fused step.
    ``use_lanes=False`` evaluates every block by core.energy_force (for comparisons)."""

    def __init__(self, model, use_lanes: bool = True):
        self.model = model
        self.N = N = model.n_nodes
        self.X = np.ascontiguousarray(model.mesh.nodes, dtype=float)
        self.Xn = np.ascontiguousarray(model.mesh.directors, dtype=float)
        self.quasi, self.mu = bool(model.quasi), float(model.mu)
        self.parts = []          # (kind, block, views...) in the model's block order
        sizes, entries = [], []  # flat fe sizes; per block (node, offset, stride) of each (e, i)
        base = 0
        for b in model.blocks:
            M, nn = b.conn.shape
            e = np.repeat(np.arange(M), nn)
            i = np.tile(np.arange(nn), M)
            if use_lanes and _uses_lanes(b):
                pk = lanes.pack(b.conn, b.c, b.c["r_zq"])
                L = lanes.LANES
                size = pk["B"] * 24 * L
                off = base + (e // L) * 24 * L + 6 * i * L + e % L
                self.parts.append(("lanes", b, pk, base, size))
                entries.append((b.conn.ravel(), off, np.full(off.size, L)))
            else:
                size = M * nn * 6
                off = base + e * nn * 6 + 6 * i
                self.parts.append(("core", b, None, base, size))
                entries.append((b.conn.ravel(), off, np.ones(off.size, np.int64)))
            sizes.append(size)
            base += size
        self.fe = np.zeros(base)
        node = np.concatenate([x[0] for x in entries])
        off = np.concatenate([x[1] for x in entries])
        stride = np.concatenate([x[2] for x in entries])
        order = np.argsort(node, kind="stable")   # per node: block order, then element order
        self.ptr = np.searchsorted(node[order], np.arange(N + 1)).astype(np.int64)
        self.off = off[order].astype(np.int64)
        self.stride = stride[order].astype(np.int64)
        self.views = []
        for kind, b, pk, o, size in self.parts:
            if kind == "lanes":
                self.views.append((self.fe[o:o + size].reshape(pk["B"], 24 * lanes.LANES),
                                   np.zeros((pk["B"], lanes.LANES))))
                pk["xs"] = np.zeros((pk["B"], 48 * lanes.LANES))   # the lane kernel's scratch
            else:
                M, nn = b.conn.shape
                self.views.append((self.fe[o:o + size].reshape(M, nn, 6), np.zeros(M)))
        self.needs_current = any(kind == "core" for kind, *_ in self.parts)
        self.F = np.zeros(6 * N)
        self.part = np.zeros(N)
        self.bad = np.zeros(N, np.int8)
        self._zero = np.zeros(0)
        self._z6 = np.zeros(6 * N)
        self._R6 = np.zeros(6 * N)
        self._nofix = np.zeros(6 * N, np.bool_)

    # ------------------------------------------------------------ element pass
    def element_pass(self, D6):
        """Element forces and energies at the displacements D6 (N, 6) into the buffers."""
        if self.needs_current:
            xo, xn, Uc = self.model._current(D6)
        nth = get_num_threads()
        for (kind, b, pk, _, _), (fe, we) in zip(self.parts, self.views):
            if kind == "lanes":
                lanes.quad_forces(self.X, self.Xn, D6, pk["conn"], pk["Cmb"], pk["Cs"], pk["Cz"], pk["r_z"],
                                  self.quasi, self.mu, pk["xs"], fe, we)
            else:
                core.energy_force(*b.args(xo, xn, Uc, self.quasi, self.mu), fe, we, nth)

    def energy(self) -> float:
        """Strain energy of the last element pass, summed as Model.energy_and_force sums it."""
        W = 0.0
        for (kind, b, pk, _, _), (_, we) in zip(self.parts, self.views):
            W += (we.ravel()[:pk["M"]] if kind == "lanes" else we).sum()
        return float(W)

    # ------------------------------------------------------------ public
    def internal(self, D, want_energy):
        """(F(D) flat, a new array; strain energy or None) -- Forces.internal's contract."""
        self.element_pass(np.ascontiguousarray(D, dtype=float).reshape(self.N, 6))
        z, R = self._z6, self._R6
        node_pass(self.fe, self.ptr, self.off, self.stride, z, z, False, self.F, R, R, z, z, z, 0.0, 0.0,
                  self._nofix, z, z, 0.0, self.part, self.bad, False)
        return self.F.copy(), (self.energy() if want_energy else None)

    def step(self, D, Dp, Dn1, R, P, C, cF, cD, cDp, fixed, presc, Mf, inv2dt, want_energy):
        """One step of Eq. (23) from D_n: F into self.F, R = P - F (+ C unless None), D_n+1 into Dn1
        (prescribed where ``fixed``, a (6N,) bool mask, values ``presc`` (6N,)).  Returns (v_n.M.v_n,
        finite, strain energy or None)."""
        self.element_pass(D.reshape(self.N, 6))
        has_C = C is not None
        node_pass(self.fe, self.ptr, self.off, self.stride, P, C if has_C else self._zero, has_C, self.F, R, Dn1,
                  D, Dp, cF, cD, cDp, fixed, presc, Mf, inv2dt, self.part, self.bad, True)
        vMv = _serial_sum(self.part)
        finite = not self.bad.any()
        return vMv, finite, (self.energy() if want_energy else None)
