"""3-node triangular ANS solid-shell element (Section 2.2, Eqs. 10-15).

Area coordinates r = 1 - s - t, s, t (N_1 = r, N_2 = s, N_3 = t).  Membrane and bending strains are
constant over the element (linear interpolation), the Jacobian J_o varies with the director and is
integrated by the three-point rule.  Transverse shear: the tangential shears at the mid-points of
edges 3-1 (d_r), 1-2 (d_s), 2-3 (d_t) (Eq. 12, with the mid-surface tangents as DESIGN.md reads it),
turned into Cartesian shears at each node from the two edges meeting there (Eq. 13) and interpolated
linearly (Eq. 14).  Thickness strain from the three nodes (Eq. 15).
"""

from __future__ import annotations

import numpy as np

from .frames import covariant_maps, fold, local_frame

NN = 3
DN = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])  # dN_i/d(s,t)
DN_GP = DN[None]  # one membrane/bending point
# three-point rule (area coordinates r, s, t) with weights summing to the reference area 1/2
GAUSS_RST = np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])
GAUSS_W = np.full(3, 1.0 / 6.0)
# tying points: mid-edge 3-1 with d_r = x1 - x3;  1-2 with d_s = x2 - x1;  2-3 with d_t = x3 - x2
ALPHA = np.array([[1.0, 0.0, -1.0], [-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]])
BETA = np.array([[0.5, 0.0, 0.5], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5]])
TIE = np.array([[0.0, 3.0, 1.0]] * 3)  # shear: (x_o, x_n) products, c_t = 1 (core.py)
# at node 1 the edges r, s meet; at node 2: s, t; at node 3: t, r  (Eq. 13)
_PAIRS = ((0, 1), (1, 2), (2, 0))


def _dot(u, v):
    return np.sum(u * v, -1)


def _bending_raw(a1, a2, b1, b2):
    """(M,3) raw natural bending strains (columns 3-5 of raw_strains' mb) from the edge vectors."""
    return np.stack([_dot(a1, b1), _dot(a2, b2), _dot(a1, b2) + _dot(a2, b1)], -1)


def raw_strains(xo, xn):
    """Raw natural strains for (M,3,3) nodal positions/directors: (M,1,6), (M,3), (M,3)."""
    a1 = xo[:, 1] - xo[:, 0]
    a2 = xo[:, 2] - xo[:, 0]
    b1 = xn[:, 1] - xn[:, 0]
    b2 = xn[:, 2] - xn[:, 0]
    mb = np.concatenate(
        [np.stack([0.5 * _dot(a1, a1), 0.5 * _dot(a2, a2), _dot(a1, a2)], -1), _bending_raw(a1, a2, b1, b2)], -1
    )[:, None, :]
    s = _dot(np.einsum("ti,mic->mtc", ALPHA, xo), np.einsum("ti,mic->mtc", BETA, xn))
    z = 0.5 * _dot(xn, xn)
    return mb, s, z


def bending_raw_strains(xo, xn):
    """(M,1,3) the bending part of raw_strains' mb alone (the adaptivity criterion's per-pass
    curvature, Eq. 25), the same floating-point operations."""
    return _bending_raw(xo[:, 1] - xo[:, 0], xo[:, 2] - xo[:, 0], xn[:, 1] - xn[:, 0], xn[:, 2] - xn[:, 0])[:, None, :]


def shear_map(Xo, ex, ey):
    """(M,3,2,3): the Cartesian transverse shears (gamma_zx, gamma_zy) at the three Gauss points
    from the three tying values (Eqs. 13-14) of triangles with initial positions Xo (M,3,3) in the
    local frame (ex, ey) (M,3)."""
    M = len(Xo)
    # Eq. (13): Cartesian shear at node k from the two tying values of the edges meeting there
    d = np.einsum("ti,mic->mtc", ALPHA, Xo)  # edge tangents d_r, d_s, d_t
    dl = np.stack([np.sum(d * ex[:, None], -1), np.sum(d * ey[:, None], -1)], -1)  # (M,3,2)
    G = np.zeros((M, 3, 2, 3))  # node k: (2 x 3 tying values)
    for k, (p, q) in enumerate(_PAIRS):  # three fixed nodes, not a mesh loop
        Mk = np.stack([dl[:, p], dl[:, q]], 1)  # rows: the two edge tangents
        inv = np.linalg.inv(Mk)
        G[:, k, :, p] += inv[:, :, 0]
        G[:, k, :, q] += inv[:, :, 1]
    return np.einsum("gk,mkat->mgat", GAUSS_RST, G)  # Eq. (14) at the Gauss points


def precompute(Xo, Xn, C_m, C_b, C_t, E_z, warp_angle, membrane="full"):
    """Fold Eqs. (6)-(8), (13)-(14) into per-element constants for triangles, initial (M,3,3) Xo, Xn.

    ``membrane`` is accepted for symmetry with quad4 and ignored: the linear triangle's membrane
    strain is constant and depends only on its edge lengths, so it has no membrane locking to cure."""
    A1 = Xo[:, 1] - Xo[:, 0]
    A2 = Xo[:, 2] - Xo[:, 0]
    Xn_g = np.einsum("gi,mic->mgc", GAUSS_RST, Xn)
    J = np.einsum("mc,mgc->mg", np.cross(A1, A2), Xn_g)  # J_o at the three points
    if np.any(J <= 0):
        raise ValueError("a triangle has a non-positive Jacobian J_o (inverted or director flipped)")
    Jw = J * GAUSS_W
    ex, ey, _ = local_frame(A1, A2, warp_angle)
    _, T = covariant_maps(A1, A2, ex, ey)
    Jsum = Jw.sum(1)
    Cmb = np.stack([fold(T, C_m, Jsum), fold(T, C_b, Jsum)], axis=1)[:, None]  # (M,1,2,3,3)
    Gg = shear_map(Xo, ex, ey)
    Cs = np.einsum("mgat,ab,mgbu,mg->mtu", Gg, C_t, Gg, Jw)
    Cz = E_z * np.einsum("gi,gj,mg->mij", GAUSS_RST, GAUSS_RST, Jw)
    r_mb, r_s, r_z = raw_strains(Xo, Xn)
    return dict(
        Cmb=np.ascontiguousarray(Cmb),
        Cs=Cs,
        Cz=Cz,
        r_mb=r_mb,
        r_s=r_s,
        r_z=r_z,
        T=T[:, None],
        J=J,
        alpha=ALPHA,
        beta=BETA,
        tie=TIE,
    )


def nodal_areas(Xo, Xn):
    """(M,3) area shares of the nodes by the vertex (trapezoidal) rule, J_o(node) x weight 1/6."""
    n = np.cross(Xo[:, 1] - Xo[:, 0], Xo[:, 2] - Xo[:, 0])
    return np.einsum("mc,mpc->mp", n, Xn) / 6.0
