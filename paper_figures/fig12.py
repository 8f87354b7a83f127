"""Fig. 12: (a) top, (b) side and (c) zoomed top views of the steady state of a 30x30 cm cloth on a
10 cm sphere by dynamic relaxation on 60x60 elements (paper §4.2); the paper's zoom shows sharp
folds (interpenetrated elements, §4.3).  Interpenetrated nodes (n_p . d_p < 0) are counted in the
json and the panel titles.  See _sphere.py; --quick: 30x30.

    python -m paper_figures.fig12 [--quick] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path

from . import common
from ._sphere import label, run_sphere

NAME = "fig12"
CAPTION = ("(a) Top, (b) side and (c) zoomed top views of the steady-state shapes of a 30x30 cm square cloth "
           "draped on a 10 cm diameter sphere predicted by dynamic relaxation using 60x60 elements.")
ZOOM = (-1.0, 9.0, -1.0, 9.0)        # [cm] the quadrant x, y > 0 around the sphere's rim (r = 5 cm)


def make(out_dir: Path, quick: bool = False) -> dict:
    plt = common.mpl()
    out, rec = run_sphere("30x30" if quick else "60x60", quick)
    X = common.positions(out.mesh, out.U)
    norm = common.height_norm(X)
    fig = plt.figure(figsize=(13.5, 4.6))
    gs = fig.add_gridspec(1, 3, wspace=0.18, width_ratios=[1, 1.15, 1])
    axes = [fig.add_subplot(gs[0, i]) for i in range(3)]
    sm = common.panel(axes[0], out, X, "top", norm=norm, title="(a) top view")
    common.panel(axes[1], out, X, "side", norm=norm, title="(b) side view")
    common.panel(axes[2], out, X, "top", norm=norm, zoom=ZOOM, title="(c) top view, zoomed")
    axes[0].add_patch(plt.Rectangle(ZOOM[::2], ZOOM[1] - ZOOM[0], ZOOM[3] - ZOOM[2], fill=False, ec="r", lw=0.8))
    common.shared_colorbar(fig, axes, sm)
    info = {"figure": NAME, "caption": CAPTION, "quick": quick, "runs": [rec],
            "differs_from_paper": "friction 0.3 on the sphere (paper: not stated); the paper's sharp folds appear only "
                                  "where nodes interpenetrate: see interpenetrated_nodes" + ("; quick: 30x30, kinetic damping" if quick else "")}
    common.save(fig, out_dir, NAME, info, suptitle=f"Fig. 12  30x30 cm cloth on a 10 cm sphere, dynamic relaxation (§4.2), {label(rec)}")
    return info


if __name__ == "__main__":
    from .registry import script_main
    script_main(NAME)
