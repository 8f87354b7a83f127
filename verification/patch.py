"""Patch tests (small deflection) on the distorted five-element patch of MacNeal & Harder (1985).

The table printer over verification.checks.elements, where the computation and its description live.
"""

from __future__ import annotations

from verification.checks.elements import AMP, AREA, INNER, MAT, NODES, OUTER, QUADS, exact_field, patch_mesh, run_one  # noqa: F401  (the computations live in the package)

from . import write_json


def run(verbose=True):
    rows = []
    if verbose:
        print(
            f"{'mesh':10s} {'case':9s} {'|U-Uex|/|U|':>12s} {'residual':>10s} {'energy err':>11s} {'bend. strain':>12s}"
        )
    for kind in ("quads", "tris", "mixed", "quads-rot", "tris-rot", "mixed-rot"):
        for case in ("membrane", "bending"):
            row = run_one(kind, case)
            rows.append(row)
            if verbose:
                bs = row.get("bending_strain_error")
                print(
                    f"{kind:10s} {case:9s} {row['displacement_error']:12.2e} {row['equilibrium_residual']:10.2e} "
                    f"{row['energy_error']:+11.2e} {'' if bs is None else f'{bs:12.2e}'}"
                )
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
                print(
                    f"  h={h:7.0e} {kind:10s} |U-Uex|/|U| {row['displacement_error']:.1e}  residual "
                    f"{row['equilibrium_residual']:.1e}  residual*(h/0.24)^2 {row['equilibrium_residual'] * (h / 0.24) ** 2:.1e}"
                )
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
