"""Internal force and the central-difference update of Eq. (23) with preallocated buffers.

One step is two compiled passes and no allocation:

1. the element pass: every element's force and energy into one flat buffer -- quadrilaterals with
   the compatible membrane by the lane kernel (``elements/lanes.py``, elements in SIMD lanes),
   with the assumed membrane by ``elements/lanes_ans.py`` (same layout), triangles by
   ``elements/core.energy_force``;
2. assembly and update, serial: the element forces are summed into the dofs in
   ``assembly.scatter_add_vec``'s order (elements in mesh order, block by block), so the assembled
   force equals the model's whenever the element forces do; then R = P - F (+ C), D_n+1 of Eq. (23)
   with the operation order of ``kernels.central_step``, the prescribed values, finiteness and
   v_n.M.v_n in one pass.  (A node-ordered gather, parallel over nodes, took 24 % of a one-thread
   step against 62 % for the element pass -- a node's contributions sit 128 bytes apart in the lane
   layout -- and on 2 threads of the loaded machine a second parallel region per step made the
   loop 0.95x the previous path: every region waits for its slowest thread.)

Nothing here depends on the thread count: elements are evaluated block by block by the same
instructions and every sum is serial in a fixed order.
"""

from __future__ import annotations

import numpy as np
from numba import get_num_threads, njit

from ...assembly import scatter_add_vec
from ...elements import core, lanes, lanes_ans, quad4


@njit(cache=True)
def scatter_lanes(conn, M, fe, F):
    """F[6 p + c] += element forces of the lane layout (lanes.pack), elements in mesh order and
    within an element dof 6 i + c in order: scatter_add_vec's order, so the same sums bit for bit.
    The block being read is 3 KB (in L1); F takes the scattered writes."""
    L = conn.shape[2]
    for b in range(conn.shape[0]):
        for k in range(L):
            if b * L + k >= M:
                break
            for i in range(4):
                o = 6 * conn[b, i, k]
                for c in range(6):
                    F[o + c] += fe[b, (6 * i + c) * L + k]


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
        self.parts = []          # (kind, block, packed lanes or None, offset, size) in block order
        base = 0
        for b in model.blocks:
            M, nn = b.conn.shape
            ans = use_lanes and lanes_ans.covers(b.c)      # the assumed-membrane quad (same layout)
            if use_lanes and (_uses_lanes(b) or ans):
                pk = (lanes_ans if ans else lanes).pack(b.conn, b.c, b.c["r_zq"])
                pk["kernel"] = lanes_ans.quad_forces if ans else lanes.quad_forces
                size = pk["B"] * 24 * lanes.LANES
                self.parts.append(("lanes", b, pk, base, size))
            else:
                size = M * nn * 6
                self.parts.append(("core", b, None, base, size))
            base += size
        self.fe = np.zeros(base)
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
        self._zero = np.zeros(0)

    # ------------------------------------------------------------ element pass
    def element_pass(self, D6):
        """Element forces and energies at the displacements D6 (N, 6) into the buffers."""
        if self.needs_current:
            xo, xn, Uc = self.model._current(D6)
        nth = get_num_threads()
        for (kind, b, pk, _, _), (fe, we) in zip(self.parts, self.views):
            if kind == "lanes":
                pk["kernel"](self.X, self.Xn, D6, pk["conn"], pk["Cmb"], pk["Cs"], pk["Cz"], pk["r_z"],
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
    def assemble(self):
        """F = the element forces of the last element pass summed into the dofs (self.F)."""
        F = self.F
        F[:] = 0.0
        for (kind, b, pk, _, _), (fe, _) in zip(self.parts, self.views):
            if kind == "lanes":
                scatter_lanes(pk["conn"], pk["M"], fe, F)
            else:
                scatter_add_vec(b.dofs, fe.reshape(len(fe), -1), F)

    def internal(self, D, want_energy):
        """(F(D) flat, a new array; strain energy or None) -- Forces.internal's contract."""
        self.element_pass(np.ascontiguousarray(D, dtype=float).reshape(self.N, 6))
        self.assemble()
        return self.F.copy(), (self.energy() if want_energy else None)

    def step(self, D, Dp, Dn1, R, P, C, cF, cD, cDp, fixed, presc, Mf, inv2dt, want_energy):
        """One step of Eq. (23) from D_n: F into self.F, R = P - F (+ C unless None), D_n+1 into Dn1
        (prescribed where ``fixed``, a (6N,) bool mask, values ``presc`` (6N,)).  Returns (v_n.M.v_n,
        finite, strain energy or None)."""
        self.element_pass(D.reshape(self.N, 6))
        self.assemble()
        has_C = C is not None
        vMv, finite = update(self.F, P, C if has_C else self._zero, has_C, R, Dn1, D, Dp, cF, cD, cDp, fixed, presc,
                             Mf, inv2dt)
        return vMv, finite, (self.energy() if want_energy else None)
