"""The quadrilateral's internal force with elements in SIMD lanes (structure of arrays).

The same energy and force as ``core.energy_force`` for the 4-node quadrilateral with the compatible
2x2 membrane (``membrane="full"``, Section 2.1, Eqs. 1-9, displacement form of Eq. 3, thickness
strain of Eq. 5 or Eq. 24), arranged so that the compiler evaluates ``LANES`` elements at once in
vector registers:

- elements are grouped in blocks of ``LANES``; every per-element array is stored (block, row,
  lane), so lane k of a block is a contiguous stream for every constant (``pack``);
- the node loops (4 nodes, 4 Gauss points, 4 shear tying points) are unrolled at compile time
  (tuples of scalars, helpers inlined), so the lane loop body is straight-line code with no
  branch: LLVM's loop vectoriser turns it into vector instructions with gathers for the nodal
  coordinates (the parallel block loop hands it arrays it knows do not alias);
- the last block is padded with copies of element 0's nodes and zero rigidities: zero force and
  energy, never scattered.

Every block is evaluated by the same instructions whatever the thread count (blocks are the unit
of work), so results do not depend on it.  They equal core.py's to round-off: the operations are
the same, their grouping within a sum and the contraction into fused multiply-adds may differ.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from . import quad4
from .core import _FM

LANES = 16
"""Elements per block: a multiple of the vector width (4 doubles in AVX2, 8 in AVX-512)."""

# dN_i/dxi, dN_i/deta at the four Gauss points (quad4.DN_GP) as compile-time tuples
_D = tuple(tuple(tuple(float(v) for v in quad4.DN_GP[g, :, j]) for j in range(2)) for g in range(4))
_D0, _D1, _D2, _D3 = _D
# the shear tying points (quad4.ALPHA, quad4.BETA): derivative of x_o and value of x_n
_A = tuple(tuple(float(v) for v in quad4.ALPHA[t]) for t in range(4))
_B = tuple(tuple(float(v) for v in quad4.BETA[t]) for t in range(4))
_A0, _A1, _A2, _A3 = _A
_B0, _B1, _B2, _B3 = _B

FLOPS_PER_ELEMENT = 2354
"""Floating-point operations of one element (Green thickness strain), counted from this source as
executed: 4 Gauss points x 458 (8 tangent combinations 168, strains 92, stresses 30, energy 12,
generalised forces 60, nodal forces 96), 4 shear ties x 50 (the tying tables have two nonzero
weights a row, and zero weights cost nothing: _w) + 28 + 9 + 8 nodal force updates x 18,
thickness 44 + 28 + 9 + 28, current coordinates 24."""

N_CMB = 4 * 2 * 9  # Cmb rows per element: (gp, membrane|bending, 3x3)
N_CS = 16  # Cs rows (4x4 shear tying)
N_CZ = 16  # Cz rows (4x4 nodal thickness)


# ---------------------------------------------------------------- layout
def pack(conn, c, quasi_rz):
    """SoA copies of a quad block's connectivity and folded constants (quad4.precompute):
    conn (B, 4, LANES) int64, Cmb (B, 72, LANES), Cs (B, 16, LANES), Cz (B, 16, LANES), r_z
    (B, 4, LANES) with B = ceil(M / LANES); padded lanes repeat element 0's nodes with zero
    rigidity."""
    M = len(conn)
    B = (M + LANES - 1) // LANES
    pad = B * LANES - M

    def soa(a, fill):
        a = a.reshape(M, -1)
        a = np.concatenate([a, np.broadcast_to(fill, (pad, a.shape[1]))]) if pad else a
        return np.ascontiguousarray(a.reshape(B, LANES, -1).transpose(0, 2, 1))

    return dict(
        conn=soa(np.asarray(conn, np.int64), np.asarray(conn[0], np.int64)),
        Cmb=soa(c["Cmb"], 0.0),
        Cs=soa(c["Cs"], 0.0),
        Cz=soa(c["Cz"], 0.0),
        r_z=soa(quasi_rz, 1.0),
        M=M,
        B=B,
    )


def unpack_forces(fe, M):
    """(M, 4, 6) element forces from the SoA (B, 24 LANES) array (for tests)."""
    return fe.reshape(-1, 24, LANES).transpose(0, 2, 1).reshape(-1, 4, 6)[:M]


# ---------------------------------------------------------------- 3-vectors as tuples
@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _w(w, x):
    """w x, or no term at all where the table weight w is a structural zero: w is a compile-time
    constant at every call, so the branch folds away, and the 0.0 left in a sum folds with no-signed-
    zeros (without no-NaN fast-math LLVM keeps 0 * x: it is NaN for x = inf)."""
    return w * x if w != 0.0 else 0.0


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _comb(d, x):
    """sum_i d_i x_i over the four nodes (3-tuple); zero weights d_i add no operation (_w)."""
    return (
        _w(d[0], x[0][0]) + _w(d[1], x[1][0]) + _w(d[2], x[2][0]) + _w(d[3], x[3][0]),
        _w(d[0], x[0][1]) + _w(d[1], x[1][1]) + _w(d[2], x[2][1]) + _w(d[3], x[3][1]),
        _w(d[0], x[0][2]) + _w(d[1], x[1][2]) + _w(d[2], x[2][2]) + _w(d[3], x[3][2]),
    )


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _lin2(s, a, t, b):
    """s a + t b."""
    return (s * a[0] + t * b[0], s * a[1] + t * b[1], s * a[2] + t * b[2])


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _acc2(f, d1, p, d2, q):
    """f_i + (d1_i p + d2_i q) for the four nodes."""
    return (
        (
            f[0][0] + (d1[0] * p[0] + d2[0] * q[0]),
            f[0][1] + (d1[0] * p[1] + d2[0] * q[1]),
            f[0][2] + (d1[0] * p[2] + d2[0] * q[2]),
        ),
        (
            f[1][0] + (d1[1] * p[0] + d2[1] * q[0]),
            f[1][1] + (d1[1] * p[1] + d2[1] * q[1]),
            f[1][2] + (d1[1] * p[2] + d2[1] * q[2]),
        ),
        (
            f[2][0] + (d1[2] * p[0] + d2[2] * q[0]),
            f[2][1] + (d1[2] * p[1] + d2[2] * q[1]),
            f[2][2] + (d1[2] * p[2] + d2[2] * q[2]),
        ),
        (
            f[3][0] + (d1[3] * p[0] + d2[3] * q[0]),
            f[3][1] + (d1[3] * p[1] + d2[3] * q[1]),
            f[3][2] + (d1[3] * p[2] + d2[3] * q[2]),
        ),
    )


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _sw(s, w, p):
    """s w p (in that order), or no term where the table weight w is a structural zero (_w)."""
    return s * w * p if w != 0.0 else 0.0


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _acc1(f, s, w, p):
    """f_i + s w_i p for the four nodes; a node with a zero weight w_i keeps f_i (_sw)."""
    return (
        (f[0][0] + _sw(s, w[0], p[0]), f[0][1] + _sw(s, w[0], p[1]), f[0][2] + _sw(s, w[0], p[2])),
        (f[1][0] + _sw(s, w[1], p[0]), f[1][1] + _sw(s, w[1], p[1]), f[1][2] + _sw(s, w[1], p[2])),
        (f[2][0] + _sw(s, w[2], p[0]), f[2][1] + _sw(s, w[2], p[1]), f[2][2] + _sw(s, w[2], p[2])),
        (f[3][0] + _sw(s, w[3], p[0]), f[3][1] + _sw(s, w[3], p[1]), f[3][2] + _sw(s, w[3], p[2])),
    )


@njit(forceinline=True, error_model="numpy")
def _node(A, B, p, o):
    """(A[p, o:o+3] + B[p, :3]) -- current = initial + displacement."""
    return (A[p, 0] + B[p, o], A[p, 1] + B[p, o + 1], A[p, 2] + B[p, o + 2])


@njit(forceinline=True, error_model="numpy")
def _disp(B, p, o):
    return (B[p, o], B[p, o + 1], B[p, o + 2])


# ---------------------------------------------------------------- one Gauss point, one tying point
@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def gradients(d, x, n, u, v):
    """(d1, d2, a1, a2, b1, b2, u1, u2, v1, v2): the point's dN/dxi, dN/deta and the xi / eta
    derivatives of x_o, x_n, U_o, U_n there (Eq. 1)."""
    d1 = d[0]
    d2 = d[1]
    return (
        d1,
        d2,
        _comb(d1, x),
        _comb(d2, x),
        _comb(d1, n),
        _comb(d2, n),
        _comb(d1, u),
        _comb(d2, u),
        _comb(d1, v),
        _comb(d2, v),
    )


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def curvatures(a1, a2, b1, b2, u1, u2, v1, v2):
    """The bending strains of Eq. (3) (k_xixi, k_etaeta, 2 k_xieta) in displacement form:
    a.b - A.B = u.b + a.v - u.v with A = a - u, B = b - v."""
    k0 = u1[0] * (b1[0] - v1[0]) + u1[1] * (b1[1] - v1[1]) + u1[2] * (b1[2] - v1[2]) + _dot(a1, v1)
    k1 = u2[0] * (b2[0] - v2[0]) + u2[1] * (b2[1] - v2[1]) + u2[2] * (b2[2] - v2[2]) + _dot(a2, v2)
    k2 = (
        u1[0] * (b2[0] - v2[0])
        + u1[1] * (b2[1] - v2[1])
        + u1[2] * (b2[2] - v2[2])
        + _dot(a1, v2)
        + u2[0] * (b1[0] - v1[0])
        + u2[1] * (b1[1] - v1[1])
        + u2[2] * (b1[2] - v1[2])
        + _dot(a2, v1)
    )
    return k0, k1, k2


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _gauss_point(d, x, n, u, v, C, b, r, k, fo, fn):
    """Membrane and bending at one Gauss point (core._element_force): (fo, fn, energy).  d: the
    point's (dN/dxi, dN/deta); x, n, u, v: nodal x_o, x_n, U_o, U_n; C[r:r+18, k] its Cmb."""
    d1, d2, a1, a2, b1, b2, u1, u2, v1, v2 = gradients(d, x, n, u, v)
    # displacement form: a.b - A.B = u.b + a.v - u.v with A = a - u, B = b - v
    e0 = u1[0] * (a1[0] - 0.5 * u1[0]) + u1[1] * (a1[1] - 0.5 * u1[1]) + u1[2] * (a1[2] - 0.5 * u1[2])
    e1 = u2[0] * (a2[0] - 0.5 * u2[0]) + u2[1] * (a2[1] - 0.5 * u2[1]) + u2[2] * (a2[2] - 0.5 * u2[2])
    e2 = u1[0] * (a2[0] - u2[0]) + u1[1] * (a2[1] - u2[1]) + u1[2] * (a2[2] - u2[2]) + _dot(a1, u2)
    k0, k1, k2 = curvatures(a1, a2, b1, b2, u1, u2, v1, v2)
    n0 = C[b, r + 0, k] * e0 + C[b, r + 1, k] * e1 + C[b, r + 2, k] * e2
    n1 = C[b, r + 3, k] * e0 + C[b, r + 4, k] * e1 + C[b, r + 5, k] * e2
    n2 = C[b, r + 6, k] * e0 + C[b, r + 7, k] * e1 + C[b, r + 8, k] * e2
    m0 = C[b, r + 9, k] * k0 + C[b, r + 10, k] * k1 + C[b, r + 11, k] * k2
    m1 = C[b, r + 12, k] * k0 + C[b, r + 13, k] * k1 + C[b, r + 14, k] * k2
    m2 = C[b, r + 15, k] * k0 + C[b, r + 16, k] * k1 + C[b, r + 17, k] * k2
    w = 0.5 * (n0 * e0 + n1 * e1 + n2 * e2 + m0 * k0 + m1 * k1 + m2 * k2)
    # generalised forces on a1, a2 (p) and b1, b2 (q)
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
    return _acc2(fo, d1, p1, d2, p2), _acc2(fn, d1, q1, d2, q2), w


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _tying(al, be, x, n, u, v):
    """Transverse shear tying strain of Eq. (4): (a, d, gamma) with a = sum alpha_i x_o,i (the
    tangent), d = sum beta_i x_n,i (the director), gamma in displacement form."""
    a = _comb(al, x)
    d = _comb(be, n)
    au = _comb(al, u)
    du = _comb(be, v)
    g = (
        (au[0] * (d[0] - du[0]) + a[0] * du[0])
        + (au[1] * (d[1] - du[1]) + a[1] * du[1])
        + (au[2] * (d[2] - du[2]) + a[2] * du[2])
    )
    return a, d, g


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _sign_quasi(x, n, i, q, r, mu):
    """s_p of Eq. (24) at corner i (neighbours q, r): +1 if n_p.d_p > -mu |n_p||d_p|, else -1."""
    uu = (x[q][0] - x[i][0], x[q][1] - x[i][1], x[q][2] - x[i][2])
    vv = (x[r][0] - x[i][0], x[r][1] - x[i][1], x[r][2] - x[i][2])
    nx = uu[1] * vv[2] - uu[2] * vv[1]
    ny = uu[2] * vv[0] - uu[0] * vv[2]
    nz = uu[0] * vv[1] - uu[1] * vv[0]
    d = n[i]
    nd = nx * d[0] + ny * d[1] + nz * d[2]
    den = np.sqrt((nx * nx + ny * ny + nz * nz) * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]))
    return 1.0 if nd > -mu * den else -1.0


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _thick(n, v, quasi, s, rz):
    """eps_zz at a node (core._thickness_strain) and the factor turning its stress into a director
    force (1 for Green, s / |x_n| for Eq. 24)."""
    d = v[0] * (n[0] - 0.5 * v[0]) + v[1] * (n[1] - 0.5 * v[1]) + v[2] * (n[2] - 0.5 * v[2])
    if not quasi:
        return d, 1.0
    nx = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    z = 2.0 * d / (nx + rz) if s > 0.0 else -nx - rz
    return z, s / nx


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _store(F, b, r, k, fo, fn, h, n):
    """Node rows r..r+5 of lane k: U_o force, U_n force plus the thickness stress times x_n.  The
    rows are LANES apart in a flat row (a compile-time distance): with a runtime row stride the
    vectoriser cannot rule out that two rows' stores overlap and leaves the loop scalar."""
    F[b, r * LANES + k] = fo[0]
    F[b, (r + 1) * LANES + k] = fo[1]
    F[b, (r + 2) * LANES + k] = fo[2]
    F[b, (r + 3) * LANES + k] = fn[0] + h * n[0]
    F[b, (r + 4) * LANES + k] = fn[1] + h * n[1]
    F[b, (r + 5) * LANES + k] = fn[2] + h * n[2]


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def store_nodes(F, b, k, fo, fn, h, n):
    """The four nodes' rows of lane k (_store): forces fo, fn, thickness stresses h (4-tuple)."""
    _store(F, b, 0, k, fo[0], fn[0], h[0], n[0])
    _store(F, b, 6, k, fo[1], fn[1], h[1], n[1])
    _store(F, b, 12, k, fo[2], fn[2], h[2], n[2])
    _store(F, b, 18, k, fo[3], fn[3], h[3], n[3])


@njit(forceinline=True, error_model="numpy")
def _store_f(F, b, r, k, fo, fn):
    """_store without a thickness stress (node rows r..r+5 of lane k: the U_o and U_n forces, rows
    LANES apart, a compile-time distance, for the vectoriser): 0 h x_n would be multiplied and
    added (0 * x is not folded without no-NaN fast-math)."""
    F[b, r * LANES + k] = fo[0]
    F[b, (r + 1) * LANES + k] = fo[1]
    F[b, (r + 2) * LANES + k] = fo[2]
    F[b, (r + 3) * LANES + k] = fn[0]
    F[b, (r + 4) * LANES + k] = fn[1]
    F[b, (r + 5) * LANES + k] = fn[2]


@njit(forceinline=True, error_model="numpy")
def store_forces(F, b, k, fo, fn):
    """The four nodes' rows of lane k with forces fo, fn and no thickness stress (the Gauss point
    stages)."""
    _store_f(F, b, 0, k, fo[0], fn[0])
    _store_f(F, b, 6, k, fo[1], fn[1])
    _store_f(F, b, 12, k, fo[2], fn[2])
    _store_f(F, b, 18, k, fo[3], fn[3])


# ---------------------------------------------------------------- the kernel
@njit(forceinline=True, error_model="numpy")
def _gather(b, s, k, X, Xn, U, conn, xs, nn):
    """Stage 0: lane k's nodal x_o, x_n, U_o, U_n into the scratch row s (entry 12 i + c: node i,
    component c of x_o | x_n | U_o | U_n), so that the later stages load contiguous lanes; ``nn``
    the element's node count, a literal at every call (4 here, 3 in lanes_tri)."""
    for i in range(nn):
        p = conn[b, i, k]
        for c in range(3):
            xs[s, (12 * i + c) * LANES + k] = X[p, c] + U[p, c]
            xs[s, (12 * i + 3 + c) * LANES + k] = Xn[p, c] + U[p, 3 + c]
            xs[s, (12 * i + 6 + c) * LANES + k] = U[p, c]
            xs[s, (12 * i + 9 + c) * LANES + k] = U[p, 3 + c]


@njit(forceinline=True, error_model="numpy")
def _row3(xs, b, r, k):
    return (xs[b, r * LANES + k], xs[b, (r + 1) * LANES + k], xs[b, (r + 2) * LANES + k])


@njit(forceinline=True, error_model="numpy")
def _nodes(xs, b, k):
    """(x, n, u, v): the four nodes' x_o, x_n, U_o, U_n of lane k from the scratch."""
    x = (_row3(xs, b, 0, k), _row3(xs, b, 12, k), _row3(xs, b, 24, k), _row3(xs, b, 36, k))
    n = (_row3(xs, b, 3, k), _row3(xs, b, 15, k), _row3(xs, b, 27, k), _row3(xs, b, 39, k))
    u = (_row3(xs, b, 6, k), _row3(xs, b, 18, k), _row3(xs, b, 30, k), _row3(xs, b, 42, k))
    v = (_row3(xs, b, 9, k), _row3(xs, b, 21, k), _row3(xs, b, 33, k), _row3(xs, b, 45, k))
    return x, n, u, v


@njit(forceinline=True, error_model="numpy")
def _forces_of(fe, s, k):
    """The U_o and U_n forces of the four nodes of lane k accumulated so far."""
    fo = (_row3(fe, s, 0, k), _row3(fe, s, 6, k), _row3(fe, s, 12, k), _row3(fe, s, 18, k))
    fn = (_row3(fe, s, 3, k), _row3(fe, s, 9, k), _row3(fe, s, 15, k), _row3(fe, s, 21, k))
    return fo, fn


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _stage_gp(b, s, k, D, r, Cmb, xs, fe, we, first):
    """Gauss point with derivatives D, rigidities Cmb[b, r:r+18]: adds its forces and energy."""
    x, n, u, v = _nodes(xs, s, k)
    if first:
        z3 = (0.0, 0.0, 0.0)
        fo = (z3, z3, z3, z3)
        fn = (z3, z3, z3, z3)
        w = 0.0
    else:
        fo, fn = _forces_of(fe, s, k)
        w = we[b, k]
    fo, fn, wg = _gauss_point(D, x, n, u, v, Cmb, b, r, k, fo, fn)
    store_forces(fe, s, k, fo, fn)
    we[b, k] = w + wg


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def _stage_rest(b, s, k, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """ANS transverse shear (Eq. 4) and thickness (Eq. 5 / Eq. 24): adds their forces and energy."""
    x, n, u, v = _nodes(xs, s, k)
    fo, fn = _forces_of(fe, s, k)
    energy = we[b, k]
    # ---- ANS transverse shear (Eq. 4): tying values, their forces (core._element_force)
    ta0, td0, g0 = _tying(_A0, _B0, x, n, u, v)
    ta1, td1, g1 = _tying(_A1, _B1, x, n, u, v)
    ta2, td2, g2 = _tying(_A2, _B2, x, n, u, v)
    ta3, td3, g3 = _tying(_A3, _B3, x, n, u, v)
    q0 = Cs[b, 0, k] * g0 + Cs[b, 1, k] * g1 + Cs[b, 2, k] * g2 + Cs[b, 3, k] * g3
    q1 = Cs[b, 4, k] * g0 + Cs[b, 5, k] * g1 + Cs[b, 6, k] * g2 + Cs[b, 7, k] * g3
    q2 = Cs[b, 8, k] * g0 + Cs[b, 9, k] * g1 + Cs[b, 10, k] * g2 + Cs[b, 11, k] * g3
    q3 = Cs[b, 12, k] * g0 + Cs[b, 13, k] * g1 + Cs[b, 14, k] * g2 + Cs[b, 15, k] * g3
    energy += 0.5 * (q0 * g0 + q1 * g1 + q2 * g2 + q3 * g3)
    fo = _acc1(fo, q0, _A0, td0)
    fn = _acc1(fn, q0, _B0, ta0)
    fo = _acc1(fo, q1, _A1, td1)
    fn = _acc1(fn, q1, _B1, ta1)
    fo = _acc1(fo, q2, _A2, td2)
    fn = _acc1(fn, q2, _B2, ta2)
    fo = _acc1(fo, q3, _A3, td3)
    fn = _acc1(fn, q3, _B3, ta3)
    # ---- ANS thickness strain at the nodes (Eq. 5 / Eq. 24)
    s0 = s1 = s2 = s3 = 1.0
    if quasi:
        s0 = _sign_quasi(x, n, 0, 1, 3, mu)
        s1 = _sign_quasi(x, n, 1, 2, 0, mu)
        s2 = _sign_quasi(x, n, 2, 3, 1, mu)
        s3 = _sign_quasi(x, n, 3, 0, 2, mu)
    z0, c0 = _thick(n[0], v[0], quasi, s0, rz[b, 0, k])
    z1, c1 = _thick(n[1], v[1], quasi, s1, rz[b, 1, k])
    z2, c2 = _thick(n[2], v[2], quasi, s2, rz[b, 2, k])
    z3_, c3 = _thick(n[3], v[3], quasi, s3, rz[b, 3, k])
    h0 = Cz[b, 0, k] * z0 + Cz[b, 1, k] * z1 + Cz[b, 2, k] * z2 + Cz[b, 3, k] * z3_
    h1 = Cz[b, 4, k] * z0 + Cz[b, 5, k] * z1 + Cz[b, 6, k] * z2 + Cz[b, 7, k] * z3_
    h2 = Cz[b, 8, k] * z0 + Cz[b, 9, k] * z1 + Cz[b, 10, k] * z2 + Cz[b, 11, k] * z3_
    h3 = Cz[b, 12, k] * z0 + Cz[b, 13, k] * z1 + Cz[b, 14, k] * z2 + Cz[b, 15, k] * z3_
    energy += 0.5 * (h0 * z0 + h1 * z1 + h2 * z2 + h3 * z3_)
    store_nodes(fe, s, k, fo, fn, (h0 * c0, h1 * c1, h2 * c2, h3 * c3), n)
    we[b, k] = energy


@njit(forceinline=True, fastmath=_FM, error_model="numpy")
def stages_rest(b, s, nl, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """The last stage (shear and thickness, _stage_rest) of the nl lanes of block b, the branch on
    the thickness strain outside the lane loop: each loop body is straight-line code."""
    if quasi:
        for k in range(nl):
            _stage_rest(b, s, k, Cs, Cz, rz, True, mu, xs, fe, we)
    else:
        for k in range(nl):
            _stage_rest(b, s, k, Cs, Cz, rz, False, mu, xs, fe, we)


@njit(cache=True, forceinline=True, fastmath=_FM, error_model="numpy")
def _block(b, s, X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """All lanes of block b, stage by stage (gather, four Gauss points, shear and thickness): each
    stage's lane loop is short enough for LLVM's vectoriser (one loop over the whole element was
    left scalar).  Inlined by LLVM into the parallel loop, whose arrays are marked non-aliasing
    there: that is what lets the lane loops vectorise over the gathered loads.  Row s of xs and of
    fe is the block's scratch and forces (energies go to we[b] in any case): a caller that runs
    blocks one after another on a thread and scatters each block's forces before the next passes
    the same row for all of them, so both stay in L1 (a row per block streamed ~1150 B per
    element through memory every step: the pass at 10^4 quads on 1 thread ran 1.3-1.5x slower).
    Every lane loop runs LANES times, a literal (padded lanes are computed anyway): LLVM then
    emits no scalar remainder loop and no runtime overlap checks, and vectorises the gather."""
    for k in range(LANES):
        _gather(b, s, k, X, Xn, U, conn, xs, 4)
    for k in range(LANES):
        _stage_gp(b, s, k, _D0, 0, Cmb, xs, fe, we, True)
    for k in range(LANES):
        _stage_gp(b, s, k, _D1, 18, Cmb, xs, fe, we, False)
    for k in range(LANES):
        _stage_gp(b, s, k, _D2, 36, Cmb, xs, fe, we, False)
    for k in range(LANES):
        _stage_gp(b, s, k, _D3, 54, Cmb, xs, fe, we, False)
    stages_rest(b, s, LANES, Cs, Cz, rz, quasi, mu, xs, fe, we)


@njit(cache=True, parallel=True, fastmath=_FM, error_model="numpy")
def quad_forces(X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we):
    """Element forces fe (B, 24 LANES) (entry (6 i + c) LANES + k: node i, dof c of lane k) and
    energies we (B, LANES) of all quads (``pack`` layout) at displacements U (N, 6) of the nodes X,
    directors Xn (N, 3); xs (B, 48 LANES) is scratch."""
    for b in prange(conn.shape[0]):
        _block(b, b, X, Xn, U, conn, Cmb, Cs, Cz, rz, quasi, mu, xs, fe, we)
