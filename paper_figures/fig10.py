"""Fig. 10: dynamic draping of a 100x100 cm wool sheet hung by two corners (paper §4.1, 50x50
elements), t = 0, 0.4, 1.4, 3.0 s.  See _hang.py.

    python -m paper_figures.fig10 [--quick] [--out DIR]
"""

from pathlib import Path

from ._hang import make_hang

NAME = "fig10"
CAPTION = "Dynamic draping process of a 100x100 cm square fabric sheet hung by two corners at t = 0, 0.4, 1.4, 3.0 s."


def make(out_dir: Path, quick: bool = False) -> dict:
    return make_hang(
        NAME,
        "hang-100",
        CAPTION,
        out_dir,
        quick,
        "Fig. 10  100x100 cm sheet hung by two adjacent corners (§4.1, explicit dynamics)",
    )


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
