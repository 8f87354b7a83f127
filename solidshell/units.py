"""Units: the paper's gf-cm-s system and SI.

The library computes in any *consistent* unit system; the fabric data of Table 1 and every built-in
scene are in the paper's system: force in gram-force (gf), length in cm, time in s.  Mass is then
measured in gf*s^2/cm (the mass that 1 gf accelerates at 1 cm/s^2); a weight per area w [gf/cm^2]
corresponds to a mass per area mu = w / g0 [gf*s^2/cm^3].
"""

G0 = 980.665
"""Standard gravity in cm/s^2 (exact by definition: 9.80665 m/s^2)."""

GF_IN_N = 9.80665e-3
"""One gram-force in newtons (exact)."""

CM_IN_M = 1.0e-2
"""One centimetre in metres."""

# SI factor of each quantity kind, as (force exponent, length exponent, time exponent):
# a value in gf^a cm^b s^c is multiplied by GF_IN_N**a * CM_IN_M**b to get SI.
_KINDS = {
    "length": (0, 1),  # cm -> m
    "area": (0, 2),  # cm^2 -> m^2
    "force": (1, 0),  # gf -> N
    "force_per_length": (1, -1),  # gf/cm -> N/m   (tensile, shear rigidity; line load)
    "pressure": (1, -2),  # gf/cm^2 -> Pa  (weight per area; surface load)
    "moment": (1, 1),  # gf*cm -> N*m   (bending rigidity per width, gf*cm^2/cm)
    "bending_rigidity": (1, 1),  # gf*cm^2/cm -> N*m
    "mass": (1, -1),  # gf*s^2/cm -> kg
    "mass_per_area": (1, -3),  # gf*s^2/cm^3 -> kg/m^2
    "acceleration": (0, 1),  # cm/s^2 -> m/s^2
    "energy": (1, 1),  # gf*cm -> J
}


def _factor(kind: str) -> float:
    try:
        a, b = _KINDS[kind]
    except KeyError:
        raise ValueError(f"unknown quantity kind {kind!r}; known: {', '.join(sorted(_KINDS))}") from None
    return GF_IN_N**a * CM_IN_M**b


def to_si(value, kind: str):
    """Convert ``value`` given in the paper's gf-cm-s units to SI (N, m, s, kg)."""
    return value * _factor(kind)


def from_si(value, kind: str):
    """Convert ``value`` given in SI (N, m, s, kg) to the paper's gf-cm-s units."""
    return value / _factor(kind)


def mass_per_area(weight_per_area: float) -> float:
    """Mass per area [gf*s^2/cm^3] of a sheet weighing ``weight_per_area`` [gf/cm^2]."""
    return weight_per_area / G0


KINDS = tuple(sorted(_KINDS))
