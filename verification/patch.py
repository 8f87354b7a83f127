"""Patch tests (small deflection) on the distorted five-element patch of MacNeal & Harder (1985).

Patch 0.24 x 0.12, outer corners 1-4 at (0,0), (0.24,0), (0.24,0.12), (0,0.12); interior nodes 5-8 at
(0.04,0.02), (0.18,0.03), (0.16,0.08), (0.08,0.08); E = 1e6, nu = 0.25, h = 0.001 (MacNeal-Harder's
data).  Meshes: the five quads; each quad split into two triangles ("tris"); the outer four quads
split and the inner one kept ("mixed"); each of these also rotated rigidly into a general plane
("...-rot", rotation about the axis (1,2,3) by 0.7 rad) to exercise the local frames.

Prescribed fields (in the patch plane's coordinates x, y, z = normal; for "-rot" meshes every vector
field is rotated with the patch):
* membrane:   U_o = 1e-3 (x + y/2, y + x/2, 0),  U_n = 0
              -> eps_xx = eps_yy = gamma_xy = 1e-3, no bending, no shear, no thickness strain;
* bending:    w = 1e-3 (x^2 + x y + y^2)/2,  U_o = (0, 0, w),
              U_n = -grad w = -1e-3 (x + y/2, y + x/2, 0)  (the rotated normal of the Kirchhoff field,
              to first order) -> bending strains (dU_n,x/dx, dU_n,y/dy, dU_n,x/dy + dU_n,y/dx) =
              -1e-3 (1, 1, 1), zero transverse shear (along every edge w_s + U_n.t = 0 pointwise, and the
              tying values are exact for a quadratic w and linear U_n), no thickness strain.
All six dofs of the four outer nodes are prescribed from the field; all six dofs of the four
interior nodes are free and solved for with K(0) u = 0.  Checks:
  (1) interior nodal U equals the field:   max|U - U_exact| / max|U_exact|;
  (2) the field is in equilibrium at the interior nodes: max|(K u_exact)_interior| / max|K u_exact|;
  (3) strain energy 1/2 u^T K u equals the constant-strain value 1/2 A e^T C e (C = C_m or C_b);
  (4) flat meshes: the bending strain norm of every element (Model.bending_strain) equals
      sqrt(3) 1e-3 (bending) or 0 (membrane).
A passing element gives (1)-(4) to round-off; a failing one is off by O(1e-3..1), independent of h.
The round-off floor of (2) grows like eps (L/h)^2 (the shear and membrane stiffnesses ~h cancel in
K u_exact against a bending response ~h^3): ~1e-9 at L/h = 240; ``thickness_scan`` shows it.

Run: ``python -m verification.patch`` -> table and verification/out/patch.json.
"""

from __future__ import annotations

from solidshell.verify.elements import (  # noqa: F401  (the computations live in the package)
    AMP, AREA, INNER, MAT, NODES, OUTER, QUADS, exact_field, patch_mesh, run_one)

from . import write_json


def run(verbose=True):
    rows = []
    if verbose:
        print(f"{'mesh':10s} {'case':9s} {'|U-Uex|/|U|':>12s} {'residual':>10s} {'energy err':>11s} {'bend. strain':>12s}")
    for kind in ("quads", "tris", "mixed", "quads-rot", "tris-rot", "mixed-rot"):
        for case in ("membrane", "bending"):
            row = run_one(kind, case)
            rows.append(row)
            if verbose:
                bs = row.get("bending_strain_error")
                print(f"{kind:10s} {case:9s} {row['displacement_error']:12.2e} {row['equilibrium_residual']:10.2e} "
                      f"{row['energy_error']:+11.2e} {'' if bs is None else f'{bs:12.2e}'}")
    return rows


def thickness_scan(verbose=True):
    """Bending patch for h = 0.1 ... 1e-4: the residual grows like (L/h)^2 (round-off of the
    membrane/shear stiffness, ~h, against the bending stiffness, ~h^3), which distinguishes
    conditioning from a patch-test failure (that would not depend on h)."""
    rows = []
    if verbose:
        print("bending patch vs thickness (round-off floor ~ eps (L/h)^2):")
    for h in (0.1, 0.01, 0.001, 0.0001):
        for kind in ("quads", "tris", "mixed-rot"):
            row = run_one(kind, "bending", h)
            rows.append(row)
            if verbose:
                print(f"  h={h:7.0e} {kind:10s} |U-Uex|/|U| {row['displacement_error']:.1e}  residual "
                      f"{row['equilibrium_residual']:.1e}  residual*(h/0.24)^2 {row['equilibrium_residual'] * (h / 0.24) ** 2:.1e}")
    return rows


def main(argv=None):
    rows = run()
    scan = thickness_scan()
    p = write_json("patch", {"description": __doc__.splitlines()[0], "rows": rows, "thickness_scan": scan})
    worst = max(max(abs(v) for k, v in r.items() if k not in ("mesh", "case", "h")) for r in rows)
    print("wrote", p, f"; worst relative deviation {worst:.2e}")
    return rows


if __name__ == "__main__":
    main()
