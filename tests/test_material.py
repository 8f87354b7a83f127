"""Sections: Table 1 wool and an isotropic shell against hand-computed numbers."""

import math

import numpy as np
import pytest

from solidshell import Fabric, InputError, IsotropicShell


def test_wool_table1():
    w = Fabric.wool()
    np.testing.assert_allclose(w.C_m, np.diag([1118.2, 759.5, 41.8]), rtol=0, atol=0)  # gf/cm
    np.testing.assert_allclose(w.C_b, np.diag([0.083, 0.063, 0.027]), rtol=0, atol=0)  # gf cm^2/cm
    assert w.weight_per_area == 0.019  # gf/cm^2
    assert w.mass_per_area == pytest.approx(0.019 / 980.665, rel=1e-15)  # gf s^2/cm^3
    assert w.thickness == 0.0593
    assert w.warp_angle == 0.0 and w.warp_angle_rad == 0.0
    assert w.poisson == 0.0


def test_wool_documented_defaults():
    w = Fabric.wool()
    t_mean = 0.5 * (1118.2 + 759.5)  # 938.85 gf/cm
    assert w.tensile_mean == pytest.approx(938.85)
    # C_t = 5/6 * T_mean / 2 (shear correction x shear modulus of a nu = 0 sheet), isotropic
    np.testing.assert_allclose(w.C_t, 5.0 / 6.0 * t_mean / 2.0 * np.eye(2), rtol=1e-15)
    assert w.C_t[0, 0] == pytest.approx(391.1875, rel=1e-12)
    # E_z = T_mean
    assert w.E_z == pytest.approx(938.85, rel=1e-15)


def test_wool_overrides_and_weft_cut():
    w = Fabric.wool(warp_angle=90.0, transverse_shear=100.0, thickness_modulus=5000.0, poisson=0.2)
    assert w.warp_angle_rad == pytest.approx(math.pi / 2)
    np.testing.assert_allclose(w.C_t, 100.0 * np.eye(2))
    assert w.E_z == 5000.0
    c = 0.2 * math.sqrt(1118.2 * 759.5)
    assert w.C_m[0, 1] == pytest.approx(c) and w.C_m[1, 0] == pytest.approx(c)
    assert w.C_b[0, 1] == pytest.approx(0.2 * math.sqrt(0.083 * 0.063))


@pytest.mark.parametrize(
    "field", ["tensile_warp", "tensile_weft", "shear", "bending_warp", "bending_weft", "torsion", "weight", "thickness"]
)
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), "abc"])
def test_fabric_rejects_nonpositive(field, value):
    with pytest.raises(InputError, match=field):
        Fabric.wool(**{field: value})


def test_isotropic_hand_computed():
    # E = 1e5, nu = 0.3, h = 0.1, density 2.0 (any consistent units)
    s = IsotropicShell(E=1e5, nu=0.3, h=0.1, density=2.0)
    # membrane: E h / (1 - nu^2) = 1e4 / 0.91 = 10989.010989...
    D = 10989.010989010989
    np.testing.assert_allclose(
        s.C_m, [[D, 3296.7032967032967, 0.0], [3296.7032967032967, D, 0.0], [0.0, 0.0, 3846.153846153846]], rtol=1e-13
    )
    # bending: E h^3 / (12 (1 - nu^2)) = 100 / 10.92 = 9.157509157...
    np.testing.assert_allclose(
        s.C_b,
        [
            [9.157509157509157, 2.747252747252747, 0.0],
            [2.747252747252747, 9.157509157509157, 0.0],
            [0.0, 0.0, 3.205128205128205],
        ],
        rtol=1e-13,
    )
    # transverse shear: 5/6 * G h = 5/6 * 38461.538... * 0.1 = 3205.128205...
    np.testing.assert_allclose(s.C_t, 3205.128205128205 * np.eye(2), rtol=1e-13)
    assert s.E_z == pytest.approx(1e4, rel=1e-15)  # E h
    assert s.mass_per_area == pytest.approx(0.2, rel=1e-15)  # density h
    assert s.weight_per_area == pytest.approx(0.2 * 980.665, rel=1e-15)
    assert s.thickness == 0.1


@pytest.mark.parametrize(
    "kw, words",
    [
        (dict(E=0.0, nu=0.3, h=0.1), r"E must be positive and finite \[force/length\^2\], got 0\.0"),
        (dict(E=1e5, nu=0.3, h=-0.1), r"h must be positive and finite \[length\], got -0\.1"),
        (dict(E=1e5, nu=0.5, h=0.1), r"nu must lie in \(-1, 0\.5\), got 0\.5"),
        (dict(E=1e5, nu=0.3, h=0.1, density=-1.0), r"density must be >= 0 \[mass/length\^3\], got -1\.0"),
    ],
)
def test_isotropic_rejects_bad(kw, words):
    with pytest.raises(InputError, match=words):
        IsotropicShell(**kw)
