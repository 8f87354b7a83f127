"""solidshell.analysis on synthetic shapes with known answers."""

import numpy as np
import pytest

from solidshell import ShellMesh
from solidshell.analysis import (
    asymmetry,
    boundary_loops,
    drape_coefficient,
    drape_summary,
    fold_count,
    polygon_area,
    projected_boundary,
    radius_profile,
)


def star(R=10.0, a=0.0, k=0, n=2000, phase=0.0, center=(0.0, 0.0)):
    t = 2 * np.pi * np.arange(n) / n
    r = R * (1 + a * np.cos(k * (t - phase)))
    return np.column_stack([center[0] + r * np.cos(t), center[1] + r * np.sin(t)])


def annulus_mesh(r_in=5.0, r_out=10.0, nr=4, nt=48):
    """Structured quad annulus (counter-clockwise quads, directors +Z)."""
    rr = np.linspace(r_in, r_out, nr + 1)
    tt = 2 * np.pi * np.arange(nt) / nt
    R, T = np.meshgrid(rr, tt, indexing="ij")  # node (i, j) -> i*nt + j
    nodes = np.column_stack([(R * np.cos(T)).ravel(), (R * np.sin(T)).ravel(), np.zeros(R.size)])
    i, j = np.meshgrid(np.arange(nr), np.arange(nt), indexing="ij")
    i, j = i.ravel(), j.ravel()
    jn = (j + 1) % nt
    quads = np.column_stack([i * nt + j, (i + 1) * nt + j, (i + 1) * nt + jn, i * nt + jn])
    return ShellMesh(nodes, quads=quads, node_sets={"clamped": np.arange(nt)})


# ------------------------------------------------------------------ polygons
def test_shoelace_square_and_orientation():
    sq = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
    assert polygon_area(sq) == pytest.approx(2.0)
    assert polygon_area(sq[::-1]) == pytest.approx(-2.0)


@pytest.mark.parametrize("k", [4, 8, 10, 12])
def test_cosine_star_folds_and_area(k):
    R, a = 10.0, 0.08
    p = star(R, a, k, n=4000)
    # shoelace of a 4000-gon converges as O(n^-2): 1e-5 relative is far above the discretisation
    assert polygon_area(p) == pytest.approx(np.pi * R**2 * (1 + a**2 / 2), rel=1e-5)
    n, ang = fold_count(p, return_angles=True)
    assert n == k
    # the folds sit at the maxima theta = 2 pi m / k
    expect = 2 * np.pi * np.arange(k) / k
    d = np.abs((np.sort(ang)[:, None] - expect[None, :] + np.pi) % (2 * np.pi) - np.pi).min(axis=1)
    assert d.max() < np.radians(1.0)


def test_circle_has_no_folds_and_is_symmetric():
    p = star(10.0, n=1000)
    assert fold_count(p) == 0
    a = asymmetry(p)
    assert max(a.values()) < 1e-4  # a 1000-gon about its centre: chord sag ~ (pi/1000)^2 / 2
    _, r = radius_profile(p, n_theta=360)
    assert np.allclose(r, 10.0, rtol=1e-4)


def test_rounded_square_has_four_folds():
    t = np.linspace(0, 2 * np.pi, 1600, endpoint=False)
    c, s = np.cos(t), np.sin(t)
    r = (np.abs(c) ** 4 + np.abs(s) ** 4) ** -0.25  # superellipse |x|^4 + |y|^4 = 1
    p = np.column_stack([r * c, r * s]) * 7.0
    n, ang = fold_count(p, return_angles=True)
    assert n == 4
    assert np.allclose(np.sort(np.degrees(ang)), [45, 135, 225, 315], atol=1.0)
    a = asymmetry(p)
    assert max(a.values()) < 1e-3


def test_ellipse_two_folds_and_rot90_asymmetry():
    t = np.linspace(0, 2 * np.pi, 1000, endpoint=False)
    p = np.column_stack([12 * np.cos(t), 8 * np.sin(t)])
    assert fold_count(p) == 2
    a = asymmetry(p)
    assert a["mirror_x"] < 1e-3 and a["mirror_y"] < 1e-3
    assert a["rot90"] == pytest.approx(4 / 10, rel=0.05)  # (12 - 8) / mean radius (~10)


def test_off_centre_and_lopsided_shape():
    p = star(10.0, 0.1, 4, phase=0.3, center=(3.0, -2.0))
    assert fold_count(p, center=(3.0, -2.0)) == 4
    a = asymmetry(p, center=(3.0, -2.0))
    assert a["mirror_x"] > 0.05  # rotated by 0.3 rad: no longer mirror-symmetric
    q = star(10.0, 0.1, 3)  # three-fold: mirror about X but not 90-deg symmetric
    a = asymmetry(q)
    assert a["mirror_x"] < 1e-3 and a["rot90"] > 0.1


@pytest.mark.parametrize("k", [0, 4, 8, 12])
def test_noise_robustness(k):
    rng = np.random.default_rng(k)
    R, a = 10.0, 0.06
    p = star(R, a, k, n=1500)
    # 0.3 % radial jitter on every vertex (~10x the sag of the coarsest paper mesh boundary)
    p = p * (1 + 0.003 * rng.standard_normal(len(p)))[:, None]
    assert fold_count(p) == k


def test_threshold_documented_behaviour():
    # a fold whose depth is below 1 % of the radius is not counted; above it is
    assert fold_count(star(10.0, 0.003, 6)) == 0  # peak-to-trough 0.6 % of R
    assert fold_count(star(10.0, 0.01, 6)) == 6  # peak-to-trough 2 %


# ------------------------------------------------------------------ meshes
def test_boundary_loops_of_annulus():
    m = annulus_mesh()
    loops = boundary_loops(m.boundary_edges())
    assert len(loops) == 2
    X = m.nodes[:, :2]
    areas = sorted(polygon_area(X[lp]) for lp in loops)
    # inner loop clockwise (negative), outer counter-clockwise
    assert areas[0] < 0 < areas[1]


def test_projected_boundary_and_dc_of_deformed_annulus():
    m = annulus_mesh(5.0, 10.0, nr=2, nt=256)
    poly, nodes = projected_boundary(m, return_nodes=True)
    assert polygon_area(poly) > 0
    assert np.allclose(np.hypot(*poly.T), 10.0)
    A_sheet = np.pi * 10.0**2  # flat circle (polygonal area of the mesh + pedestal)
    A_ped = np.pi * 5.0**2
    # undeformed: DC = 1 (areas of the 256-gon on both sides, so compare with the mesh's own)
    s = drape_summary(m, None, pedestal_area=A_ped, sheet_area=polygon_area(poly))
    assert s["drape_coefficient"] == pytest.approx(1.0)
    assert s["fold_count"] == 0
    assert np.allclose(s["center"], 0.0, atol=1e-12)
    # deform: every node moves to radius r0 + (r - r0) * f(theta) and drops in z
    X = m.nodes
    r = np.hypot(X[:, 0], X[:, 1])
    th = np.arctan2(X[:, 1], X[:, 0])
    rn = 5.0 + (r - 5.0) * 0.5 * (1 + 0.3 * np.cos(8 * th))
    U = np.zeros((m.n_nodes, 6))
    U[:, 0] = rn * np.cos(th) - X[:, 0]
    U[:, 1] = rn * np.sin(th) - X[:, 1]
    U[:, 2] = -(r - 5.0) * 0.8
    s = drape_summary(m, U, pedestal_area=A_ped, sheet_area=A_sheet)
    # outer radius 5 + 2.5 (1 + 0.3 cos 8t) = 7.5 (1 + 0.1 cos 8t): area pi 7.5^2 (1 + 0.005); the 256-gon (32 vertices per
    # wave) under-estimates it by chord sag, ~0.1 %
    A_exact = np.pi * 7.5**2 * (1 + 0.1**2 / 2)
    assert s["projected_area"] == pytest.approx(A_exact, rel=2e-3)
    assert s["drape_coefficient"] == pytest.approx((A_exact - A_ped) / (A_sheet - A_ped), rel=1e-2)
    assert s["fold_count"] == 8
    assert s["envelope_area"] == pytest.approx(s["projected_area"], rel=5e-3)


def test_drape_coefficient_formula():
    assert drape_coefficient(300.0, 400.0, 100.0) == pytest.approx(200 / 300)
    with pytest.raises(ValueError, match=r"sheet area \(1\.0\) must exceed the pedestal area \(2\.0\)"):
        drape_coefficient(1.0, 1.0, 2.0)


def test_strip_boundary_single_loop():
    nx = 5
    x = np.linspace(0, 5, nx + 1)
    nodes = np.array([[xi, y, 0.0] for y in (0.0, 1.0) for xi in x])
    quads = np.array([[i, i + 1, nx + 2 + i, nx + 1 + i] for i in range(nx)])
    m = ShellMesh(nodes, quads=quads)
    loops = boundary_loops(m.boundary_edges())
    assert len(loops) == 1 and len(loops[0]) == 2 * (nx + 1)
    assert polygon_area(projected_boundary(m)) == pytest.approx(5.0)


def test_paper_pedestal_meshes_undeformed():
    """The flat hanging parts of the paper's pedestal meshes: DC = 1, centre found from the hole,
    a square sheet shows its 4 corners as folds, a disc none."""
    from solidshell.meshing import build_mesh

    m = build_mesh("square_on_square", "8x4x4")  # 20x20 sheet on a 10x10 pedestal
    s = drape_summary(m, None, pedestal_area=100.0)
    assert s["sheet_area"] == pytest.approx(400.0)
    assert s["projected_area"] == pytest.approx(400.0)
    assert s["drape_coefficient"] == pytest.approx(1.0)
    assert np.allclose(s["center"], 0.0, atol=1e-9)
    assert s["fold_count"] == 4
    assert np.allclose(sorted(s["fold_angles_deg"]), [45, 135, 225, 315], atol=1.0)
    assert s["asymmetry_rot90"] < 1e-9
    m = build_mesh("disc_on_disc", "4x40")
    A_ped = np.pi * 6.35**2
    s = drape_summary(m, None, pedestal_area=A_ped)
    # both mesh circles are 40-gons (area factor sin(2pi/40)/(2pi/40) = 0.9959) while A_pedestal is
    # the exact circle: DC = (0.9959 R^2 - r^2) / (0.9959 (R^2 - r^2)) = 0.9986 for R = 2r
    assert s["drape_coefficient"] == pytest.approx(0.99863, abs=2e-5)
    assert s["fold_count"] == 0


def test_numpy_smoothing_and_peaks_match_scipy():
    """analysis.py's own Gaussian smoothing and prominent-peak search (they replace scipy.ndimage
    and scipy.signal, whose import cost ~1.9 s CPU and 54 MB per drape run) against scipy itself:
    the smoothing to round-off (1e-13 of the data: sums of ~17 terms in another order), the peak
    indices exactly, on noisy data, on smoothed drape-like profiles and on flat tops."""
    from scipy.ndimage import gaussian_filter1d
    from scipy.signal import find_peaks

    from solidshell.analysis import _gaussian_wrap, _prominent_peaks

    rng = np.random.default_rng(5)
    th = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    cases = [
        rng.standard_normal(720),
        10 + 0.3 * np.cos(8 * th) + 0.05 * rng.standard_normal(720),
        np.round(5 + np.cos(4 * th) + 0.2 * np.cos(12 * th), 1),
    ]  # rounded: flat tops
    for r in cases:
        for sigma in (0.7, 4.0, 9.5):
            ref = gaussian_filter1d(r, sigma, mode="wrap")
            assert np.abs(_gaussian_wrap(r, sigma) - ref).max() <= 1e-13 * np.abs(r).max()
        x = np.concatenate([r, r, r])
        for p in (0.0, 0.01, 0.1, 0.5):
            assert np.array_equal(_prominent_peaks(x, p), find_peaks(x, prominence=p)[0])
