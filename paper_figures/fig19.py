"""Fig. 19: A 20x20 cm square fabric sheet draped over a 10x10 cm square pedestal: the adaptive mesh and deformed shapes at different instants (level 0: 48 quadrilaterals).
See _adaptive.py for the settings.

    python -m paper_figures.fig19 [--quick] [--out DIR]
"""

from pathlib import Path

from ._adaptive import make_adaptive

NAME = "fig19"
CAPTION = "A 20x20 cm square fabric sheet draped over a 10x10 cm square pedestal: the adaptive mesh and deformed shapes at different instants (level 0: 48 quadrilaterals)."


def make(out_dir: Path, quick: bool = False) -> dict:
    return make_adaptive(
        NAME,
        "square-pedestal",
        CAPTION,
        out_dir,
        quick,
        "Fig. 19  20x20 cm sheet on a 10x10 cm pedestal, adaptive (§6.1)",
    )


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
