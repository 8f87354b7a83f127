"""Fig. 20: A 40x40 cm square fabric sheet draped over a 20x20 cm square pedestal. (a) to (d) are isometric and top views of the mesh in the dynamic process.
See _adaptive.py for the settings.

    python -m paper_figures.fig20 [--quick] [--out DIR]
"""

from pathlib import Path

from ._adaptive import make_adaptive

NAME = "fig20"
CAPTION = "A 40x40 cm square fabric sheet draped over a 20x20 cm square pedestal. (a) to (d) are isometric and top views of the mesh in the dynamic process."


def make(out_dir: Path, quick: bool = False) -> dict:
    return make_adaptive(
        NAME,
        "large-square-pedestal",
        CAPTION,
        out_dir,
        quick,
        "Fig. 20  40x40 cm sheet on a 20x20 cm pedestal, adaptive (§6.2)",
    )


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
