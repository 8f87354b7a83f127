"""Figs. 9 and 10: square wool sheets hung by two adjacent corners, falling from rest (paper §4.1),
explicit dynamics (Eq. 23, Rayleigh alpha = 5/s, no mass scaling), snapshots at the paper's times:
isometric views above, side views below (looking along -x, across the held edge, raised 15 deg and
turned 25 deg so that a sheet seen edge-on still shows its face), one colour scale for the figure;
every panel of a row has the same frame.  --quick: a 12x12 mesh with the director masses x1e4 (the translational masses,
which carry the swing, are the true ones; tested against the unscaled run in
verification/dynamic_scenes.py for x10).

Threads: the solver's default (2 on 2 cores: 1600 and 2500 quads); the explicit loop's state does
not depend on the count (element pass over 4 fixed chunks, serial sums; tests/test_lanes.py,
tests/test_dynamic_scenes.py), so on a shared machine run ``NUMBA_NUM_THREADS=1 solidshell figures
9 10``, which is several times faster there (paper_figures/_sphere.py has the measurement)."""

from __future__ import annotations

from pathlib import Path

from . import common


def make_hang(name, scene, caption, out_dir: Path, quick: bool, title: str) -> dict:
    plt = common.mpl()
    kw = dict(mass_scaling=1e4, mass_scaling_mode="director") if quick else {}
    m = "12x12" if quick else None
    from solidshell.scenes import load

    times = list(load(scene).output["snapshots"])
    out, rec = common.run(scene, mesh=m, solver="explicit", snapshots=times, **kw)
    frames = [common.frame_at(out, t) for t in times]
    norm = common.height_norm(*[X for _, _, X in frames])
    # one frame for every panel of a row: the union of all the snapshots' screen extents
    from solidshell.render.geometry import CAMERAS, oblique, scene_surfaces, screen_extent

    cams = {"iso": CAMERAS["iso"], "side": oblique(15.0, 25.0)}

    def extent(cam):
        boxes = [screen_extent(scene_surfaces(mm, X, []), cam) for _, mm, X in frames]
        return (min(b[0] for b in boxes), max(b[1] for b in boxes), min(b[2] for b in boxes), max(b[3] for b in boxes))

    ext = {v: extent(c) for v, c in cams.items()}
    fig = plt.figure(figsize=(3.1 * len(times) + 0.8, 6.4))
    gs = fig.add_gridspec(2, len(times), wspace=0.05, hspace=0.12)
    axes, sm = [], None
    for k, (tk, mk, Xk) in enumerate(frames):
        for i, v in enumerate(("iso", "side")):
            ax = fig.add_subplot(gs[i, k])
            sm = common.panel(
                ax,
                mk,
                Xk,
                cams[v],
                scene=out.scene,
                norm=norm,
                extent=ext[v],
                labels=(k == 0),
                # both rows captioned: the same instant seen isometrically and from the side
                title=f"({'abcd'[k]}) t = {tk:.2f} s, " + ("isometric" if i == 0 else "side, looking along -x"),
            )
            axes.append(ax)
    common.shared_colorbar(fig, axes, sm)
    info = {
        "figure": name,
        "caption": caption,
        "quick": quick,
        "runs": [rec],
        "times": times,
        "frame_times": [f[0] for f in frames],
        "differs_from_paper": "quick: 12x12 mesh, director masses x1e4" if quick else "",
    }
    common.save(fig, out_dir, name, info, suptitle=title)
    return info
