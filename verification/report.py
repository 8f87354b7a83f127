"""Collect the element verification into verification/out/report.md.

``python -m verification.report``         reads verification/out/{plates,locking,patch}.json
``python -m verification.report --run``   first re-runs verification.plates, .locking and .patch
(about a minute on one core) and then writes the report.  The references come from reference/
(plates.json via reference/kirchhoff_plate.py; beams.py closed forms).
"""

from __future__ import annotations

import argparse
import json

from . import OUT, plate_reference


def _load(name):
    p = OUT / f"{name}.json"
    return json.loads(p.read_text()) if p.exists() else None


def _fmt(x, f="+.3e"):
    return "" if x is None else format(x, f)


def plates_section(d) -> list[str]:
    ref = plate_reference()
    L = [
        "## Square plate, uniform pressure (verification/plates.py)",
        "",
        f"Reference alpha = w_c D/(q a^4): SS {ref['alpha']['simply_supported']:.10f}, "
        f"clamped {ref['alpha']['clamped']:.10f} (reference/plates.md). ν = 0.3; "
        "error relative to the Kirchhoff series; rate = observed order from N/2 to N. "
        "For hard SS the last column compares with the Reissner–Mindlin value alpha + c (h/a)^2.",
        "",
        "| support | mesh | a/h | N | alpha | rel. error | rate | vs Mindlin |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in d["rows"]:
        L.append(
            f"| {r['support']} | {r['mesh']} | {r['a_over_h']:.0f} | {r['n']} | {r['alpha']:.8f} | "
            f"{_fmt(r['rel_error'])} | {_fmt(r['rate'], '.2f')} | {_fmt(r.get('rel_error_vs_mindlin'))} |"
        )
    m = d.get("triangle_vs_independent_mitc3")
    if m:
        L += [
            "",
            "Solid-shell triangle vs an independent MITC3 plate implementation (same mesh, '/' split):",
            "",
            "| support | a/h | N | tri3 | MITC3 | rel. difference |",
            "|---|---|---|---|---|---|",
        ]
        for r in m:
            L.append(
                f"| {r['support']} | {r['a_over_h']:.0f} | {r['n']} | {r['solid_shell']:.8e} | {r['mitc3']:.8e} | "
                f"{_fmt(r['rel_difference'], '+.1e')} |"
            )
    b = d.get("buckling")
    if b:
        L += [
            "",
            "Buckling of the SS square plate under uniaxial compression (a/h = 100), k = N_cr a²/(π² D), "
            "references 4, 6.25, 11.11:",
            "",
            "| mesh | N | k | rel. errors |",
            "|---|---|---|---|",
        ]
        for r in b:
            L.append(
                f"| {r['kind']} | {r['n']} | {', '.join(f'{v:.4f}' for v in r['k'])} | "
                f"{', '.join(f'{e:+.2e}' for e in r['rel_error'])} |"
            )
    return L + [""]


def locking_section(d) -> list[str]:
    L = [
        "## Cantilever strip (verification/locking.py)",
        "",
        "Tip load, ν = 0, 8 elements along, 1 across; error vs Timoshenko beam and vs the exact 8-element "
        "tied-shear Timoshenko beam (reference/beams.py).",
        "",
        "| mesh | L/h | vs Timoshenko | vs 8-element beam |",
        "|---|---|---|---|",
    ]
    for r in d["tip_load"]:
        L.append(
            f"| {r['kind']} | {r['L_over_h']:.0f} | {_fmt(r['rel_error'])} | {_fmt(r['rel_error_vs_beam_element'])} |"
        )
    L += [
        "",
        "End moment, ν = 0.3, vs plane-stress theory (free: M = EI κ, κ_y = −ν κ; restrained: M = D b κ; "
        "clamped root: no closed form, informative).",
        "",
        "| mesh | root | L/h | tip rotation error | tip deflection error | κ_y/κ_x |",
        "|---|---|---|---|---|---|",
    ]
    for r in d["end_moment"]:
        L.append(
            f"| {r['kind']} | {r['support']} | {r['L_over_h']:.0f} | {_fmt(r['rel_error_rotation'])} | "
            f"{_fmt(r['rel_error_deflection'])} | {r['kappa_y'] / r['kappa_x']:.6f} |"
        )
    mh = d.get("macneal_harder_beam")
    if mh:
        L += [
            "",
            "MacNeal–Harder straight cantilever (6 quads), tip displacement / reference:",
            "",
            "| load | shape | tip | normalised |",
            "|---|---|---|---|",
        ]
        for r in mh:
            L.append(f"| {r['load']} | {r['shape']} | {r['tip']:.5e} | {r['normalised']:.4f} |")
    col = d.get("column_buckling")
    if col:
        L += [
            "",
            "Euler buckling of the strip (L/h = 100), reference π²EI/(4L²):",
            "",
            "| mesh | n | P_cr error | 2nd/1st (9) |",
            "|---|---|---|---|",
        ]
        for r in col:
            L.append(f"| {r['kind']} | {r['n']} | {_fmt(r['rel_error'])} | {r['second_over_first']:.3f} |")
    curv = d.get("curved_cantilever")
    if curv:
        L += [
            "",
            "Quarter-circle strip (trapezoidal cross-sections), tip load, error vs thin curved-beam theory:",
            "",
            "| mesh | load | n | R/h | rel. error |",
            "|---|---|---|---|---|",
        ]
        for r in curv:
            L.append(f"| {r['kind']} | {r['load']} | {r['n']} | {r['R_over_h']:.0f} | {_fmt(r['rel_error'])} |")
    circ = d.get("circle")
    if circ:
        L += [
            "",
            "Large rotation: strip rolled into a circle by a prescribed tip director (L/h = 100, ν = 0); "
            "reference: arc of radius L/φ, tip moment EIφ/L:",
            "",
            "| mesh | n | φ/π | converged | tip error / L | M/(EIφ/L) | max abs(x_n)−1 |",
            "|---|---|---|---|---|---|---|",
        ]
        for r in circ:
            L.append(
                f"| {r['kind']} | {r['n']} | {r['phi_over_pi']:.1f} | {r['converged']} | {r['error_over_L']:.2e} | "
                f"{r['moment_ratio']:.5f} | {r['max_director_stretch']:.1e} |"
            )
    return L + [""]


def patch_section(d) -> list[str]:
    L = [
        "## Patch tests, MacNeal–Harder 5-element patch (verification/patch.py)",
        "",
        "| mesh | field | interior U error | equilibrium residual | energy error | bending-strain error |",
        "|---|---|---|---|---|---|",
    ]
    for r in d["rows"]:
        L.append(
            f"| {r['mesh']} | {r['case']} | {r['displacement_error']:.1e} | {r['equilibrium_residual']:.1e} | "
            f"{_fmt(r['energy_error'], '+.1e')} | {_fmt(r.get('bending_strain_error'), '.1e')} |"
        )
    scan = d.get("thickness_scan")
    if scan:
        L += [
            "",
            "Bending patch vs thickness: the residual's floor scales like (L/h)^2 (round-off), "
            "residual·(h/L)^2 stays constant:",
            "",
            "| h | mesh | U error | residual | residual·(h/0.24)^2 |",
            "|---|---|---|---|---|",
        ]
        for r in scan:
            L.append(
                f"| {r['h']:.0e} | {r['mesh']} | {r['displacement_error']:.1e} | {r['equilibrium_residual']:.1e} | "
                f"{r['equilibrium_residual'] * (r['h'] / 0.24) ** 2:.1e} |"
            )
    return L + [""]


def main(argv=None):
    ap = argparse.ArgumentParser(description="element verification report")
    ap.add_argument("--run", action="store_true", help="re-run the verification scripts first")
    args = ap.parse_args(argv)
    if args.run:
        from . import locking, patch, plates

        plates.main([])
        locking.main([])
        patch.main([])
    parts = [
        "# Element verification report",
        "",
        "Generated by `python -m verification.report` from verification/out/*.json.",
        "",
    ]
    parts += [
        "The plate-buckling and column-buckling rows check the geometric (Green-strain) part of the "
        "tangent against closed forms.",
        "",
    ]
    for name, fn in (("plates", plates_section), ("locking", locking_section), ("patch", patch_section)):
        d = _load(name)
        parts += fn(d) if d else [f"## {name}: not run (python -m verification.{name})", ""]
    OUT.mkdir(exist_ok=True)
    p = OUT / "report.md"
    p.write_text("\n".join(parts))
    print("wrote", p)


if __name__ == "__main__":
    main()
