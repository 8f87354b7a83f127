"""4-node quadrilateral ANS solid-shell element (Section 2.1, Eqs. 1-9).

Natural coordinates (xi, eta) in [-1, 1]^2, nodes counter-clockwise, 2x2 Gauss rule for membrane,
bending, shear and thickness energies; ANS transverse shear from the edge mid-points
(xi, eta) = (0, -1), (0, +1) for gamma_z,xi and (-1, 0), (+1, 0) for gamma_z,eta (Eq. 4); ANS
thickness strain from the four nodes (Eq. 5).

Membrane strains (``membrane=``):

``"full"``  the compatible Green membrane strains at the 2x2 Gauss points (the paper's element).
    The bilinear membrane has a parasitic in-plane shear (gamma_xy linear in xi, eta) that locks
    in-plane bending, and when a flat element is twisted by a fold running across it, its Gauss
    points see a mean stretch -|h|^2/3 that its edges do not (h: the hourglass vector
    sum_i xi_i eta_i x_i / 4).  With a fabric's tensile rigidity ~1e4 times its bending rigidity per
    cm^2 both stiffen coarse meshes (measurements: docs/elements.md, section 4).
``"ans"``  an assumed membrane strain field, in a Cartesian frame at the element centre (x along
    a_xi):  eps_xx = e1 + b4 (eta - eta_c),  eps_yy = e2 + b5 (xi - xi_c),  gamma_xy = e3  (the field
    of Pian & Sumihara's membrane element).
    - (e1, e2, e3): the J_o-weighted mean of the compatible strains at the four Gauss points, plus
      c/3 on the natural stretches (xi-xi and eta-eta) with c = |h - alpha a_xi - beta a_eta|^2
      (alpha, beta: the reference hourglass vector in the centre tangents).  c/3 cancels the
      twist's parasitic mean stretch (exactly on parallelograms: a rectangle folded along a
      diagonal keeps its edge lengths and then stores no normal membrane strain, see
      tests/test_elements.py), and c vanishes with its first derivative for every affine motion of
      a flat element, so (with the J_o-weighted centroid (xi_c, eta_c)) the field has the
      compatible mean for small strains: a constant stress does the same work on it as on the
      compatible strains and the membrane patch test holds on any flat quadrilateral, in its energy
      and its equilibrium form.
    - b4, b5 (in-plane bending) from five tying strains: the stretches of the two xi-edges and the
      two eta-edges at their mid-points and the shear a_xi . a_eta at the centre, which a Cartesian
      field (e, b4, b5) must reproduce (a 5x5 solve per element, done once).
    In-plane bending of a rectangle is then exact for nu = 0; by MacNeal's theorem an element that
    passes the patch test must lock for some distortion (the trapezoidal beam).  Five independent
    parameters: no spurious zero-energy mode.  The MacNeal-Harder, Scordelis-Lo and square-pedestal
    measurements of both membranes: docs/elements.md, section 4.  All of this is beyond the paper,
    whose quadrilateral integrates the compatible membrane strains by the 2x2 rule; ``"full"``
    stays the default.
    Stored form: the field's 22 raw tying products (12 compatible strains at the Gauss points, 5
    tying strains, 5 twist terms) enter only through the five parameters, so their rigidity is
    P^T C5 P (rank 5), and each product is a fixed combination (R_MEM) of the six products of the
    centre tangents and the hourglass vector (a bilinear quad's tangents are a_xi + eta h and
    a_eta + xi h).  The kernels see six membrane "tying" products with a 6x6 rigidity (Cs is 10x10
    instead of the 4x4 shear block); its cost against the compatible quad's: docs/elements.md,
    section 4.
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


N_GP = np.array([shape(*p)[0] for p in GAUSS])  # (4 gp, 4 nodes)
DN_GP = np.array([shape(*p)[1] for p in GAUSS])  # (4 gp, 4 nodes, 2)
# tying points A (0,-1), C (0,+1) for gamma_z,xi;  B (-1,0), D (+1,0) for gamma_z,eta
_TY = [((0.0, -1.0), 0), ((0.0, 1.0), 0), ((-1.0, 0.0), 1), ((1.0, 0.0), 1)]
ALPHA = np.array([shape(*p)[1][:, k] for p, k in _TY])  # d/d(xi or eta) of x_o at the tying point
BETA = np.array([shape(*p)[0] for p, _ in _TY])  # x_n interpolated at the tying point


def _shear_interp(xi, eta):
    """(2,4): natural (gamma_z,xi, gamma_z,eta) at (xi, eta) from the 4 tying values (Eq. 4)."""
    return np.array([[0.5 * (1 - eta), 0.5 * (1 + eta), 0.0, 0.0], [0.0, 0.0, 0.5 * (1 - xi), 0.5 * (1 + xi)]])


S_GP = np.array([_shear_interp(*p) for p in GAUSS])  # (4 gp, 2, 4)
TIE = np.array([[0.0, 3.0, 1.0]] * 4)  # shear: (x_o, x_n) products, c_t = 1 (core.py)

# the five tying strains of the assumed membrane field: (point, derivative of the first factor, of
# the second, c_t, natural strain row): stretches of the xi-edges, of the eta-edges, centre shear
_MTY = [
    ((0.0, -1.0), 0, 0, 0.5, 0),
    ((0.0, 1.0), 0, 0, 0.5, 0),
    ((-1.0, 0.0), 1, 1, 0.5, 1),
    ((1.0, 0.0), 1, 1, 0.5, 1),
    ((0.0, 0.0), 0, 1, 1.0, 2),
]
# the compatible membrane strains at the Gauss points as tying terms: a1.a1/2, a2.a2/2, a1.a2
_GPM = [(g, k, l, c) for g in range(4) for k, l, c in ((0, 0, 0.5), (1, 1, 0.5), (0, 1, 1.0))]
# the twist terms: products of the hourglass vector h = sum_i xi_i eta_i x_i / 4 and the centre
# tangents a_xi, a_eta (with the centre shear, tying strain 16, they make |h - alpha a_xi - beta a_eta|^2)
_HG = XI[:, 0] * XI[:, 1] / 4.0
_DC = shape(0.0, 0.0)[1]
_TW = [
    (_HG, _HG, 1.0),
    (_HG, _DC[:, 0], 1.0),
    (_HG, _DC[:, 1], 1.0),
    (_DC[:, 0], _DC[:, 0], 0.5),
    (_DC[:, 1], _DC[:, 1], 0.5),
]
M_ALPHA = np.array(
    [DN_GP[g, :, k] for g, k, _, _ in _GPM] + [shape(*p)[1][:, k] for p, k, _, _, _ in _MTY] + [u for u, _, _ in _TW]
)
M_BETA = np.array(
    [DN_GP[g, :, l] for g, _, l, _ in _GPM] + [shape(*p)[1][:, l] for p, _, l, _, _ in _MTY] + [v for _, v, _ in _TW]
)
M_TIE = np.array(
    [[0.0, 0.0, c] for *_, c in _GPM] + [[0.0, 0.0, c] for _, _, _, c, _ in _MTY] + [[0.0, 0.0, c] for *_, c in _TW]
)
N_MEM = len(M_TIE)  # 22 raw membrane strains
# On a bilinear quadrilateral x = x_c + xi a_xi + eta a_eta + xi eta h, so every tangent is
# a_xi + eta h or a_eta + xi h, and each of the 22 products above is a fixed combination of the six
# products y = (a_xi.a_xi/2, a_eta.a_eta/2, a_xi.a_eta, h.h/2, a_xi.h, a_eta.h) of the centre
# tangents and the hourglass vector: raw = R_MEM y.  The membrane rigidity therefore acts on y as
# the 6x6 R^T P^T C5 P R (rank 5), and the kernels form six products instead of 22.
_V = np.stack([_DC[:, 0], _DC[:, 1], _HG], 1)  # (4,3): orthogonal columns, |column|^2 = 1/4
_PAIRS = ((0, 0, 0.5), (1, 1, 0.5), (0, 1, 1.0), (2, 2, 0.5), (0, 2, 1.0), (1, 2, 1.0))
P_ALPHA = np.array([_V[:, k] for k, _, _ in _PAIRS])
P_BETA = np.array([_V[:, l] for _, l, _ in _PAIRS])
P_TIE = np.array([[0.0, 0.0, c] for *_, c in _PAIRS])
N_PROD = len(P_TIE)  # the six membrane products


def products_map(alpha, beta, tie):
    """(nt,6) R with c_t (alpha_t . x)(beta_t . x) = R_t . y for any nodal x (y: the six products
    P_ALPHA/P_BETA/P_TIE), for x_o.x_o tying rows alpha, beta (nt,4) whose weights sum to zero."""
    a = 4.0 * alpha @ _V  # coordinates on the basis _V
    b = 4.0 * beta @ _V
    R = np.zeros((len(alpha), N_PROD))
    for p, (k, l, c) in enumerate(_PAIRS):
        w = a[:, k] * b[:, l] + (a[:, l] * b[:, k] if k != l else 0.0)
        R[:, p] = tie[:, 2] * w / c
    return R


R_MEM = products_map(M_ALPHA, M_BETA, M_TIE)  # (22,6)
MEMBRANES = ("full", "ans")


def _assumed_field(xi, eta):
    """(3,5): Cartesian (eps_xx, eps_yy, gamma_xy) at (xi, eta) from the five parameters b."""
    return np.array([[1.0, 0.0, 0.0, eta, 0.0], [0.0, 1.0, 0.0, 0.0, xi], [0.0, 0.0, 1.0, 0.0, 0.0]])


def _cartesian_to_natural(Xo, p, ex, ey):
    """(M,3,3): natural raw membrane strains (a1.a1/2, a2.a2/2, a1.a2 minus reference) at the point
    p = (xi, eta) of a Cartesian strain (eps_xx, eps_yy, gamma_xy) in the frame (ex, ey) (M,3)."""
    dN = shape(*p)[1]
    A = [np.einsum("i,mic->mc", dN[:, k], Xo) for k in (0, 1)]
    g = [np.stack([np.sum(a * ex, -1), np.sum(a * ey, -1)], -1) for a in A]  # (M,2) each
    (g1x, g1y), (g2x, g2y) = (g[0][:, 0], g[0][:, 1]), (g[1][:, 0], g[1][:, 1])
    return np.stack(
        [
            np.stack([g1x * g1x, g1y * g1y, g1x * g1y], -1),
            np.stack([g2x * g2x, g2y * g2y, g2x * g2y], -1),
            np.stack([2 * g1x * g2x, 2 * g1y * g2y, g1x * g2y + g1y * g2x], -1),
        ],
        -2,
    )


def tying_raw(alpha, beta, tie, xo, xn):
    """(M,nt) raw tying strains c_t (alpha_t . y)(beta_t . z) of (M,4,3) positions/directors."""
    y = np.stack([xo, xn])  # offset 0 -> x_o, 3 -> x_n
    ia = (tie[:, 0] // 3).astype(int)
    ib = (tie[:, 1] // 3).astype(int)
    a = np.einsum("ti,tmic->mtc", alpha, y[ia])
    b = np.einsum("ti,tmic->mtc", beta, y[ib])
    return tie[:, 2] * np.sum(a * b, -1)


_DN_ROWS = np.ascontiguousarray(DN_GP.transpose(0, 2, 1).reshape(-1, DN_GP.shape[1]))
"""DN_GP as rows (point g, direction k) x node i: the tangents of all points by one product."""


def _tangents(xo, xn):
    """(M,4,2,3) natural tangents of the positions and of the directors at the Gauss points."""
    M = len(xo)
    a = (_DN_ROWS @ xo).reshape(M, len(DN_GP), 2, 3)  # batched products: einsum took 10x as long
    b = (_DN_ROWS @ xn).reshape(M, len(DN_GP), 2, 3)
    return a, b


def _bending_raw(a, b):
    """(M,4,3) raw natural bending strains (columns 3-5 of raw_strains' mb) from the tangents."""
    return np.stack(
        [
            _dot(a[:, :, 0], b[:, :, 0]),
            _dot(a[:, :, 1], b[:, :, 1]),
            _dot(a[:, :, 0], b[:, :, 1]) + _dot(a[:, :, 1], b[:, :, 0]),
        ],
        -1,
    )


def _dot(u, v):
    return np.sum(u * v, -1)


def raw_strains(xo, xn):
    """Raw natural strains of elements with nodal (M,4,3) positions/directors: (M,4,6), (M,4), (M,4).
    The same products the kernel forms (core.py); used here for the reference state."""
    a, b = _tangents(xo, xn)
    mb = np.concatenate(
        [
            np.stack(
                [0.5 * _dot(a[:, :, 0], a[:, :, 0]), 0.5 * _dot(a[:, :, 1], a[:, :, 1]), _dot(a[:, :, 0], a[:, :, 1])],
                -1,
            ),
            _bending_raw(a, b),
        ],
        -1,
    )
    s = _dot(ALPHA @ xo, BETA @ xn)
    z = 0.5 * _dot(xn, xn)
    return mb, s, z


def bending_raw_strains(xo, xn):
    """(M,4,3) the bending part of raw_strains' mb alone (the adaptivity criterion's per-pass
    curvature, Eq. 25), the same floating-point operations."""
    return _bending_raw(*_tangents(xo, xn))


def _assumed_membrane(Xo, Cm_gp, Jw):
    """The assumed membrane field (module docstring) as factors: P (M,5,22) takes the 22 raw
    strains (M_ALPHA/M_BETA/M_TIE: 12 compatible ones at the Gauss points, the 5 tying strains, 5
    twist terms) to the five parameters (e1, e2, e3, b4, b5), C5 (M,5,5) = sum_g F_g^T W_g^T Cm_g
    W_g F_g is the rigidity on them (F_g: the field at Gauss point g, W_g: Cartesian to natural
    strains there), from the natural-strain rigidities Cm_gp (M,4,3,3) = T^T C_m T J_o w at the
    Gauss points.  The rigidity on the 22 raw strains is P^T C5 P: of rank 5."""
    P, WF = assumed_membrane_field(Xo, Jw)
    C5 = _sum_gauss_quadratic(WF, Cm_gp)
    return P, 0.5 * (C5 + np.swapaxes(C5, 1, 2))


def assumed_membrane_field(Xo, Jw):
    """The assumed membrane field's geometry of quads with initial positions Xo (M,4,3) and J_o w
    Jw (M,4): P (M,5,22), the five parameters from the 22 raw strains, and W F (M,4,3,5), the
    natural membrane strains at the Gauss points from the parameters -- so the natural strains at
    Gauss point g are (W F)_g P (raw - raw_ref) (solidshell/fields.py reads them out this way)."""
    M = len(Xo)
    A1c = np.einsum("i,mic->mc", _DC[:, 0], Xo)  # centre tangents
    A2c = np.einsum("i,mic->mc", _DC[:, 1], Xo)
    ex0 = A1c / np.linalg.norm(A1c, axis=-1, keepdims=True)
    ez0 = np.cross(A1c, A2c)
    ey0 = np.cross(ez0 / np.linalg.norm(ez0, axis=-1, keepdims=True), ex0)
    W = np.stack([_cartesian_to_natural(Xo, p, ex0, ey0) for p in GAUSS], 1)  # (M,4,3,3)
    area = Jw.sum(1)
    xi_c = Jw @ GAUSS[:, 0] / area
    eta_c = Jw @ GAUSS[:, 1] / area
    # tying strain t of a field (e, b4, b5): row r_t of the natural strains at its point
    Mt = np.stack(
        [
            np.einsum("ma,ab->mb", _cartesian_to_natural(Xo, p, ex0, ey0)[:, r], _assumed_field(*p))
            for p, _, _, _, r in _MTY
        ],
        1,
    )  # (M,5,5)
    b45 = np.linalg.inv(Mt)[:, 3:]  # (M,2,5): b4, b5 from the tying
    mean = np.zeros((M, 3, N_MEM))  # (e1, e2, e3) from the 12 gp strains
    Winv = np.linalg.inv(W)
    for g in range(4):  # the four Gauss points
        mean[:, :, 3 * g : 3 * g + 3] = (Jw[:, g] / area)[:, None, None] * Winv[:, g]
    # twist correction: the mean of a_xi.a_xi/2 over the Gauss points carries |h|^2/6 where the
    # edges carry |h|^2/2, so a flat element twisted with its edge lengths kept (a fold across it)
    # shows a parasitic mean stretch -|h|^2/3 in xi and eta: add c/3, c = |h - alpha a_xi -
    # beta a_eta|^2 (alpha, beta: the reference hourglass H in the centre tangents), which is zero
    # with zero slope for every affine motion of a flat element, so the patch test is unaffected
    H = np.einsum("i,mic->mc", _HG, Xo)
    G = np.stack(
        [
            np.einsum("mc,mc->m", A1c, A1c),
            np.einsum("mc,mc->m", A1c, A2c),
            np.einsum("mc,mc->m", A1c, A2c),
            np.einsum("mc,mc->m", A2c, A2c),
        ],
        -1,
    ).reshape(M, 2, 2)
    ab = np.linalg.solve(G, np.stack([np.einsum("mc,mc->m", H, A1c), np.einsum("mc,mc->m", H, A2c)], -1)[..., None])[
        ..., 0
    ]
    a_, b_ = ab[:, 0], ab[:, 1]
    # c = t17 - 2 alpha t18 - 2 beta t19 + 2 alpha^2 t20 + 2 beta^2 t21 + 2 alpha beta t16
    coef = np.zeros((M, N_MEM))
    coef[:, 17], coef[:, 18], coef[:, 19] = 1.0, -2.0 * a_, -2.0 * b_
    coef[:, 20], coef[:, 21], coef[:, 16] = 2.0 * a_ * a_, 2.0 * b_ * b_, 2.0 * a_ * b_
    tw = np.einsum("mg,mgab,b->ma", Jw / area[:, None], Winv, np.array([1.0, 1.0, 0.0]) / 3.0)
    mean += tw[:, :, None] * coef[:, None, :]
    P = np.zeros((M, 5, N_MEM))
    P[:, :3] = mean
    P[:, 3:, 12:17] = b45
    F = np.zeros((M, 4, 3, 5))  # the field at gp g (_assumed_field)
    F[:, :, 0, 0] = F[:, :, 1, 1] = F[:, :, 2, 2] = 1.0
    F[:, :, 0, 3] = GAUSS[None, :, 1] - eta_c[:, None]
    F[:, :, 1, 4] = GAUSS[None, :, 0] - xi_c[:, None]
    return P, W @ F


def dense_membrane(Xo, c, C_m):
    """(M,22,22) P^T C5 P: the assumed membrane's rigidity on its 22 raw tying products
    (M_ALPHA/M_BETA/M_TIE), the form before the factorisation into the six products, from
    precompute's constants ``c`` (its T and J) of quads with initial positions Xo (M,4,3) and the
    section's C_m: the reference the compact form is tested and timed against."""
    Jw = c["J"] * GAUSS_W
    P, C5 = _assumed_membrane(Xo, fold(c["T"], C_m, Jw), Jw)
    return np.swapaxes(P, 1, 2) @ C5 @ P


def _sum_gauss_quadratic(S, C):
    """sum_g S_g^T C_g S_g per element: S (M,G,a,t), C (M,G,a,a) or broadcastable -> (M,t,t), by
    batched matrix products (a multi-operand einsum loops over every index at once: 10x slower)."""
    return (np.swapaxes(S, -1, -2) @ (C @ S)).sum(1)


def precompute(Xo, Xn, C_m, C_b, C_t, E_z, warp_angle, membrane="full"):
    """Fold Eqs. (6)-(8) into per-element constants for quads with initial nodal (M,4,3) Xo, Xn.

    membrane : "full" (compatible strains at the Gauss points) or "ans" (assumed membrane strains,
        see the module docstring: their rigidity moves from Cmb into the tying block of Cs).
    Returns dict(Cmb (M,4,2,3,3), Cs (M,nt,nt), Cz (M,4,4), r_mb, r_s, r_z, T (M,4,3,3), J (M,4),
    alpha, beta (nt,4), tie (nt,3)) with nt = 4 ("full") or 10 ("ans": the 4 shear ties, then
    the six membrane products P_ALPHA/P_BETA/P_TIE with their 6x6 rigidity).
    """
    if membrane not in MEMBRANES:
        raise ValueError(f"membrane must be one of {MEMBRANES}, got {membrane!r}")
    A1 = np.einsum("gi,mic->mgc", DN_GP[:, :, 0], Xo)
    A2 = np.einsum("gi,mic->mgc", DN_GP[:, :, 1], Xo)
    Xn_g = np.einsum("gi,mic->mgc", N_GP, Xn)
    J = np.einsum("mgc,mgc->mg", np.cross(A1, A2), Xn_g)  # Eq. (8)
    if np.any(J <= 0):
        raise ValueError("a quadrilateral has a non-positive Jacobian J_o (inverted or director flipped)")
    ex, ey, _ = local_frame(A1, A2, warp_angle)
    Q, T = covariant_maps(A1, A2, ex, ey)
    Jw = J * GAUSS_W
    Cmb = np.stack([fold(T, C_m, Jw), fold(T, C_b, Jw)], axis=2)
    QS = np.einsum("mgab,gbt->mgat", Q, S_GP)  # local shear from tying values
    Cs = _sum_gauss_quadratic(QS, C_t * Jw[:, :, None, None])
    # per element, not a matrix product over the elements: BLAS sums differently for one row, and
    # an element's constants must not depend on the others it is computed with (model.ElementConstants)
    Cz = E_z * np.einsum("mg,gij->mij", Jw, N_GP[:, :, None] * N_GP[:, None, :])
    r_mb, r_s, r_z = raw_strains(Xo, Xn)
    alpha, beta, tie = ALPHA, BETA, TIE
    if membrane == "ans":
        Cmb[:, :, 0] = 0.0  # the membrane moves into the tying block
        P, C5 = _assumed_membrane(Xo, fold(T, C_m, Jw), Jw)
        Q = P @ R_MEM  # (M,5,6): the field's parameters from y
        Cm = np.swapaxes(Q, 1, 2) @ C5 @ Q
        nts = Cs.shape[1]
        Cs_all = np.zeros((len(Xo), nts + N_PROD, nts + N_PROD))
        Cs_all[:, :nts, :nts] = Cs
        Cs_all[:, nts:, nts:] = 0.5 * (Cm + np.swapaxes(Cm, 1, 2))  # exactly symmetric
        Cs = Cs_all
        alpha = np.vstack([ALPHA, P_ALPHA])
        beta = np.vstack([BETA, P_BETA])
        tie = np.vstack([TIE, P_TIE])
        r_s = tying_raw(alpha, beta, tie, Xo, Xn)
    return dict(
        Cmb=np.ascontiguousarray(Cmb),
        Cs=np.ascontiguousarray(Cs),
        Cz=Cz,
        r_mb=r_mb,
        r_s=np.ascontiguousarray(r_s),
        r_z=r_z,
        T=T,
        J=J,
        alpha=np.ascontiguousarray(alpha),
        beta=np.ascontiguousarray(beta),
        tie=np.ascontiguousarray(tie),
    )


def nodal_areas(Xo, Xn):
    """(M,4) area shares of the nodes by the trapezoidal (nodal) rule, J_o(node) x weight 1 (Section 4)."""
    dN = np.array([shape(*p)[1] for p in XI])  # (4 nodes as points, 4, 2)
    A1 = np.einsum("pi,mic->mpc", dN[:, :, 0], Xo)
    A2 = np.einsum("pi,mic->mpc", dN[:, :, 1], Xo)
    return np.einsum("mpc,mpc->mp", np.cross(A1, A2), Xn)
