"""Shear and thickness locking: cantilever plate strip vs closed-form beam/plate theory.

Strip [0,L] x [-b/2, b/2], L = 10, b = 1, one element across the width, n = 8 elements along
(other meshes by option), thickness h = L / ratio for ratio = L/h = 10 ... 10 000, E = 1.

1. Shear locking (nu = 0), end shear P = 1 split equally on the tip nodes (U_o,z), root nodes clamped
   (U_o = U_n = 0).  Reference: Timoshenko beam delta = P L^3/(3EI) + P L/(kappa G A), kappa = 5/6
   (reference/beams.py; exact for a nu = 0 Reissner-Mindlin strip).  Meshes: 8x1 quads; the same
   quads split into two triangles along diagonal 1-3 ("/") and along 2-4 ("\\").  A locking element's
   error grows like (L/h)^2; a locking-free one has an error independent of L/h.  The 8x1 quad, one
   element across a nu = 0 strip, is exactly the 2-node Timoshenko beam element with mid-element
   (tied) shear, whose tip deflection is delta - P L (L/n)^2/(12EI) (too stiff by 0.39 % for n = 8),
   also printed: the quad should match it to round-off.
2. Thickness locking (nu = 0.3), end moment M = 1 as generalised forces M/2 on U_n,x of the two tip
   nodes (a couple of forces +-F at z = +-h/2 does virtual work F h dU_n,x, so a moment M enters the
   U_n,x dofs directly).  Root support that lets the anticlastic curvature develop: U_o = 0 and
   U_n,x = 0 on the root nodes, U_n,y and U_n,z free.  Then the uniform moment state (kappa_x =
   M/EI, kappa_y = -nu kappa_x) is an exact plate solution, representable by both elements, and the
   plane-stress references are: tip U_n,x = M L/(EI), tip w = -M L^2/(2EI), U_n,y difference across
   the width = +nu kappa_x b ("free").  With U_n,y = 0 imposed on every node the curvature is
   cylindrical and the references carry a factor (1 - nu^2) ("restrained").  A thickness-locked
   solid-shell would be 1.099x (free) / 1.225x (restrained) too stiff.  Also reported: a fully
   clamped root (U_n = 0 also restrains the anticlastic curvature at the root, so the strip is
   slightly stiffer than EI -- informative only, no closed form).

3. MacNeal & Harder's straight cantilever (1985): 6 rectangular / trapezoidal / parallelogram quads,
   L = 6, b = 0.2, h = 0.1, E = 1e7, nu = 0.3, unit tip load out of plane (plate bending; reference
   0.4321) and in plane (membrane, in-plane bending of the strip; reference 0.1081).  The in-plane
   case exposes the membrane of Eq. (6): a plain bilinear (Q4) membrane with no enhanced or
   incompatible modes, which shear-locks in in-plane bending (the paper applies ANS only to the
   transverse shear and thickness strains).

4. Euler buckling of the strip (axial tip load): a check of the geometric stiffness.
5. Quarter-circle strip (trapezoidal cross-sections) vs curved-beam theory for R/h = 10 ... 10^4.
6. Large rotation: the strip rolled into a circle (up to a closed ring) by a prescribed tip director.

Run: ``python -m verification.locking`` -> tables and verification/out/locking.json, locking.png.
"""

from __future__ import annotations

import argparse

from verification.checks.cantilevers import (  # noqa: F401  (the computations live in the package)
    MH_REF,
    RATIOS,
    B,
    E,
    L,
    beams,
    circle,
    column_buckling,
    curved_cantilever,
    end_moment,
    macneal_harder_beam,
    macneal_harder_mesh,
    strip_mesh,
    tip_load,
)

from . import OUT, write_json


def run(ratios=RATIOS, n=8, verbose=True):
    shear = []
    if verbose:
        print(
            f"Shear locking: cantilever {n}x1, nu = 0, tip load; error vs Timoshenko beam "
            f"(and vs the {n}-element Timoshenko beam, {beams.discrete_timoshenko_tip_deflection(1, L, E, B, L / 1000, n) / beams.timoshenko_tip_deflection(1, L, E, B, L / 1000) - 1:+.3%} vs Timoshenko)"
        )
        print(f"{'mesh':6s} {'L/h':>7s} {'tip/ref - 1':>12s} {'vs beam el.':>12s}")
    for kind in ("quad", "tri/", "tri\\"):
        for r in ratios:
            row = tip_load(r, kind, n)
            shear.append(row)
            if verbose:
                print(f"{kind:6s} {r:7.0f} {row['rel_error']:+12.4e} {row['rel_error_vs_beam_element']:+12.4e}")
    bend = []
    if verbose:
        print("Thickness locking: end moment, nu = 0.3, vs plane-stress theory")
        print(
            f"{'mesh':6s} {'support':10s} {'L/h':>7s} {'rot/ref - 1':>12s} {'w/ref - 1':>12s} {'kappa_y/kappa_x':>16s}"
        )
    for kind in ("quad", "tri/", "tri\\"):
        for support in ("free", "restrained", "clamped"):
            for r in ratios:
                row = end_moment(r, kind, 0.3, support, n)
                bend.append(row)
                if verbose:
                    print(
                        f"{kind:6s} {support:10s} {r:7.0f} {row['rel_error_rotation']:+12.4e} "
                        f"{row['rel_error_deflection']:+12.4e} {row['kappa_y'] / row['kappa_x']:16.6f}"
                    )
    mh = []
    if verbose:
        print("MacNeal-Harder straight cantilever (6 elements), tip displacement / reference:")
    for load in ("out-of-plane", "in-plane"):
        for shape in ("rectangular", "trapezoidal", "parallelogram"):
            row = macneal_harder_beam(shape, load)
            mh.append(row)
            if verbose:
                print(f"  {load:13s} {shape:14s} {row['tip']:.5e}  normalised {row['normalised']:.4f}")
    col = []
    if verbose:
        print("Euler buckling of the cantilever strip, L/h = 100 (reference pi^2 EI/(4L^2), 2nd/1st = 9):")
    for kind in ("quad", "tri/"):
        for nn in (8, 16, 32):
            row = column_buckling(nn, kind)
            col.append(row)
            if verbose:
                print(
                    f"  {kind:5s} n={nn:3d}  P_cr/ref - 1 = {row['rel_error']:+.3e}   2nd/1st {row['second_over_first']:.3f}"
                )
    curv = []
    if verbose:
        print("Quarter-circle strip (trapezoidal/membrane locking), tip load, error vs curved-beam theory:")
    for kind in ("quad", "tri/"):
        for load in ("radial", "tangential"):
            for nn in (8, 16, 32):
                rr = [curved_cantilever(nn, kind, r, load) for r in (10.0, 100.0, 1000.0, 10000.0)]
                curv += rr
                if verbose:
                    print(
                        f"  {kind:5s} {load:10s} n={nn:3d} "
                        + "  ".join(f"R/h={x['R_over_h']:.0f}: {x['rel_error']:+.3e}" for x in rr)
                    )
    circ = []
    if verbose:
        print("Large rotation: strip rolled into a circle by a prescribed tip director (L/h = 100):")
    for kind in ("quad", "tri/"):
        for nn in (8, 16, 32):
            for row in circle(nn, kind):
                circ.append(row)
                if verbose:
                    print(
                        f"  {kind:5s} n={nn:3d} phi={row['phi_over_pi']:.1f}pi converged={row['converged']} "
                        f"tip error/L {row['error_over_L']:.2e}  M/(EI phi/L) {row['moment_ratio']:.5f}  "
                        f"max||x_n|-1| {row['max_director_stretch']:.1e}"
                    )
    return shear, bend, mh, col, circ, curv


def plot(shear, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for kind, mk in (("quad", "o"), ("tri/", "^"), ("tri\\", "v")):
        sel = [r for r in shear if r["kind"] == kind]
        ax.loglog([r["L_over_h"] for r in sel], [max(abs(r["rel_error"]), 1e-16) for r in sel], marker=mk, label=kind)
    ax.axhline(0.01, color="grey", lw=0.5)
    ax.set_xlabel("L/h")
    ax.set_ylabel("|tip deflection error| vs Timoshenko")
    ax.set_title("cantilever strip 8x1, tip load, nu = 0")
    ax.grid(True, which="both", lw=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description="shear and thickness locking checks")
    ap.add_argument("-n", type=int, default=8, help="elements along the strip")
    args = ap.parse_args(argv)
    shear, bend, mh, col, circ, curv = run(n=args.n)
    p = write_json(
        "locking",
        {
            "description": __doc__.splitlines()[0],
            "L": L,
            "b": B,
            "E": E,
            "tip_load": shear,
            "end_moment": bend,
            "macneal_harder_beam": mh,
            "column_buckling": col,
            "circle": circ,
            "curved_cantilever": curv,
        },
    )
    plot(shear, OUT / "locking.png")
    print("wrote", p, "and", OUT / "locking.png")
    return shear, bend, mh, col, circ, curv


if __name__ == "__main__":
    main()
