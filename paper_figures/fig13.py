"""Fig. 13: the steady state of the 30x30 cm cloth on the 10 cm sphere on 100x100 elements with the
Green thickness strain (paper §4.3: no interpenetration, no sharp folds).  See _sphere.py;
--quick: 40x40.

    python -m paper_figures.fig13 [--quick] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path

from . import common
from ._sphere import label, run_sphere

NAME = "fig13"
CAPTION = (
    "The steady-state shapes of a 30x30 cm square cloth draped on a 10 cm diameter sphere predicted by "
    "dynamic relaxation using 100x100 elements."
)


def make(out_dir: Path, quick: bool = False) -> dict:
    out, rec = run_sphere("40x40" if quick else "100x100", quick)
    X = common.positions(out.mesh, out.U)
    fig, _ = common.views_figure([(label(rec), out, X)], views=("top", "iso", "side"), panel_size=4.2)
    info = {
        "figure": NAME,
        "caption": CAPTION,
        "quick": quick,
        "runs": [rec],
        "differs_from_paper": "friction 0.3 on the sphere" + ("; quick: 40x40, kinetic damping" if quick else ""),
    }
    common.save(
        fig, out_dir, NAME, info, suptitle="Fig. 13  30x30 cm cloth on a 10 cm sphere, dynamic relaxation (§4.3)"
    )
    return info


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
