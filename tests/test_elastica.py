"""The elastica references: internal consistency and agreement with closed forms / tables (fast)."""

import json

import numpy as np
import pytest

from verification.checks import references

el = references.module("elastica")


def test_small_deflection_limit():
    # w L^3 / B = 1e-4: the linear result w L^4 / (8 B) holds to O((wL^3/B)^2) relative
    B, L = 1.0, 2.0
    w = 1e-4 * B / L**3
    r = el.solve_bvp_elastica(w, 0.0, B, L)
    assert -r["tip_z"] == pytest.approx(w * L**4 / (8 * B), rel=1e-6)


def test_heavy_strip_bvp_matches_shooting():
    r = el.heavy_cantilever(0.083, 0.019, 5.0, n_out=51)
    assert r["bvp_vs_shooting_max_abs"] < 1e-8  # both solved to ~1e-10 or better
    # inextensible: the curve has length L (chord sum of a fine resampling approaches L from below)
    seg = np.hypot(np.diff(r["x"]), np.diff(r["z"]))
    assert seg.sum() == pytest.approx(5.0, rel=2e-4)
    assert r["m"][-1] == pytest.approx(0.0, abs=1e-10)


@pytest.mark.parametrize("alpha", sorted(el.MATTIASSON_1981))
def test_tip_load_against_mattiasson(alpha):
    u_t, w_t, p_t = el.MATTIASSON_1981[alpha]
    r = el.tip_load_cantilever(alpha)
    # the table is printed to 5 decimals: agreement to half a unit in the last place
    assert -r["tip_z"] == pytest.approx(w_t, abs=6e-6)
    assert 1 - r["tip_x"] == pytest.approx(u_t, abs=6e-6)
    if p_t is not None:
        assert r["tip_phi"] == pytest.approx(p_t, abs=6e-6)
    uL, wL, p0 = el.tip_load_elliptic(alpha)
    assert (uL, wL, p0) == pytest.approx((1 - r["tip_x"], -r["tip_z"], r["tip_phi"]), abs=1e-8)


def test_end_moment_circle_closes():
    B, L = 2.0, 3.0
    x, z = el.end_moment_cantilever(2 * np.pi * B / L, B, L)
    assert abs(x[-1]) < 1e-12 and abs(z[-1]) < 1e-12
    R = L / (2 * np.pi)
    assert np.allclose(np.hypot(x, z - R), R)


def test_stored_json_is_current():
    with open(el.JSON_PATH) as fh:
        d = json.load(fh)
    for cut, B in (("warp", 0.083), ("weft", 0.063)):
        s = d["strip"][cut]
        assert s["B"] == B and s["L"] == 5.0 and s["w"] == pytest.approx(0.019)
        assert len(s["curve"]["x"]) == 101
        assert s["curve"]["z"][-1] == pytest.approx(s["tip_z"])
        assert s["bvp_vs_shooting_max_abs"] < 1e-8
    assert d["strip"]["warp"]["tip_z"] == pytest.approx(-4.3446830622, abs=1e-8)
    assert d["strip"]["weft"]["tip_z"] == pytest.approx(-4.4533307085, abs=1e-8)
