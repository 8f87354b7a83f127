"""Fast subsets of the element verification (verification/checks/*.py) against independent references.

Every tolerance is stated next to the measured value it has to admit and the failure it must catch.
"""

from __future__ import annotations

import pytest

from verification.checks import cantilevers as locking
from verification.checks import elements as patch
from verification.checks import plates


# ----------------------------------------------------------------------------- shear locking
@pytest.mark.parametrize("ratio", [10.0, 1000.0, 10000.0])
def test_cantilever_quads_no_shear_locking(ratio):
    row = locking.tip_load(ratio, "quad", n=8)
    # vs the continuum (Timoshenko beam incl. shear): the brief's 1 %; measured -0.39 % at every L/h
    # (a shear-locking quad is off by a factor ~(L/h)^2 at L/h = 1000)
    assert abs(row["rel_error"]) < 0.01
    # vs the exact 8-element Timoshenko beam with tied shear (reference/beams.py), which the 8x1 ANS
    # quad is for nu = 0: measured 5e-13, 4e-9, 3.4e-7 at L/h = 10, 1e3, 1e4 -- round-off growing
    # like eps (L/h)^2 (membrane/shear vs bending stiffness); 2e-6 admits that and fails for any
    # change in the element's shear interpolation (which moves the result by >1e-4)
    assert abs(row["rel_error_vs_beam_element"]) < 2e-6


@pytest.mark.parametrize("kind", ["tri/", "tri\\"])
def test_cantilever_triangles_error_does_not_grow_with_slenderness(kind):
    errs = [locking.tip_load(r, kind, n=8)["rel_error"] for r in (10.0, 1000.0, 10000.0)]
    # measured -0.379 %, -0.391 %, -0.391 %: within the 1 % of the quads and flat in L/h; a locking
    # triangle's error would approach -100 % as L/h grows
    assert all(abs(e) < 0.01 for e in errs)
    assert abs(errs[-1]) < 1.1 * abs(errs[0]) + 1e-4


# ----------------------------------------------------------------------------- thickness locking
@pytest.mark.parametrize("kind", ["quad", "tri/"])
@pytest.mark.parametrize("support", ["free", "restrained"])
def test_pure_bending_plane_stress_nu03(kind, support):
    row = locking.end_moment(100.0, kind, 0.3, support)
    # uniform curvature is exactly representable, so the plane-stress value M = EI kappa (free) or
    # M = D b kappa (restrained) must come out to round-off (measured < 5e-11 at L/h = 100); thickness
    # locking would make it 9.9 % (free) or 22.5 % (restrained) too stiff, and a plate stiffness D in
    # the free case (anticlastic curvature suppressed) 9 % too stiff
    assert abs(row["rel_error_rotation"]) < 1e-8
    assert abs(row["rel_error_deflection"]) < 1e-8
    expected_ky = -0.3 * row["kappa_x"] if support == "free" else 0.0
    assert abs(row["kappa_y"] - expected_ky) < 1e-8 * abs(row["kappa_x"])


# ----------------------------------------------------------------------------- patch tests
@pytest.mark.parametrize(
    "kind,membrane",
    [(k, "full") for k in ("quads", "tris", "mixed", "quads-rot", "tris-rot", "mixed-rot")]
    + [(k, "ans") for k in ("quads", "mixed", "quads-rot", "mixed-rot")],
)  # ans: a quad's option
@pytest.mark.parametrize("case", ["membrane", "bending"])
def test_patch(kind, case, membrane):
    row = patch.run_one(kind, case, membrane=membrane)
    # MacNeal-Harder patch, L/h = 240.  Measured: displacements <= 8e-11, energy <= 1.3e-10, residual
    # <= 1.1e-8 -- the residual's round-off floor is ~ 2e-13 (L/h)^2 (see patch.thickness_scan:
    # residual * (h/L)^2 stays 1e-14..2e-13 from h = 0.1 to 1e-4), so it is bounded by 1e-12 (L/h)^2
    # = 5.8e-8.  A patch-test failure is an O(1e-3..1) error that does not shrink with h.
    assert row["displacement_error"] < 1e-9
    assert abs(row["energy_error"]) < 1e-9
    assert row["equilibrium_residual"] < 1e-12 * (0.24 / patch.MAT.h) ** 2
    if "bending_strain_error" in row:
        assert row["bending_strain_error"] < 1e-9


# ----------------------------------------------------------------------------- plates
@pytest.mark.parametrize(
    "support,lo,hi",
    [
        # 16x16 quads, a/h = 1000 (Kirchhoff regime: the Mindlin shear correction is 5e-6), vs the series
        # (reference/plates.json).  Measured -0.288 % (clamped) and -0.126 % (hard SS), the O(h^2)
        # discretisation error of a sequence with observed rate 2.00-2.03 from N = 8 to 32; bands of about
        # +-40 % around them: a wrong boundary condition (clamped <-> SS is a factor 3), a stiffness error
        # of a few tenths of a percent, or a shear-tying error (tying the quad's director at the corners
        # instead of the edge mid-points gives -99.9 %) leaves the band.  (Soft and hard SS differ by only
        # 1e-5 here, at a/h = 1000, so this test does not distinguish them.)
        ("clamped", -0.0040, -0.0017),
        ("ss_hard", -0.0018, -0.0007),
    ],
)
def test_plate_16x16_quads(support, lo, hi):
    ref = plates.plate_reference()["alpha"]
    exact = ref["clamped"] if support == "clamped" else ref["simply_supported"]
    w = plates.centre_deflection(16, "quad", support, 1000.0)
    assert lo < (w - exact) / exact < hi


def test_plate_32x32_quads_within_one_percent():
    # the brief's requirement: <= 1 % at 32x32 quads; measured -0.071 % (clamped), -0.031 % (SS), a/h=1000
    ref = plates.plate_reference()["alpha"]
    for support, exact in (("clamped", ref["clamped"]), ("ss_hard", ref["simply_supported"])):
        w = plates.centre_deflection(32, "quad", support, 1000.0)
        assert abs(w - exact) / exact < 0.01


@pytest.mark.parametrize("support", ["clamped", "ss_hard"])
def test_triangle_is_mitc3(support):
    # the solid-shell triangle on a flat plate must coincide with an independent MITC3 code
    # (verification/plates.py): measured 1e-13..4e-10 relative difference; 1e-8 bounds the round-off
    # at a/h = 1000 while any deviation of Eqs. (12)-(14) from the Nedelec shear field shows as >1e-3
    a = plates.centre_deflection(8, "tri", support, 1000.0)
    b = plates.mitc3_plate(8, support, 1000.0)
    assert abs(a - b) / abs(b) < 1e-8


# ----------------------------------------------------------------------------- MacNeal-Harder beam
@pytest.mark.parametrize("shape", ["rectangular", "trapezoidal", "parallelogram"])
def test_macneal_harder_beam_out_of_plane(shape):
    # plate bending of 6 distorted quads, reference 0.4321 (beam theory incl. shear); measured
    # 0.980 / 0.963 / 0.977: the tied-shear beam-element stiffening of 1/(4*36) = 0.7 % plus the
    # nu = 0.3 free-edge and distortion effects.  [0.95, 1.0] fails for shear or trapezoidal locking
    # (a locked element gives << 0.9) and for an over-flexible element (> 1).
    row = locking.macneal_harder_beam(shape, "out-of-plane")
    assert 0.95 < row["normalised"] < 1.0


@pytest.mark.xfail(
    strict=True,
    reason="known limitation: the membrane of Eq. (6) is a plain bilinear "
    "(Q4) membrane and shear-locks in in-plane bending (measured 0.093 of the reference "
    "for 6 rectangular elements of aspect 5, 0.026 trapezoidal); strict, so that an "
    "enhanced membrane makes this test pass and be noticed",
)
def test_macneal_harder_beam_in_plane():
    row = locking.macneal_harder_beam("rectangular", "in-plane")
    assert 0.9 < row["normalised"] < 1.05


def test_assumed_membrane_in_plane_bending():
    # membrane="ans" removes the parasitic in-plane shear: the rectangular MacNeal-Harder beam goes
    # from 0.093 to 0.904 of the reference.  With nu = 0.3 the exact answer needs eps_yy = -nu eps_xx
    # varying with y, which the field (eps_yy linear in x only) cannot follow: a (1 - nu^2) = 0.91
    # stiffening is what is left, hence the band [0.89, 0.92]; a locked membrane gives < 0.1.  For the
    # trapezoid it stays locked (0.044): MacNeal's theorem, the price of passing the patch test.
    row = locking.macneal_harder_beam("rectangular", "in-plane", membrane="ans")
    assert 0.89 < row["normalised"] < 0.92
    assert locking.macneal_harder_beam("trapezoidal", "in-plane", membrane="ans")["normalised"] < 0.1


def test_assumed_membrane_scordelis_lo():
    # the membrane-dominated Scordelis-Lo roof, 16x16 quads, vs 0.3024: measured -2.67 % with the
    # compatible membrane, +0.59 % with the assumed one (8x8: -5.4 % / +5.0 %, 32x32: -1.1 % /
    # -0.25 %).  The bands (+-1 % about the measured values) fail for a membrane that locks again or
    # for one gone soft (a spurious mode or a lost rigidity makes the roof >> 1 % too flexible).
    ref = patch.REFERENCE
    assert -0.037 < patch.midside_deflection(16, membrane="full") / ref - 1 < -0.017
    assert -0.004 < patch.midside_deflection(16, membrane="ans") / ref - 1 < 0.016


# ----------------------------------------------------------------------------- geometric stiffness
def test_column_buckling_quads():
    # Euler load pi^2 EI/(4 L^2) of the 8x1 strip from the element's own tangent (Green strains):
    # measured +0.645 % (n = 8), +0.160 % (16), +0.039 % (32) -- O(n^-2) from above.  The band
    # (+0.3 %, +1 %) fails for a geometric stiffness off by a factor (e.g. a missing 1/2 in the
    # Green strain doubles P_cr) and for a wrong second mode ratio (9 for a cantilever).
    row = locking.column_buckling(8, "quad")
    assert 0.003 < row["rel_error"] < 0.01
    assert abs(row["second_over_first"] - 9.0) < 0.6


def test_plate_buckling_quads():
    # SS square plate, uniaxial compression, k = N_cr a^2/(pi^2 D) = 4 (m = 1), 6.25 (m = 2):
    # measured on 8x8 quads +2.1 % and +7.8 %, converging O(h^2) (+0.47 %, +1.7 % on 16x16).
    # Bands: a geometric stiffness error of >1 % or a wrong boundary condition leaves them.
    b = plates.plate_buckling(8, "quad", k=2)
    assert 0.01 < b["rel_error"][0] < 0.035
    assert 0.0 < b["rel_error"][1] < 0.12


# ----------------------------------------------------------------------------- large rotation
def test_strip_rolls_into_half_circle():
    # prescribed tip director rotated by pi, tip position free -> an arc of radius L/pi (elastica
    # under a pure end moment, reference/beams.py).  16x1 quads, 8 Newton increments: measured tip
    # error 9.7e-4 L (2.0e-4 L with 32 elements: O(n^-2)) and tip moment 0.9933 E I pi/L.  A wrong
    # nonlinear bending strain (e.g. the linearised one) misses the arc by O(L); 1.5e-3 L and 1 %
    # admit the discretisation error only.
    rows = locking.circle(16, "quad", phi_max=3.141592653589793, steps=8, report_at=(1.0,))
    r = rows[-1]
    assert r["converged"]
    assert r["error_over_L"] < 1.5e-3
    assert abs(r["moment_ratio"] - 1.0) < 0.01


# ----------------------------------------------------------------------------- curved: trapezoidal locking
@pytest.mark.parametrize("kind", ["quad", "tri/"])
@pytest.mark.parametrize("load", ["radial", "tangential"])
def test_curved_strip_no_trapezoidal_locking(kind, load):
    # quarter-circle strip, 16 elements, vs thin curved-beam theory: measured +0.080 % (radial) and
    # +0.242 % (tangential) at R/h = 1000 and 10000 alike (O(n^-2) discretisation error; at R/h = 100
    # the O((h/R)^2) thick-beam terms add 3e-5).  Trapezoidal or membrane locking would make the error
    # grow towards -100 % with R/h; the bounds admit the measured error and a 2e-5 drift
    # (measured <= 6e-6, round-off) between R/h = 1000 and 10^4.
    errs = [locking.curved_cantilever(16, kind, r, load)["rel_error"] for r in (1000.0, 10000.0)]
    assert all(0.0 < e < 0.004 for e in errs)
    assert abs(errs[1] - errs[0]) < 2e-5
