"""State of newly inserted nodes (paper §5.4, Eqs. 27-34): discrete-Kirchhoff (DK) mid-edge transfer
in the co-rotated edge frame, linear transfer for comparison, 8-node serendipity centre nodes.

Every state here is a nodal displacement U = [U_o | U_n] (Eq. 1), U_o the mid-surface displacement
[length], U_n the director displacement (x_n = X_n + U_n, dimensionless).  The same functions
transfer D_n and D_n-1, so the central-difference velocity (D_n - D_n-1)/dt follows ("similar
approach is used to get the velocity", §5.4).

DK mid-edge transfer, general form
----------------------------------
Edge A-B with mid-edge node M, E a third corner of an element owning the edge.  A frame
R = [x | y | z] (columns) is built the same way in the initial and in the current configuration:
origin at A, y along A->B, z normal to the plane E-A-B (E on the x-y plane), x = y cross z; its
z side is chosen once, in the initial configuration, on the side of the directors X_nA + X_nB.
With R0 the initial and R1 the current frame, Q = R1 R0^T is the edge's rigid rotation and

    M^c  = A' + Q (X_oM - X_oA),            x_nM^c = Q X_nM                 (Eq. 34)

is the co-rotated mid node.  Local deviations from the co-rotated configuration, in R1's axes:
u_o of A is 0, of B (0, |A'B'| - L, 0) (Eq. 31); the director deviations are
d = R1^T x_n - R0^T X_n (Eqs. 30-31: with X_n along z this is the paper's (u_n, v_n, w_n)).
Along the edge, w is the Hermite (thin-beam) cubic with w = 0 at both ends (A' and B' lie on y)
and the DK slopes w' = -v_n (Eqs. 27-29); evaluated at M's position s = y_M / L along the edge
(s = 1/2 for a chord mid-point) it gives

    w_oM = L s(1-s) [(1-s) (-v_nA) - s (-v_nB)]          (Eq. 32 at s = 1/2: -L/8 (v_nA - v_nB))
    v_nM = -w'(s) = (1-s)(1-3s) v_nA + s(3s-2) v_nB      (Eq. 32 at s = 1/2: -1/4 (v_nA + v_nB))

and u_o, v_o, u_n are interpolated linearly in s (the averages of Eq. 32).  Then (Eq. 33)
x_oM = M^c + R1 u_oM and x_nM = R1 (R0^T X_nM + d_M).

The director's stretch (w_nM).  Eq. (32) averages w_n = n_z.x_n - 1, which is the director's
stretch only to first order: a director rotated by theta against the chord normal has
w_n = cos(theta) - 1 although its length is unchanged, so on a bend of angle kappa L the literal
average shortens the new director by ~(kappa L)^2/8 and puts a spurious thickness strain of that
size into the new node (so does linear transfer).  The default ``stretch="length"`` therefore
keeps u_nM, v_nM of Eq. (32) and sets the z component so that |x_nM| / |X_nM| is the same linear
average of the end nodes' stretches |x_n| / |X_n|; it equals Eq. (32) to first order in the
rotations.  ``stretch="paper"`` is Eq. (32) literally.

Exactness.  A rigid motion of A, B, E and their directors gives d = 0, |A'B'| = L, Q = the motion's
rotation, so M is moved rigidly, for any X_oM (on or off the chord, e.g. on a curved boundary) and
any initial directors (normal to the plane E-A-B or not).  A cylindrical bend of curvature kappa
(edge across the generators, directors normal) puts M on the arc to O(kappa^3 L^4): the sagitta is
L/4 sin(kappa L/2) against the exact (1 - cos(kappa L/2))/kappa, an error of kappa^3 L^4 / 384;
its director is the exact normal (tests/test_adapt_transfer.py).  The DK slope relation w' = -v_n
assumes the initial director along z; for a director tilted by phi from the edge plane's normal it
reads the slope from v_n only (a first-order error factor cos(phi) in the bending part).

Centre nodes (§5.4): position by the 8-node serendipity functions of the four corners and the four
mid-edge nodes (inactive mid-edge nodes derived on the fly by the same DK rule); the director by
default from the Kirchhoff condition at the centre (:func:`kirchhoff_centre_director`), or by the
serendipity functions as the paper words it (``centre="serendipity"``).

Measured (verification/out/adapt_transfer.md, static drapes refined 1-to-4 everywhere): DK injects
1.2-3.2 % of the strain energy and 0.9-3.3 % of the kinetic-energy peak that linear transfer does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "Edges",
    "dk_midedge",
    "linear_midedge",
    "serendipity_centre",
    "kirchhoff_centre_director",
    "fill_new_nodes",
    "to_new_mesh",
    "STRETCH_MODES",
    "METHODS",
    "CENTRE_MODES",
]

STRETCH_MODES = ("length", "paper")
METHODS = ("dk", "linear")
CENTRE_MODES = ("serendipity", "kirchhoff")


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _edge_frame(A, B, E, dirs, side=None):
    """(K,3,3) frames [x|y|z] (columns) of the edges A->B with z normal to the plane E-A-B, and the
    z side (+-1 per edge).  ``side`` None (the initial frame): z is put on the side of ``dirs``;
    else (the current frame) the given side is used, so both frames are built the same way.
    Where E' has come onto the line A'-B' (a degenerate current state) z is taken along the
    component of ``dirs`` normal to the edge instead."""
    y = _unit(B - A)
    n = np.cross(y, E - A)
    nn = np.linalg.norm(n, axis=-1)
    bad = nn <= 1e-10 * np.linalg.norm(E - A, axis=-1)
    if np.any(bad):
        if side is None:
            raise ValueError(f"E is collinear with A-B in the initial configuration of {int(bad.sum())} edge(s)")
        dz = dirs[bad] - np.sum(dirs[bad] * y[bad], -1, keepdims=True) * y[bad]
        n = n.copy()
        n[bad] = dz * side[bad, None]  # side is applied again below
        nn = np.linalg.norm(n, axis=-1)
    z = n / nn[:, None]
    if side is None:
        side = np.where(np.sum(z * dirs, -1) < 0.0, -1.0, 1.0)
    z = z * side[:, None]
    return np.stack([np.cross(y, z), y, z], axis=-1), side


@dataclass(frozen=True)
class Edges:
    """The initial geometry of K edges A-B with their mid-edge nodes M (the reference state
    :func:`dk_midedge` transfers from): XoA, XoB, XoE, XoM (K,3) initial positions of A, B, E (a
    third corner of an element owning the edge, fixing the co-rotated frame) and M [length];
    XnA, XnB, XnM (K,3) initial directors of A, B, M."""

    XoA: np.ndarray
    XoB: np.ndarray
    XoE: np.ndarray
    XoM: np.ndarray
    XnA: np.ndarray
    XnB: np.ndarray
    XnM: np.ndarray

    @classmethod
    def of(cls, Xo, Xn, A, B, E, M) -> Edges:
        """The edges of node index arrays A, B, E, M (K,) into initial positions Xo and directors Xn."""
        return cls(Xo[A], Xo[B], Xo[E], Xo[M], Xn[A], Xn[B], Xn[M])


def dk_midedge(edges: Edges, UA, UB, UE, *, stretch: str = "length"):
    """Discrete-Kirchhoff state of K mid-edge nodes M of edges A-B (Eqs. 27-34, §5.4).

    Parameters
    ----------
    edges : the edges' initial geometry (:class:`Edges`)
    UA, UB, UE : (K,6) states [U_o | U_n] of A, B, E (only U_o of E is used)
    stretch : "length" (default: the director length of M is the average of A's and B's stretches)
        or "paper" (Eq. 32's w_nM = (w_nA + w_nB)/2 literally); see the module docstring.

    Returns
    -------
    UM : (K,6) state of M.  Vectorised over edges; exact for rigid motions.
    """
    if stretch not in STRETCH_MODES:
        raise ValueError(f"stretch must be one of {STRETCH_MODES}, got {stretch!r}")
    e = edges
    XoA, XoB, XoE, XoM, XnA, XnB, XnM = (
        np.asarray(a, float) for a in (e.XoA, e.XoB, e.XoE, e.XoM, e.XnA, e.XnB, e.XnM)
    )
    UA, UB, UE = (np.asarray(a, float) for a in (UA, UB, UE))
    xA, xB, xE = XoA + UA[:, :3], XoB + UB[:, :3], XoE + UE[:, :3]
    xnA, xnB = XnA + UA[:, 3:], XnB + UB[:, 3:]

    R0, side = _edge_frame(XoA, XoB, XoE, XnA + XnB)
    R1, _ = _edge_frame(xA, xB, xE, xnA + xnB, side)

    def loc0(v):
        return np.einsum("kji,kj->ki", R0, v)  # R0^T v

    def loc1(v):
        return np.einsum("kji,kj->ki", R1, v)  # R1^T v

    L = np.linalg.norm(XoB - XoA, axis=-1)
    mloc = loc0(XoM - XoA)  # M in the initial edge frame
    s = mloc[:, 1] / L  # its position along the edge (1/2 at the chord middle)
    vB = np.linalg.norm(xB - xA, axis=-1) - L  # Eq. (31): v_oB
    dA = loc1(xnA) - loc0(XnA)  # Eq. (30)
    dB = loc1(xnB) - loc0(XnB)  # Eq. (31)
    nM0 = loc0(XnM)

    # Hermite cubic with w_oA = w_oB = 0 and DK slopes w'_A = -v_nA, w'_B = -v_nB (Eqs. 27-29, 32)
    tA, tB = -dA[:, 1], -dB[:, 1]
    w_oM = L * s * (1.0 - s) * ((1.0 - s) * tA - s * tB)
    v_nM = -((1.0 - s) * (1.0 - 3.0 * s) * tA + s * (3.0 * s - 2.0) * tB)
    u_nM = (1.0 - s) * dA[:, 0] + s * dB[:, 0]

    uloc = np.stack([np.zeros_like(s), s * vB, w_oM], axis=-1)  # u_oM, v_oM, w_oM
    xM = xA + np.einsum("kij,kj->ki", R1, mloc + uloc)  # Eqs. (33)-(34)

    cx, cy = nM0[:, 0] + u_nM, nM0[:, 1] + v_nM
    if stretch == "paper":
        cz = nM0[:, 2] + (1.0 - s) * dA[:, 2] + s * dB[:, 2]
    else:
        lam = (1.0 - s) * np.linalg.norm(xnA, axis=-1) / np.linalg.norm(XnA, axis=-1) + s * np.linalg.norm(
            xnB, axis=-1
        ) / np.linalg.norm(XnB, axis=-1)
        ell2 = (lam * np.linalg.norm(XnM, axis=-1)) ** 2
        cz = np.copysign(np.sqrt(np.maximum(ell2 - cx * cx - cy * cy, 0.0)), nM0[:, 2])
    xnM = np.einsum("kij,kj->ki", R1, np.stack([cx, cy, cz], axis=-1))
    return np.concatenate([xM - XoM, xnM - XnM], axis=1)


def linear_midedge(UA, UB):
    """Linear transfer (the usual choice the paper compares against): U_M = (U_A + U_B)/2, (K,6)."""
    return 0.5 * (np.asarray(UA, float) + np.asarray(UB, float))


def serendipity_centre(Ucorners, Umids):
    """Centre value of the 8-node serendipity element (§5.4): N_corner(0,0) = -1/4, N_mid(0,0) = 1/2.

    Ucorners, Umids : (K,4,c) values at the corners and at the mid-edge nodes -> (K,c).
    Exact for fields in the serendipity space (every quadratic in x, y on a parallelogram)."""
    return -0.25 * np.sum(Ucorners, axis=1) + 0.5 * np.sum(Umids, axis=1)


def kirchhoff_centre_director(Xo_c, Xn_c, Xo_m, U_m, U_c, stretch_c):
    """Director of K centre nodes satisfying the Kirchhoff condition at the centre (an extension of
    the paper's serendipity rule, ``centre="kirchhoff"`` of :func:`fill_new_nodes`).

    The serendipity interpolation of U_n on an element that is twisted or bent in two directions
    leaves the centre director off the surface normal by O(rotation differences^2) (on the wool
    sheet's hanging corner of verification/adapt_transfer.py, by ~0.07 rad), which the element's
    ANS shear (tied at edge mid-points) hid at the coarse level but the four children see.  Here
    the transverse shear strains of Eq. (3) at the centre, x_n.x_o,xi - X_n.X_o,xi and likewise
    for eta, are set to zero with the tangents of the serendipity geometry at the centre,
    x_o,xi = (x_m1 - x_m3)/2, x_o,eta = (x_m2 - x_m0)/2, and the director length to
    stretch_c |X_n|; its side is that of the serendipity director.

    Xo_c, Xn_c : (K,3) initial centre position (unused but for shape) and director
    Xo_m : (K,4,3) initial mid-edge positions (m0..m3: edges 0-1, 1-2, 2-3, 3-0); U_m (K,4,6) their
    states; U_c (K,6) the serendipity state of the centre; stretch_c (K,) the director stretch.
    Returns (K,3) the centre's U_n.
    """
    xm = Xo_m + U_m[..., :3]
    T = np.stack([Xo_m[:, 1] - Xo_m[:, 3], Xo_m[:, 2] - Xo_m[:, 0]], axis=1) * 0.5  # (K,2,3)
    t = np.stack([xm[:, 1] - xm[:, 3], xm[:, 2] - xm[:, 0]], axis=1) * 0.5
    a = np.einsum("kj,kij->ki", Xn_c, T)  # X_n.X_o,xi and X_n.X_o,eta
    G = np.einsum("kij,klj->kil", t, t)  # Gram matrix of the tangents
    # an element folded flat onto a line has no tangent plane: keep the serendipity director there
    flat = np.linalg.det(G) <= 1e-12 * np.einsum("kii->k", G) ** 2
    G[flat] = np.eye(2)
    p = np.einsum("kij,ki->kj", t, np.linalg.solve(G, a[..., None])[..., 0])
    nu = _unit(np.cross(t[:, 0], t[:, 1]))
    ell2 = (stretch_c * np.linalg.norm(Xn_c, axis=-1)) ** 2
    side = np.where(np.sum((Xn_c + U_c[:, 3:]) * nu, -1) < 0.0, -1.0, 1.0)
    g = side * np.sqrt(np.maximum(ell2 - np.sum(p * p, -1), 0.0))
    out = p + g[:, None] * nu - Xn_c
    out[flat] = U_c[flat, 3:]
    return out


def _midedge_values(bg, U, A, B, E, M, method, stretch):
    if method == "linear":
        return linear_midedge(U[A], U[B])
    return dk_midedge(Edges.of(bg.Xo, bg.Xn, A, B, E, M), U[A], U[B], U[E], stretch=stretch)


def fill_new_nodes(
    bg, Ubg, new_nodes, method: str = "dk", known=None, *, stretch: str = "length", centre: str = "kirchhoff"
):
    """States of newly inserted background nodes from already known ones (§5.4).

    Parameters
    ----------
    bg : the background mesh (attributes Xo, Xn, node_level, mid_parent [A,B,E], centre_parent
        [c0..c3, m0..m3]; see notes/adapt_interface.md)
    Ubg : (Nb,6) states of the background nodes; rows of ``new_nodes`` are overwritten
    new_nodes : int array of the background nodes inserted now (mid-edge and centre nodes)
    method : "dk" (Eqs. 27-34) or "linear" (mid-edge nodes by averaging)
    known : (Nb,) bool, the nodes whose rows of Ubg are valid (the active nodes before the
        insertion); default: every node not in ``new_nodes``
    stretch : director stretch rule of :func:`dk_midedge`
    centre : "kirchhoff" (default: position by the serendipity functions, director by
        :func:`kirchhoff_centre_director` with the serendipity-interpolated stretch; method="dk"
        only) or "serendipity" (the paper literally: all six components by the 8-node functions).
        Measured in verification/out/adapt_transfer.md: on the square-pedestal drapes the
        Kirchhoff director cuts the energy a 1-to-4 refinement injects by 40-42 % and the kinetic
        energy peak that follows by 35-39 % against the literal rule; no change on the strip.

    Nodes are filled level by level (``node_level`` ascending), at each level mid-edge nodes first
    (from [A, B, E]), then centre nodes by the serendipity interpolation of their element's four
    corners and four mid-edge nodes.  A mid-edge node that is neither known nor inserted (a side of
    a transition element that stays unsplit) is computed on the fly by the same rule, "regardless
    whether [it needs] to be inserted or not" (§5.4), with E the corner after the edge, and is not
    written.  Returns a new (Nb,6) array; ValueError if a needed parent is neither known nor filled.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if centre not in CENTRE_MODES:
        raise ValueError(f"centre must be one of {CENTRE_MODES}, got {centre!r}")
    U = np.array(Ubg, dtype=float, copy=True)
    new = np.unique(np.asarray(new_nodes, dtype=np.int64))
    valid = np.ones(len(U), bool) if known is None else np.array(known, dtype=bool, copy=True)
    valid[new] = False
    mid_p = np.asarray(bg.mid_parent)
    cen_p = np.asarray(bg.centre_parent)
    is_mid = mid_p[new, 0] >= 0
    is_cen = cen_p[new, 0] >= 0
    if np.any(~(is_mid | is_cen)):
        raise ValueError(
            f"nodes {new[~(is_mid | is_cen)][:5].tolist()} are neither mid-edge nor "
            "centre nodes: level-0 nodes cannot be inserted"
        )
    level = np.asarray(bg.node_level)[new]

    def need(nodes, what):
        if not np.all(valid[nodes]):
            bad = np.unique(nodes[~valid[nodes]])
            raise ValueError(
                f"{what} needs nodes {bad[:5].tolist()} that are neither known nor inserted at a lower level"
            )

    for lev in np.unique(level):
        mids = new[is_mid & (level == lev)]
        if len(mids):
            A, B, E = mid_p[mids].T
            need(mid_p[mids].ravel() if method == "dk" else np.concatenate([A, B]), "a mid-edge node")
            U[mids] = _midedge_values(bg, U, A, B, E, mids, method, stretch)
            valid[mids] = True
        cens = new[is_cen & (level == lev)]
        if len(cens):
            cp = cen_p[cens]
            corners, m = cp[:, :4], cp[:, 4:]
            need(corners.ravel(), "a centre node")
            Um = U[m]  # (k,4,6)
            todo = ~valid[m]
            if np.any(todo):
                ki, kk = np.nonzero(todo)  # element, edge k (corner k -> k+1)
                Um[ki, kk] = _midedge_values(
                    bg,
                    U,
                    corners[ki, kk],
                    corners[ki, (kk + 1) % 4],
                    corners[ki, (kk + 2) % 4],
                    m[ki, kk],
                    method,
                    stretch,
                )
            Uc = serendipity_centre(U[corners], Um)
            if centre == "kirchhoff" and method == "dk":
                Xn = np.asarray(bg.Xn)

                def lam(nodes, Ux):
                    return (np.linalg.norm(Xn[nodes] + Ux[..., 3:], axis=-1) / np.linalg.norm(Xn[nodes], axis=-1))[
                        ..., None
                    ]

                stretch_c = serendipity_centre(lam(corners, U[corners]), lam(m, Um))[:, 0]
                Uc[:, 3:] = kirchhoff_centre_director(
                    np.asarray(bg.Xo)[cens], Xn[cens], np.asarray(bg.Xo)[m], Um, Uc, stretch_c
                )
            U[cens] = Uc
            valid[cens] = True
    return U


def to_new_mesh(bg, U, old_nodes, new_nodes, method: str = "dk", centre: str = "kirchhoff"):
    """A state (n_old*6,) or (n_old,6) on the active mesh of background nodes ``old_nodes`` carried to
    the one of ``new_nodes`` (both sorted): surviving nodes keep their rows, the nodes inserted now
    are filled by :func:`fill_new_nodes` from the old ones.  Returns the flat (n_new*6,) state."""
    old_nodes, new_nodes = np.asarray(old_nodes), np.asarray(new_nodes)
    Nb = len(bg.Xo)
    Ubg = np.zeros((Nb, 6))
    Ubg[old_nodes] = np.asarray(U, dtype=float).reshape(-1, 6)
    known = np.zeros(Nb, dtype=bool)
    known[old_nodes] = True
    inserted = np.setdiff1d(new_nodes, old_nodes, assume_unique=True)
    return fill_new_nodes(bg, Ubg, inserted, method, known=known, centre=centre)[new_nodes].ravel()
