"""Shared by the figure scripts: running a scene, its deformed positions, panels and saving.

Every figure script defines ``NAME``, ``CAPTION`` (the paper's caption) and ``make(out_dir, quick)``
returning a dict (files written, the numbers shown, the runs' settings and wall times, and notes
on how the figure differs from the paper's).  ``--quick`` runs coarser meshes and faster
relaxation so that the whole set renders in minutes; the full settings are the paper's.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from solidshell.render import ViewStyle, bodies_of, draw_view, height_norm, scene_warp_deg
from solidshell.render import colorbar as colorbar  # re-exported: the figure scripts call common.colorbar


def mpl():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def run(scene, mesh=None, solver=None, overrides=None, adaptive=None, **settings):
    """run_scene without files or progress bar; returns (RunOutput, a record of what ran)."""
    from solidshell.run import run_scene

    t = time.perf_counter()
    out = run_scene(
        scene,
        mesh=mesh,
        solver=solver,
        out_dir=None,
        progress=False,
        overrides=overrides,
        adaptive=adaptive,
        **settings,
    )
    s = out.summary
    rec = {
        "scene": s["scene"],
        "mesh": s["mesh"],
        "solver": s["solver"],
        "overrides": dict(overrides or {}),
        "settings": {k: v for k, v in settings.items()},
        "converged": s.get("converged"),
        "message": s.get("message"),
        "wall_s": round(time.perf_counter() - t, 2),
    }
    for k in (
        "drape_coefficient",
        "fold_count",
        "interpenetrated_nodes",
        "max_interpenetrated_nodes",
        "max_active_nodes",
        "remesh_count",
        "t_final",
        "steps",
        "tip_position",
        "iterations",
        "positive_definite",
        "min_tangent_eigenvalue",
        "fold_angles_deg",
    ):
        if s.get(k) is not None:
            rec[k] = s[k]
    if s.get("warnings"):
        rec["warnings"] = s["warnings"]
    return out, rec


def positions(mesh, U):
    """Deformed mid-surface positions X_o + U_o (N,3) [cm]."""
    return np.asarray(mesh.nodes, float) + np.asarray(U, float).reshape(-1, 6)[:, :3]


def frame_at(out, t):
    """(time, mesh, X) of the kept frame nearest to t [s] (an adaptive run's frames each have
    their own mesh)."""
    frames = out.result.frames or []
    if not frames:
        return None
    times = np.array([float(f[0]) for f in frames])
    j = int(np.argmin(np.abs(times - t)))
    mesh = out.mesh if out.series is None else out.series[j][1]
    return float(times[j]), mesh, positions(mesh, frames[j][1])


def panel(ax, out_or_mesh, X, view, scene=None, norm=None, title=None, zoom=None, extent=None, **style):
    """One view (solidshell.render.draw_view) with the scene's bodies and warp labels; ``style``:
    the fields of solidshell.render.ViewStyle (labels, mesh_lines, ...)."""
    mesh = out_or_mesh.mesh if hasattr(out_or_mesh, "mesh") else out_or_mesh
    sc = scene if scene is not None else getattr(out_or_mesh, "scene", None)
    sm = draw_view(
        ax,
        mesh,
        X,
        view,
        bodies=bodies_of(sc),
        norm=norm or height_norm(X),
        warp_deg=scene_warp_deg(sc),
        zoom=zoom,
        extent=extent,
        style=ViewStyle(**style),
    )
    if title:
        ax.set_title(title, fontsize=9)
    return sm


def shared_colorbar(fig, axes, sm, label="height z [cm]"):
    """One colour bar for a row/grid of panels that share one colour scale."""
    cb = fig.colorbar(sm, ax=list(np.ravel(axes)), shrink=0.8, pad=0.02, fraction=0.03)
    cb.set_label(label, fontsize=8)
    cb.ax.tick_params(labelsize=7)
    return cb


def save(fig, out_dir: Path, name: str, info: dict, suptitle: str | None = None, dpi: int = 150) -> Path:
    """Write ``name``.png (and ``name``.json with ``info``) into out_dir; closes the figure."""
    plt = mpl()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if suptitle:
        fig.suptitle(suptitle, fontsize=10)
    p = out_dir / f"{name}.png"
    fig.savefig(p, dpi=dpi, bbox_inches="tight", pad_inches=0.1)
    plt.close(fig)
    info = dict(info)
    info["files"] = sorted(set(info.get("files", [])) | {p.name, f"{name}.json"})
    (out_dir / f"{name}.json").write_text(json.dumps(info, indent=1, default=_json) + "\n")
    return p


def _json(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    return str(o)


def boundary_panel(ax, runs, pedestal=None, styles=None):
    """Projected boundaries on the X-Y plane [cm] of several runs (label -> projected_boundary
    points), with the pedestal outline; equal axes."""
    import matplotlib.patches as mpatches

    styles = styles or ["-", "--", ":", "-."]
    for i, (label, pts) in enumerate(runs.items()):
        pts = np.asarray(pts, float)
        if not len(pts):
            continue
        closed = np.vstack([pts, pts[:1]])
        ax.plot(closed[:, 0], closed[:, 1], styles[i % len(styles)], lw=1.3, label=label)
    if pedestal is not None:
        kw = dict(fill=False, lw=0.8, ec="0.4", ls=(0, (2, 2)))
        if pedestal.get("shape") == "disc":
            ax.add_patch(mpatches.Circle((0, 0), pedestal["diameter"] / 2, label="pedestal", **kw))
        else:
            a = pedestal["size"]
            ax.add_patch(mpatches.Rectangle((-a / 2, -a / 2), a, a, label="pedestal", **kw))
    ax.set_aspect("equal")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=7, loc="upper right")
    ax.tick_params(labelsize=8)


def projected_boundary(out):
    """The run's projected boundary (M,2) [cm] (solidshell.analysis), recomputed from its state."""
    from solidshell import analysis
    from solidshell.run.summary import pedestal_area

    sc = out.scene
    kw = {"pedestal_area": pedestal_area(sc) or 0.0}
    sph = [c for c in sc.contact if c["type"] == "sphere"]
    if sph:
        kw["center"] = tuple(sph[0]["centre"][:2])
    return np.asarray(analysis.drape_summary(out.mesh, out.U, **kw)["projected_boundary"], float)


def views_figure(
    rows, views=("top", "iso"), boundaries=None, pedestal=None, boundary_title=None, panel_size=3.6, mesh_lines=True
):
    """A figure of ``rows`` = [(label, RunOutput or (mesh, scene), X)], one row per state with one
    panel per view, all on ONE colour scale (one colour bar, in its own column), plus an optional
    panel of projected boundaries (label -> (M,2) points) on the right.  Returns (fig, axes)."""
    plt = mpl()
    nr, nv = len(rows), len(views)
    widths = [1.4 if v == "iso" else 1.0 for v in views] + [0.05]
    if boundaries:
        widths += [0.35, 1.25]  # room for the boundary panel's y label beside the colour bar's label
    fig = plt.figure(figsize=(panel_size * sum(widths) + 0.6, panel_size * nr * 0.95 + 0.5))
    gs = fig.add_gridspec(nr, len(widths), width_ratios=widths, wspace=0.2, hspace=0.32)
    norm = height_norm(*[X for _, _, X in rows])
    axes, sm = [], None
    for i, (label, src, X) in enumerate(rows):
        mesh, sc = (src.mesh, src.scene) if hasattr(src, "mesh") else src
        for j, v in enumerate(views):
            ax = fig.add_subplot(gs[i, j])
            sm = panel(ax, mesh, X, v, scene=sc, norm=norm, mesh_lines=mesh_lines)
            if j == 0:  # the row's label once, over its first panel
                ax.set_title(label, fontsize=9, loc="left")
            axes.append(ax)
    cax = fig.add_subplot(gs[:, nv])
    cb = fig.colorbar(sm, cax=cax)
    cb.set_label("height z [cm]", fontsize=8)
    cb.ax.tick_params(labelsize=7)
    if boundaries:
        ax = fig.add_subplot(gs[:, -1])
        boundary_panel(ax, boundaries, pedestal)
        ax.set_anchor("W")  # equal axes leave the cell wider than the panel: keep it by the colour bar
        ax.set_xlabel("x [cm]", fontsize=8)
        ax.set_ylabel("y [cm]", fontsize=8)
        ax.set_title(boundary_title or "projected boundaries on the X-Y plane", fontsize=9)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.1), ncol=1, frameon=False)
        axes.append(ax)
    return fig, axes


def interpenetrated(out):
    """(N,) bool: the nodes of a run's final state where n_p . d_p < 0 in some element (§4.3)."""
    from solidshell.scenes.build import build_problem

    return build_problem(out.scene, out.mesh).model.interpenetrated_nodes(out.U)


def save_state(out_dir: Path, name: str, out, **extra) -> Path:
    """``name``.npz in out_dir: the run's mesh (nodes, quads, tris) and final U (N,6), so that a
    figure of an expensive run can be looked into again without re-running it."""
    p = Path(out_dir) / f"{name}.npz"
    p.parent.mkdir(parents=True, exist_ok=True)
    m = out.mesh
    np.savez_compressed(
        p,
        nodes=m.nodes,
        quads=getattr(m, "quads", None) if getattr(m, "quads", None) is not None else np.zeros((0, 4), int),
        U=np.asarray(out.U, float),
        **extra,
    )
    return p


def interpenetration_note(rec) -> str:
    """'' or one clause naming the nodes interpenetrated at the end of a run (n_p . d_p < 0, §4.3),
    which the paper reports only for Fig. 12."""
    n = rec.get("interpenetrated_nodes")
    return (
        f"{n} node(s) of {rec['mesh']} interpenetrated at the end (n_p . d_p < 0, §4.3; the paper reports none here)"
        if n
        else ""
    )


def describe(rec) -> str:
    """'mesh 48x16x4: DC 0.596, 4 folds' for a run record."""
    parts = [f"mesh {rec['mesh']}"]
    if rec.get("drape_coefficient") is not None:
        parts.append(f"DC {rec['drape_coefficient']:.3f}")
    if rec.get("fold_count") is not None:
        parts.append(f"{rec['fold_count']} folds")
    if rec.get("converged") is False:
        parts.append("NOT converged")
    if rec.get("positive_definite") is not None:  # static runs: the final tangent's verdict
        lmin = rec.get("min_tangent_eigenvalue")
        parts.append(
            ("stable" if rec["positive_definite"] else "NOT stable")
            + (f" (min eig {lmin:.2g})" if isinstance(lmin, float) else "")
        )
    return ", ".join(parts)
