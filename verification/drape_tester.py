"""The drape tester (issue 38 item 5): DC and folds of the library's fabrics, their sensitivity to
bending rigidity, shear rigidity and weight, the specimen sizes, and measured DCs where a source
gives them (docs/fabrics.md).

    NUMBA_NUM_THREADS=1 nice .venv/bin/python -m verification.drape_tester --ladder   # ~10 min, 2 cores
    .venv/bin/python -m verification.drape_tester --mesh 12x96 --factors 0.5 2        # quicker, no ladder

Every case is the packaged scene ``drape-tester`` (30 cm specimen on the 18 cm disc of a Cusick
support with an 18 cm clamp) solved statically from the flat specimen on one mesh (default 24x192:
0.25 cm radially, 0.49 cm round the rim; its DC lies 0.012 above the mesh ladder's limit).  Per fabric of the library:

* the fabric as published, and with its bending rigidities (B_warp, B_weft and the torsional
  rigidity together), its shear rigidity G, its weight W each multiplied by the ``--factors``;
* all of B, G, the tensile rigidities and W doubled together: a static drape feels only the
  rigidities per unit weight, so the DC must not move (a check of the study itself);
* the 24 and 36 cm specimens of the standard.

Each row: the DC as summary.json reports it, (A_projected - A_disc) / (A_specimen - A_disc) with the
shoelace area of the projected outline; the DC of the shadow, the star-shaped envelope of that
outline (the same number when no fold tucks back under another, which the row shows); the fold
count; the bending length c = (B_mean / W)^(1/3) [cm] (Peirce's, the drape's own length scale);
whether the static solve converged to a stable equilibrium; and the contact and self-contact
contracts recounted from the written files by verification/penetration_check and
verification/self_check (nodes/face points beyond 2 % of h, intersecting triangle pairs).

``--ladder`` solves the fabric as published on 8x64 ... 32x256 (the DC against the mesh).
Measured DCs: a library entry with a ``[NAME.drape]`` table (dc, specimen_diameter, disc_diameter,
source) gets a simulated-vs-measured row on that specimen.  Writes verification/out/drape_tester.{md,json}.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"
LADDER = ("8x64", "12x96", "16x128", "24x192", "32x256")


def _case(mesh: str, overrides: dict, work: Path) -> dict:
    from solidshell import run_scene
    from verification import penetration_check, self_check

    run_dir = work / f"run{len(list(work.iterdir()))}"
    t0 = time.perf_counter()
    ov = {**overrides, "output.pictures": []}
    out = run_scene("drape-tester", mesh=mesh, out_dir=run_dir, progress=False, overrides=ov)
    wall = time.perf_counter() - t0
    s = out.summary
    pen_lines, pen_clean = penetration_check.check_run(run_dir, 5)
    self_line, self_clean = self_check.check_run(run_dir)
    a_disc, a_spec = s["pedestal_area"], s["sheet_area"]
    return {
        "mesh": mesh,
        "overrides": overrides,
        "dc": s["drape_coefficient"],
        "dc_shadow": (s["envelope_area"] - a_disc) / (a_spec - a_disc),
        "folds": s["fold_count"],
        "converged": bool(s["converged"]),
        "stable": bool(s.get("positive_definite")),
        "contact_clean": bool(pen_clean),
        "self_clean": bool(self_clean),
        "checks": [*pen_lines, self_line],
        "wall_s": wall,
    }


def _row(label: str, fab: dict, r: dict) -> str:
    c = (0.5 * (fab["bending_warp"] + fab["bending_weft"]) / fab["weight"]) ** (1 / 3)
    ok = "yes" if r["converged"] and r["stable"] else ("saddle" if r["converged"] else "no")
    clean = "clean" if r["contact_clean"] and r["self_clean"] else "VIOLATED"
    return (
        f"| {label} | {fab['bending_warp']:.4g} / {fab['bending_weft']:.4g} | {fab['shear']:.4g} | "
        f"{fab['weight']:.4g} | {c:.3f} | {r['dc']:.4f} | {r['dc_shadow']:.4f} | {r['folds']} | {ok} | {clean} | "
        f"{r['wall_s']:.0f} |"
    )


HEAD = (
    "| case | B warp / weft [gf cm^2/cm] | shear [gf/cm] | W [gf/cm^2] | c [cm] | DC | DC shadow | folds | "
    "stable | contact, self | s |\n|---|---|---|---|---|---|---|---|---|---|---|"
)


def _scaled(fields: dict, what: str, k: float) -> dict:
    keys = {"B": ("bending_warp", "bending_weft", "torsion"), "G": ("shear",), "W": ("weight",)}[what]
    return {**fields, **{q: fields[q] * k for q in keys}}


def main(argv=None) -> int:
    from solidshell import fabrics

    ap = argparse.ArgumentParser(prog="python -m verification.drape_tester", description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", default="24x192", help="the mesh of every case (default 24x192)")
    ap.add_argument("--factors", type=float, nargs="*", default=[0.25, 0.5, 2.0, 4.0])
    ap.add_argument("--ladder", action="store_true", help="also solve each fabric on 8x64 ... 32x256")
    ap.add_argument("--out", default=str(OUT / "drape_tester"), help="report stem (.md and .json)")
    args = ap.parse_args(argv)

    lines, rows = [], []
    with tempfile.TemporaryDirectory(prefix="drape_tester_") as tmp:
        work = Path(tmp)
        for name, lib in fabrics.library().items():
            base = dict(lib.fields)

            def run(label, fields, extra=None, mesh=args.mesh):
                ov = {"material.fabric": name, **{f"material.{k}": v for k, v in fields.items()}, **(extra or {})}
                r = _case(mesh, ov, work)
                r.update(label=label, fabric=name, fields=fields)
                rows.append(r)
                lines.append(_row(label, fields, r))
                print(lines[-1], flush=True)
                return r

            lines += ["", f"### {name}: {lib.title} (mesh {args.mesh}, 30 cm specimen unless said)", "", HEAD]
            print("\n".join(lines[-4:]), flush=True)
            ref = run("as published", base)
            for what in ("B", "G", "W"):
                for k in args.factors:
                    run(f"{what} x {k:g}", _scaled(base, what, k))
            both = {
                **base,
                **{
                    q: base[q] * 2
                    for q in (
                        "bending_warp",
                        "bending_weft",
                        "torsion",
                        "shear",
                        "tensile_warp",
                        "tensile_weft",
                        "weight",
                    )
                },
            }
            same = run("B, G, tensile, W all x 2", both)
            lines.append(f"\nAll rigidities and the weight doubled: DC {same['dc']:.5f} against {ref['dc']:.5f}.")
            for d in (24.0, 36.0):
                run(f"{d:g} cm specimen", base, {"geometry.diameter": d})
            if lib.drape:
                dr = lib.drape
                m = run(
                    f"measured: DC {dr['dc']:g}",
                    base,
                    {"geometry.diameter": dr["specimen_diameter"], "geometry.pedestal_diameter": dr["disc_diameter"]},
                )
                lines.append(
                    f"\nSimulated {m['dc']:.4f} against measured {dr['dc']:g} ({dr.get('source', lib.source)})."
                )
            else:
                lines.append(f"\nNo measured drape coefficient of {name} in the library (its source gives none).")
            if args.ladder:
                lines += ["", f"Mesh ladder, {name} as published:", "", HEAD]
                for m in LADDER:
                    run(f"mesh {m}", base, mesh=m)
    cmd = " ".join(["python -m verification.drape_tester", *(sys.argv[1:] if argv is None else argv)])
    report = "\n".join(
        [
            "# The drape tester: DC against bending rigidity, shear rigidity and weight",
            "",
            f"Written by `{cmd}` (verification/drape_tester.py says what each column is; docs/fabrics.md",
            "discusses it). Static solves from the flat specimen; wall times [s] on a shared 2-core machine.",
            *lines,
        ]
    )
    Path(args.out).with_suffix(".md").write_text(report + "\n")
    Path(args.out).with_suffix(".json").write_text(json.dumps(rows, indent=1, default=float) + "\n")
    bad = [r["label"] for r in rows if not (r["contact_clean"] and r["self_clean"] and r["converged"])]
    print(
        f"\nwrote {Path(args.out).with_suffix('.md')}; {len(rows)} cases, {len(bad)} not converged or not clean {bad}"
    )
    return 0 if not bad and math.isfinite(sum(r["dc"] for r in rows)) else 1


if __name__ == "__main__":
    raise SystemExit(main())
