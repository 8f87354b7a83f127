"""4-node quadrilateral ANS solid-shell element (Section 2.1, Eqs. 1-9).

Natural coordinates (xi, eta) in [-1, 1]^2, nodes counter-clockwise, 2x2 Gauss rule for membrane,
bending, shear and thickness energies; ANS transverse shear from the edge mid-points
(xi, eta) = (0, -1), (0, +1) for gamma_z,xi and (-1, 0), (+1, 0) for gamma_z,eta (Eq. 4); ANS
thickness strain from the four nodes (Eq. 5).
"""

from __future__ import annotations

import numpy as np

from .frames import covariant_maps, fold, local_frame

NN = 4
XI = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
_G = 1.0 / np.sqrt(3.0)
GAUSS = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])
GAUSS_W = np.ones(4)


def shape(xi, eta):
    """N_i (Eq. 1) and dN_i/d(xi, eta) at one point: (4,), (4,2)."""
    N = 0.25 * (1 + XI[:, 0] * xi) * (1 + XI[:, 1] * eta)
    dN = np.stack([0.25 * XI[:, 0] * (1 + XI[:, 1] * eta), 0.25 * XI[:, 1] * (1 + XI[:, 0] * xi)], -1)
    return N, dN


N_GP = np.array([shape(*p)[0] for p in GAUSS])          # (4 gp, 4 nodes)
DN_GP = np.array([shape(*p)[1] for p in GAUSS])         # (4 gp, 4 nodes, 2)
# tying points A (0,-1), C (0,+1) for gamma_z,xi;  B (-1,0), D (+1,0) for gamma_z,eta
_TY = [((0.0, -1.0), 0), ((0.0, 1.0), 0), ((-1.0, 0.0), 1), ((1.0, 0.0), 1)]
ALPHA = np.array([shape(*p)[1][:, k] for p, k in _TY])  # d/d(xi or eta) of x_o at the tying point
BETA = np.array([shape(*p)[0] for p, _ in _TY])         # x_n interpolated at the tying point


def _shear_interp(xi, eta):
    """(2,4): natural (gamma_z,xi, gamma_z,eta) at (xi, eta) from the 4 tying values (Eq. 4)."""
    return np.array([[0.5 * (1 - eta), 0.5 * (1 + eta), 0.0, 0.0],
                     [0.0, 0.0, 0.5 * (1 - xi), 0.5 * (1 + xi)]])


S_GP = np.array([_shear_interp(*p) for p in GAUSS])     # (4 gp, 2, 4)


def raw_strains(xo, xn):
    """Raw natural strains of elements with nodal (M,4,3) positions/directors: (M,4,6), (M,4), (M,4).
    The same products the kernel forms (core.py); used here for the reference state."""
    a = np.einsum("gik,mic->mgkc", DN_GP, xo)
    b = np.einsum("gik,mic->mgkc", DN_GP, xn)
    dot = lambda u, v: np.sum(u * v, -1)
    mb = np.stack([0.5 * dot(a[:, :, 0], a[:, :, 0]), 0.5 * dot(a[:, :, 1], a[:, :, 1]),
                   dot(a[:, :, 0], a[:, :, 1]), dot(a[:, :, 0], b[:, :, 0]), dot(a[:, :, 1], b[:, :, 1]),
                   dot(a[:, :, 0], b[:, :, 1]) + dot(a[:, :, 1], b[:, :, 0])], -1)
    s = dot(np.einsum("ti,mic->mtc", ALPHA, xo), np.einsum("ti,mic->mtc", BETA, xn))
    z = 0.5 * dot(xn, xn)
    return mb, s, z


def precompute(Xo, Xn, C_m, C_b, C_t, E_z, warp_angle):
    """Fold Eqs. (6)-(8) into per-element constants for quads with initial nodal (M,4,3) Xo, Xn.

    Returns dict(Cmb (M,4,2,3,3), Cs (M,4,4), Cz (M,4,4), r_mb, r_s, r_z, T (M,4,3,3), J (M,4)).
    """
    A1 = np.einsum("gi,mic->mgc", DN_GP[:, :, 0], Xo)
    A2 = np.einsum("gi,mic->mgc", DN_GP[:, :, 1], Xo)
    Xn_g = np.einsum("gi,mic->mgc", N_GP, Xn)
    J = np.einsum("mgc,mgc->mg", np.cross(A1, A2), Xn_g)        # Eq. (8)
    if np.any(J <= 0):
        raise ValueError("a quadrilateral has a non-positive Jacobian J_o (inverted or director flipped)")
    ex, ey, _ = local_frame(A1, A2, warp_angle)
    Q, T = covariant_maps(A1, A2, ex, ey)
    Jw = J * GAUSS_W
    Cmb = np.stack([fold(T, C_m, Jw), fold(T, C_b, Jw)], axis=2)
    QS = np.einsum("mgab,gbt->mgat", Q, S_GP)                  # local shear from tying values
    Cs = np.einsum("mgat,ab,mgbu,mg->mtu", QS, C_t, QS, Jw)
    Cz = E_z * np.einsum("gi,gj,mg->mij", N_GP, N_GP, Jw)
    r_mb, r_s, r_z = raw_strains(Xo, Xn)
    return dict(Cmb=np.ascontiguousarray(Cmb), Cs=Cs, Cz=Cz, r_mb=r_mb, r_s=r_s, r_z=r_z, T=T, J=J)


def nodal_areas(Xo, Xn):
    """(M,4) area shares of the nodes by the trapezoidal (nodal) rule, J_o(node) x weight 1 (Section 4)."""
    dN = np.array([shape(*p)[1] for p in XI])                     # (4 nodes as points, 4, 2)
    A1 = np.einsum("pi,mic->mpc", dN[:, :, 0], Xo)
    A2 = np.einsum("pi,mic->mpc", dN[:, :, 1], Xo)
    return np.einsum("mpc,mpc->mp", np.cross(A1, A2), Xn)
