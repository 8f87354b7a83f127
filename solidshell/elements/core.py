"""Batched ANS solid-shell kernels shared by the quadrilateral and the triangle (Eqs. 1-15).

Every strain of Eq. (7) is written as a difference of products of nodal vectors of the *current*
configuration x_o = X_o + U_o and x_n = X_n + U_n (Eq. 2 with the truncations of Eq. 3):

- at each membrane/bending point g, with a_k = sum_i dN_ik x_oi and b_k = sum_i dN_ik x_ni
  (k = xi, eta or s, t):  e = (a1.a1/2, a2.a2/2, a1.a2),   k = (a1.b1, a2.b2, a1.b2 + a2.b1);
- at each ANS tying point t: gamma_t = c_t (sum_i alpha_ti y_i).(sum_i beta_ti z_i) with (y, z) =
  (x_o, x_n) for the transverse shears (Eq. 4, Eq. 12; c_t = 1) and (x_o, x_o) for the assumed
  membrane strains of the quadrilateral (c_t = 1/2 for a stretch, 1 for a shear; quad4.py): the
  table ``tie`` (nt,3) holds (offset of y, offset of z, c_t), offsets 0 = x_o, 3 = x_n;
- at each node i (Eq. 5, Eq. 15): eps_zz,i = x_ni.x_ni / 2 (Green) or the quasi-engineering strain of
  Eq. (24);

minus the same quantities at X ("raw" natural strains).  The differences are formed in the
displacement form of Eq. (3), never as x.x - X.X: with u = sum dN U (U_o or U_n) and a the current
vector, a.b - A.B = u.b + a.v - u.v and a.a/2 - A.A/2 = u.(a - u/2).  Subtracting two products of
size |X|^2 would leave a strain of size |U||X| with an absolute error eps |X|^2, i.e. lose
log10(|X|/|U|) digits -- all of them in the linear regime of a stiff plate or in a unit system where
coordinates are large (issue 11).  The transformation to the local frame
(Eq. 6), the ANS interpolation to the integration points, the rigidities and J_o w of Eq. (7)--(8)
are all linear in the raw strains and depend only on the initial geometry, so they are folded once
per element into constant matrices (``Cmb``, ``Cs``, ``Cz``; see quad4.py / tri3.py).  The energy is

    U^e = 1/2 sum_g (e_g^T Cm_g e_g + k_g^T Cb_g k_g) + 1/2 gamma^T Cs gamma + 1/2 eps^T Cz eps,

its gradient (Eq. 9, f) and Hessian (k_t) follow in closed form.  Kernels know nothing of meshes:
they take node coordinates, displacements, connectivity and the element constants.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

# fastmath without nnan/ninf: a blown-up state must stay visibly non-finite for the solvers.
_FM = {"nsz", "arcp", "contract", "reassoc"}
"""The flags of the lane kernels (lanes*.py, solvers/explicit/fused.py), not of this module's."""

_FM_EXACT = {"nsz"}
"""This module's kernels: no flag that lets LLVM change a result (reassoc, contract = FMA fusion,
arcp = x/y as x*(1/y)), so a kernel rounds the same wherever numba compiled it.  Numba compiles a
jitted callee (_element_force, _element_tangent, ...) into a library of its own and again,
re-optimised, inside each caller's library.  The process that compiles the caller runs the callee's
own library; a process that loads the caller from numba's on-disk cache (``cache=True``) runs the
copy inside it.  With _FM the two copies of _element_tangent differed (other vectorisation and FMA
fusion): on the same element, a freshly compiled force_tangent and the cached one differed by one
ulp in 6 of 13824 tangent entries (quads-ans-quasi, tests/test_half_tangent.py), so a run's last
bits depended on what an earlier process had cached, and the whole and half tangents differed
whenever one came from the cache and the other was compiled.  Cost measured in one process on
4800 quads, one thread: half tangent kernel +4-7 %, force kernel +0-10 %."""


@njit(cache=True, fastmath=_FM_EXACT, inline="always")
def _sign_quasi(xo, xn, conn_e, nn, i, mu):
    """Sign s_p of Eq. (24) at local node i: +1 if n_p.d_p > -mu, else -1 (n_p from the corner)."""
    q = (i + 1) % nn
    r = (i + nn - 1) % nn
    p0 = conn_e[i]
    pq = conn_e[q]
    pr = conn_e[r]
    ux = xo[pq, 0] - xo[p0, 0]
    uy = xo[pq, 1] - xo[p0, 1]
    uz = xo[pq, 2] - xo[p0, 2]
    vx = xo[pr, 0] - xo[p0, 0]
    vy = xo[pr, 1] - xo[p0, 1]
    vz = xo[pr, 2] - xo[p0, 2]
    nx = uy * vz - uz * vy
    ny = uz * vx - ux * vz
    nz = ux * vy - uy * vx
    dx = xn[p0, 0]
    dy = xn[p0, 1]
    dz = xn[p0, 2]
    nd = nx * dx + ny * dy + nz * dz
    den = np.sqrt((nx * nx + ny * ny + nz * nz) * (dx * dx + dy * dy + dz * dz))
    if nd > -mu * den:
        return 1.0
    return -1.0


@njit(cache=True, fastmath=_FM_EXACT, inline="always")
def _thickness_strain(xe, i, quasi, sign, norm_X):
    """eps_zz at local node i (Eq. 5 / Eq. 15) in displacement form: x.x/2 - X.X/2 = v.(x - v/2)
    (Green) or, for Eq. (24), s|x| - |X| with |x| - |X| = v.(2x - v)/(|x| + |X|) (v = U_n)."""
    x0 = xe[i, 3]
    x1 = xe[i, 4]
    x2 = xe[i, 5]
    v0 = xe[i, 9]
    v1 = xe[i, 10]
    v2 = xe[i, 11]
    d = v0 * (x0 - 0.5 * v0) + v1 * (x1 - 0.5 * v1) + v2 * (x2 - 0.5 * v2)
    if not quasi:
        return d
    nx = np.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
    if sign > 0.0:
        return 2.0 * d / (nx + norm_X)
    return -nx - norm_X


@njit(cache=True, fastmath=_FM_EXACT, error_model="numpy")
def _element_force(e, xo, xn, U, conn, dN, alpha, beta, tie, Cmb, Cs, Cz, r_z, quasi, mu, fe, gs, gz, zs, at, dt, xe):
    """Energy of element e; its force into fe (nn,6).  Workspaces: gs (nt,), gz, zs (nn,),
    at, dt (nt,3) (tying-point tangent and director), xe (nn,12) (the element's x_o | x_n | U_o |
    U_n).  Every strain is formed in the displacement form of Eq. (3) (module docstring)."""
    nn = conn.shape[1]
    ngp = dN.shape[0]
    nt = alpha.shape[0]
    ce = conn[e]
    for i in range(nn):
        p = ce[i]
        for c in range(3):
            xe[i, c] = xo[p, c]
            xe[i, 3 + c] = xn[p, c]
        for c in range(6):
            xe[i, 6 + c] = U[p, c]
            fe[i, c] = 0.0
    energy = 0.0
    # ---- membrane and bending at the integration points
    for g in range(ngp):
        a1x = 0.0
        a1y = 0.0
        a1z = 0.0
        a2x = 0.0
        a2y = 0.0
        a2z = 0.0
        b1x = 0.0
        b1y = 0.0
        b1z = 0.0
        b2x = 0.0
        b2y = 0.0
        b2z = 0.0
        u1x = 0.0
        u1y = 0.0
        u1z = 0.0
        u2x = 0.0
        u2y = 0.0
        u2z = 0.0
        v1x = 0.0
        v1y = 0.0
        v1z = 0.0
        v2x = 0.0
        v2y = 0.0
        v2z = 0.0
        for i in range(nn):
            d1 = dN[g, i, 0]
            d2 = dN[g, i, 1]
            a1x += d1 * xe[i, 0]
            a1y += d1 * xe[i, 1]
            a1z += d1 * xe[i, 2]
            a2x += d2 * xe[i, 0]
            a2y += d2 * xe[i, 1]
            a2z += d2 * xe[i, 2]
            b1x += d1 * xe[i, 3]
            b1y += d1 * xe[i, 4]
            b1z += d1 * xe[i, 5]
            b2x += d2 * xe[i, 3]
            b2y += d2 * xe[i, 4]
            b2z += d2 * xe[i, 5]
            u1x += d1 * xe[i, 6]
            u1y += d1 * xe[i, 7]
            u1z += d1 * xe[i, 8]
            u2x += d2 * xe[i, 6]
            u2y += d2 * xe[i, 7]
            u2z += d2 * xe[i, 8]
            v1x += d1 * xe[i, 9]
            v1y += d1 * xe[i, 10]
            v1z += d1 * xe[i, 11]
            v2x += d2 * xe[i, 9]
            v2y += d2 * xe[i, 10]
            v2z += d2 * xe[i, 11]
        # displacement form: a.b - A.B = u.b + a.v - u.v with A = a - u, B = b - v
        e0 = u1x * (a1x - 0.5 * u1x) + u1y * (a1y - 0.5 * u1y) + u1z * (a1z - 0.5 * u1z)
        e1 = u2x * (a2x - 0.5 * u2x) + u2y * (a2y - 0.5 * u2y) + u2z * (a2z - 0.5 * u2z)
        e2 = u1x * (a2x - u2x) + u1y * (a2y - u2y) + u1z * (a2z - u2z) + a1x * u2x + a1y * u2y + a1z * u2z
        k0 = u1x * (b1x - v1x) + u1y * (b1y - v1y) + u1z * (b1z - v1z) + a1x * v1x + a1y * v1y + a1z * v1z
        k1 = u2x * (b2x - v2x) + u2y * (b2y - v2y) + u2z * (b2z - v2z) + a2x * v2x + a2y * v2y + a2z * v2z
        k2 = (
            u1x * (b2x - v2x)
            + u1y * (b2y - v2y)
            + u1z * (b2z - v2z)
            + a1x * v2x
            + a1y * v2y
            + a1z * v2z
            + u2x * (b1x - v1x)
            + u2y * (b1y - v1y)
            + u2z * (b1z - v1z)
            + a2x * v1x
            + a2y * v1y
            + a2z * v1z
        )
        C = Cmb[e, g]
        n0 = C[0, 0, 0] * e0 + C[0, 0, 1] * e1 + C[0, 0, 2] * e2
        n1 = C[0, 1, 0] * e0 + C[0, 1, 1] * e1 + C[0, 1, 2] * e2
        n2 = C[0, 2, 0] * e0 + C[0, 2, 1] * e1 + C[0, 2, 2] * e2
        m0 = C[1, 0, 0] * k0 + C[1, 0, 1] * k1 + C[1, 0, 2] * k2
        m1 = C[1, 1, 0] * k0 + C[1, 1, 1] * k1 + C[1, 1, 2] * k2
        m2 = C[1, 2, 0] * k0 + C[1, 2, 1] * k1 + C[1, 2, 2] * k2
        energy += 0.5 * (n0 * e0 + n1 * e1 + n2 * e2 + m0 * k0 + m1 * k1 + m2 * k2)
        # generalised forces on a1, a2, b1, b2
        p1x = n0 * a1x + n2 * a2x + m0 * b1x + m2 * b2x
        p1y = n0 * a1y + n2 * a2y + m0 * b1y + m2 * b2y
        p1z = n0 * a1z + n2 * a2z + m0 * b1z + m2 * b2z
        p2x = n1 * a2x + n2 * a1x + m1 * b2x + m2 * b1x
        p2y = n1 * a2y + n2 * a1y + m1 * b2y + m2 * b1y
        p2z = n1 * a2z + n2 * a1z + m1 * b2z + m2 * b1z
        q1x = m0 * a1x + m2 * a2x
        q1y = m0 * a1y + m2 * a2y
        q1z = m0 * a1z + m2 * a2z
        q2x = m1 * a2x + m2 * a1x
        q2y = m1 * a2y + m2 * a1y
        q2z = m1 * a2z + m2 * a1z
        for i in range(nn):
            d1 = dN[g, i, 0]
            d2 = dN[g, i, 1]
            fe[i, 0] += d1 * p1x + d2 * p2x
            fe[i, 1] += d1 * p1y + d2 * p2y
            fe[i, 2] += d1 * p1z + d2 * p2z
            fe[i, 3] += d1 * q1x + d2 * q2x
            fe[i, 4] += d1 * q1y + d2 * q2y
            fe[i, 5] += d1 * q1z + d2 * q2z
    # ---- ANS tying strains: transverse shear (Eq. 4 / Eq. 12-14), assumed membrane (quad4.py)
    for t in range(nt):
        oa = int(tie[t, 0])
        ob = int(tie[t, 1])
        s = 0.0
        for c in range(3):
            av = 0.0
            dv = 0.0
            au = 0.0
            du = 0.0
            for i in range(nn):
                av += alpha[t, i] * xe[i, oa + c]
                dv += beta[t, i] * xe[i, ob + c]
                au += alpha[t, i] * xe[i, 6 + oa + c]
                du += beta[t, i] * xe[i, 6 + ob + c]
            at[t, c] = av
            dt[t, c] = dv
            s += au * (dv - du) + av * du
        gs[t] = tie[t, 2] * s
    for t in range(nt):
        oa = int(tie[t, 0])
        ob = int(tie[t, 1])
        q = 0.0
        for u in range(nt):
            q += Cs[e, t, u] * gs[u]
        energy += 0.5 * q * gs[t]
        qt = q * tie[t, 2]
        for i in range(nn):
            qa = qt * alpha[t, i]
            qb = qt * beta[t, i]
            for c in range(3):
                fe[i, oa + c] += qa * dt[t, c]
                fe[i, ob + c] += qb * at[t, c]
    # ---- ANS thickness strain at the nodes (Eq. 5 / Eq. 15), Green or Eq. (24)
    for i in range(nn):
        if quasi:
            zs[i] = _sign_quasi(xo, xn, ce, nn, i, mu)
        gz[i] = _thickness_strain(xe, i, quasi, zs[i], r_z[e, i])
    for i in range(nn):
        q = 0.0
        for j in range(nn):
            q += Cz[e, i, j] * gz[j]
        energy += 0.5 * q * gz[i]
        if quasi:
            sc = q * zs[i] / np.sqrt(xe[i, 3] ** 2 + xe[i, 4] ** 2 + xe[i, 5] ** 2)
        else:
            sc = q
        for c in range(3):
            fe[i, 3 + c] += sc * xe[i, 3 + c]
    return energy


@njit(cache=True)
def _force_workspace(nn, nt):
    """Per-thread scratch of _element_force: gs (nt,), gz, zs (nn,), at, dt (nt,3), xe (nn,12)."""
    m = max(nt, 1)
    return np.empty(m), np.empty(nn), np.empty(nn), np.empty((m, 3)), np.empty((m, 3)), np.empty((nn, 12))


@njit(cache=True, parallel=True, fastmath=_FM_EXACT)
def energy_force(xo, xn, U, conn, dN, alpha, beta, tie, Cmb, Cs, Cz, r_z, quasi, mu, f_out, w_out, nth):
    """Element energies into w_out (M,) and element forces into f_out (M, nn, 6), all elements.

    xo, xn : (N,3) current nodal mid-surface positions and directors (X + U)
    U      : (N,6) the displacements [U_o | U_n] themselves: the strains are formed from them
             (displacement form of Eq. 3), so they keep their digits when U << X
    conn   : (M,nn) connectivity;  dN (ngp,nn,2), alpha/beta (nt,nn), tie (nt,3): the element
             type's constants (tie: see the module docstring)
    Cmb (M,ngp,2,3,3), Cs (M,nt,nt), Cz (M,nn,nn): folded rigidities;  r_z (M,nn): |X_n| at the
             nodes (used by the quasi-engineering thickness strain of Eq. 24 only)
    nth    : number of work chunks (numba threads); each chunk allocates its workspace once
    """
    M = conn.shape[0]
    nn = conn.shape[1]
    nt = alpha.shape[0]
    chunk = (M + nth - 1) // nth
    for th in prange(nth):
        gs, gz, zs, at, dt, xe = _force_workspace(nn, nt)
        for e in range(th * chunk, min(M, (th + 1) * chunk)):
            w_out[e] = _element_force(
                e, xo, xn, U, conn, dN, alpha, beta, tie, Cmb, Cs, Cz, r_z, quasi, mu, f_out[e], gs, gz, zs, at, dt, xe
            )


@njit(cache=True, inline="always")
def _row_end(a, nd, half):
    """Columns 0.._row_end-1 of row a are formed: all of them, or with ``half`` those left of and in
    a's node block (the block lower triangle, _element_tangent)."""
    return 6 * (a // 6) + 6 if half else nd


@njit(cache=True, fastmath=_FM_EXACT)
def _add_bt_d_gp(Ke, B, D, gp_membrane, half):
    """Ke[a, b] += B[r, a] D[r, b] for the strain rows r = 0..5 of one integration point, in that
    order for every entry (membrane rows only on U_o dofs and with gp_membrane; columns as
    _row_end): the material part of k_t, Eq. (9).  One pass over b forms three rows of Ke (a
    node's U_o or U_n dofs), each entry one chain of six or three terms: the loop overhead and the
    loads of D, not the flops, were the cost of one pass per row and strain row (six rows per
    pass measured 6 % slower than three: more runtime alias checks per pass).  Without
    reassociation (_FM_EXACT) each chain is summed exactly as the separate passes summed it."""
    nd = Ke.shape[1]
    for a in range(0, nd, 3):
        nb = _row_end(a, nd, half)
        x3 = B[3, a]
        y3 = B[3, a + 1]
        z3 = B[3, a + 2]
        x4 = B[4, a]
        y4 = B[4, a + 1]
        z4 = B[4, a + 2]
        x5 = B[5, a]
        y5 = B[5, a + 1]
        z5 = B[5, a + 2]
        if (a % 6) < 3 and gp_membrane:
            x0 = B[0, a]
            y0 = B[0, a + 1]
            z0 = B[0, a + 2]
            x1 = B[1, a]
            y1 = B[1, a + 1]
            z1 = B[1, a + 2]
            x2 = B[2, a]
            y2 = B[2, a + 1]
            z2 = B[2, a + 2]
            for b in range(nb):
                d0 = D[0, b]
                d1 = D[1, b]
                d2 = D[2, b]
                d3 = D[3, b]
                d4 = D[4, b]
                d5 = D[5, b]
                Ke[a, b] = (((((Ke[a, b] + x0 * d0) + x1 * d1) + x2 * d2) + x3 * d3) + x4 * d4) + x5 * d5
                Ke[a + 1, b] = (((((Ke[a + 1, b] + y0 * d0) + y1 * d1) + y2 * d2) + y3 * d3) + y4 * d4) + y5 * d5
                Ke[a + 2, b] = (((((Ke[a + 2, b] + z0 * d0) + z1 * d1) + z2 * d2) + z3 * d3) + z4 * d4) + z5 * d5
        else:  # the membrane rows vanish on director dofs (and everywhere without gp_membrane)
            for b in range(nb):
                d3 = D[3, b]
                d4 = D[4, b]
                d5 = D[5, b]
                Ke[a, b] = ((Ke[a, b] + x3 * d3) + x4 * d4) + x5 * d5
                Ke[a + 1, b] = ((Ke[a + 1, b] + y3 * d3) + y4 * d4) + y5 * d5
                Ke[a + 2, b] = ((Ke[a + 2, b] + z3 * d3) + z4 * d4) + z5 * d5


@njit(cache=True, fastmath=_FM_EXACT)
def _tying_d(D, B, Cs_e, nt):
    """D[t, b] = sum_u Cs_e[t, u] B[u, b] for the tying rows, the sum over u in order for every
    entry: one pass over b per (t, u) (vectorised over b) instead of a short sum per entry."""
    nd = D.shape[1]
    for t in range(nt):
        for b in range(nd):
            D[t, b] = 0.0
        for u in range(nt):
            c = Cs_e[t, u]
            for b in range(nd):
                D[t, b] = D[t, b] + c * B[u, b]


@njit(cache=True, fastmath=_FM_EXACT)
def _add_bt_d_tying(Ke, B, D, nt, half, tk):
    """Ke[a, b] += B[t, a] D[t, b] for the tying rows t = 0..nt-1 in that order (columns as
    _row_end), three rows of Ke and one tying row per pass (_add_bt_d_gp says why).  A tying
    strain involves the nodes of its point's edge only, so for about half of the tying rows B[t, .]
    is zero on all three: those are left out (adding 0 * D[t, b] leaves a finite entry as it is).
    ``tk`` (nt,) int scratch."""
    nd = Ke.shape[1]
    for a in range(0, nd, 3):
        nb = _row_end(a, nd, half)
        n = 0
        for t in range(nt):
            if B[t, a] != 0.0 or B[t, a + 1] != 0.0 or B[t, a + 2] != 0.0:
                tk[n] = t
                n += 1
        for p in range(n):
            t = tk[p]
            x = B[t, a]
            y = B[t, a + 1]
            z = B[t, a + 2]
            for b in range(nb):
                d = D[t, b]
                Ke[a, b] = Ke[a, b] + x * d
                Ke[a + 1, b] = Ke[a + 1, b] + y * d
                Ke[a + 2, b] = Ke[a + 2, b] + z * d


@njit(cache=True, fastmath=_FM_EXACT, error_model="numpy")
def _element_tangent(
    e,
    xo,
    xn,
    conn,
    dN,
    alpha,
    beta,
    tie,
    Cmb,
    Cs,
    Cz,
    r_z,
    quasi,
    mu,
    gp_membrane,
    slot,
    half,
    Ke,
    B,
    D,
    oo,
    on,
    nz,
    gs,
    gz,
    zs,
    at,
    dt,
    v4,
    xe,
    tk,
):
    """Tangent k_t of Eq. (9) of element e into Ke (nd,nd), nd = 6 nn, its dofs in the node order
    ``slot`` (local node i's dofs are 6 slot[i] + c: U_o then U_n).

    ``half`` True: only the block lower triangle is formed, the columns left of and in row a's node
    block (_row_end), with the nodes in decreasing global order (``slot`` from half_slots): there
    it holds every entry whose global column is >= its global row, i.e. one triangle of the
    assembled (symmetric) matrix, the one a solver that stores one triangle needs.  The material
    sums B^T D, the bulk of the cost, are skipped elsewhere; the entries written there (geometric
    and thickness terms) are not meaningful.  Every formed entry is the same floating-point
    expression, summed in the same order, in both forms: the half matrix equals the whole one's
    entries to the last bit.

    ``xe`` (nn,12) [x_o | x_n | U_o | U_n], the tying values ``gs``, ``at``, ``dt`` and the nodal
    thickness strains ``gz`` (with the signs ``zs`` of Eq. 24) must be as _element_force leaves them
    for this element (force_tangent calls it first).  ``gp_membrane`` False: the
    membrane rigidity at the integration points is zero (assumed membrane strains at tying points
    instead), so those B rows are skipped.
    Material part sum B^T C B over the strain rows (membrane+bending per point, then shear tying,
    then nodal thickness); geometric part sum sigma * d2(strain) as multiples of I3 between nodal
    vectors.  Row-major axpy loops (inner loop over contiguous columns) so that LLVM vectorises.
    """
    nn = conn.shape[1]
    ngp = dN.shape[0]
    nt = alpha.shape[0]
    nd = 6 * nn
    conn[e]
    for a in range(nd):
        for b in range(nd):
            Ke[a, b] = 0.0
    for i in range(nn):
        for j in range(nn):
            oo[i, j] = 0.0
            on[i, j] = 0.0
        for c in range(3):
            for d in range(3):
                nz[i, c, d] = 0.0
    a1 = v4[0]
    a2 = v4[1]
    b1 = v4[2]
    b2 = v4[3]
    st = v4[4]
    sig = v4[5]
    u1 = v4[6]
    u2 = v4[7]
    w1 = v4[8]
    w2 = v4[9]
    for g in range(ngp):
        for c in range(3):
            a1[c] = 0.0
            a2[c] = 0.0
            b1[c] = 0.0
            b2[c] = 0.0
            u1[c] = 0.0
            u2[c] = 0.0
            w1[c] = 0.0
            w2[c] = 0.0
        for i in range(nn):
            for c in range(3):
                a1[c] += dN[g, i, 0] * xe[i, c]
                a2[c] += dN[g, i, 1] * xe[i, c]
                b1[c] += dN[g, i, 0] * xe[i, 3 + c]
                b2[c] += dN[g, i, 1] * xe[i, 3 + c]
                u1[c] += dN[g, i, 0] * xe[i, 6 + c]
                u2[c] += dN[g, i, 1] * xe[i, 6 + c]
                w1[c] += dN[g, i, 0] * xe[i, 9 + c]
                w2[c] += dN[g, i, 1] * xe[i, 9 + c]
        # the strains in displacement form, exactly as _element_force forms them
        for r in range(6):
            st[r] = 0.0
        for c in range(3):
            st[0] += u1[c] * (a1[c] - 0.5 * u1[c])
            st[1] += u2[c] * (a2[c] - 0.5 * u2[c])
            st[2] += u1[c] * (a2[c] - u2[c]) + a1[c] * u2[c]
            st[3] += u1[c] * (b1[c] - w1[c]) + a1[c] * w1[c]
            st[4] += u2[c] * (b2[c] - w2[c]) + a2[c] * w2[c]
            st[5] += u1[c] * (b2[c] - w2[c]) + a1[c] * w2[c] + u2[c] * (b1[c] - w1[c]) + a2[c] * w1[c]
        for r in range(3):
            sig[r] = Cmb[e, g, 0, r, 0] * st[0] + Cmb[e, g, 0, r, 1] * st[1] + Cmb[e, g, 0, r, 2] * st[2]
            sig[3 + r] = Cmb[e, g, 1, r, 0] * st[3] + Cmb[e, g, 1, r, 1] * st[4] + Cmb[e, g, 1, r, 2] * st[5]
        # B rows (e11, e22, e12, k11, k22, k12) over the element dofs
        for i in range(nn):
            d1 = dN[g, i, 0]
            d2 = dN[g, i, 1]
            o = 6 * slot[i]
            for c in range(3):
                B[0, o + c] = d1 * a1[c]
                B[1, o + c] = d2 * a2[c]
                B[2, o + c] = d1 * a2[c] + d2 * a1[c]
                B[0, o + 3 + c] = 0.0
                B[1, o + 3 + c] = 0.0
                B[2, o + 3 + c] = 0.0
                B[3, o + c] = d1 * b1[c]
                B[3, o + 3 + c] = d1 * a1[c]
                B[4, o + c] = d2 * b2[c]
                B[4, o + 3 + c] = d2 * a2[c]
                B[5, o + c] = d1 * b2[c] + d2 * b1[c]
                B[5, o + 3 + c] = d2 * a1[c] + d1 * a2[c]
        for r in range(3):
            c0 = Cmb[e, g, 0, r, 0]
            c1 = Cmb[e, g, 0, r, 1]
            c2 = Cmb[e, g, 0, r, 2]
            k0 = Cmb[e, g, 1, r, 0]
            k1 = Cmb[e, g, 1, r, 1]
            k2 = Cmb[e, g, 1, r, 2]
            for b in range(nd):
                D[r, b] = c0 * B[0, b] + c1 * B[1, b] + c2 * B[2, b]
                D[3 + r, b] = k0 * B[3, b] + k1 * B[4, b] + k2 * B[5, b]
        _add_bt_d_gp(Ke, B, D, gp_membrane, half)
        for i in range(nn):
            di1 = dN[g, i, 0]
            di2 = dN[g, i, 1]
            for j in range(nn):
                dj1 = dN[g, j, 0]
                dj2 = dN[g, j, 1]
                oo[i, j] += sig[0] * di1 * dj1 + sig[1] * di2 * dj2 + sig[2] * (di1 * dj2 + di2 * dj1)
                on[i, j] += sig[3] * di1 * dj1 + sig[4] * di2 * dj2 + sig[5] * (di1 * dj2 + di2 * dj1)
    # tying strains (gs, at, dt as the force pass left them); rows of B reused for them
    for t in range(nt):
        oa = int(tie[t, 0])
        ob = int(tie[t, 1])
        ct = tie[t, 2]
        for b in range(nd):
            B[t, b] = 0.0
        for i in range(nn):
            o = 6 * slot[i]
            for c in range(3):
                B[t, o + oa + c] += ct * alpha[t, i] * dt[t, c]
                B[t, o + ob + c] += ct * beta[t, i] * at[t, c]
    for t in range(nt):
        q = 0.0
        for u in range(nt):
            q += Cs[e, t, u] * gs[u]
        qt = q * tie[t, 2]
        if tie[t, 1] > tie[t, 0]:  # x_o . x_n product: a U_o-U_n block
            for i in range(nn):
                for j in range(nn):
                    on[i, j] += qt * alpha[t, i] * beta[t, j]
        else:  # x_o . x_o product: a symmetric U_o-U_o block
            for i in range(nn):
                for j in range(nn):
                    oo[i, j] += qt * (alpha[t, i] * beta[t, j] + beta[t, i] * alpha[t, j])
    _tying_d(D, B, Cs[e], nt)
    _add_bt_d_tying(Ke, B, D, nt, half, tk)
    # thickness strains at the nodes: d eps_i / d x_ni = w_i x_ni (w_i = 1 Green, s_i/|x_ni| Eq. 24)
    for i in range(nn):
        if quasi:
            zs[i] = zs[i] / np.sqrt(xe[i, 3] ** 2 + xe[i, 4] ** 2 + xe[i, 5] ** 2)
        else:
            zs[i] = 1.0
    for i in range(nn):
        q = 0.0
        for j in range(nn):
            q += Cz[e, i, j] * gz[j]
        if quasi:
            ln2 = xe[i, 3] ** 2 + xe[i, 4] ** 2 + xe[i, 5] ** 2
            for c in range(3):
                for d in range(3):
                    nz[i, c, d] += q * zs[i] * ((1.0 if c == d else 0.0) - xe[i, 3 + c] * xe[i, 3 + d] / ln2)
        else:
            for c in range(3):
                nz[i, c, c] += q
        oi = 6 * slot[i] + 3
        for j in range(nn):
            oj = 6 * slot[j] + 3
            cij = Cz[e, i, j] * zs[i] * zs[j]
            for c in range(3):
                for d in range(3):
                    Ke[oi + c, oj + d] += cij * xe[i, 3 + c] * xe[j, 3 + d]
    # geometric blocks
    for i in range(nn):
        oi = 6 * slot[i]
        for j in range(nn):
            oj = 6 * slot[j]
            for c in range(3):
                Ke[oi + c, oj + c] += oo[i, j]
                Ke[oi + c, oj + 3 + c] += on[i, j]
                Ke[oj + 3 + c, oi + c] += on[i, j]
        for c in range(3):
            for d in range(3):
                Ke[oi + 3 + c, oi + 3 + d] += nz[i, c, d]


@njit(cache=True)
def _tangent_workspace(nn, nt):
    """Per-thread scratch of _element_tangent: B, D (max(6, nt), nd), oo, on (nn,nn), nz (nn,3,3),
    v4 (10,6) (the vectors a_k, b_k, u_k, w_k of a point, its strains and stresses), tk (max(6, nt),)
    int (_add_bt_d_tying)."""
    nd = 6 * nn
    m = max(6, nt)
    return (
        np.empty((m, nd)),
        np.empty((m, nd)),
        np.empty((nn, nn)),
        np.empty((nn, nn)),
        np.empty((nn, 3, 3)),
        np.empty((10, 6)),
        np.empty(m, dtype=np.int64),
    )


@njit(cache=True, parallel=True, fastmath=_FM_EXACT)
def force_tangent(
    xo,
    xn,
    U,
    conn,
    dN,
    alpha,
    beta,
    tie,
    Cmb,
    Cs,
    Cz,
    r_z,
    quasi,
    mu,
    gp_membrane,
    f_out,
    w_out,
    K_out,
    nth,
    half=False,
):
    """Energies, forces (M,nn,6) and tangents (M,nd,nd) of all elements.  ``gp_membrane``: some
    membrane rigidity sits at the integration points (False when all of it is in the tying terms).

    ``half`` False: each tangent whole and in the local node order.  True: half tangents, each
    element's nodes in decreasing global order (half_slots) and only the block lower triangle
    formed (_element_tangent), which holds the entries of k_t (Eq. 9) whose global column dof is
    >= their global row dof (half_entries), one triangle of the assembled matrix.  Those entries
    have the same bits as in the whole matrices; about 60 % of the material part's flops."""
    M = conn.shape[0]
    nn = conn.shape[1]
    nt = alpha.shape[0]
    chunk = (M + nth - 1) // nth
    for th in prange(nth):
        B, D, oo, on, nz, v4, tk = _tangent_workspace(nn, nt)
        gs, gz, zs, at, dt, xe = _force_workspace(nn, nt)
        slot = np.arange(nn)
        for e in range(th * chunk, min(M, (th + 1) * chunk)):
            w_out[e] = _element_force(
                e, xo, xn, U, conn, dN, alpha, beta, tie, Cmb, Cs, Cz, r_z, quasi, mu, f_out[e], gs, gz, zs, at, dt, xe
            )
            if half:
                half_slots(conn[e], slot)
            _element_tangent(
                e,
                xo,
                xn,
                conn,
                dN,
                alpha,
                beta,
                tie,
                Cmb,
                Cs,
                Cz,
                r_z,
                quasi,
                mu,
                gp_membrane,
                slot,
                half,
                K_out[e],
                B,
                D,
                oo,
                on,
                nz,
                gs,
                gz,
                zs,
                at,
                dt,
                v4,
                xe,
                tk,
            )


@njit(cache=True)
def half_slots(conn_e, slot):
    """slot[i] = the number of the element's nodes with a greater global number than local node i
    (nodes distinct): the node order of the half element matrix (force_tangent with ``half``)."""
    nn = conn_e.size
    for i in range(nn):
        k = 0
        for j in range(nn):
            if conn_e[j] > conn_e[i]:
                k += 1
        slot[i] = k


def half_entries(nn):
    """(rows, columns) of the entries of a half element matrix (force_tangent with ``half``) that hold one
    triangle of the assembled matrix, row by row: in row a, the columns of the node blocks left
    of a's, then b >= a in a's own block.  nd(nd+1)/2 entries, nd = 6 nn."""
    nd = 6 * nn
    rows, cols = [], []
    for a in range(nd):
        s = 6 * (a // 6)
        b = list(range(s)) + list(range(a, s + 6))
        rows += [a] * len(b)
        cols += b
    return np.array(rows, dtype=np.int64), np.array(cols, dtype=np.int64)
