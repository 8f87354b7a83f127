"""Unit conversions between the paper's gf-cm-s system and SI."""

import math

import pytest

from solidshell import units
from solidshell.units import CM_IN_M, G0, GF_IN_N, from_si, mass_per_area, to_si


def test_constants():
    assert G0 == 980.665  # cm/s^2, exact (9.80665 m/s^2)
    assert GF_IN_N == pytest.approx(9.80665e-3, rel=1e-15)
    assert CM_IN_M == 1e-2
    # one gram-force is one gram under standard gravity: 1e-3 kg * 9.80665 m/s^2
    assert GF_IN_N == pytest.approx(1e-3 * G0 * CM_IN_M, rel=1e-15)


@pytest.mark.parametrize(
    "kind, value, si",
    [
        ("force", 1.0, 9.80665e-3),  # 1 gf = 9.80665 mN
        ("length", 1.0, 0.01),  # 1 cm = 0.01 m
        ("area", 1.0, 1e-4),
        ("force_per_length", 1118.2, 1118.2 * 9.80665e-3 / 1e-2),  # tensile rigidity -> N/m
        ("pressure", 1.0, 98.0665),  # 1 gf/cm^2 = 98.0665 Pa
        ("bending_rigidity", 0.083, 0.083 * 9.80665e-3 * 1e-2),  # gf cm^2/cm -> N m
        ("moment", 1.0, 9.80665e-5),
        ("acceleration", G0, 9.80665),
        ("energy", 1.0, 9.80665e-5),  # gf cm -> J
    ],
)
def test_to_si(kind, value, si):
    assert to_si(value, kind) == pytest.approx(si, rel=1e-12)


def test_bending_rigidity_of_wool_in_si():
    # 0.083 gf cm^2/cm = 0.083 * 9.80665e-3 N * 1e-2 m = 8.13952e-6 N m
    assert to_si(0.083, "bending_rigidity") == pytest.approx(8.1395195e-6, rel=1e-7)


@pytest.mark.parametrize("kind", units.KINDS)
def test_round_trip(kind):
    for v in (0.0, 1.0, 0.019, 1118.2, -3.5e4):
        assert from_si(to_si(v, kind), kind) == pytest.approx(v, rel=1e-14, abs=1e-300)


def test_mass_per_area_of_wool():
    mu = mass_per_area(0.019)  # gf s^2/cm^3
    assert mu == pytest.approx(0.019 / 980.665, rel=1e-15)
    # 0.019 gf/cm^2 is 0.019 g/cm^2 = 0.19 kg/m^2
    assert to_si(mu, "mass_per_area") == pytest.approx(0.19, rel=1e-12)
    # and the weight of that mass under g0 is the weight again
    assert mu * G0 == pytest.approx(0.019, rel=1e-15)


def test_mass_unit():
    # 1 gf s^2/cm is the mass 1 gf accelerates at 1 cm/s^2: 9.80665e-3 N / 1e-2 m/s^2 = 0.980665 kg
    assert to_si(1.0, "mass") == pytest.approx(0.980665, rel=1e-12)


def test_unknown_kind():
    with pytest.raises(ValueError, match="unknown quantity kind"):
        to_si(1.0, "furlongs")
    assert math.isclose(from_si(9.80665e-3, "force"), 1.0)
