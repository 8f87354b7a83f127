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
import importlib.util

import numpy as np

from solidshell import IsotropicShell, Model, ShellMesh

from . import OUT, REFERENCE, buckling_factors, linear_solve, rect_grid, split_quads, write_json

L, B, E = 10.0, 1.0, 1.0
RATIOS = (10.0, 100.0, 1000.0, 10000.0)


def _beams():
    spec = importlib.util.spec_from_file_location("reference_beams", REFERENCE / "beams.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


beams = _beams()


def strip_mesh(n: int = 8, m: int = 1, kind: str = "quad") -> ShellMesh:
    nodes, quads = rect_grid(n, m, L, B, 0.0, -B / 2)
    if kind == "quad":
        return ShellMesh(nodes, quads=quads)
    return ShellMesh(nodes, tris=split_quads(quads, {"tri/": "/", "tri\\": "\\", "trix": "x"}[kind]))


def _ends(mesh):
    x = mesh.nodes[:, 0]
    return np.flatnonzero(np.abs(x) < 1e-9 * L), np.flatnonzero(np.abs(x - L) < 1e-9 * L)


def tip_load(ratio: float, kind: str = "quad", n: int = 8, m: int = 1, P: float = 1.0) -> dict:
    h = L / ratio
    mesh = strip_mesh(n, m, kind)
    model = Model(mesh, IsotropicShell(E=E, nu=0.0, h=h))
    root, tip = _ends(mesh)
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    fixed[root] = True
    loads = np.zeros((mesh.n_nodes, 6))
    # end shear P uniform over the width: line-load shares of the tip nodes (P/2 each for m = 1)
    w = np.zeros(mesh.n_nodes)
    ys = np.sort(mesh.nodes[tip, 1])
    for i in tip:
        y = mesh.nodes[i, 1]
        k = np.searchsorted(ys, y)
        lo = ys[k - 1] if k > 0 else y
        hi = ys[k + 1] if k + 1 < len(ys) else y
        w[i] = 0.5 * (hi - lo) / B
    loads[tip, 2] = P * w[tip]
    U, _ = linear_solve(model, fixed, loads)
    d = float(np.mean(U[tip, 2]))
    ref = beams.timoshenko_tip_deflection(P, L, E, B, h)
    disc = beams.discrete_timoshenko_tip_deflection(P, L, E, B, h, n)
    return dict(kind=kind, n=n, m=m, L_over_h=ratio, tip=d, timoshenko=ref, rel_error=(d - ref) / ref,
                beam_element=disc, rel_error_vs_beam_element=(d - disc) / disc,
                tip_spread=float(np.ptp(U[tip, 2]) / abs(d)))


def end_moment(ratio: float, kind: str = "quad", nu: float = 0.3, support: str = "free", n: int = 8,
               m: int = 1, M: float = 1.0) -> dict:
    h = L / ratio
    mesh = strip_mesh(n, m, kind)
    model = Model(mesh, IsotropicShell(E=E, nu=nu, h=h))
    root, tip = _ends(mesh)
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    fixed[root, :3] = True
    fixed[root, 3] = True                      # U_n,x = 0: no rotation about the width axis
    if support == "clamped":
        fixed[root, 3:] = True
    elif support == "restrained":
        fixed[:, 4] = True                     # U_n,y = 0 everywhere: cylindrical bending
    elif support != "free":
        raise ValueError(support)
    loads = np.zeros((mesh.n_nodes, 6))
    ys = np.sort(mesh.nodes[tip, 1])
    for i in tip:                              # moment per width M/B, tributary widths
        y = mesh.nodes[i, 1]
        k = np.searchsorted(ys, y)
        lo = ys[k - 1] if k > 0 else y
        hi = ys[k + 1] if k + 1 < len(ys) else y
        loads[i, 3] = M * 0.5 * (hi - lo) / B
    U, _ = linear_solve(model, fixed, loads)
    ref = beams.end_moment_small(M, L, E, B, h, nu, "restrained" if support == "restrained" else "free")
    rot = float(np.mean(U[tip, 3]))            # U_n,x = -dw/dx = kappa_x L at the tip
    w = float(np.mean(U[tip, 2]))
    out = dict(kind=kind, n=n, m=m, L_over_h=ratio, nu=nu, support=support,
               tip_rotation=rot, tip_rotation_ref=ref["tip_rotation"],
               rel_error_rotation=(rot - ref["tip_rotation"]) / ref["tip_rotation"],
               tip_deflection=-w, tip_deflection_ref=ref["tip_deflection"],
               rel_error_deflection=(-w - ref["tip_deflection"]) / ref["tip_deflection"])
    # anticlastic curvature from the tip U_n,y (U_n,y = -dw/dy, kappa_y = dU_n,y/dy)
    yt = mesh.nodes[tip, 1]
    ky = float(np.polyfit(yt, U[tip, 4], 1)[0])
    out.update(kappa_y=ky, kappa_y_ref=ref["kappa_y"], kappa_x=rot / L)
    return out


# ---------------------------------------------------------------------------------------------
# MacNeal & Harder (1985) straight cantilever: L = 6, width 0.2, thickness 0.1, E = 1e7, nu = 0.3,
# 6 elements (rectangular, trapezoidal with +-45 deg sides, parallelogram with 45 deg sides), unit
# tip load.  References (MacNeal-Harder's, = beam theory incl. shear): out-of-plane 0.4321 (the
# plate bending of this element), in-plane 0.1081 (its membrane, in-plane bending of the strip).
MH_REF = {"out-of-plane": 0.4321, "in-plane": 0.1081}


def macneal_harder_mesh(shape: str) -> ShellMesh:
    xb = np.arange(7, dtype=float)                    # bottom edge (y = 0) node x
    xt = xb.copy()                                    # top edge (y = 0.2)
    if shape == "trapezoidal":
        xt[1:6] += 0.2 * np.array([1, -1, 1, -1, 1])  # alternating 45 deg sides
    elif shape == "parallelogram":
        xt[1:6] += 0.2                                # all sides at 45 deg
    elif shape != "rectangular":
        raise ValueError(shape)
    nodes = np.zeros((14, 3))
    nodes[:7, 0] = xb
    nodes[7:, 0] = xt
    nodes[7:, 1] = 0.2
    quads = np.array([[i, i + 1, i + 8, i + 7] for i in range(6)])
    return ShellMesh(nodes, quads=quads)


def macneal_harder_beam(shape: str, load: str, membrane: str = "full") -> dict:
    mesh = macneal_harder_mesh(shape)
    model = Model(mesh, IsotropicShell(E=1.0e7, nu=0.3, h=0.1), membrane=membrane)
    fixed = np.zeros((14, 6), dtype=bool)
    fixed[[0, 7]] = True
    loads = np.zeros((14, 6))
    comp = 2 if load == "out-of-plane" else 1
    loads[[6, 13], comp] = 0.5
    U, _ = linear_solve(model, fixed, loads)
    tip = float(np.mean(U[[6, 13], comp]))
    return dict(shape=shape, load=load, membrane=membrane, tip=tip, reference=MH_REF[load],
                normalised=tip / MH_REF[load])


def column_buckling(n: int = 8, kind: str = "quad", ratio: float = 100.0) -> dict:
    """Euler buckling of the cantilever strip (nu = 0) under an axial compressive tip load: P_cr =
    pi^2 E I / (4 L^2) (Timoshenko's shear correction 1/(1 + P_E/(kappa G A)) is 1 - 5e-5 at L/h = 100).
    Checks the element's geometric stiffness (the Green-strain part of the tangent)."""
    h = L / ratio
    mesh = strip_mesh(n, 1, kind)
    model = Model(mesh, IsotropicShell(E=E, nu=0.0, h=h))
    root, tip = _ends(mesh)
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    fixed[root] = True
    loads = np.zeros((mesh.n_nodes, 6))
    loads[tip, 0] = -1.0 / len(tip)
    lam, _ = buckling_factors(model, fixed, loads, k=2)
    EI = E * B * h**3 / 12
    PE = np.pi**2 * EI / (4 * L**2)
    Pcr = PE / (1 + PE / (5 / 6 * E / 2 * B * h))
    return dict(n=n, kind=kind, L_over_h=ratio, P_cr=float(lam[0]), reference=Pcr, rel_error=float(lam[0] / Pcr - 1),
                second_over_first=float(lam[1] / lam[0]))


def circle(n: int = 16, kind: str = "quad", phi_max: float = 2 * np.pi, steps: int = 32, ratio: float = 100.0,
           report_at=(0.5, 1.0, 1.5, 2.0)) -> list[dict]:
    """Large rotation: pure bending of the nu = 0 strip into a circular arc (reference/beams.py
    end_moment_circle).  The root is clamped and the tip *director* is prescribed rotated by phi about
    the width axis (U_n = (-sin phi, 0, cos phi - 1)), the tip position left free: the only reaction
    at the tip is then a pure moment and the exact (elastica) shape is an arc of radius R = L/phi,
    tip at (R sin phi, R (1 - cos phi)), moment E I phi / L; phi = 2 pi closes a full ring.  Solved by
    Newton (solidshell.solve_static) in ``steps`` equal increments of phi, each starting from the
    previous state (a linear interpolation of the prescribed director would pass through a zero
    director at phi = pi).  Reports the tip-position error / L at the phi's in ``report_at`` (x pi)."""
    from solidshell import solve_static

    h = L / ratio
    mesh = strip_mesh(n, 1, kind)
    model = Model(mesh, IsotropicShell(E=E, nu=0.0, h=h))
    root, tip = _ends(mesh)
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    fixed[root] = True
    fixed[tip, 3:] = True
    U = np.zeros((mesh.n_nodes, 6))
    rows, ok = [], True
    for k in range(1, steps + 1):
        phi = k * phi_max / steps
        pre = np.zeros((mesh.n_nodes, 6))
        pre[tip, 3] = -np.sin(phi)
        pre[tip, 5] = np.cos(phi) - 1.0
        res = solve_static(model, fixed, np.zeros((mesh.n_nodes, 6)), load_factors=[1.0], prescribed=pre, U0=U,
                           check_stability=False)
        ok = ok and bool(res.converged)
        U = res.U
        if any(abs(phi - f * np.pi) < 1e-9 for f in report_at):
            R = L / phi
            tx, tz = L + U[tip, 0].mean(), U[tip, 2].mean()
            ex, ez = R * np.sin(phi), R * (1 - np.cos(phi))
            F = model.internal_force(U)
            # moment = generalised force on the tip director conjugate to a rotation d(phi):
            # dU_n/dphi = (-cos phi, 0, -sin phi)
            Mt = -np.cos(phi) * F[tip, 3].sum() - np.sin(phi) * F[tip, 5].sum()
            EI = E * B * h**3 / 12
            rows.append(dict(kind=kind, n=n, phi_over_pi=phi / np.pi, converged=ok, tip_x=float(tx), tip_z=float(tz),
                             ref_x=float(ex), ref_z=float(ez), error_over_L=float(np.hypot(tx - ex, tz - ez) / L),
                             moment_ratio=float(Mt / (EI * phi / L)),
                             max_director_stretch=float(np.abs(np.linalg.norm(mesh.directors + U[:, 3:], axis=1) - 1).max())))
    return rows


def curved_cantilever(n: int = 16, kind: str = "quad", R_over_h: float = 100.0, load: str = "radial",
                      R: float = 10.0, b: float = 1.0) -> dict:
    """Trapezoidal / membrane locking: a quarter-circle strip (radius R, width b, nu = 0) curved in
    the plane of its director (nodes (R cos t, y, R sin t), radial directors, so the element cross-
    sections are trapezoids), clamped at t = 0, unit end load at t = pi/2 either radial (+z) or
    tangential (-x).  Reference: Castigliano for the thin curved beam,
      radial:     delta = pi P R^3/(4EI) + (pi/4) P R (1/EA + 1/(kappa G A)),
      tangential: delta = (3 pi/4 - 2) P R^3/(EI) + (pi/4) P R (1/EA + 1/(kappa G A))
    (extension and shear terms are ~1e-5 relative at R/h = 100; curvature corrections are O((h/R)^2),
    0.3 % at R/h = 10).  A locking element's error grows with R/h; a sound one's does not."""
    h = R / R_over_h
    th = np.linspace(0.0, np.pi / 2, n + 1)
    nodes = np.zeros((2 * (n + 1), 3))
    D = np.zeros_like(nodes)
    for j, y in enumerate((-b / 2, b / 2)):
        sl = slice(j * (n + 1), (j + 1) * (n + 1))
        nodes[sl] = np.column_stack([R * np.cos(th), np.full(n + 1, y), R * np.sin(th)])
        D[sl] = np.column_stack([np.cos(th), np.zeros(n + 1), np.sin(th)])
    i = np.arange(n)
    q = np.column_stack([i, i + n + 1, i + n + 2, i + 1])      # counter-clockwise about the outward director
    if kind == "quad":
        mesh = ShellMesh(nodes, quads=q, directors=D)
    else:
        mesh = ShellMesh(nodes, tris=split_quads(q, {"tri/": "/", "tri\\": "\\"}[kind]), directors=D)
    model = Model(mesh, IsotropicShell(E=E, nu=0.0, h=h))
    k = np.arange(len(nodes)) % (n + 1)
    root, tip = np.flatnonzero(k == 0), np.flatnonzero(k == n)
    fixed = np.zeros((len(nodes), 6), dtype=bool)
    fixed[root] = True
    loads = np.zeros((len(nodes), 6))
    comp, sign = (2, 1.0) if load == "radial" else (0, -1.0)
    loads[tip, comp] = 0.5 * sign
    U, _ = linear_solve(model, fixed, loads)
    d = float(U[tip, comp].mean() * sign)
    EI, EA, kGA = E * b * h**3 / 12, E * b * h, 5 / 6 * E / 2 * b * h
    bend = np.pi / 4 if load == "radial" else 3 * np.pi / 4 - 2
    ref = bend * R**3 / EI + np.pi / 4 * R * (1 / EA + 1 / kGA)
    return dict(kind=kind, n=n, R_over_h=R_over_h, load=load, tip=d, reference=ref, rel_error=d / ref - 1)


def run(ratios=RATIOS, n=8, verbose=True):
    shear = []
    if verbose:
        print(f"Shear locking: cantilever {n}x1, nu = 0, tip load; error vs Timoshenko beam "
              f"(and vs the {n}-element Timoshenko beam, {beams.discrete_timoshenko_tip_deflection(1, L, E, B, L / 1000, n) / beams.timoshenko_tip_deflection(1, L, E, B, L / 1000) - 1:+.3%} vs Timoshenko)")
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
        print(f"{'mesh':6s} {'support':10s} {'L/h':>7s} {'rot/ref - 1':>12s} {'w/ref - 1':>12s} {'kappa_y/kappa_x':>16s}")
    for kind in ("quad", "tri/", "tri\\"):
        for support in ("free", "restrained", "clamped"):
            for r in ratios:
                row = end_moment(r, kind, 0.3, support, n)
                bend.append(row)
                if verbose:
                    print(f"{kind:6s} {support:10s} {r:7.0f} {row['rel_error_rotation']:+12.4e} "
                          f"{row['rel_error_deflection']:+12.4e} {row['kappa_y'] / row['kappa_x']:16.6f}")
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
                print(f"  {kind:5s} n={nn:3d}  P_cr/ref - 1 = {row['rel_error']:+.3e}   2nd/1st {row['second_over_first']:.3f}")
    curv = []
    if verbose:
        print("Quarter-circle strip (trapezoidal/membrane locking), tip load, error vs curved-beam theory:")
    for kind in ("quad", "tri/"):
        for load in ("radial", "tangential"):
            for nn in (8, 16, 32):
                rr = [curved_cantilever(nn, kind, r, load) for r in (10.0, 100.0, 1000.0, 10000.0)]
                curv += rr
                if verbose:
                    print(f"  {kind:5s} {load:10s} n={nn:3d} " + "  ".join(f"R/h={x['R_over_h']:.0f}: {x['rel_error']:+.3e}" for x in rr))
    circ = []
    if verbose:
        print("Large rotation: strip rolled into a circle by a prescribed tip director (L/h = 100):")
    for kind in ("quad", "tri/"):
        for nn in (8, 16, 32):
            for row in circle(nn, kind):
                circ.append(row)
                if verbose:
                    print(f"  {kind:5s} n={nn:3d} phi={row['phi_over_pi']:.1f}pi converged={row['converged']} "
                          f"tip error/L {row['error_over_L']:.2e}  M/(EI phi/L) {row['moment_ratio']:.5f}  "
                          f"max||x_n|-1| {row['max_director_stretch']:.1e}")
    return shear, bend, mh, col, circ, curv


def plot(shear, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for kind, mk in (("quad", "o"), ("tri/", "^"), ("tri\\", "v")):
        sel = [r for r in shear if r["kind"] == kind]
        ax.loglog([r["L_over_h"] for r in sel], [max(abs(r["rel_error"]), 1e-16) for r in sel], marker=mk,
                  label=kind)
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
    p = write_json("locking", {"description": __doc__.splitlines()[0], "L": L, "b": B, "E": E,
                               "tip_load": shear, "end_moment": bend, "macneal_harder_beam": mh,
                               "column_buckling": col, "circle": circ, "curved_cantilever": curv})
    plot(shear, OUT / "locking.png")
    print("wrote", p, "and", OUT / "locking.png")
    return shear, bend, mh, col, circ, curv


if __name__ == "__main__":
    main()
