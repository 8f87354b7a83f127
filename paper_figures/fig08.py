"""Fig. 8: a 40x40 cm wool sheet draped over a 20x20 cm square pedestal (paper §3.5), static,
45x15x4 elements.  --quick: 24x8x4.

    python -m paper_figures.fig08 [--quick] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path

from . import common

NAME = "fig08"
CAPTION = "Predictions of a 40x40 cm square fabric sheet draped over a 20x20 cm square pedestal."


def make(out_dir: Path, quick: bool = False) -> dict:
    m = "24x8x4" if quick else "45x15x4"
    out, rec = common.run("large-square-pedestal", mesh=m, solver="static")
    fig, _ = common.views_figure([(common.describe(rec), out, common.positions(out.mesh, out.U))], panel_size=4.6)
    info = {
        "figure": NAME,
        "caption": CAPTION,
        "quick": quick,
        "runs": [rec],
        "differs_from_paper": "; ".join(
            x for x in (common.interpenetration_note(rec), "quick: 24x8x4 instead of 45x15x4" if quick else "") if x
        ),
    }
    common.save(
        fig, out_dir, NAME, info, suptitle="Fig. 8  40x40 cm sheet on a 20x20 cm square pedestal (§3.5, static)"
    )
    return info


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
