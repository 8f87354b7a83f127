"""The figure scripts by name, and the driver behind ``solidshell figures``."""

from __future__ import annotations

import argparse
import importlib
import json
import logging
import time
from pathlib import Path

from solidshell.errors import InputError

FIGURES = ("4", "5", "6", "7", "8", "9", "10", "11", "12", "13", "19", "20", "21", "22")
log = logging.getLogger("solidshell")


def module_name(fig: str) -> str:
    """'5', 'fig5', 'fig05', 'Fig5' -> 'fig05'; InputError naming the valid names otherwise."""
    s = str(fig).strip().lower()
    s = s[3:] if s.startswith("fig") else s
    if s.lstrip("0") not in FIGURES:
        raise InputError(f"unknown figure {fig!r}; valid: {', '.join(FIGURES)}")
    return f"fig{int(s):02d}"


def make_figures(figs=None, quick: bool = False, out_dir="figures", say=print) -> list[dict]:
    """Render the figures (all when ``figs`` is empty) into out_dir; returns each one's info.
    Every name is checked before anything runs."""
    names = [module_name(f) for f in (figs or FIGURES)]
    out = Path(out_dir)
    done = []
    for name in dict.fromkeys(names):
        mod = importlib.import_module(f"paper_figures.{name}")
        t = time.perf_counter()
        info = mod.make(out, quick=quick)
        wall = time.perf_counter() - t
        info["wall_s"] = round(wall, 1)
        (out / f"{name}.json").write_text(json.dumps(info, indent=1, default=str) + "\n")
        say(f"{name}: {wall:6.1f} s  -> {out / (name + '.png')}")
        done.append(info)
    return done


def script_main(name: str) -> None:
    """``python -m paper_figures.figNN [--quick] [--out DIR]``."""
    p = argparse.ArgumentParser(prog=f"python -m paper_figures.{name}")
    p.add_argument("--quick", action="store_true", help="coarser meshes and faster relaxation (minutes)")
    p.add_argument("--out", default="figures", help="output folder (default: figures)")
    a = p.parse_args()
    make_figures([name], quick=a.quick, out_dir=a.out)
