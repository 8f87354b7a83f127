"""Fig. 22: A 30x30 cm square cloth draped on a 10 cm diameter sphere: adaptive meshes and deformed shapes at different instants (level 0: 16x16 quadrilaterals).
See _adaptive.py for the settings.

    python -m paper_figures.fig22 [--quick] [--out DIR]
"""

from pathlib import Path

from ._adaptive import make_adaptive

NAME = "fig22"
CAPTION = "A 30x30 cm square cloth draped on a 10 cm diameter sphere: adaptive meshes and deformed shapes at different instants (level 0: 16x16 quadrilaterals)."


def make(out_dir: Path, quick: bool = False) -> dict:
    return make_adaptive(
        NAME, "sphere", CAPTION, out_dir, quick, "Fig. 22  30x30 cm cloth on a 10 cm sphere, adaptive (§6.4)"
    )


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
