"""Fig. 4: a 5x1 cm wool strip clamped at one end (paper §3.1).  (a) isometric view of the deformed
warp-cut strip on 10x1 elements; (b) side views of the warp- and weft-cut strips on 10x1 and 20x1
elements over the reference curve.  The paper's reference is a 50x5 S4R (Abaqus) model; ours is the
heavy inextensible elastica (reference/elastica_strip.json, reference/elastica.py), an exact
solution of the same beam problem.  Cheap: --quick runs the same settings.

    python -m paper_figures.fig04 [--quick] [--out DIR]
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from . import common

NAME = "fig04"
CAPTION = (
    "A 5x1 cm wool strip clamped at one end. (a) The isometric view of the deformed warp-cut strip "
    "predicted by 10x1 elements; (b) the side view of the deformed predictions."
)
REFERENCE = Path(__file__).resolve().parents[1] / "reference" / "elastica_strip.json"


def centreline(out):
    """(x, z) of the strip's centre line [cm]: nodal positions averaged across the width."""
    X = common.positions(out.mesh, out.U)
    x0 = np.round(out.mesh.nodes[:, 0], 9)
    xs = np.unique(x0)
    return np.array([X[x0 == v][:, [0, 2]].mean(axis=0) for v in xs])


def make(out_dir: Path, quick: bool = False) -> dict:
    plt = common.mpl()
    ref = json.loads(REFERENCE.read_text())["strip"]
    runs, recs = {}, []
    for cut in ("warp", "weft"):
        for m in ("10x1", "20x1"):
            out, rec = common.run(f"strip-{cut}", mesh=m, solver="static")
            runs[cut, m] = out
            c = centreline(out)
            rec["tip_z_error_vs_elastica"] = float(c[-1, 1] - ref[cut]["tip_z"])
            recs.append(rec)
    fig = plt.figure(figsize=(10.0, 5.0))
    ax_a = fig.add_axes([0.0, 0.04, 0.44, 0.82])
    o = runs["warp", "10x1"]
    X = common.positions(o.mesh, o.U)
    sm = common.panel(ax_a, o, X, "iso", title="(a) warp-cut strip, 10x1 elements, isometric view")
    common.colorbar(fig, ax_a, sm)
    ax_b = fig.add_axes([0.5, 0.1, 0.28, 0.76])
    colours = {"warp": "C0", "weft": "C3"}
    for cut in ("warp", "weft"):
        r = ref[cut]["curve"]
        ax_b.plot(
            r["x"],
            r["z"],
            "-",
            color="0.2",
            lw=2.4,
            alpha=0.35,
            label=f"{cut}: elastica (reference)" if cut == "warp" else "weft: elastica (reference)",
        )
        for m, mk in (("10x1", "o"), ("20x1", "s")):
            c = centreline(runs[cut, m])
            ax_b.plot(
                c[:, 0],
                c[:, 1],
                mk + "-",
                color=colours[cut],
                ms=3.2,
                lw=0.9,
                mfc="none" if m == "20x1" else None,
                label=f"{cut}-cut, {m}",
            )
    ax_b.set_aspect("equal")
    ax_b.set_xlabel("x [cm]  (along the strip)")
    ax_b.set_ylabel("z [cm]")
    ax_b.grid(True, lw=0.3, alpha=0.5)
    ax_b.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.03, 0.5), frameon=False)
    ax_b.set_title("(b) side view: centre lines over the elastica", fontsize=9)
    info = {
        "figure": NAME,
        "caption": CAPTION,
        "quick": quick,
        "runs": recs,
        "differs_from_paper": "reference curve: the heavy elastica instead of the paper's 50x5 S4R model",
    }
    common.save(fig, out_dir, NAME, info, suptitle="Fig. 4  A 5x1 cm wool strip clamped at one end (§3.1)")
    return info


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
