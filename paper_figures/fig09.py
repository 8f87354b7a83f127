"""Fig. 9: dynamic draping of a 20x20 cm wool sheet hung by two corners (paper §4.1, 40x40
elements), t = 0, 0.1, 0.4, 2.1 s.  See _hang.py.

    python -m paper_figures.fig09 [--quick] [--out DIR]
"""

from pathlib import Path

from ._hang import make_hang

NAME = "fig09"
CAPTION = (
    "Dynamic draping process of a 20x20 cm square fabric sheet hung by two corners. (a) to (d) are the "
    "isometric and side views at different time instants."
)


def make(out_dir: Path, quick: bool = False) -> dict:
    return make_hang(
        NAME,
        "hang-20",
        CAPTION,
        out_dir,
        quick,
        "Fig. 9  20x20 cm sheet hung by two adjacent corners (§4.1, explicit dynamics)",
    )


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
