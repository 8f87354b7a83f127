"""Figs. 19-22: drapes by dynamic relaxation on the reversibly refined mesh (paper §5-6), the mesh
drawn: (a) the level-0 mesh at t = 0, (b) and (c) two instants of the fall, (d) the last state;
isometric views above, top views below, one colour scale.  Settings: the paper's relaxation path
(Section 4.2: Rayleigh alpha = 5 /s, all masses x100) with the scene's [adapt] table (the §6 table's
settings: const, assumed membrane strains on the coarse quads, the freeze after t = 6 s; settled
directors and new nodes, a pass every 1000 steps; docs/adaptivity.md), to t = 40 s or the steady
state.  Full: the scene's levels (three, the paper's; four on large-square-pedestal, whose ears'
creases interpenetrate at three).  --quick: two levels, to t = 15 s of simulated time or the steady
state (the state reached is shown; the json and the title say whether it is steady).  The quick cap
is simulated time, not wall time, so that the state drawn does not depend on the machine's load
(verification/figures_quick.py compares it with reference/figures_quick.json); a 120 s wall-time
cap stopped three of the four at t = 12-30 s on a loaded machine (2026-12, 1 thread, load 3-5)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import common

T_QUICK = 15.0  # [s] simulated: --quick's end (the freeze is at 6 s; at 10 s the disc still fell fast)


def make_adaptive(
    name, scene, caption, out_dir: Path, quick: bool, title: str, uniform_nodes: int | None = None
) -> dict:
    plt = common.mpl()
    kw = dict(
        damping="rayleigh", alpha=5.0, mass_scaling=100.0, mass_scaling_mode="uniform", t_max=T_QUICK if quick else 40.0
    )
    over = {"adapt.levels": 2} if quick else {}
    out, rec = common.run(scene, solver="relax", adaptive=True, overrides=over, **kw)
    times = np.array([float(f[0]) for f in out.result.frames])
    tf = float(times[-1])
    picks = [0.0, 0.15 * tf, 0.4 * tf, tf]
    frames = [common.frame_at(out, t) for t in picks]
    norm = common.height_norm(*[X for _, _, X in frames])
    # one frame for every panel of a row (the union of the snapshots' screen extents): each top
    # view fitted to its own sheet made the lower panels of different sizes, out of line
    from solidshell.render.geometry import CAMERAS, bodies_of, scene_surfaces, screen_extent

    bodies = bodies_of(out.scene)

    def extent(v):
        boxes = [screen_extent(scene_surfaces(mm, X, bodies), CAMERAS[v]) for _, mm, X in frames]
        return (min(b[0] for b in boxes), max(b[1] for b in boxes), min(b[2] for b in boxes), max(b[3] for b in boxes))

    ext = {v: extent(v) for v in ("iso", "top")}
    fig = plt.figure(figsize=(3.3 * 4 + 0.8, 6.8))
    gs = fig.add_gridspec(2, 4, wspace=0.08, hspace=0.14)
    axes, sm = [], None
    for k, (tk, mk, Xk) in enumerate(frames):
        for i, v in enumerate(("iso", "top")):
            ax = fig.add_subplot(gs[i, k])
            head = f"({'abcd'[k]}) t = {tk:.2f} s, {mk.n_nodes} nodes, {mk.n_elements} elements" if i == 0 else None
            sm = common.panel(
                ax, mk, Xk, v, scene=out.scene, norm=norm, title=head, labels=(k == 0 or v == "iso"), extent=ext[v]
            )
            if head:
                ax.title.set_fontsize(7.5)
            if k and v == "top":
                ax.tick_params(labelleft=False)
            axes.append(ax)
    common.shared_colorbar(fig, axes, sm)
    rec["frame_times"] = [f[0] for f in frames]
    rec["frame_nodes"] = [int(f[1].n_nodes) for f in frames]  # the titles' node counts, for the json
    if uniform_nodes:
        rec["uniform_mesh_nodes"] = uniform_nodes
    steady = "steady" if rec.get("converged") else "NOT steady"
    info = {
        "figure": name,
        "caption": caption,
        "quick": quick,
        "runs": [rec],
        "differs_from_paper": "directors and new nodes settled after each remesh, D_n-1 one quasi-static "
        "step behind: a step beyond the bare DK transfer (docs/adaptivity.md)"
        + (f"; quick: two levels, to t = {T_QUICK:g} s" if quick else ""),
    }
    sub = f"{rec.get('fold_count')} folds, DC {rec.get('drape_coefficient', float('nan')):.3f}, max {rec.get('max_active_nodes')} active nodes, {steady}"
    common.save(fig, out_dir, name, info, suptitle=f"{title}\n{sub}")
    return info
