"""The assumed-membrane quadrilateral's internal force with elements in SIMD lanes.

The same energy and force as ``core.energy_force`` for the 4-node quadrilateral with
``membrane="ans"`` (quad4.py: Section 2.1's element with an assumed membrane strain field; bending
at the 2x2 Gauss points, Eq. 7; transverse shear of Eq. 4; thickness strain of Eq. 5 or Eq. 24;
displacement form of Eq. 3), in the layout of ``lanes.py`` (blocks of ``LANES`` elements, every
per-element array stored (block, row, lane), the last block padded with zero rigidities, whose
force and energy are zero).

The assumed membrane field has five parameters, each linear in its 22 raw tying products, and
each of those is a fixed combination of the six products y = (a_xi.a_xi/2, a_eta.a_eta/2,
a_xi.a_eta, h.h/2, a_xi.h, a_eta.h) of the centre tangents a_xi, a_eta and the hourglass vector h
(quad4.R_MEM).  quad4.precompute stores the membrane as the 6x6 rigidity K on y (rank 5), so the
membrane costs one stage: three nodal combinations of x_o and of U_o, six products, K y, and the
forces of a_xi, a_eta, h.  The Gauss points carry only bending (their membrane rigidity is zero),
and the transverse shear and thickness stage is lanes.py's own.

Stages per block: gather (lanes), membrane, four bending points, shear and thickness (lanes).
Results do not depend on the thread count (blocks are the unit of work); they equal core.py's to
round-off (the same operations, grouped and contracted differently).

lanes.py's helpers are inlined here: numba's on-disk cache of this module is keyed on this file
only, so after a change of those helpers (or of their names) delete this module's cache files
(``__pycache__/lanes_ans*.nbi/.nbc``) or touch this file; tests/test_lanes_ans.py catches a
mismatch with core either way.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from . import lanes, quad4
from .core import _FM
from .lanes import (
    _D0,
    _D1,
    _D2,
    _D3,
    LANES,
    _acc1,
    _acc2,
    _comb,
    _dot,
    _forces_of,
    _gather,
    _lin2,
    _nodes,
    curvatures,
    gradients,
    stages_rest,
    store_forces,
)

# the basis of the six products: dN_i/dxi, dN_i/deta at the centre and the hourglass weights
# xi_i eta_i / 4 (quad4.P_ALPHA rows 0, 1 and 3: the products (0,0), (1,1), (0,1), (2,2), (0,2),
# (1,2) of this basis, in that order, with c_t 1/2 for squares)
_C1 = tuple(float(v) for v in quad4.P_ALPHA[0])
_C2 = tuple(float(v) for v in quad4.P_ALPHA[1])
_H = tuple(float(v) for v in quad4.P_ALPHA[3])
assert quad4._PAIRS == ((0, 0, 0.5), (1, 1, 0.5), (0, 1, 1.0), (2, 2, 0.5), (0, 2, 1.0), (1, 2, 1.0))

N_BEND = 36  # bending rows: Gauss point g, 3x3 Cb at 9 g + 3 r + s
N_K = 21  # membrane rows after them: K's upper triangle, row by row
N_ROWS = N_BEND + N_K

FLOPS_PER_ELEMENT = 2458
"""Floating-point operations of one element (Green thickness strain), counted from this source as
executed, as lanes.FLOPS_PER_ELEMENT is: membrane 420 (6 nodal combinations 126, products 87,
K y 66, energy 12, forces on a_xi, a_eta, h 45, nodal forces 84); 4 bending points x 379 (8
tangent combinations 168, curvatures 57, moments 15, energy 7, generalised forces 36, nodal forces
96); shear, thickness and current coordinates as lanes.py's 522."""


def covers(c) -> bool:
    """Whether quad constants ``c`` (quad4.precompute) are the assumed-membrane form this kernel
    evaluates: no membrane at the Gauss points, the 4 shear ties then the six membrane products."""
    a = c["alpha"]
    return (
        a.shape == (4 + quad4.N_PROD, 4)
        and np.array_equal(a, np.vstack([quad4.ALPHA, quad4.P_ALPHA]))
        and np.array_equal(c["beta"], np.vstack([quad4.BETA, quad4.P_BETA]))
        and np.array_equal(c["tie"], np.vstack([quad4.TIE, quad4.P_TIE]))
        and not np.any(c["Cmb"][:, :, 0])
    )


def pack(conn, c, quasi_rz):
    """SoA copies (lanes.pack's layout and keys) of an assumed-membrane quad block: ``Cmb`` (B, 57,
    LANES) holds the bending rigidities of the four Gauss points then the upper triangle of the
    membrane's 6x6 K; ``Cs`` (B, 16, LANES) the shear ties' 4x4; ``Cz``, ``r_z``, ``conn`` as
    lanes.pack.  ValueError unless ``covers(c)``."""
    if not covers(c):
        raise ValueError("lanes_ans.pack needs the constants of quad4.precompute(..., membrane='ans')")
    M = len(conn)
    iu = np.triu_indices(quad4.N_PROD)
    rows = np.concatenate([c["Cmb"][:, :, 1].reshape(M, N_BEND), c["Cs"][:, 4:, 4:][:, iu[0], iu[1]]], 1)
    return lanes.pack(conn, dict(Cmb=rows, Cs=np.ascontiguousarray(c["Cs"][:, :4, :4]), Cz=c["Cz"]), quasi_rz)


# ---------------------------------------------------------------- stages
@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _bending_point(d, x, n, u, v, C, b, r, k, fo, fn):
    """Bending at one Gauss point (core._element_force with a zero membrane rigidity): (fo, fn,
    energy).  d: the point's (dN/dxi, dN/deta); C[b, r:r+9, k] its Cb."""
    d1, d2, a1, a2, b1, b2, u1, u2, v1, v2 = gradients(d, x, n, u, v)
    k0, k1, k2 = curvatures(a1, a2, b1, b2, u1, u2, v1, v2)
    m0 = C[b, r + 0, k] * k0 + C[b, r + 1, k] * k1 + C[b, r + 2, k] * k2
    m1 = C[b, r + 3, k] * k0 + C[b, r + 4, k] * k1 + C[b, r + 5, k] * k2
    m2 = C[b, r + 6, k] * k0 + C[b, r + 7, k] * k1 + C[b, r + 8, k] * k2
    w = 0.5 * (m0 * k0 + m1 * k1 + m2 * k2)
    p1 = _lin2(m0, b1, m2, b2)
    p2 = _lin2(m1, b2, m2, b1)
    q1 = _lin2(m0, a1, m2, a2)
    q2 = _lin2(m1, a2, m2, a1)
    return _acc2(fo, d1, p1, d2, p2), _acc2(fn, d1, q1, d2, q2), w


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _stage_bend(b, s, k, D, r, C, xs, fe, we):
    """Gauss point with derivatives D, rigidities C[b, r:r+9]: adds its forces and energy."""
    x, n, u, v = _nodes(xs, s, k)
    fo, fn = _forces_of(fe, s, k)
    fo, fn, wg = _bending_point(D, x, n, u, v, C, b, r, k, fo, fn)
    store_forces(fe, s, k, fo, fn)
    we[b, k] = we[b, k] + wg


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _stage_membrane(b, s, k, C, xs, fe, we):
    """The assumed membrane (quad4.py) on the six products y: energy y.K y / 2 and its forces; the
    first stage, so it starts the lane's forces and energy."""
    x, n, u, v = _nodes(xs, s, k)
    A1 = _comb(_C1, x)
    A2 = _comb(_C2, x)
    H = _comb(_H, x)
    U1 = _comb(_C1, u)
    U2 = _comb(_C2, u)
    UH = _comb(_H, u)
    # displacement form of Eq. (3), as core forms a tying product: a.b - A.B = u.(b - w) + a.w
    y0 = 0.5 * (U1[0] * (A1[0] - U1[0]) + U1[1] * (A1[1] - U1[1]) + U1[2] * (A1[2] - U1[2]) + _dot(A1, U1))
    y1 = 0.5 * (U2[0] * (A2[0] - U2[0]) + U2[1] * (A2[1] - U2[1]) + U2[2] * (A2[2] - U2[2]) + _dot(A2, U2))
    y2 = U1[0] * (A2[0] - U2[0]) + U1[1] * (A2[1] - U2[1]) + U1[2] * (A2[2] - U2[2]) + _dot(A1, U2)
    y3 = 0.5 * (UH[0] * (H[0] - UH[0]) + UH[1] * (H[1] - UH[1]) + UH[2] * (H[2] - UH[2]) + _dot(H, UH))
    y4 = U1[0] * (H[0] - UH[0]) + U1[1] * (H[1] - UH[1]) + U1[2] * (H[2] - UH[2]) + _dot(A1, UH)
    y5 = U2[0] * (H[0] - UH[0]) + U2[1] * (H[1] - UH[1]) + U2[2] * (H[2] - UH[2]) + _dot(A2, UH)
    r = N_BEND
    k00 = C[b, r, k]
    k01 = C[b, r + 1, k]
    k02 = C[b, r + 2, k]
    k03 = C[b, r + 3, k]
    k04 = C[b, r + 4, k]
    k05 = C[b, r + 5, k]
    k11 = C[b, r + 6, k]
    k12 = C[b, r + 7, k]
    k13 = C[b, r + 8, k]
    k14 = C[b, r + 9, k]
    k15 = C[b, r + 10, k]
    k22 = C[b, r + 11, k]
    k23 = C[b, r + 12, k]
    k24 = C[b, r + 13, k]
    k25 = C[b, r + 14, k]
    k33 = C[b, r + 15, k]
    k34 = C[b, r + 16, k]
    k35 = C[b, r + 17, k]
    k44 = C[b, r + 18, k]
    k45 = C[b, r + 19, k]
    k55 = C[b, r + 20, k]
    s0 = k00 * y0 + k01 * y1 + k02 * y2 + k03 * y3 + k04 * y4 + k05 * y5
    s1 = k01 * y0 + k11 * y1 + k12 * y2 + k13 * y3 + k14 * y4 + k15 * y5
    s2 = k02 * y0 + k12 * y1 + k22 * y2 + k23 * y3 + k24 * y4 + k25 * y5
    s3 = k03 * y0 + k13 * y1 + k23 * y2 + k33 * y3 + k34 * y4 + k35 * y5
    s4 = k04 * y0 + k14 * y1 + k24 * y2 + k34 * y3 + k44 * y4 + k45 * y5
    s5 = k05 * y0 + k15 * y1 + k25 * y2 + k35 * y3 + k45 * y4 + k55 * y5
    w = 0.5 * (s0 * y0 + s1 * y1 + s2 * y2 + s3 * y3 + s4 * y4 + s5 * y5)
    # forces on a_xi, a_eta, h (the products' derivatives), then on the nodes
    p1 = (s0 * A1[0] + s2 * A2[0] + s4 * H[0], s0 * A1[1] + s2 * A2[1] + s4 * H[1], s0 * A1[2] + s2 * A2[2] + s4 * H[2])
    p2 = (s1 * A2[0] + s2 * A1[0] + s5 * H[0], s1 * A2[1] + s2 * A1[1] + s5 * H[1], s1 * A2[2] + s2 * A1[2] + s5 * H[2])
    ph = (s3 * H[0] + s4 * A1[0] + s5 * A2[0], s3 * H[1] + s4 * A1[1] + s5 * A2[1], s3 * H[2] + s4 * A1[2] + s5 * A2[2])
    z3 = (0.0, 0.0, 0.0)
    fo = _acc2((z3, z3, z3, z3), _C1, p1, _C2, p2)
    fo = _acc1(fo, 1.0, _H, ph)
    store_forces(fe, s, k, fo, (z3, z3, z3, z3))
    we[b, k] = w


@njit(cache=True, forceinline=True, fastmath=_FM, error_model="numpy")
def _block(b, s, X, Xn, U, conn, C, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """All lanes of block b, stage by stage (lanes._block's scheme: one short straight-line lane
    loop per stage, so that each vectorises)."""
    for k in range(LANES):
        _gather(b, s, k, X, Xn, U, conn, xs, 4)
    for k in range(LANES):
        _stage_membrane(b, s, k, C, xs, fe, we)
    for k in range(LANES):
        _stage_bend(b, s, k, _D0, 0, C, xs, fe, we)
    for k in range(LANES):
        _stage_bend(b, s, k, _D1, 9, C, xs, fe, we)
    for k in range(LANES):
        _stage_bend(b, s, k, _D2, 18, C, xs, fe, we)
    for k in range(LANES):
        _stage_bend(b, s, k, _D3, 27, C, xs, fe, we)
    stages_rest(b, s, LANES, Cs, Cz, rz, quasi, mu, xs, fe, we)


@njit(cache=True, parallel=True, fastmath=_FM, error_model="numpy")
def quad_forces(X, Xn, U, conn, C, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """lanes.quad_forces's contract for assumed-membrane quads packed by ``pack`` (C: its ``Cmb``):
    element forces fe (B, 24 LANES), energies we (B, LANES) at displacements U (N, 6) of the nodes
    X, directors Xn (N, 3); xs (B, 48 LANES) is scratch."""
    for b in prange(conn.shape[0]):
        _block(b, b, X, Xn, U, conn, C, Cs, Cz, rz, quasi, mu, xs, fe, we)
