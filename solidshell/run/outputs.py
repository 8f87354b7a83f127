"""A run's files: the run folder (solidshell.rundir) opened and checked before any work, then the
mesh, the state, its series, the projected boundary and the pictures, each stamped with the run id."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import io as sio
from .. import solvers
from ..errors import IOFailure
from ..rundir import RunFolder
from ..scenes import Scene
from . import state_fields


def prepare_folder(out_dir, run_id: str, force: bool, settings: dict | None, output: dict):
    """The run's RunFolder, checked (nothing written yet), or None when ``out_dir`` is None.  The
    solver's checkpoint and restart files in it are kept; when the scene draws pictures, whether
    VTK can render is asked in a child process now, while the run meshes."""
    if out_dir is None:
        return None
    folder = RunFolder(
        out_dir, run_id, force=force, keep=[settings.get(k) for k in ("checkpoint", "restart")] if settings else ()
    )
    folder.check()
    if output["pictures"] or output["snapshots"]:
        # the pictures' child process (solidshell.render.server) starts now: its imports, its VTK
        # probe and warm-up run while we mesh and solve.  Without it, whether VTK can render is
        # asked in a child process (~2 s) that also runs while we mesh
        from ..render import server, vtk_backend

        if server.start() is None:
            vtk_backend.start_probe()
    return folder


def folder_warnings(folder) -> list[str]:
    """A warning for files in the folder that solidshell did not write (kept with --force)."""
    if folder is None or not folder.foreign:
        return []
    return [
        f"output folder {folder.path} holds {len(folder.foreign)} file(s) solidshell did "
        f"not write, left untouched (--force): {', '.join(folder.foreign[:5])}"
    ]


def _snapshot_plan(sc, kind, result) -> list:
    """[(time, frame index or None, warning or None)] for the scene's output snapshots: a picture
    iso_t<time>.png for each snapshot with a kept frame, a warning for each without one (a time
    past the run's end, or frames not kept)."""
    snaps = sc.output["snapshots"]
    if not snaps or kind == "none" or result is None:
        return []
    if kind == "static":
        return [(None, None, f"output.snapshots ({len(snaps)} time(s)) ignored: the static solver has no time")]
    frames = result.frames or []
    times = np.array([float(tf) for tf, _ in frames]) if frames else np.zeros(0)
    info = result.info or {}
    t_final = info.get("t_final")
    said = {float(x) for x in (info.get("snapshots_after_t_end_dropped") or [])}  # the solver's warning
    out = []
    for ts in snaps:
        j = int(np.argmin(np.abs(times - ts))) if len(times) else -1
        if j >= 0 and abs(times[j] - ts) <= 1e-6 + 1e-3 * max(ts, 1.0) and np.all(np.isfinite(frames[j][1])):
            out.append((ts, j, None))
        elif ts in said:
            out.append((ts, None, None))
        else:
            why = (
                f"after the run's end t = {t_final:.6g} s"
                if isinstance(t_final, (int, float)) and ts > t_final
                else "no frame kept at that time"
            )
            out.append((ts, None, f"snapshot t = {ts:g} s dropped: {why}"))
    return out


def _write_outputs(folder, sc: Scene, kind: str, mesh_name: str, solved, summary: dict, snaps, cb) -> list:
    """Write a run's files (each stamped with the run id) into its folder; returns their paths.
    ``solved``: the run's driver.Solved; an adaptive run's ``series`` [(t, mesh, U)], each frame on
    its own mesh, is written as series.pvd of VTUs."""
    rid = folder.run_id
    mesh, U, result = solved.mesh, solved.U, solved.result
    finite = result is not None and bool(np.all(np.isfinite(U)))
    # the pictures first: with a picture process (solidshell.render.server) they are drawn there
    # while this process writes the other files, and collected at the end
    pictures = _Pictures(folder, cb)
    files = _picture_files(pictures, sc, kind, mesh_name, solved, summary, snaps, finite)
    files += [folder.write(name, sio.write_mesh_file, mesh, run_id=rid) for name in ("mesh.xdmf", "mesh.vtu")]
    if result is not None:
        files += _state_files(folder, sc, kind, solved, summary, finite)
    boundary = summary.get("projected_boundary")
    if boundary is not None:

        def csv(p):
            with sio.atomic_write(p) as f:
                f.write(
                    f"# projected boundary of the draped sheet on the X-Y plane [cm]\n# solidshell run_id={rid}\nx,y\n"
                )
                f.writelines(f"{x:.6g},{y:.6g}\n" for x, y in boundary)
            return p

        files.append(folder.write("projected_boundary.csv", csv))

    pictures.collect()
    return files


class _Pictures:
    """A run's pictures, each drawn by the run's picture process when there is one (submitted,
    then collected), else -- or when the child could not draw it -- here; stamped with the run id."""

    def __init__(self, folder, cb):
        from ..render import server

        self.folder, self.cb = folder, cb
        self.child = server.current()
        self.sent: dict = {}  # path -> (name, args, kwargs)

    def _here(self, p, *a, **kw) -> Path:
        from ..plotting import render  # matplotlib only when a picture is drawn here

        return sio.stamp_png(render(p, *a, **kw), self.folder.run_id)

    def draw(self, name: str, *args, **kwargs) -> Path:
        """The picture ``name`` of ``plotting.render(path, *args, **kwargs)``: sent or drawn."""

        def send(p, *a, **kw):
            if self.child is not None and self.child.submit(p, a, kw, self.folder.run_id):
                self.sent[Path(p)] = (name, a, kw)
                return Path(p)
            return self._here(p, *a, **kw)

        return self.folder.write(name, send, *args, **kwargs)

    def collect(self) -> None:
        """Wait for the child's pictures; draw here what it could not (a write failure is raised
        as the run's I/O failure, naming the file)."""
        if self.child is None:
            return
        if self.sent:
            self.cb(0.97, "pictures")
        failed = self.child.collect()
        self.child.close()
        for p, why in failed.items():
            name, a, kw = self.sent[p]
            if why.startswith(("OSError", "PermissionError", "FileNotFoundError")):
                raise IOFailure(self.folder.path / name, why.split(": ", 1)[-1])
            self.folder.write(name, self._here, *a, **kw)


def _picture_files(pictures, sc, kind, mesh_name, solved, summary, snaps, finite) -> list:
    """The run's pictures (the scene's views of the final state, with its crossings marked, and
    the snapshots), handed to ``pictures``; returns their paths."""
    from ..render.panel import SceneLook

    mesh, U, result, series = solved.mesh, solved.U, solved.result, solved.series
    files = []
    state = U if finite else None
    sub = _subtitle(sc, mesh_name, mesh, kind, summary)
    views = sc.output["pictures"]
    # the bodies and the warp as plain data: the pictures' process need not import the scenes' module
    look = SceneLook.of(sc) if views or any(j is not None for _, j, _ in snaps) else None
    ref = _strip_curve(summary) if state is not None else None
    marks = _marks(solved, summary) if state is not None and views else None
    for i, view in enumerate(views):
        pictures.cb(0.92 + 0.05 * i / max(1, len(views)), f"{view} picture")
        files.append(
            pictures.draw(
                f"{view}.png",
                mesh,
                state,
                view=view,
                title=sc.title,
                scene=look,
                subtitle=sub,
                reference=ref,
                marks=marks,
            )
        )
    for ts, j, _ in snaps:
        if j is not None:
            tj = float(result.frames[j][0])
            mj = mesh if series is None else series[j][1]
            sub_j = f"t = {tj:.3f} s" + ("" if series is None else f", {mj.n_nodes} active nodes")
            for view in ("iso", "top") if series is not None else ("iso",):
                files.append(
                    pictures.draw(
                        f"{view}_t{ts:.3f}.png",
                        mj,
                        result.frames[j][1],
                        view=view,
                        title=sc.title,
                        scene=look,
                        subtitle=sub_j,
                    )
                )
    return files


def _state_files(folder, sc, kind: str, solved, summary: dict, finite: bool) -> list:
    """The solved state's files: result (and deformed) mesh files and the run's series."""
    rid = folder.run_id
    mesh, U, result, series = solved.mesh, solved.U, solved.result, solved.series
    # the fields users colour by (solidshell.fields) and the clamped, unmeshed parts of the sheet
    fields_of = state_fields.series_fields(sc, kind, solved) if finite else None
    fp = fields_of(state_fields.final_load_factor(kind, result), mesh, U) if fields_of else (None, ())
    kw = dict(run_id=rid, fields=fp[0], patches=fp[1])
    files = [
        folder.write("result.xdmf", sio.write_mesh_file, mesh, U, **kw),
        folder.write("result.vtu", sio.write_mesh_file, mesh, U, **kw),
    ]
    if finite:
        files.append(folder.write("deformed.vtu", sio.write_mesh_file, mesh, U, deformed=True, **kw))
    frames = [(float(tf), Uf) for tf, Uf in (result.frames or [])]
    if series is None:  # a fixed mesh: the displacement-only XDMF series, and the same frames in series.pvd
        if not solvers.dynamic(kind) and frames and frames[0][0] != 0.0:
            frames = [(0.0, np.zeros_like(np.asarray(frames[0][1], float)))] + frames  # the load path from rest
        if len(frames) > 1:
            files.append(folder.write("series.xdmf", sio.write_time_series, mesh, frames, run_id=rid))
        series = [(t, mesh, Uf) for t, Uf in frames] if fields_of is not None else []
    if len(series) > 1:
        files.append(folder.write("series.pvd", sio.write_mesh_series, series, run_id=rid, fields_of=fields_of))
        files += sio.series_frame_paths(folder.path / "series.pvd", len(series))
        summary["series_parameter"] = "time [s]" if solvers.dynamic(kind) else "load factor"
    return files


def _marks(solved, summary: dict) -> dict | None:
    """The final state's crossings the pictures mark red (solidshell.plotting.crossing_marks): on
    whenever summary.json counts self-intersections or interpenetrated nodes; None without a
    solidshell Model (a user's own model has no element blocks to flag)."""
    model = getattr(solved.problem, "model", None)
    if model is None or not hasattr(model, "blocks"):
        return None
    from ..plotting import crossing_marks

    return crossing_marks(model, solved.U, summary)


def _strip_curve(summary: dict) -> dict | None:
    """The heavy elastica's centre line for the side picture of a strip that is a stored one."""
    from ..references import strip_elastica

    ref = strip_elastica(summary)
    if ref is None:
        return None
    r = ref[1]
    return {"x": r["curve"]["x"], "z": r["curve"]["z"], "label": "heavy elastica"}


def _subtitle(sc, mesh_name, mesh, kind, summary) -> str:
    parts = [f"mesh {mesh_name}", f"{mesh.n_nodes} nodes", f"{mesh.n_elements} elements"]
    if kind == "none":
        parts.append("undeformed")
    else:
        parts.append(kind)
        dc = summary.get("drape_coefficient")
        if isinstance(dc, (int, float)):
            parts.append(f"DC = {dc:.3f}")
        if summary.get("fold_count") is not None and summary.get("pedestal_area") is not None:
            parts.append(f"{summary['fold_count']} folds")
        if summary.get("converged") is False:
            parts.append("NOT CONVERGED")
    return ", ".join(parts)


def write_run(folder, sc: Scene, kind: str, mesh_name: str, solved, summary: dict, cb) -> tuple[list, list]:
    """The write step: the scene's snapshot plan (its warnings), then -- with a folder -- the
    earlier run's files cleared (their names in ``summary["replaced_files"]``) and this run's
    written.  Returns (file paths, warnings)."""
    snaps = _snapshot_plan(sc, kind, solved.result)
    warnings = [w for _, _, w in snaps if w]
    if folder is None:
        return [], warnings
    cb(0.9, "writing results")
    replaced = folder.clear_stale()
    if replaced:
        summary["replaced_files"] = replaced
    return _write_outputs(folder, sc, kind, mesh_name, solved, summary, snaps, cb), warnings
