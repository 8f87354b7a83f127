"""Fig. 21: A 50x50 cm square fabric sheet draped over a 20 cm diameter pedestal: adaptive meshes and deformed shapes at different instants (level 0: 4x32 quadrilaterals).
See _adaptive.py for the settings.

    python -m paper_figures.fig21 [--quick] [--out DIR]
"""

from pathlib import Path

from ._adaptive import make_adaptive

NAME = "fig21"
CAPTION = "A 50x50 cm square fabric sheet draped over a 20 cm diameter pedestal: adaptive meshes and deformed shapes at different instants (level 0: 4x32 quadrilaterals)."


def make(out_dir: Path, quick: bool = False) -> dict:
    return make_adaptive(
        NAME,
        "square-on-disc",
        CAPTION,
        out_dir,
        quick,
        "Fig. 21  50x50 cm sheet on a 20 cm diameter pedestal, adaptive (§6.3)",
    )


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
