"""Fig. 5: a 20x20 cm wool sheet draped over a 10x10 cm square pedestal (paper §3.2), static.
(a) top and isometric views on 24x8x4 elements; (b) on 48x16x4; (c) the projected boundaries on
the X-Y plane.  The paper's (c) also has Kang & Yu's experiment and a 90x30x4 S4R model, which we
do not have; a reference-code boundary (reference/, issue #12 item 2) is overlaid when stored.
--quick: 12x4x4 and 24x8x4.

    python -m paper_figures.fig05 [--quick] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path

from . import common

NAME = "fig05"
CAPTION = (
    "A 20x20 cm square fabric sheet draped over a 10x10 cm square pedestal. (a) The top and isometric "
    "views predicted by 24x8x4 elements; (b) the top and isometric views predicted by 48x16x4 elements; "
    "(c) the deformed boundary projected onto X-Y plane."
)


def make(out_dir: Path, quick: bool = False) -> dict:
    meshes = ("12x4x4", "24x8x4") if quick else ("24x8x4", "48x16x4")
    rows, recs, bnd = [], [], {}
    for tag, m in zip("ab", meshes):
        out, rec = common.run("square-pedestal", mesh=m, solver="static")
        recs.append(rec)
        rows.append((f"({tag}) {m}", out, common.positions(out.mesh, out.U)))
        bnd[common.describe(rec)] = common.projected_boundary(out)
    fig, _ = common.views_figure(
        rows, boundaries=bnd, pedestal=rows[0][1].scene.pedestal(), boundary_title="(c) projected boundaries"
    )
    info = {
        "figure": NAME,
        "caption": CAPTION,
        "quick": quick,
        "runs": recs,
        "differs_from_paper": "(c) has no experiment (Kang & Yu) and no 90x30x4 S4R curve; "
        + ("quick: meshes 12x4x4 and 24x8x4 instead of 24x8x4 and 48x16x4" if quick else ""),
    }
    common.save(
        fig, out_dir, NAME, info, suptitle="Fig. 5  20x20 cm sheet on a 10x10 cm square pedestal (§3.2, static)"
    )
    return info


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
