"""Fast checks of the independent references in reference/ (no solidshell model involved)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from verification.checks import references

REF = references.reference_dir()
kp = references.module("kirchhoff_plate")
beams = references.module("beams")


# ----------------------------------------------------------------------------- plate series
def test_ss_series_match_published_coefficient():
    # 0.00406235 is the published 6-significant-digit value; rounding allows 0.5e-8 absolute,
    # i.e. 1.3e-6 relative, so 1e-5 is generous but still fails for a wrong term (the m = 3 term
    # alone changes alpha by 8e-4 relative).
    for a in (kp.levy_ss_alpha(21), kp.navier_ss_alpha(801)):
        assert abs(a - 0.00406235) / 0.00406235 < 1e-5
    # the two series are independent sums of the same solution: they agree to their truncation
    assert abs(kp.levy_ss_alpha(21) - kp.navier_ss_alpha(2001)) < 1e-12
    # Timoshenko & Woinowsky-Krieger's 3-digit table value
    assert round(kp.levy_ss_alpha(21), 5) == 0.00406


def test_clamped_superposition_matches_published_coefficient():
    a = kp.clamped_superposition_alpha(81, n_quad=2000)
    # Taylor & Govindjee (2004): 0.00126532 (rounded: 4e-6 relative); T&W-K: 0.00126
    assert abs(a - 0.00126532) / 0.00126532 < 1e-5
    assert round(a, 5) == 0.00127 and abs(a - 0.00126) < 1e-5
    # truncation converged: doubling the number of edge-moment terms (81 -> 161) changes alpha by
    # 1.4e-9 relative (the truncation error decays roughly like m^-3); 1e-8 bounds that
    assert abs(kp.clamped_superposition_alpha(161, n_quad=2000) - a) / a < 1e-8


def test_mindlin_shear_coefficient_closed_form():
    # Marcus moment at the centre of a square under unit load: 0.0736713 q a^2 (classical)
    assert abs(kp.marcus_moment_centre(2001) - 0.0736713) < 2e-7
    c = kp.mindlin_ss_shear_coefficient(0.3)
    assert abs(c - 0.0736713 / (6 * 5 / 6 * 0.7)) < 1e-7


def test_stored_plates_json_is_consistent():
    data = json.loads((REF / "plates.json").read_text())
    assert abs(data["alpha"]["simply_supported"] - kp.levy_ss_alpha(21)) < 1e-13
    assert abs(data["alpha"]["clamped"] - 0.00126532) / 0.00126532 < 1e-5
    for key in ("morley_simply_supported", "morley_clamped", "argyris_simply_supported", "argyris_clamped"):
        rows = data["skfem"][key]
        assert len(rows) >= 4
        # the finest stored mesh agrees with the series: Morley within 0.1 %, Argyris within 1e-6
        tol = 1e-3 if key.startswith("morley") else 1e-6
        assert abs(rows[-1]["rel_error"]) < tol


# ----------------------------------------------------------------------------- scikit-fem solves
@pytest.mark.parametrize(
    "support,exact,lo,hi",
    [
        # Morley on the union-jack mesh h = 1/16 (1024 triangles): the stored convergence table shows a
        # clean O(h^2) error from above, +1.65 % (SS) and +5.05 % (clamped); the bands are +-20 % around
        # those values, so a wrong boundary condition (SS <-> clamped swaps alpha by 3x) or a wrong D
        # (e.g. 1 - nu instead of 1 - nu^2) fails.
        ("simply_supported", 0.0040623527, 0.013, 0.020),
        ("clamped", 0.0012653191, 0.040, 0.061),
    ],
)
def test_morley_within_known_error(support, exact, lo, hi):
    row = kp.skfem_plate("morley", support, 4)
    err = (row["alpha"] - exact) / exact
    assert lo < err < hi
    # and the observed order between h = 1/8 and 1/16 is 2 (+-0.15)
    err8 = (kp.skfem_plate("morley", support, 3)["alpha"] - exact) / exact
    assert abs(math.log2(err8 / err) - 2.0) < 0.15


@pytest.mark.parametrize("support,exact", [("simply_supported", 0.0040623527), ("clamped", 0.0012653191)])
def test_argyris_matches_series(support, exact):
    # quintic C1 element, 64 triangles: measured 1.7e-6 (SS) and 1.1e-5 (clamped); 3e-5 allows that
    # and still fails for any error in the boundary-dof selection (which costs >1e-3).
    row = kp.skfem_plate("argyris", support, 2)
    assert abs(row["alpha"] - exact) / exact < 3e-5


# ----------------------------------------------------------------------------- beams
def test_timoshenko_tip_deflection_terms():
    E, b, h, L, P = 2.0, 1.0, 0.1, 1.0, 3.0
    I = b * h**3 / 12
    G = E / 2
    assert beams.timoshenko_tip_deflection(P, L, E, b, h) == pytest.approx(
        P * L**3 / (3 * E * I) + P * L / (5 / 6 * G * b * h), rel=1e-14
    )


def test_discrete_timoshenko_one_element_by_hand():
    # one 2-node element with tied (constant) shear, clamped at node 1: minimise
    # EI/(2L) th^2 + kGA L/2 (w/L - th/2)^2 - P w over (w, th) directly and compare
    E, b, h, L, P = 1.0, 1.0, 0.05, 1.0, 1.0
    EI = E * b * h**3 / 12
    kGA = 5 / 6 * E / 2 * b * h
    K = np.array([[kGA / L, -kGA / 2], [-kGA / 2, EI / L + kGA * L / 4]])
    w, th = np.linalg.solve(K, [P, 0.0])
    assert beams.discrete_timoshenko_tip_deflection(P, L, E, b, h, 1) == pytest.approx(w, rel=1e-12)


def test_end_moment_and_locking_factors():
    r = beams.end_moment_small(2.0, 3.0, 5.0, 1.0, 0.2, 0.3, "free")
    EI = 5.0 * 0.2**3 / 12
    assert r["tip_rotation"] == pytest.approx(2.0 * 3.0 / EI, rel=1e-14)
    assert r["kappa_y"] == pytest.approx(-0.3 * r["kappa_x"], rel=1e-14)
    rr = beams.end_moment_small(2.0, 3.0, 5.0, 1.0, 0.2, 0.3, "restrained")
    assert rr["kappa_x"] / r["kappa_x"] == pytest.approx(1 - 0.09, rel=1e-14)
    assert beams.thickness_locking_factor(0.3) == pytest.approx(1 / 0.91)
    assert beams.thickness_locking_factor(0.3, "restrained") == pytest.approx(0.49 / 0.4)
    assert beams.thickness_locking_factor(0.0) == 1.0
    c = beams.end_moment_circle(2 * math.pi * EI / 3.0, 3.0, 5.0, 1.0, 0.2)
    assert abs(c["tip_x"]) < 1e-12 and abs(c["tip_z"]) < 1e-12  # a closed circle
