"""4-node quadrilateral ANS solid-shell element (Section 2.1, Eqs. 1-9).

Natural coordinates (xi, eta) in [-1, 1]^2, nodes counter-clockwise, 2x2 Gauss rule for membrane,
bending, shear and thickness energies; ANS transverse shear from the edge mid-points
(xi, eta) = (0, -1), (0, +1) for gamma_z,xi and (-1, 0), (+1, 0) for gamma_z,eta (Eq. 4); ANS
thickness strain from the four nodes (Eq. 5).

Membrane strains (``membrane=``):

``"full"``  the compatible Green membrane strains at the 2x2 Gauss points (the paper's element).
    When a flat bilinear element is bent into a fold, its interior points stretch although its
    edges and diagonals keep their lengths, and with a fabric's tensile rigidity ~1e4 times its
    bending rigidity (per cm^2) that parasitic membrane energy stiffens coarse meshes markedly
    ("membrane locking"): square-pedestal DC 0.679 / 0.596 / 0.562 on 24x8x4 / 48x16x4 / 96x32x4.
``"ans"``  an assumed membrane strain field, in a Cartesian frame at the element centre (x along
    a_xi):  eps_xx = e1 + b4 (eta - eta_c),  eps_yy = e2 + b5 (xi - xi_c),  gamma_xy = e3  (the field
    of Pian & Sumihara's membrane element).  (e1, e2, e3) is the J_o-weighted mean of the compatible
    strains at the four Gauss points and (eta_c, xi_c) the J_o-weighted centroid, so the field has
    the compatible mean: a constant stress does the same work on it as on the compatible strains and
    the membrane patch test holds on any quadrilateral, in its energy and its equilibrium form.  b4,
    b5 -- the in-plane bending strains -- come from five tying strains: the stretches of the two
    xi-edges and the two eta-edges at their mid-points and the shear a_xi . a_eta at the centre,
    which a Cartesian field (e, b4, b5) must reproduce (a 5x5 solve per element, done once).  The
    bilinear element's parasitic in-plane shear (gamma_xy linear in xi and eta) is gone: in-plane
    bending of a rectangle is exact for nu = 0 (MacNeal-Harder in-plane beam 0.093 -> 0.904 of the
    reference at nu = 0.3; the rest is eps_yy not following -nu eps_xx).  By MacNeal's theorem an
    element that passes the patch test must lock for some distortion: the trapezoidal MacNeal-Harder
    beam gives 0.044 (full: 0.026).  The field has five independent parameters, so there is no
    spurious zero-energy mode.  All of this is beyond the paper, whose quadrilateral integrates the
    compatible membrane strains by the 2x2 rule; ``"full"`` stays the default.
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
TIE = np.array([[0.0, 3.0, 1.0]] * 4)                  # shear: (x_o, x_n) products, c_t = 1 (core.py)

# the five tying strains of the assumed membrane field: (point, derivative of the first factor, of
# the second, c_t, natural strain row): stretches of the xi-edges, of the eta-edges, centre shear
_MTY = [((0.0, -1.0), 0, 0, 0.5, 0), ((0.0, 1.0), 0, 0, 0.5, 0),
        ((-1.0, 0.0), 1, 1, 0.5, 1), ((1.0, 0.0), 1, 1, 0.5, 1), ((0.0, 0.0), 0, 1, 1.0, 2)]
# the compatible membrane strains at the Gauss points as tying terms: a1.a1/2, a2.a2/2, a1.a2
_GPM = [(g, k, l, c) for g in range(4) for k, l, c in ((0, 0, 0.5), (1, 1, 0.5), (0, 1, 1.0))]
M_ALPHA = np.array([DN_GP[g, :, k] for g, k, _, _ in _GPM] + [shape(*p)[1][:, k] for p, k, _, _, _ in _MTY])
M_BETA = np.array([DN_GP[g, :, l] for g, _, l, _ in _GPM] + [shape(*p)[1][:, l] for p, _, l, _, _ in _MTY])
M_TIE = np.array([[0.0, 0.0, c] for *_, c in _GPM] + [[0.0, 0.0, c] for _, _, _, c, _ in _MTY])
MEMBRANES = ("full", "ans")


def _assumed_field(xi, eta):
    """(3,5): Cartesian (eps_xx, eps_yy, gamma_xy) at (xi, eta) from the five parameters b."""
    return np.array([[1.0, 0.0, 0.0, eta, 0.0], [0.0, 1.0, 0.0, 0.0, xi], [0.0, 0.0, 1.0, 0.0, 0.0]])


def _cartesian_to_natural(Xo, p, ex, ey):
    """(M,3,3): natural raw membrane strains (a1.a1/2, a2.a2/2, a1.a2 minus reference) at the point
    p = (xi, eta) of a Cartesian strain (eps_xx, eps_yy, gamma_xy) in the frame (ex, ey) (M,3)."""
    dN = shape(*p)[1]
    A = [np.einsum("i,mic->mc", dN[:, k], Xo) for k in (0, 1)]
    g = [np.stack([np.sum(a * ex, -1), np.sum(a * ey, -1)], -1) for a in A]     # (M,2) each
    (g1x, g1y), (g2x, g2y) = (g[0][:, 0], g[0][:, 1]), (g[1][:, 0], g[1][:, 1])
    return np.stack([np.stack([g1x * g1x, g1y * g1y, g1x * g1y], -1),
                     np.stack([g2x * g2x, g2y * g2y, g2x * g2y], -1),
                     np.stack([2 * g1x * g2x, 2 * g1y * g2y, g1x * g2y + g1y * g2x], -1)], -2)


def tying_raw(alpha, beta, tie, xo, xn):
    """(M,nt) raw tying strains c_t (alpha_t . y)(beta_t . z) of (M,4,3) positions/directors."""
    y = np.stack([xo, xn])                                   # offset 0 -> x_o, 3 -> x_n
    ia = (tie[:, 0] // 3).astype(int)
    ib = (tie[:, 1] // 3).astype(int)
    a = np.einsum("ti,tmic->mtc", alpha, y[ia])
    b = np.einsum("ti,tmic->mtc", beta, y[ib])
    return tie[:, 2] * np.sum(a * b, -1)


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


def _assumed_membrane(Xo, Cm_gp, Jw):
    """(M,17,17): rigidity of the assumed membrane field (module docstring) on its 17 raw strains
    (M_ALPHA/M_BETA/M_TIE: 12 compatible ones at the Gauss points, then the 5 tying strains), from
    the natural-strain rigidities Cm_gp (M,4,3,3) = T^T C_m T J_o w at the Gauss points."""
    M = len(Xo)
    A1c = np.einsum("i,mic->mc", shape(0.0, 0.0)[1][:, 0], Xo)
    A2c = np.einsum("i,mic->mc", shape(0.0, 0.0)[1][:, 1], Xo)
    ex0 = A1c / np.linalg.norm(A1c, axis=-1, keepdims=True)
    ez0 = np.cross(A1c, A2c)
    ey0 = np.cross(ez0 / np.linalg.norm(ez0, axis=-1, keepdims=True), ex0)
    W = np.stack([_cartesian_to_natural(Xo, p, ex0, ey0) for p in GAUSS], 1)     # (M,4,3,3)
    area = Jw.sum(1)
    xi_c = Jw @ GAUSS[:, 0] / area
    eta_c = Jw @ GAUSS[:, 1] / area
    # tying strain t of a field (e, b4, b5): row r_t of the natural strains at its point
    Mt = np.stack([np.einsum("ma,ab->mb", _cartesian_to_natural(Xo, p, ex0, ey0)[:, r],
                             _assumed_field(*p)) for p, _, _, _, r in _MTY], 1)      # (M,5,5)
    b45 = np.linalg.inv(Mt)[:, 3:]                               # (M,2,5): b4, b5 from the tying
    mean = np.zeros((M, 3, 17))                                  # (e1, e2, e3) from the 12 gp strains
    Winv = np.linalg.inv(W)
    for g in range(4):                                           # the four Gauss points
        mean[:, :, 3 * g:3 * g + 3] = (Jw[:, g] / area)[:, None, None] * Winv[:, g]
    S = np.empty((M, 4, 3, 17))                                  # natural strains at gp g
    for g, (xg, eg) in enumerate(GAUSS):
        E = mean.copy()
        E[:, 0, 12:] += (eg - eta_c)[:, None] * b45[:, 0]
        E[:, 1, 12:] += (xg - xi_c)[:, None] * b45[:, 1]
        S[:, g] = np.einsum("mab,mbt->mat", W[:, g], E)
    return np.einsum("mgat,mgab,mgbu->mtu", S, Cm_gp, S)


def precompute(Xo, Xn, C_m, C_b, C_t, E_z, warp_angle, membrane="full"):
    """Fold Eqs. (6)-(8) into per-element constants for quads with initial nodal (M,4,3) Xo, Xn.

    membrane : "full" (compatible strains at the Gauss points) or "ans" (assumed membrane strains,
        see the module docstring: their rigidity moves from Cmb into the tying block of Cs).
    Returns dict(Cmb (M,4,2,3,3), Cs (M,nt,nt), Cz (M,4,4), r_mb, r_s, r_z, T (M,4,3,3), J (M,4),
    alpha, beta (nt,4), tie (nt,3)) with nt = 4 ("full") or 21 ("ans").
    """
    if membrane not in MEMBRANES:
        raise ValueError(f"membrane must be one of {MEMBRANES}, got {membrane!r}")
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
    alpha, beta, tie = ALPHA, BETA, TIE
    if membrane == "ans":
        Cmb[:, :, 0] = 0.0                       # the membrane moves into the tying block
        Cm = _assumed_membrane(Xo, fold(T, C_m, Jw), Jw)
        nts = Cs.shape[1]
        nm = Cm.shape[1]
        Cs_all = np.zeros((len(Xo), nts + nm, nts + nm))
        Cs_all[:, :nts, :nts] = Cs
        Cs_all[:, nts:, nts:] = Cm
        Cs = Cs_all
        alpha = np.vstack([ALPHA, M_ALPHA])
        beta = np.vstack([BETA, M_BETA])
        tie = np.vstack([TIE, M_TIE])
        r_s = tying_raw(alpha, beta, tie, Xo, Xn)
    return dict(Cmb=np.ascontiguousarray(Cmb), Cs=np.ascontiguousarray(Cs), Cz=Cz, r_mb=r_mb,
                r_s=np.ascontiguousarray(r_s), r_z=r_z, T=T, J=J, alpha=np.ascontiguousarray(alpha),
                beta=np.ascontiguousarray(beta), tie=np.ascontiguousarray(tie))


def nodal_areas(Xo, Xn):
    """(M,4) area shares of the nodes by the trapezoidal (nodal) rule, J_o(node) x weight 1 (Section 4)."""
    dN = np.array([shape(*p)[1] for p in XI])                     # (4 nodes as points, 4, 2)
    A1 = np.einsum("pi,mic->mpc", dN[:, :, 0], Xo)
    A2 = np.einsum("pi,mic->mpc", dN[:, :, 1], Xo)
    return np.einsum("mpc,mpc->mp", np.cross(A1, A2), Xn)
