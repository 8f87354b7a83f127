"""Node transfer (paper §5.4, Eqs. 27-34) and the split/merge criteria (§5.2, Eqs. 25-26).

Tolerances: "round-off" checks use 1e-12 relative to the problem's lengths (a few dozen flops of
O(1) numbers, measured ~1e-15); convergence orders are checked on the ratio of errors under halving
(an order p gives 2^p; the bounds leave room for the next term of the series only).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from solidshell import Fabric, ShellMesh
from solidshell.adapt import criteria as C
from solidshell.adapt.settings import parse_adapt
from solidshell.adapt.transfer import Edges, dk_midedge, fill_new_nodes, linear_midedge, serendipity_centre
from solidshell.errors import InputError
from solidshell.model import Model
from verification.adapt_transfer import refine

RNG = np.random.default_rng(20150601)


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _rigid(X, Xn, Q, t):
    """States (K,6) of nodes at X with directors Xn under x -> Q x + t."""
    return np.concatenate([X @ Q.T + t - X, Xn @ Q.T - Xn], axis=-1)


# ----------------------------------------------------------------------------- DK: rigid motions
def test_dk_rigid_motion_is_exact_for_any_geometry():
    K = 200
    XoA, XoB, XoE = RNG.normal(size=(3, K, 3))
    # M off the chord (as on a curved boundary) and not at its middle; directors tilted from the
    # normal of the plane E-A-B (only their side matters) and not unit
    n = _unit(np.cross(XoB - XoA, XoE - XoA))
    XoM = 0.5 * (XoA + XoB) + 0.2 * RNG.normal(size=(K, 3))
    XnA, XnB, XnM = (n + 0.4 * RNG.normal(size=(K, 3))) * RNG.uniform(0.8, 1.2, size=(3, K, 1))
    Q = Rotation.random(K, random_state=1).as_matrix()
    t = RNG.normal(size=(K, 3)) * 10.0

    def move(X, Xn):
        return np.concatenate([np.einsum("kij,kj->ki", Q, X) + t - X, np.einsum("kij,kj->ki", Q, Xn) - Xn], axis=-1)

    UA, UB, UE = move(XoA, XnA), move(XoB, XnB), move(XoE, XnA)
    for stretch in ("length", "paper"):
        UM = dk_midedge(Edges(XoA, XoB, XoE, XoM, XnA, XnB, XnM), UA, UB, UE, stretch=stretch)
        # the exact rigid image of M and its director; measured 1e-14 on lengths ~10
        err = np.abs(UM - move(XoM, XnM)).max()
        assert err < 1e-12 * 10.0, (stretch, err)


def test_dk_zero_state_gives_zero():
    XoA, XoB, XoE = np.eye(3)[None, [0, 1, 2]].transpose(1, 0, 2)
    Xn = np.array([[0.0, 0.0, 1.0]])
    Z = np.zeros((1, 6))
    UM = dk_midedge(Edges(XoA, XoB, np.array([[0.3, 0.9, 0.0]]), 0.5 * (XoA + XoB), Xn, Xn, Xn), Z, Z, Z)
    assert np.abs(UM).max() < 1e-15


# ----------------------------------------------------------------------------- DK: reduction to Eq. (32)
def _paper_formulas(XoA, XoB, XoE, XnA, XnB, UA, UB, UE):
    """Eqs. (30)-(34) written out literally for one edge, M at the chord middle, X_n = the initial
    normal of plane E-A-B (so that the co-rotated director of M is n_z')."""
    xA, xB, xE = XoA + UA[:3], XoB + UB[:3], XoE + UE[:3]
    ny = _unit(xB - xA)
    nz = _unit(np.cross(ny, xE - xA))
    if nz @ (XnA + UA[3:]) < 0:
        nz = -nz
    nx = np.cross(ny, nz)
    L = np.linalg.norm(XoB - XoA)
    xnA, xnB = XnA + UA[3:], XnB + UB[3:]
    u_nA, v_nA, w_nA = nx @ xnA, ny @ xnA, nz @ xnA - 1.0  # Eq. (30)
    u_nB, v_nB, w_nB = nx @ xnB, ny @ xnB, nz @ xnB - 1.0  # Eq. (31)
    u_oA = v_oA = w_oA = u_oB = w_oB = 0.0
    v_oB = np.linalg.norm(xB - xA) - L
    u_oM = 0.5 * (u_oA + u_oB)  # Eq. (32)
    v_oM = 0.5 * (v_oA + v_oB)
    w_oM = 0.5 * (w_oA + w_oB) - L / 8.0 * (v_nA - v_nB)
    v_nM = 1.5 / L * (w_oA - w_oB) - 0.25 * (v_nA + v_nB)
    u_nM, w_nM = 0.5 * (u_nA + u_nB), 0.5 * (w_nA + w_nB)
    XoM, XnM = 0.5 * (XoA + XoB), _unit(XnA + XnB)
    UcoM = UA[:3] + L / 2.0 * ny - (XoM - XoA)  # Eq. (34)
    UcnM = nz - XnM
    return np.concatenate(
        [
            UcoM + u_oM * nx + v_oM * ny + w_oM * nz,  # Eq. (33)
            UcnM + u_nM * nx + v_nM * ny + w_nM * nz,
        ]
    )


@pytest.mark.parametrize("size", [1e-3, 0.3])
def test_dk_reduces_to_eq32_in_the_papers_frame(size):
    """A flat quad A, B, (C), E with normal directors, M the chord middle, an arbitrary (not small,
    not rigid) state: stretch="paper" is Eqs. (30)-(34) to round-off; the default director differs
    from it only in its length, by second order in the director deviations."""
    XoA, XoB, XoE = np.array([0.0, 0, 0]), np.array([0.3, 1.1, 0]), np.array([-0.9, 0.2, 0])
    Xn = np.array([0.0, 0.0, 1.0])
    Q = Rotation.from_rotvec([0.3, -0.5, 0.7]).as_matrix()  # a general plane, not z = 0
    XoA, XoB, XoE, Xn = XoA @ Q.T, XoB @ Q.T, XoE @ Q.T, Xn @ Q.T
    diffs = []
    for scale in (size, size / 2):
        UA, UB, UE = (
            np.array(
                [[0.1, -0.2, 0.3, 0.2, -0.1, 0.05], [-0.1, 0.3, 0.2, -0.3, 0.2, -0.1], [0.2, 0.1, -0.3, 0.0, 0.0, 0.0]]
            )
            * scale
        )
        ref = _paper_formulas(XoA, XoB, XoE, Xn, Xn, UA, UB, UE)
        args = (
            Edges(XoA[None], XoB[None], XoE[None], 0.5 * (XoA + XoB)[None], Xn[None], Xn[None], Xn[None]),
            UA[None],
            UB[None],
            UE[None],
        )
        paper = dk_midedge(*args, stretch="paper")[0]
        length = dk_midedge(*args)[0]
        # round-off of O(1) numbers (measured ~1e-16)
        assert np.abs(paper - ref).max() < 1e-13
        # the position does not depend on the stretch rule at all
        assert np.abs(length[:3] - ref[:3]).max() < 1e-13
        diffs.append(np.abs(length[3:] - ref[3:]).max())
        # the two directors differ along n_z' only (u_nM, v_nM are Eq. 32's in both)
        xA, xB, xE = XoA + UA[:3], XoB + UB[:3], XoE + UE[:3]
        nz = _unit(np.cross(_unit(xB - xA), xE - xA))
        d = length[3:] - ref[3:]
        assert np.linalg.norm(d - (d @ nz) * nz) < 1e-13
    # second order: halving the state quarters the difference (measured ratio 3.9-4.0)
    assert 3.5 < diffs[0] / diffs[1] < 4.5


# ----------------------------------------------------------------------------- DK: cylindrical bend
def _bend_states(kappa, L):
    """Edge A (0,0,0) - B (0,L,0), E (L,0,0), M (0,L/2,0), directors +z, bent onto the cylinder
    (x, y, 0) -> (x, sin(k y)/k, (1 - cos(k y))/k) with the cylinder's normals as directors."""
    P = np.array([[0, 0, 0], [0, L, 0], [L, 0, 0], [0, L / 2, 0]], float)
    y = P[:, 1]
    x = np.stack([P[:, 0], np.sin(kappa * y) / kappa, (1 - np.cos(kappa * y)) / kappa], 1)
    xn = np.stack([0 * y, -np.sin(kappa * y), np.cos(kappa * y)], 1)
    Xn = np.tile([0.0, 0.0, 1.0], (4, 1))
    return P, Xn, np.concatenate([x - P, xn - Xn], 1)


def _bend_errors(kappa, L, method):
    P, Xn, U = _bend_states(kappa, L)
    if method == "dk":
        UM = dk_midedge(Edges(P[[0]], P[[1]], P[[2]], P[[3]], Xn[[0]], Xn[[1]], Xn[[3]]), U[[0]], U[[1]], U[[2]])[0]
    else:
        UM = linear_midedge(U[[0]], U[[1]])[0]
    return np.linalg.norm(UM[:3] - U[3, :3]), np.linalg.norm(UM[3:] - U[3, 3:])


def test_dk_cylindrical_bend_puts_m_on_the_arc_to_fourth_order():
    kappa = 2.0  # 1/cm: a fold of radius 0.5 cm in wool
    Ls = [0.4, 0.2, 0.1]  # bend angles kappa L = 0.8, 0.4, 0.2 rad
    pos = [_bend_errors(kappa, L, "dk") for L in Ls]
    for (ep, en), L in zip(pos, Ls):
        # the sagitta L/4 sin(kL/2) against (1 - cos(kL/2))/k: error k^3 L^4 / 384 + O(k^5 L^6)
        # (measured within 0.8 % of the leading term at kL = 0.8)
        assert ep == pytest.approx(kappa**3 * L**4 / 384.0, rel=0.02)
        # the DK director is the cylinder's exact normal (v_nM = 0 by symmetry, unit length)
        assert en < 1e-14
    # order 4 in L: halving L divides the error by 16 (measured 15.7, 15.9)
    for a, b in zip(pos, pos[1:]):
        assert 15.0 < a[0] / b[0] < 16.5
    # linear transfer misses the arc by the sagitta k L^2 / 8 (order 2: ratio 4) and shortens the
    # director by (kL)^2/8: 48 / (kL)^2 times DK's position error, 300 times at kL = 0.4
    lin = [_bend_errors(kappa, L, "linear") for L in Ls]
    for (ep, en), L in zip(lin, Ls):
        assert ep == pytest.approx(kappa * L**2 / 8.0, rel=0.02)
        assert en == pytest.approx((kappa * L) ** 2 / 8.0, rel=0.02)
    assert lin[1][0] / pos[1][0] == pytest.approx(48.0 / (kappa * Ls[1]) ** 2, rel=0.03)


def test_dk_literal_eq32_shortens_the_director_on_a_bend():
    """Eq. (32)'s w_nM = (w_nA + w_nB)/2 reads the rotation of the end directors against the chord
    as a shrink: |x_nM| = cos(k L / 2), as linear transfer; the default keeps the length."""
    kappa, L = 2.0, 0.4
    P, Xn, U = _bend_states(kappa, L)
    args = (Edges(P[[0]], P[[1]], P[[2]], P[[3]], Xn[[0]], Xn[[1]], Xn[[3]]), U[[0]], U[[1]], U[[2]])
    paper = dk_midedge(*args, stretch="paper")[0]
    length = dk_midedge(*args)[0]
    assert np.linalg.norm(Xn[3] + paper[3:]) == pytest.approx(np.cos(kappa * L / 2), abs=1e-14)
    assert np.linalg.norm(Xn[3] + length[3:]) == pytest.approx(1.0, abs=1e-14)


def test_dk_averages_the_director_stretch():
    """Directors stretched by 1.1 at A and 1.3 at B on a flat, unmoved edge: M gets 1.2 (and the
    same direction, the normal)."""
    XoA, XoB, XoE, XoM = (
        np.array([[0.0, 0, 0]]),
        np.array([[1.0, 0, 0]]),
        np.array([[0.0, 1, 0]]),
        np.array([[0.5, 0, 0]]),
    )
    Xn = np.array([[0.0, 0, 1]])
    UA = np.array([[0, 0, 0, 0, 0, 0.1]])
    UB = np.array([[0, 0, 0, 0, 0, 0.3]])
    for stretch in ("length", "paper"):
        UM = dk_midedge(Edges(XoA, XoB, XoE, XoM, Xn, Xn, Xn), UA, UB, 0 * UA, stretch=stretch)
        assert np.allclose(UM, [[0, 0, 0, 0, 0, 0.2]], atol=1e-15)


# ----------------------------------------------------------------------------- serendipity centre
def test_serendipity_centre_reproduces_quadratics():
    """On a parallelogram (an affine image of the reference square) every quadratic in x, y is in
    the serendipity space, so the centre value is exact (to round-off)."""
    K = 50
    c0 = RNG.normal(size=(K, 2))
    a, b = RNG.normal(size=(2, K, 2))
    ref = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float)
    mids = 0.5 * (ref + np.roll(ref, -1, axis=0))

    def phys(r):
        return c0[:, None] + r[None, :, :1] * a[:, None] + r[None, :, 1:] * b[:, None]

    coef = RNG.normal(size=(K, 6, 6))  # 6 components, 6 monomials each

    def f(p):
        x, y = p[..., 0], p[..., 1]
        mono = np.stack([np.ones_like(x), x, y, x * x, x * y, y * y], -1)
        return np.einsum("kcm,knm->knc", coef, mono)

    got = serendipity_centre(f(phys(ref)), f(phys(mids)))
    want = f(c0[:, None])[:, 0]
    assert np.abs(got - want).max() < 1e-12 * np.abs(want).max()


# ----------------------------------------------------------------------------- fill_new_nodes
def _sheet(nx=3, ny=2, h=1.0):
    """A flat nx x ny sheet of h x h quads in the x-y plane."""
    x, y = np.meshgrid(np.linspace(0, nx * h, nx + 1), np.linspace(0, ny * h, ny + 1))
    X = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    n0 = (j * (nx + 1) + i).ravel()
    return ShellMesh(X, quads=np.column_stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1]))


def test_fill_new_nodes_rigid_motion_two_levels():
    bg, _ = refine(_sheet(), levels=2)
    Q = Rotation.from_rotvec([0.4, 1.1, -0.6]).as_matrix()
    t = np.array([3.0, -1.0, 2.0])
    exact = _rigid(bg.Xo, bg.Xn, Q, t)
    N0 = int(np.sum(bg.node_level == 0))
    U = np.zeros_like(exact)
    U[:N0] = exact[:N0]
    new = RNG.permutation(np.arange(N0, len(U)))  # any order: filled level by level
    for method in ("dk", "linear"):
        got = fill_new_nodes(bg, U, new, method=method)
        assert np.abs(got[:N0] - U[:N0]).max() == 0.0  # known rows untouched
        if method == "dk":
            # measured 4e-15 on a 3 x 2 cm sheet
            assert np.abs(got - exact).max() < 1e-12 * 3.0
    # one call over both levels equals two calls, level by level
    lv1 = new[bg.node_level[new] == 1]
    step = fill_new_nodes(bg, U, lv1)
    step = fill_new_nodes(bg, step, new[bg.node_level[new] == 2])
    assert np.array_equal(step, fill_new_nodes(bg, U, new))


def test_fill_new_nodes_bend_uses_dk_and_serendipity():
    """On a one-element background bent onto a cylinder, the mid-edge nodes are dk_midedge of their
    [A, B, E] and the centre the serendipity value of the corners and those mids."""
    bg, _ = refine(_sheet(1, 1), levels=1)
    kappa = 1.5
    X = bg.Xo
    x = np.stack([X[:, 0], np.sin(kappa * X[:, 1]) / kappa, (1 - np.cos(kappa * X[:, 1])) / kappa], 1)
    xn = np.stack([0 * X[:, 0], -np.sin(kappa * X[:, 1]), np.cos(kappa * X[:, 1])], 1)
    exact = np.concatenate([x - X, xn - bg.Xn], 1)
    U = exact.copy()
    U[4:] = np.nan  # the unknown rows must not be read
    got = fill_new_nodes(bg, U, np.arange(4, 9), centre="serendipity")
    mids = np.arange(4, 8)
    A, B, E = bg.mid_parent[mids].T
    want = dk_midedge(Edges(X[A], X[B], X[E], X[mids], bg.Xn[A], bg.Xn[B], bg.Xn[mids]), exact[A], exact[B], exact[E])
    assert np.array_equal(got[mids], want)
    cp = bg.centre_parent[8]
    assert np.allclose(got[8], serendipity_centre(got[cp[:4]][None], got[cp[4:]][None])[0], atol=1e-15)
    # and the bent state is reproduced to the DK order (edges of 1 cm and 0 at kL = 1.5 across y):
    # measured 0.0089 cm (kappa^3 L^4 / 384 = 0.0088 on the y edges; the centre inherits it)
    assert np.abs(got[:, :3] - exact[:, :3]).max() < 0.012


def test_fill_new_nodes_centre_with_inactive_mids_computed_on_the_fly():
    """A centre inserted with only two of its mid-edge nodes (a transition element): the other two
    are derived by DK regardless (§5.4) and not written; on a one-element mesh that equals
    inserting all four."""
    bg, _ = refine(_sheet(1, 1), levels=1)
    U = np.zeros((len(bg.Xo), 6))
    U[:4] = RNG.normal(size=(4, 6)) * 0.05
    full = fill_new_nodes(bg, U, np.arange(4, 9))
    known = np.zeros(len(U), bool)
    known[:4] = True
    part_in = U.copy()
    part_in[[6, 7]] = 123.0  # stale values of inactive nodes
    part = fill_new_nodes(bg, part_in, [4, 5, 8], known=known)
    assert np.array_equal(part[[4, 5]], full[[4, 5]])
    assert np.allclose(part[8], full[8], atol=1e-15)
    assert np.all(part[[6, 7]] == 123.0)  # not written
    # linear: the centre of linear mids is the corners' average
    lin = fill_new_nodes(bg, part_in, [8], method="linear", known=known)
    assert np.allclose(lin[8], U[:4].mean(0), atol=1e-15)


def test_kirchhoff_centre_director():
    """centre="kirchhoff" (the default): rigid motions stay exact; on a cylindrical bend the centre director is
    the exact normal; on any state the centre's transverse shear strains x_n.x_o,xi - X_n.X_o,xi
    (serendipity tangents) vanish and the position is the serendipity one."""
    bg, _ = refine(_sheet(2, 2), levels=1)
    N0 = int(np.sum(bg.node_level == 0))
    new = np.arange(N0, len(bg.Xo))
    Q = Rotation.from_rotvec([-0.7, 0.2, 1.3]).as_matrix()
    exact = _rigid(bg.Xo, bg.Xn, Q, np.array([1.0, 2.0, 3.0]))
    got = fill_new_nodes(bg, exact, new, centre="kirchhoff")
    assert np.abs(got - exact).max() < 1e-12 * 2.0
    kappa, X = 1.2, bg.Xo
    x = np.stack([X[:, 0], np.sin(kappa * X[:, 1]) / kappa, (1 - np.cos(kappa * X[:, 1])) / kappa], 1)
    xn = np.stack([0 * X[:, 0], -np.sin(kappa * X[:, 1]), np.cos(kappa * X[:, 1])], 1)
    bend = np.concatenate([x - X, xn - bg.Xn], 1)
    got = fill_new_nodes(bg, bend, new, centre="kirchhoff")
    cen = np.flatnonzero(bg.centre_parent[:, 0] >= 0)
    # measured 2e-16: the centre lies on the symmetry plane of its element's bend
    assert np.abs(got[cen, 3:] - bend[cen, 3:]).max() < 1e-13
    # a random state: zero shear at the centre, |x_n| = the interpolated stretch
    U = np.zeros_like(bend)
    U[:N0] = RNG.normal(size=(N0, 6)) * 0.1
    ser = fill_new_nodes(bg, U, new, centre="serendipity")
    kir = fill_new_nodes(bg, U, new)  # the default
    assert np.array_equal(ser[:, :3], kir[:, :3])
    cp = bg.centre_parent[cen]
    xm = bg.Xo[cp[:, 4:]] + kir[cp[:, 4:], :3]
    for a, b in ((1, 3), (2, 0)):
        t, T = xm[:, a] - xm[:, b], bg.Xo[cp[:, 4 + a]] - bg.Xo[cp[:, 4 + b]]
        g = np.sum((bg.Xn[cen] + kir[cen, 3:]) * t, 1) - np.sum(bg.Xn[cen] * T, 1)
        assert np.abs(g).max() < 1e-13
    with pytest.raises(ValueError, match="centre"):
        fill_new_nodes(bg, U, new, centre="bilinear")


def test_dk_refinement_of_a_bent_sheet_adds_little_energy_linear_a_lot():
    """The study's claim in miniature (verification/adapt_transfer.py): a wool sheet whose coarse
    nodes lie on a cylinder (kappa = 1 /cm) is refined 1-to-4; the strain energy of the fine mesh
    above that of the exact cylinder state is tiny with DK and large with linear transfer, whose
    chord-and-averaged-director kink loads the stiff transverse shear."""
    kappa, excess = 1.0, {}
    for h in (0.5, 0.25):  # coarse bend angle per element 0.5, 0.25
        bg, fine = refine(_sheet(4, 4, h), levels=1)
        X = bg.Xo
        x = np.stack([X[:, 0], np.sin(kappa * X[:, 1]) / kappa, (1 - np.cos(kappa * X[:, 1])) / kappa], 1)
        xn = np.stack([0 * X[:, 0], -np.sin(kappa * X[:, 1]), np.cos(kappa * X[:, 1])], 1)
        exact = np.concatenate([x - X, xn - bg.Xn], 1)
        model = Model(fine, Fabric.wool())
        E = model.energy(exact)
        new = np.flatnonzero(bg.node_level == 1)
        for method in ("dk", "linear"):
            U = fill_new_nodes(bg, exact, new, method=method)
            excess[method, h] = (model.energy(U) - E) / E
    # measured: DK +0.70 % and +0.011 %, two parts membrane to one part shear, both from the
    # O(k^3 L^4) mid-node error: strains ~ k^4 L^3, excess energy ~ L^8 on a sheet of area ~ L^2,
    # i.e. ~ L^6 relative (ratio 63); linear +9232 % and +2431 %, all transverse shear:
    # C_t (kL/4)^2 over the bending energy B k^2, ~ L^2 (ratio 3.8)
    assert 0.0 < excess["dk", 0.5] < 0.01 and excess["dk", 0.25] < 2e-4
    assert excess["linear", 0.5] > 50.0 and excess["linear", 0.25] > 15.0
    assert excess["dk", 0.5] / excess["dk", 0.25] > 40.0
    assert 3.0 < excess["linear", 0.5] / excess["linear", 0.25] < 4.5


def test_fill_new_nodes_refuses_unknown_parents_and_level0_nodes():
    bg, _ = refine(_sheet(1, 1), levels=2)
    U = np.zeros((len(bg.Xo), 6))
    level2 = np.flatnonzero(bg.node_level == 2)
    known = bg.node_level == 0
    with pytest.raises(ValueError, match="neither known nor"):
        fill_new_nodes(bg, U, level2, known=known)
    with pytest.raises(ValueError, match="level-0"):
        fill_new_nodes(bg, U, [0])
    with pytest.raises(ValueError, match="method"):
        fill_new_nodes(bg, U, level2, method="cubic")


# ----------------------------------------------------------------------------- criteria
def test_bending_strain_of_a_cylindrical_bend_is_its_curvature():
    """The meaning of const: ||eps_b|| (Model.bending_strain, Eq. 6) of a cylindrical bend is kappa
    up to O((kappa L)^2), so ||eps_b|| L is the bend angle across an element."""
    kappa = 0.8
    for h in (1.0, 0.25):  # kappa L = 0.8 and 0.2 rad
        mesh = _sheet(6, 4, h)
        X = mesh.nodes
        x = np.stack([X[:, 0], np.sin(kappa * X[:, 1]) / kappa, (1 - np.cos(kappa * X[:, 1])) / kappa], 1)
        xn = np.stack([0 * X[:, 0], -np.sin(kappa * X[:, 1]), np.cos(kappa * X[:, 1])], 1)
        eb = Model(mesh, Fabric.wool()).bending_strain(np.concatenate([x - X, xn - mesh.directors], 1))
        # measured kappa (1 - 0.98 (kappa h)^2 / 12) at kappa h = 0.8 and 0.999 x that at 0.2: the
        # flat element's chord-based curvature; 5 % of the deficit admits the next term only
        deficit = 1.0 - eb / kappa
        assert np.allclose(deficit, (kappa * h) ** 2 / 12.0, rtol=0.05)


def test_thresholds_refused():
    for const, eps, words in [
        (0.2, 0.2, r"eps = 0\.2 must be less than const = 0\.2 \(Eq\. 26\)"),
        (0.1, 0.2, r"eps = 0\.2 must be less than const = 0\.1 \(Eq\. 26\)"),
        (0.0, -0.1, r"const = 0\.0: must be a positive number \(Eq\. 25\)"),
        (-1.0, 0.5, r"const = -1\.0: must be a positive number"),
        (0.5, 0.0, r"eps = 0\.0: must be a positive number \(Eq\. 26\)"),
        (float("nan"), 0.1, r"const = nan: must be a positive number"),
        (0.5, float("inf"), r"eps = inf: must be a positive number"),
        ("a", 0.1, r"const = 'a', eps = 0\.1: numbers expected"),
    ]:
        with pytest.raises(InputError, match=words):
            C.check_thresholds(const, eps)
        with pytest.raises(InputError, match=words):
            C.mark([1.0], [[0, 0]], [np.ones(1)], const=const, eps=eps)
    assert C.check_thresholds(C.DEFAULT_CONST, C.DEFAULT_EPS) == (0.5, 0.2)
    with pytest.raises(InputError, match="eps"):
        parse_adapt({"const": 0.3, "eps": 0.3})
    with pytest.raises(InputError, match="unknown"):
        parse_adapt({"constant": 0.3})
    s = parse_adapt(None)
    assert (s.const, s.eps) == (C.DEFAULT_CONST, C.DEFAULT_EPS)


def _two_level_L():
    bg, _ = refine(_sheet(2, 1), levels=2)  # 1 x 1 cm level-0 quads
    return bg, C.level_side_lengths(bg)


def test_side_lengths_per_level():
    bg, L = _two_level_L()
    assert [len(x) for x in L] == [2, 8, 32]
    assert np.allclose(L[0], 1.0) and np.allclose(L[1], 0.5) and np.allclose(L[2], 0.25)


def test_split_marks_eq25():
    _, L = _two_level_L()
    leaves = np.array([[0, 0], [1, 4], [1, 5], [2, 0], [2, 1]])
    c = 0.5
    # just above / below const / L_i per leaf; level 2 is the top: never split
    eb = np.array([c / 1.0 * 1.001, c / 0.5 * 0.999, c / 0.5 * 1.001, 10.0, 0.0])
    m = C.mark(eb, leaves, L, const=c, eps=0.2)
    assert m.split.tolist() == [True, False, True, False, False]
    m = C.mark(eb, leaves, L, const=c, eps=0.2, max_level=1)  # no level-2 children now
    assert m.split.tolist() == [True, False, False, False, False]
    m = C.mark(eb, leaves, L, const=c, eps=0.2, max_level=0)
    assert not m.split.any()


def test_merge_marks_eq26():
    _, L = _two_level_L()
    c, e = 0.5, 0.2
    lim = (c - e) / 1.0  # merging level-1 children of (0,1)
    lim2 = (c - e) / 0.5  # merging level-2 children of (1,p)
    leaves = np.array(
        [
            [1, 4],
            [1, 5],
            [1, 6],
            [1, 7],  # the four children of (0,1)
            [2, 0],
            [2, 1],
            [2, 2],
            [2, 3],  # the four children of (1,0)
            [2, 4],
            [2, 5],
            [2, 6],
        ]
    )  # three of (1,1): one is split further
    eb = np.array([lim, lim * 0.5, 0.0, lim * 0.99, lim2 * 1.001, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    m = C.mark(eb, leaves, L, const=c, eps=e)
    assert m.merge.tolist() == [[0, 1]]  # (1,0) vetoed by one child; (1,1) incomplete
    eb[4] = lim2
    m = C.mark(eb, leaves, L, const=c, eps=e)
    assert m.merge.tolist() == [[0, 1], [1, 0]]
    assert not m.split.any()


def test_leaf_bending_strain_is_the_max_over_a_leafs_elements():
    elem_leaf = np.array([[1, 3], [0, 2], [1, 3], [1, 3], [0, 2]])
    leaves, eb = C.leaf_bending_strain([0.1, 0.5, 0.7, 0.2, 0.4], elem_leaf)
    assert leaves.tolist() == [[0, 2], [1, 3]]
    assert eb.tolist() == [0.5, 0.7]


def test_leaf_alignment_is_the_min_over_a_leafs_elements():
    elem_leaf = np.array([[1, 3], [0, 2], [1, 3], [1, 3], [0, 2]])
    leaves, nd = C.leaf_alignment([0.9, 0.5, -0.2, 0.7, 0.95], elem_leaf)
    assert leaves.tolist() == [[0, 2], [1, 3]]
    assert nd.tolist() == [0.5, -0.2]


def test_guard_splits_below_its_threshold_and_keeps_low_siblings_apart():
    """criteria.guard: a leaf whose lowest n_p . d_p is below the threshold g splits, up to max_level,
    whatever Eq. (25) said; four siblings merge only when each reads at least cos(acos(g) / 2) (the
    parent's angle halved: 0.9487 for g = 0.8); g = -1 changes nothing.  Thresholds are the exact
    cut points +- 1e-3, far above round-off and far below the values' spacing."""
    _, L = _two_level_L()
    g = 0.8
    half = np.cos(0.5 * np.arccos(g))
    leaves = np.array([[0, 0], [1, 4], [1, 5], [1, 6], [1, 7], [2, 0], [2, 1], [2, 2], [2, 3]])
    eb = np.zeros(len(leaves))  # flat: Eq. (26) merges both parents
    m = C.mark(eb, leaves, L, const=0.5, eps=0.2)
    assert m.merge.tolist() == [[0, 1], [1, 0]] and not m.split.any()
    nd = np.array([g - 1e-3, g + 1e-3, 1.0, 1.0, half - 1e-3, 1.0, 1.0, half + 1e-3, 0.5])
    out = C.guard(m, nd, leaves, g, max_level=2)
    assert out.split.tolist() == [True, False, False, False, False, False, False, False, False]
    # (0,1)'s child (1,7) reads below cos(acos(g)/2): vetoed; (1,0)'s child (2,3) reads 0.5 < g:
    # below max_level it would split -- at max_level 2 it cannot, and its merge is vetoed too
    assert out.merge.tolist() == []
    nd[8] = 1.0
    out = C.guard(m, nd, leaves, g, max_level=2)
    assert out.merge.tolist() == [[1, 0]]
    assert C.guard(m, nd, leaves, g, max_level=0).split.sum() == 0  # capped at level 0
    off = C.guard(m, np.full(len(leaves), -1.0), leaves, C.GUARD_OFF, max_level=2)
    assert off is m
    with pytest.raises(ValueError, match=r"guard threshold 1\.0 must lie in \[-1, 1\)"):
        C.guard(m, nd, leaves, 1.0, max_level=2)
