"""Fig. 12: (a) top, (b) side and (c) zoomed top views of the steady state of a 30x30 cm cloth on a
10 cm sphere by dynamic relaxation on 60x60 elements (paper §4.2); the paper's zoom shows sharp
folds (interpenetrated elements, §4.3).  Interpenetrated nodes (n_p . d_p < 0) are counted in the
json and the title, marked with red crosses on (a) and (c), and (c) zooms on them (else on the
quadrant x, y > 0); the final state is kept in fig12.npz.  See _sphere.py; --quick: 30x30.

    python -m paper_figures.fig12 [--quick] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import common
from ._sphere import label, run_sphere

NAME = "fig12"
CAPTION = (
    "(a) Top, (b) side and (c) zoomed top views of the steady-state shapes of a 30x30 cm square cloth "
    "draped on a 10 cm diameter sphere predicted by dynamic relaxation using 60x60 elements."
)
ZOOM = (-1.0, 9.0, -1.0, 9.0)  # [cm] the quadrant x, y > 0 around the sphere's rim (r = 5 cm)
HALF = 5.0  # [cm] half the zoom window's side


def zoom_window(X, flagged):
    """The zoom (xmin, xmax, ymin, ymax) [cm]: a 10 cm square centred on the densest cluster of
    interpenetrated nodes (the one with the most others within HALF; the paper's zoom shows its
    sharp folds), else the quadrant ZOOM."""
    if not np.any(flagged):
        return ZOOM
    P = X[flagged, :2]
    near = (np.linalg.norm(P[:, None, :] - P[None, :, :], axis=-1) < HALF).sum(axis=1)
    cx, cy = P[int(np.argmax(near))]  # the first of equally dense ones (a symmetric drape has several)
    return (cx - HALF, cx + HALF, cy - HALF, cy + HALF)


def make(out_dir: Path, quick: bool = False) -> dict:
    plt = common.mpl()
    out, rec = run_sphere("30x30" if quick else "60x60", quick)
    X = common.positions(out.mesh, out.U)
    flagged = common.interpenetrated(out)
    zoom = zoom_window(X, flagged)
    common.save_state(out_dir, NAME, out, interpenetrated=flagged)
    norm = common.height_norm(X)
    fig = plt.figure(figsize=(13.5, 4.6))
    gs = fig.add_gridspec(1, 3, wspace=0.3, width_ratios=[1, 1.15, 1])  # room for (b)'s z label
    axes = [fig.add_subplot(gs[0, i]) for i in range(3)]
    sm = common.panel(axes[0], out, X, "top", norm=norm, title="(a) top view")
    common.panel(axes[1], out, X, "side", norm=norm, title="(b) side view")
    # whole-cm ticks every 5 cm and a padded label: "z [cm]" sat on the -12.5-wide tick labels
    from matplotlib.ticker import MultipleLocator

    axes[1].yaxis.set_major_locator(MultipleLocator(5.0))
    axes[1].yaxis.labelpad = 8.0
    common.panel(axes[2], out, X, "top", norm=norm, zoom=zoom, title="(c) top view, zoomed")
    axes[0].add_patch(plt.Rectangle(zoom[::2], zoom[1] - zoom[0], zoom[3] - zoom[2], fill=False, ec="r", lw=0.8))
    if flagged.any():  # marked over the picture: a node on a fold's underside is hidden in the view
        for ax, ms in ((axes[0], 3), (axes[2], 5)):
            ax.plot(
                X[flagged, 0],
                X[flagged, 1],
                "x",
                color="red",
                ms=ms,
                mew=0.9,
                zorder=5,
                label="interpenetrated node (n_p . d_p < 0)",
            )
        axes[2].legend(fontsize=7, loc="lower left")
    common.shared_colorbar(fig, axes, sm)
    info = {
        "figure": NAME,
        "caption": CAPTION,
        "quick": quick,
        "runs": [rec],
        "zoom_cm": [float(z) for z in zoom],
        "interpenetrated_node_ids": np.flatnonzero(flagged).tolist(),
        "differs_from_paper": "; ".join(
            x
            for x in (
                "friction 0.3 on the sphere (paper: not stated)",
                (
                    f"{int(flagged.sum())} interpenetrated node(s) at the end (the paper's sharp folds are interpenetration, "
                    "§4.3); (c) is centred on them"
                    if flagged.any()
                    else "no interpenetrated node at the end: the paper's sharp folds (c) do not appear"
                ),
                "quick: 30x30, kinetic damping" if quick else "",
            )
            if x
        ),
    }
    common.save(
        fig,
        out_dir,
        NAME,
        info,
        suptitle=f"Fig. 12  30x30 cm cloth on a 10 cm sphere, dynamic relaxation (§4.2), {label(rec)}",
    )
    return info


if __name__ == "__main__":
    from .registry import script_main

    script_main(NAME)
