"""Closed-form references for a cantilever plate strip (length L along x, width b, thickness h).

Every function is a textbook closed form; nothing here uses solidshell.  See reference/beams.md for
what each one assumes and which element test uses it.  ``python reference/beams.py`` prints a few
values.

Notation: E Young's modulus, nu Poisson's ratio, I = b h^3 / 12, A = b h, G = E / (2 (1 + nu)),
kappa the shear correction factor (5/6), D = E h^3 / (12 (1 - nu^2)) the plate bending stiffness per
width.
"""

from __future__ import annotations

import math


def second_moment(b: float, h: float) -> float:
    return b * h**3 / 12.0


def timoshenko_tip_deflection(
    P: float, L: float, E: float, b: float, h: float, nu: float = 0.0, kappa: float = 5.0 / 6.0
) -> float:
    """Tip deflection of a cantilever under an end shear force P (Timoshenko beam):
    delta = P L^3 / (3 E I) + P L / (kappa G A).

    For a plate strip this is also the exact Reissner-Mindlin plate solution when nu = 0 (the
    cylindrical field w(x), theta(x) then satisfies the free-edge conditions M_y = M_xy = Q_y = 0
    exactly); with nu != 0 the plate has anticlastic edge effects and the beam value is only an
    approximation, so the locking test uses nu = 0."""
    G = E / (2.0 * (1.0 + nu))
    return P * L**3 / (3.0 * E * second_moment(b, h)) + P * L / (kappa * G * b * h)


def euler_bernoulli_tip_deflection(P: float, L: float, E: float, b: float, h: float) -> float:
    """P L^3 / (3 E I): the shear-free part of timoshenko_tip_deflection."""
    return P * L**3 / (3.0 * E * second_moment(b, h))


def discrete_timoshenko_tip_deflection(
    P: float, L: float, E: float, b: float, h: float, n: int, nu: float = 0.0, kappa: float = 5.0 / 6.0
) -> float:
    """Tip deflection of n equal 2-node Timoshenko beam elements with linear w, theta and a constant
    (one-point / mid-element tied) shear strain, under an end load.  Such a mesh is nodally exact for
    a Timoshenko beam whose shear flexibility is *reduced* by L_e^2 / (12 E I) per unit length:
    delta_n = delta_Timoshenko - P L (L/n)^2 / (12 E I), too stiff by 1/(4 n^2) of the bending part
    (-0.39 % for n = 8; n = 1 in the thin limit gives P L^3/(4EI) instead of P L^3/(3EI): the tied
    shear makes w_2 = L theta_2 / 2 and the energy EI theta^2/(2L) - P w_2 is minimal at
    theta_2 = P L^2/(2EI)).  A bilinear quad with the ANS shear of Eq. (4), one element across a
    nu = 0 strip, is exactly this beam element, so this is the value an 8x1 quad mesh should
    reproduce to round-off -- a sharper check than the 1 % tolerance against the continuum."""
    Le = L / n
    return timoshenko_tip_deflection(P, L, E, b, h, nu, kappa) - P * L * Le**2 / (12.0 * E * second_moment(b, h))


def end_moment_small(
    M: float, L: float, E: float, b: float, h: float, nu: float = 0.0, anticlastic: str = "free"
) -> dict:
    """Small-deflection pure bending of a cantilever by an end moment M (total, about the width axis).

    anticlastic = "free": the width edges are free; the uniform moment state m_x = M/b, m_y = 0 is an
    exact solution of Kirchhoff and Reissner-Mindlin plate theory with free edges (no boundary layer
    for a uniform moment), so kappa_x = M/(E I) and the anticlastic curvature kappa_y = -nu kappa_x:
    M = E I kappa exactly as for a beam, independent of nu.
    anticlastic = "restrained": kappa_y = 0 is enforced (cylindrical bending, e.g. the rotation about
    x fixed everywhere or a very wide plate away from its edges): m_x = D kappa_x, so kappa_x =
    M (1 - nu^2)/(E I).
    Both are plane stress through the thickness (sigma_zz = 0).  A solid-shell with thickness locking
    (3-D constitutive law with a thickness strain that cannot vary linearly through the thickness,
    no plane-stress enforcement) bends with the z-plane-strain moduli instead: too stiff by
    thickness_locking_factor(nu) = 1/(1 - nu^2) = 1.099 (free) or (1 - nu)^2/(1 - 2 nu) = 1.225
    (restrained) for nu = 0.3 -- the error this test would expose; for nu = 0 both factors are 1.

    Returns curvature kappa_x, tip rotation theta = kappa L, tip deflection kappa L^2 / 2, and
    kappa_y."""
    EI = E * second_moment(b, h)
    if anticlastic == "free":
        k = M / EI
        ky = -nu * k
    elif anticlastic == "restrained":
        k = M * (1.0 - nu**2) / EI
        ky = 0.0
    else:
        raise ValueError(anticlastic)
    return {"kappa_x": k, "kappa_y": ky, "tip_rotation": k * L, "tip_deflection": 0.5 * k * L**2}


def end_moment_circle(M: float, L: float, E: float, b: float, h: float) -> dict:
    """Large-rotation pure bending by a *follower* end moment (Euler elastica with constant
    curvature): the strip rolls into a circular arc of radius R = E I / M.  Tip position relative to
    the root (root tangent along +x, bending towards +z): x = R sin(L/R), z = R (1 - cos(L/R));
    M = 2 pi E I / L closes a full circle.  (A dead couple of forces does not stay a pure moment
    as the end rotates, so this reference applies only to follower-moment loading.)"""
    EI = E * second_moment(b, h)
    R = EI / M
    phi = L / R
    return {"radius": R, "tip_angle": phi, "tip_x": R * math.sin(phi), "tip_z": R * (1.0 - math.cos(phi))}


def thickness_locking_factor(nu: float, anticlastic: str = "free") -> float:
    """Stiffness ratio (locked / plane stress) in pure bending when the linear-in-z part of the
    thickness strain is zero (sigma_zz != 0): with the anticlastic curvature free the bending fibres
    are in uniaxial stress of a z-plane-strain solid, E/(1 - nu^2) instead of E: 1/(1 - nu^2);
    with it restrained, lambda + 2 mu = E (1-nu)/((1+nu)(1-2nu)) instead of E/(1-nu^2):
    (1 - nu)^2/(1 - 2 nu).  1.0989 and 1.2250 for nu = 0.3; both 1 for nu = 0 (why a nu = 0 test
    cannot expose thickness locking)."""
    if anticlastic == "free":
        return 1.0 / (1.0 - nu**2)
    if anticlastic == "restrained":
        return (1.0 - nu) ** 2 / (1.0 - 2.0 * nu)
    raise ValueError(anticlastic)


if __name__ == "__main__":
    E, b, L, P, M = 1.0e6, 1.0, 10.0, 1.0, 1.0
    for ratio in (10, 100, 1000, 10000):
        h = L / ratio
        t = timoshenko_tip_deflection(P, L, E, b, h)
        eb = euler_bernoulli_tip_deflection(P, L, E, b, h)
        d8 = discrete_timoshenko_tip_deflection(P, L, E, b, h, 8)
        print(
            f"L/h={ratio:6d}: Timoshenko {t:.6e}  shear share {(t - eb) / t:.2e}  8-element beam / exact - 1 = {d8 / t - 1:+.4e}"
        )
    print("end moment, nu=0.3, free:", end_moment_small(M, L, E, b, 0.1, 0.3, "free"))
    print("end moment, nu=0.3, restrained:", end_moment_small(M, L, E, b, 0.1, 0.3, "restrained"))
    print(
        "thickness-locking factors nu=0.3 (free, restrained):",
        thickness_locking_factor(0.3),
        thickness_locking_factor(0.3, "restrained"),
    )
    print("circle, M = pi E I / L:", end_moment_circle(math.pi * E * second_moment(b, 0.1) / L, L, E, b, 0.1))
