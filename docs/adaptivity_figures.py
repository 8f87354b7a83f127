"""Pictures for docs/adaptivity.md: the hybrid macro-transition patterns (Section 5.3, Fig. 16b)
and an adapted mesh holding all of them; and frames of adaptive runs' series side by side.

    PYTHONPATH=. python docs/adaptivity_figures.py      -> docs/img/transition_patterns.png,
                                                           docs/img/adapted_mesh.png
    PYTHONPATH=. python docs/adaptivity_figures.py --series OUT.png "LABEL=RUN_DIR" ... --times 1.1 1.3 2
                                                        -> OUT.png: a row per run, a column per time
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402

from solidshell.adapt.transition import CENTRE, PATTERN_NAMES, TABLE, choose_variant, element_quality, local_points  # noqa: E402
from solidshell.meshing import build_mesh  # noqa: E402

OUT = Path(__file__).parent / "img"
CANON = {0: 0, 1: 0b0001, 2: 0b0011, 3: 0b0101, 4: 0b0111, 5: 0b1111}
COLOURS = {0: "#dddddd", 1: "#9ecae1", 2: "#a1d99b", 3: "#fdd0a2", 4: "#bcbddc", 5: "#fcbba1"}


def draw(ax, pts, q, t, colour, numbers=False):
    for cells, fc in ((q, colour), (t, "#fb6a4a")):
        for c in cells:
            ax.add_patch(Polygon(pts[c], closed=True, fc=fc, ec="k", lw=1.2))
            if numbers:
                a, r = element_quality(pts[c][None])
                ax.text(*pts[c].mean(0), f"{a[0]:.0f}°", ha="center", va="center", fontsize=7)
    used = np.unique(np.concatenate([np.ravel(q), np.ravel(t)]))
    ax.plot(pts[used, 0], pts[used, 1], "ko", ms=3)
    ax.set_aspect("equal")
    ax.axis("off")


def patterns():
    sq = local_points(np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]]))
    m = build_mesh("square_on_square", "6x2x4", sheet=20, pedestal=10)
    trap = m.nodes[m.quads[0]][:, :2]
    tp = local_points(trap)
    fig, axes = plt.subplots(3, 7, figsize=(14, 7.0))
    for j, (pid, mask) in enumerate(CANON.items()):
        q, t = TABLE[mask][1][0]
        draw(axes[0, j], sq, q, t, COLOURS[pid], numbers=True)
        axes[0, j].set_title(f"{pid}: {PATTERN_NAMES[pid]}", fontsize=10)
    alts = [(1, v) for v in (1, 2, 3, 4)] + [(4, v) for v in (1, 2, 3)]
    for j, (pid, v) in enumerate(alts):
        q, t = TABLE[CANON[pid]][1][v]
        draw(axes[1, j], sq, q, t, COLOURS[pid], numbers=True)
        lean = CENTRE not in np.ravel(q) and CENTRE not in np.ravel(t)
        axes[1, j].set_title(f"{pid}: variant {v + 1}" + (" (no centre)" if lean else ""), fontsize=10)
    axes[0, 6].axis("off")
    axes[0, 6].text(
        0.0,
        0.5,
        "refined edges get their\nmid-edge node (dots);\ntriangles in red;\n"
        'numbers: min angle\nof each element;\n"no centre": the\nvariants adapt.transitions\n= fewest_nodes takes',
        fontsize=9,
        va="center",
        transform=axes[0, 6].transAxes,
    )
    for j, (pid, mask) in enumerate(CANON.items()):
        # the rotation of each pattern whose chosen variant has the smallest angle on this parent
        best = None
        for mk in [mk for mk in range(16) if TABLE[mk][0] == pid]:
            v = int(choose_variant(mk, tp[None], "quality")[0])
            q, t = TABLE[mk][1][v]
            a = min(element_quality(tp[c])[0].min() for c in (q, t) if len(c))
            if best is None or a < best[0]:
                best = (a, q, t)
        draw(axes[2, j], tp, best[1], best[2], COLOURS[pid], numbers=True)
        axes[2, j].set_title(f'{pid}: worst rotation ("quality")', fontsize=9)
    axes[2, 6].axis("off")
    for ax in axes.ravel():
        ax.autoscale_view()
    fig.suptitle(
        "Hybrid macro-transition elements (level i+1/2): rows 1-2 unit-square parent, "
        "row 3 the worst parent of the square-pedestal 6x2x4 mesh",
        fontsize=11,
    )
    fig.subplots_adjust(left=0.01, right=0.99, top=0.9, bottom=0.02, hspace=0.25)
    fig.savefig(OUT / "transition_patterns.png", dpi=110)


def adapted():
    import sys

    sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
    from test_adapt_mesh import FLAT8, every_pattern_state

    am, a = every_pattern_state(FLAT8)
    mesh = a.mesh
    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    cells = list(mesh.quads) + list(mesh.tris)
    for c, k in zip(cells, a.elem_kind):
        ax.add_patch(
            Polygon(mesh.nodes[c, :2], closed=True, fc=COLOURS[int(k)] if len(c) == 4 else "#fb6a4a", ec="k", lw=0.7)
        )
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.axis("off")
    ax.set_title(
        "Adapted 8x8 jittered grid (levels 0-2) holding every pattern\n"
        "grey plain, blue 1, green 2, orange 3, purple 4, pink 5, red triangles",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(OUT / "adapted_mesh.png", dpi=110)


def series_frames(out: Path, runs: dict, times) -> None:
    """The frames of each run folder's ``series.pvd`` nearest to ``times`` [s]: a row per run (label ->
    folder), the deformed sheet seen from above with its mesh lines, the node count in each title."""
    import xml.etree.ElementTree as ET

    import meshio
    from matplotlib.collections import PolyCollection

    fig, axes = plt.subplots(len(runs), len(times), figsize=(2.6 * len(times), 2.8 * len(runs)), squeeze=False)
    for row, (label, folder) in zip(axes, runs.items()):
        folder = Path(folder)
        steps = [(float(d.get("timestep")), d.get("file")) for d in ET.parse(folder / "series.pvd").iter("DataSet")]
        ts = np.array([t for t, _ in steps])
        for ax, t in zip(row, times):
            k = int(np.argmin(abs(ts - t)))
            m = meshio.read(folder / steps[k][1])
            X = m.points + m.point_data["displacement"]
            polys = [X[c, :2] for block in m.cells for c in block.data]
            ax.add_collection(PolyCollection(polys, facecolor="#dbe6f5", edgecolor="k", linewidths=0.12))
            ax.autoscale_view()
            ax.set_aspect("equal")
            ax.axis("off")
            ax.set_title(f"{label}\nt = {ts[k]:.2f} s, {len(X)} nodes", fontsize=7.5)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--series", metavar="OUT.png", help="frames of run folders instead (LABEL=DIR ...)")
    ap.add_argument("runs", nargs="*", help="LABEL=RUN_DIR, with --series")
    ap.add_argument("--times", type=float, nargs="+", default=[1.1, 1.3, 1.5, 2.0, 4.0, 8.0])
    a = ap.parse_args()
    if a.series:
        series_frames(Path(a.series), dict(r.split("=", 1) for r in a.runs), a.times)
    else:
        OUT.mkdir(exist_ok=True)
        patterns()
        adapted()
