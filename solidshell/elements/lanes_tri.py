"""The 3-node triangle's internal force with elements in SIMD lanes.

The same energy and force as ``core.energy_force`` for tri3.py's element (Section 2.2, Eqs.
10-15: constant membrane and bending strains at one point, Eq. 11; the transverse shears tied at
the three edge mid-points, Eqs. 12-14; the thickness strain at the three nodes, Eq. 15, Green
(Eq. 5) or quasi-engineering (Eq. 24); displacement form of Eq. 3), in the layout of ``lanes.py``:
blocks of ``LANES`` elements, every per-element array stored (block, row, lane), the last block
padded with copies of element 0's nodes and zero rigidities (zero force and energy, never
scattered).

The triangle's interpolation constants are 0 and +-1 (dN/ds, dN/dt) or 0 and 1/2 (the tying
points' beta), so the kernel writes their combinations as the differences and half-sums they are:
x_1 - x_0 is exactly core's (-1) x_0 + 1 x_1 + 0 x_2 (each product is exact, adding a zero too),
so the tangents, tying vectors and strains are core's to the bit; the stress sums and the force
accumulation are grouped and contracted differently (round-off).

Stages per block, one short straight-line lane loop each (lanes._block's scheme): gather,
membrane and bending, shear and thickness.  Results do not depend on the thread count (blocks are
the unit of work).

lanes.py's helpers are inlined here: numba's on-disk cache of this module is keyed on this file
only, so after a change of those helpers (or of their names) delete this module's cache files
(``__pycache__/lanes_tri*.nbi/.nbc``) or touch this file (and likewise solvers/explicit/fused.py,
whose lanes_tri_scatter inlines this module's ``_block``); tests/test_lanes_tri.py catches a
mismatch with core either way.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from . import lanes, tri3
from .core import _FM
from .lanes import LANES, _dot, _gather, _lin2, _row3, _sign_quasi, _store, _store_f, _thick, curvatures

assert np.array_equal(tri3.DN, [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
assert np.array_equal(tri3.ALPHA, [[1.0, 0.0, -1.0], [-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]])
assert np.array_equal(tri3.BETA, [[0.5, 0.0, 0.5], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5]])
assert np.array_equal(tri3.TIE, [[0.0, 3.0, 1.0]] * 3)

NN = 3
N_CMB = 18  # Cmb rows per element: membrane 3x3 then bending 3x3 (row-major)
N_CS = 9  # Cs rows (3x3 shear tying)
N_CZ = 9  # Cz rows (3x3 nodal thickness)
N_XS = 12 * NN  # scratch rows: x_o | x_n | U_o | U_n per node
N_FE = 6 * NN  # force rows: U_o, U_n per node

FLOPS_PER_ELEMENT = 518
"""Floating-point operations of one element (Green thickness strain), counted from this source as
executed, as lanes.FLOPS_PER_ELEMENT is (a negation counted as one): current coordinates 18;
membrane and bending 231 (8 tangent differences 24, strains 93 -- membrane 36, curvatures 57 --,
stresses 30, energy 12, generalised forces 60, node 0's forces 12); shear 193 (3 ties x 32 --
tangent 3, director 6, their displacement parts 3 + 6, strain 14 --, stresses 15, energy 7, U_o
forces 36, U_n forces 3 + 36); thickness 76 (strains 33, stresses 15, energy 7, director forces
3 + 18)."""


def covers(c) -> bool:
    """Whether constants ``c`` are tri3.precompute's: one membrane/bending point and the three
    shear ties of Eq. (12) (the form this kernel evaluates)."""
    return (
        c["Cmb"].shape[1:] == (1, 2, 3, 3)
        and c["Cs"].shape[1:] == (3, 3)
        and c["Cz"].shape[1:] == (3, 3)
        and np.array_equal(c["alpha"], tri3.ALPHA)
        and np.array_equal(c["beta"], tri3.BETA)
        and np.array_equal(c["tie"], tri3.TIE)
    )


def pack(conn, c, quasi_rz):
    """SoA copies (lanes.pack's layout and keys) of a triangle block: conn (B, 3, LANES) int64, Cmb
    (B, 18, LANES) (membrane 3x3 then bending 3x3, row-major), Cs (B, 9, LANES), Cz (B, 9, LANES),
    r_z (B, 3, LANES) with B = ceil(M / LANES); padded lanes repeat element 0's nodes with zero
    rigidity.  ValueError unless ``covers(c)``."""
    if not covers(c):
        raise ValueError("lanes_tri.pack needs the constants of tri3.precompute")
    return lanes.pack(conn, dict(Cmb=c["Cmb"], Cs=c["Cs"], Cz=c["Cz"]), quasi_rz)


def unpack_forces(fe, M):
    """(M, 3, 6) element forces from the SoA (B, 18 LANES) array (for tests)."""
    return fe.reshape(-1, N_FE, LANES).transpose(0, 2, 1).reshape(-1, NN, 6)[:M]


# ---------------------------------------------------------------- helpers on 3-tuples
@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _half(a, b):
    """(a + b) / 2: core's 0.5 a + 0 c + 0.5 b (scaling by 1/2 is exact)."""
    return (0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2]))


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _tie(a, d, au, du):
    """The shear tying strain of Eq. (12) in displacement form: au.(d - du) + a.du, with a the
    current tangent (its displacement part au) and d the current director (du)."""
    return (
        (au[0] * (d[0] - du[0]) + a[0] * du[0])
        + (au[1] * (d[1] - du[1]) + a[1] * du[1])
        + (au[2] * (d[2] - du[2]) + a[2] * du[2])
    )


@njit(forceinline=True, error_model="numpy")
def _nodes(xs, b, k):
    """(x, n, u, v): the three nodes' x_o, x_n, U_o, U_n of lane k from the scratch."""
    x = (_row3(xs, b, 0, k), _row3(xs, b, 12, k), _row3(xs, b, 24, k))
    n = (_row3(xs, b, 3, k), _row3(xs, b, 15, k), _row3(xs, b, 27, k))
    u = (_row3(xs, b, 6, k), _row3(xs, b, 18, k), _row3(xs, b, 30, k))
    v = (_row3(xs, b, 9, k), _row3(xs, b, 21, k), _row3(xs, b, 33, k))
    return x, n, u, v


# ---------------------------------------------------------------- stages
@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _stage_mb(b, s, k, C, xs, fe, we):
    """Membrane and bending at the element's one point (Eq. 11; core._element_force with dN =
    tri3.DN): starts lane k's forces and energy."""
    x, n, u, v = _nodes(xs, s, k)
    # dN/ds = (-1, 1, 0), dN/dt = (-1, 0, 1): the tangents are edge vectors
    a1 = _sub(x[1], x[0])
    a2 = _sub(x[2], x[0])
    b1 = _sub(n[1], n[0])
    b2 = _sub(n[2], n[0])
    u1 = _sub(u[1], u[0])
    u2 = _sub(u[2], u[0])
    v1 = _sub(v[1], v[0])
    v2 = _sub(v[2], v[0])
    e0 = u1[0] * (a1[0] - 0.5 * u1[0]) + u1[1] * (a1[1] - 0.5 * u1[1]) + u1[2] * (a1[2] - 0.5 * u1[2])
    e1 = u2[0] * (a2[0] - 0.5 * u2[0]) + u2[1] * (a2[1] - 0.5 * u2[1]) + u2[2] * (a2[2] - 0.5 * u2[2])
    e2 = u1[0] * (a2[0] - u2[0]) + u1[1] * (a2[1] - u2[1]) + u1[2] * (a2[2] - u2[2]) + _dot(a1, u2)
    k0, k1, k2 = curvatures(a1, a2, b1, b2, u1, u2, v1, v2)
    n0 = C[b, 0, k] * e0 + C[b, 1, k] * e1 + C[b, 2, k] * e2
    n1 = C[b, 3, k] * e0 + C[b, 4, k] * e1 + C[b, 5, k] * e2
    n2 = C[b, 6, k] * e0 + C[b, 7, k] * e1 + C[b, 8, k] * e2
    m0 = C[b, 9, k] * k0 + C[b, 10, k] * k1 + C[b, 11, k] * k2
    m1 = C[b, 12, k] * k0 + C[b, 13, k] * k1 + C[b, 14, k] * k2
    m2 = C[b, 15, k] * k0 + C[b, 16, k] * k1 + C[b, 17, k] * k2
    we[b, k] = 0.5 * (n0 * e0 + n1 * e1 + n2 * e2 + m0 * k0 + m1 * k1 + m2 * k2)
    # generalised forces on a1, a2 (p) and b1, b2 (q); node 0 gets -(p1 + p2), 1 p1, 2 p2
    p1 = (
        n0 * a1[0] + n2 * a2[0] + m0 * b1[0] + m2 * b2[0],
        n0 * a1[1] + n2 * a2[1] + m0 * b1[1] + m2 * b2[1],
        n0 * a1[2] + n2 * a2[2] + m0 * b1[2] + m2 * b2[2],
    )
    p2 = (
        n1 * a2[0] + n2 * a1[0] + m1 * b2[0] + m2 * b1[0],
        n1 * a2[1] + n2 * a1[1] + m1 * b2[1] + m2 * b1[1],
        n1 * a2[2] + n2 * a1[2] + m1 * b2[2] + m2 * b1[2],
    )
    q1 = _lin2(m0, a1, m2, a2)
    q2 = _lin2(m1, a2, m2, a1)
    p0 = (-(p1[0] + p2[0]), -(p1[1] + p2[1]), -(p1[2] + p2[2]))
    q0 = (-(q1[0] + q2[0]), -(q1[1] + q2[1]), -(q1[2] + q2[2]))
    _store_f(fe, s, 0, k, p0, q0)
    _store_f(fe, s, 6, k, p1, q1)
    _store_f(fe, s, 12, k, p2, q2)


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _stage_rest(b, s, k, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """Transverse shear (Eqs. 12-14, folded into Cs) and thickness (Eq. 15 with Eq. 5 / Eq. 24):
    adds their forces and energy to lane k's."""
    x, n, u, v = _nodes(xs, s, k)
    # tying points (tri3.ALPHA, tri3.BETA): edge 3-1 (x_1 - x_3), 1-2 (x_2 - x_1), 2-3 (x_3 - x_2),
    # directors the edges' mid-point averages
    ta0 = _sub(x[0], x[2])
    ta1 = _sub(x[1], x[0])
    ta2 = _sub(x[2], x[1])
    td0 = _half(n[0], n[2])
    td1 = _half(n[0], n[1])
    td2 = _half(n[1], n[2])
    g0 = _tie(ta0, td0, _sub(u[0], u[2]), _half(v[0], v[2]))
    g1 = _tie(ta1, td1, _sub(u[1], u[0]), _half(v[0], v[1]))
    g2 = _tie(ta2, td2, _sub(u[2], u[1]), _half(v[1], v[2]))
    s0 = Cs[b, 0, k] * g0 + Cs[b, 1, k] * g1 + Cs[b, 2, k] * g2
    s1 = Cs[b, 3, k] * g0 + Cs[b, 4, k] * g1 + Cs[b, 5, k] * g2
    s2 = Cs[b, 6, k] * g0 + Cs[b, 7, k] * g1 + Cs[b, 8, k] * g2
    energy = we[b, k] + 0.5 * (s0 * g0 + s1 * g1 + s2 * g2)
    # d g_t / d x_o,i = alpha_ti d_t, d g_t / d x_n,i = beta_ti a_t
    fo0 = _row3(fe, s, 0, k)
    fo1 = _row3(fe, s, 6, k)
    fo2 = _row3(fe, s, 12, k)
    fo0 = (
        fo0[0] + (s0 * td0[0] - s1 * td1[0]),
        fo0[1] + (s0 * td0[1] - s1 * td1[1]),
        fo0[2] + (s0 * td0[2] - s1 * td1[2]),
    )
    fo1 = (
        fo1[0] + (s1 * td1[0] - s2 * td2[0]),
        fo1[1] + (s1 * td1[1] - s2 * td2[1]),
        fo1[2] + (s1 * td1[2] - s2 * td2[2]),
    )
    fo2 = (
        fo2[0] + (s2 * td2[0] - s0 * td0[0]),
        fo2[1] + (s2 * td2[1] - s0 * td0[1]),
        fo2[2] + (s2 * td2[2] - s0 * td0[2]),
    )
    h0 = 0.5 * s0
    h1 = 0.5 * s1
    h2 = 0.5 * s2
    fn0 = _row3(fe, s, 3, k)
    fn1 = _row3(fe, s, 9, k)
    fn2 = _row3(fe, s, 15, k)
    fn0 = (
        fn0[0] + (h0 * ta0[0] + h1 * ta1[0]),
        fn0[1] + (h0 * ta0[1] + h1 * ta1[1]),
        fn0[2] + (h0 * ta0[2] + h1 * ta1[2]),
    )
    fn1 = (
        fn1[0] + (h1 * ta1[0] + h2 * ta2[0]),
        fn1[1] + (h1 * ta1[1] + h2 * ta2[1]),
        fn1[2] + (h1 * ta1[2] + h2 * ta2[2]),
    )
    fn2 = (
        fn2[0] + (h0 * ta0[0] + h2 * ta2[0]),
        fn2[1] + (h0 * ta0[1] + h2 * ta2[1]),
        fn2[2] + (h0 * ta0[2] + h2 * ta2[2]),
    )
    # thickness strain at the nodes (Eq. 15 with Eq. 5 / Eq. 24); Eq. 24's corner normal at node i
    # from its neighbours i+1, i-1 as core takes them
    z0 = z1 = z2 = 1.0
    if quasi:
        z0 = _sign_quasi(x, n, 0, 1, 2, mu)
        z1 = _sign_quasi(x, n, 1, 2, 0, mu)
        z2 = _sign_quasi(x, n, 2, 0, 1, mu)
    e0, c0 = _thick(n[0], v[0], quasi, z0, rz[b, 0, k])
    e1, c1 = _thick(n[1], v[1], quasi, z1, rz[b, 1, k])
    e2, c2 = _thick(n[2], v[2], quasi, z2, rz[b, 2, k])
    t0 = Cz[b, 0, k] * e0 + Cz[b, 1, k] * e1 + Cz[b, 2, k] * e2
    t1 = Cz[b, 3, k] * e0 + Cz[b, 4, k] * e1 + Cz[b, 5, k] * e2
    t2 = Cz[b, 6, k] * e0 + Cz[b, 7, k] * e1 + Cz[b, 8, k] * e2
    we[b, k] = energy + 0.5 * (t0 * e0 + t1 * e1 + t2 * e2)
    _store(fe, s, 0, k, fo0, fn0, t0 * c0, n[0])
    _store(fe, s, 6, k, fo1, fn1, t1 * c1, n[1])
    _store(fe, s, 12, k, fo2, fn2, t2 * c2, n[2])


@njit(cache=True, forceinline=True, fastmath=_FM, error_model="numpy")
def _block(b, s, X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """All lanes of block b, stage by stage (gather, membrane and bending, shear and thickness;
    lanes._block's scheme), the branch on the thickness strain outside the lane loop."""
    for k in range(LANES):
        _gather(b, s, k, X, Xn, U, conn, xs, NN)
    for k in range(LANES):
        _stage_mb(b, s, k, Cmb, xs, fe, we)
    if quasi:
        for k in range(LANES):
            _stage_rest(b, s, k, Cs, Cz, rz, True, mu, xs, fe, we)
    else:
        for k in range(LANES):
            _stage_rest(b, s, k, Cs, Cz, rz, False, mu, xs, fe, we)


@njit(cache=True, parallel=True, fastmath=_FM, error_model="numpy")
def tri_forces(X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """Element forces fe (B, 18 LANES) (entry (6 i + c) LANES + k: node i, dof c of lane k) and
    energies we (B, LANES) of all triangles (``pack`` layout) at displacements U (N, 6) of the
    nodes X, directors Xn (N, 3); xs (B, 36 LANES) is scratch."""
    for b in prange(conn.shape[0]):
        _block(b, b, X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we)
