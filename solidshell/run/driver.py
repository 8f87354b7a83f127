"""run_scene: scene -> mesh -> model + problem -> solver -> files.

    out = run_scene("square-pedestal", mesh="48x16x4", solver="static", out_dir="runs/sp")
    out.summary["converged"], out.U, out.mesh, out.out_dir

A run is five steps, each owned by a module: check (scenes.build.run_settings, outputs.
prepare_folder, adapt_settings) -> build (scenes.build.setup_scene) -> solve (here) ->
summarise (summary) -> write (outputs).  The model, boundary, contact, analysis and solver modules
are imported only when a solver runs, so building and writing a mesh (``solver="none"``, what
``solidshell mesh`` does) stays fast.
"""

from __future__ import annotations

import json
import logging
import sys
import tempfile
import time
import uuid
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import io as sio
from .. import solvers
from ..errors import IOFailure, SolverError
from ..rundir import check_checkpoint
from ..scenes import Scene, load
from ..scenes.build import build_problem, build_scene_mesh, run_settings, setup_scene, support_mask
from .adaptive import adapt_settings, level0_mesh
from .adaptive import prepare as prepare_adaptive
from .outputs import folder_warnings, prepare_folder, write_run
from .progress import _phase, reporting
from .summary import close_summary, describe_run, record_state

log = logging.getLogger("solidshell")


@dataclass(repr=False)
class RunOutput:
    """What :func:`run_scene` returns: ``out.summary`` (the summary.json dict), ``out.U`` (N,6),
    ``out.mesh`` (the ShellMesh solved on), ``out.run_id``, ``out.converged``, ... .  It also unpacks
    as ``summary, U, mesh, run_id = run_scene(...)``; its repr is one line (:meth:`__repr__`)."""

    summary: dict
    U: np.ndarray
    mesh: Any
    out_dir: Path | None
    scene: Scene | None = None
    result: Any = None  # the solver's SolveResult (None for a mesh-only run)
    files: list = field(default_factory=list)
    run_id: str = ""  # uuid4 hex, also in summary.json and every file
    series: list | None = None  # adaptive runs: [(t, ShellMesh, U)], each frame on its own mesh
    projected_boundary: np.ndarray | None = None  # the analysed drape's outline (analysis.projected_boundary)
    problem: Any = None  # the Problem the solver ran (adaptive: on the final mesh, with its
    # per-quad membranes); None for a mesh-only run

    @property
    def converged(self):
        return self.summary.get("converged")

    @property
    def interrupted(self) -> bool:
        return bool(self.summary.get("interrupted"))

    @property
    def warnings(self) -> list:
        return list(self.summary.get("warnings", []))

    def __iter__(self):
        """``summary, U, mesh, run_id = out``: the four a script most often wants, in that order."""
        return iter((self.summary, self.U, self.mesh, self.run_id))

    def __repr__(self) -> str:
        """One line: scene, solver, mesh and its size, the outcome, the scene's headline figure
        (DC and folds, or the strip's tip), the run id and the folder -- not the arrays."""
        s = self.summary or {}
        c = s.get("counts") or {}
        size = f"{c.get('nodes', '?')} nodes, {c.get('elements', '?')} elements"
        if s.get("solver") == "none":
            outcome = "mesh only"
        elif s.get("interrupted"):
            outcome = "interrupted"
        else:
            outcome = "converged" if s.get("converged") else "NOT converged"
        what = "mesh" if s.get("solver") == "none" else f"{s.get('solver', '?')} on"
        parts = [f"{s.get('scene', '?')}: {what} {s.get('mesh', '?')} ({size})", outcome]
        dc = s.get("drape_coefficient")
        if isinstance(dc, (int, float)):
            parts.append(f"DC {dc:.4g}" + (f", {s['fold_count']} folds" if s.get("fold_count") is not None else ""))
        tip = s.get("tip_position")
        if tip is not None and len(tip) == 3:
            parts.append("tip (" + ", ".join(f"{round(float(v), 3) + 0.0:.3f}" for v in tip) + ") cm")
        if s.get("warnings"):
            parts.append(f"{len(s['warnings'])} warning(s)")
        parts.append(f"run_id {self.run_id[:8]}")
        parts.append(f"out_dir {str(self.out_dir) if self.out_dir is not None else None}")
        return f"<RunOutput {', '.join(parts)}>"


@dataclass
class RunPlan:
    """What a run was asked: the scene (overrides applied), the solver kind and the call's options."""

    scene: Scene
    kind: str  # a solver kind of solidshell.solvers.KINDS, or "none"
    mesh: Any = None  # run_scene's ``mesh`` argument
    out_dir: Any = None
    settings: dict = field(default_factory=dict)  # the call's solver settings
    overrides: dict | None = None
    force: bool = False
    allow_large: bool = False


@dataclass
class Solved:
    """The solve step's outcome: the state on the (final) mesh and what produced it.  A mesh-only
    run has no result and a zero state."""

    mesh: Any
    fixed: np.ndarray
    U: np.ndarray
    result: Any = None
    problem: Any = None
    series: list | None = None  # adaptive: [(t, mesh, U)] on each frame's own mesh


# --------------------------------------------------------------------------- the run
def run_scene(
    scene,
    mesh=None,
    solver=None,
    out_dir=None,
    progress=True,
    overrides=None,
    *,
    force=False,
    allow_large=False,
    adaptive=None,
    **settings,
) -> RunOutput:
    """Run a scene (a name, a .toml path or a Scene).

    mesh        : None (the scene's density), a density like "24x8x4", a mesh file, or a ShellMesh
    solver      : None (the scene's [solver] kind), "static" | "explicit" | "relax", or "none"
                  (build and write the mesh only)
    out_dir     : directory for the files (created); None writes nothing
    progress    : True (a tqdm bar on stderr when it is a terminal), False, or a callback(fraction, text)
    overrides   : dotted scene keys, e.g. {"solver.static.c": 2e-3, "material.warp_angle": 90}
    force       : write into a folder that holds files solidshell did not write (left untouched)
    allow_large : skip the size guard (estimated memory against the machine's available memory)
    adaptive    : True/False switch the scene's adaptive subdivision (§5) on/off (None: the scene's
                  ``adapt.enabled``); an adaptive run starts from ``mesh`` or the scene's
                  ``mesh.adaptive_level0`` and needs the explicit or relax solver
    settings    : overrides of the chosen solver's settings (e.g. t_end=0.4, alpha=1.0)

    Everything is checked before any file is written (InputError): the scene and its overrides,
    the solver settings (their typed schema), the mesh size, node sets, loads and the initial
    contact.  Files of an earlier run in ``out_dir`` are replaced only once the solver has returned
    (solidshell.rundir); every file carries the run's ``run_id``.  I/O failures raise
    solidshell.errors.IOFailure naming the path.  A solver stopped by Ctrl-C returns its last state
    (info["status"] == "interrupted"): it is written, with ``summary["interrupted"] = True``.
    Warnings (the solver's info["warnings"] and the runner's own) are logged on the "solidshell"
    logger and listed in ``summary["warnings"]``.
    """
    t_start = time.perf_counter()
    sc = load(scene)
    if adaptive is not None:
        overrides = {**(overrides or {}), "adapt.enabled": bool(adaptive)}
    sc = sc.with_overrides(overrides)
    kind = sc.solver["kind"] if solver is None else str(solver)
    if kind != "none":
        solvers.kind(kind)  # the registry's one-line error for an unknown kind
    plan = RunPlan(sc, kind, mesh, out_dir, settings, overrides, force, allow_large)
    with reporting(progress, sc.name) as cb:
        try:
            out = _run(plan, cb, t_start)
        except BaseException:
            _discard_pictures_process()
            raise
    for w in out.summary["warnings"]:  # after the bar is gone: one clean line each
        log.warning(w)
    return out


def _discard_pictures_process() -> None:
    """A run that raised (bad input found after its folder was checked, a solver error, Ctrl-C
    with no state): its pictures' child, started with the folder (outputs.prepare_folder) or by
    the CLI, is ended now instead of idling until this process ends (render.server.discard)."""
    server = sys.modules.get("solidshell.render.server")
    if server is not None:
        server.discard()


def _run(plan: RunPlan, cb, t_start: float) -> RunOutput:
    sc, kind = plan.scene, plan.kind
    run_id = uuid.uuid4().hex
    timings = {}

    # check: every input, before anything is written
    settings = run_settings(sc, kind, plan.settings)
    if settings and settings.get("checkpoint"):
        check_checkpoint(settings["checkpoint"], plan.out_dir)
    folder = prepare_folder(plan.out_dir, run_id, plan.force, settings, sc.output)
    adapt = adapt_settings(sc, kind)

    # build: the mesh, supports, loads, contact and start (an adaptive run: its background mesh)
    cb(0.0, "meshing")
    t = time.perf_counter()
    mesh_arg = plan.mesh if adapt is None else level0_mesh(sc, plan.mesh)
    setup = setup_scene(sc, kind, mesh_arg, settings, plan.allow_large)
    arun, mesh_name = (None, setup.mesh_name) if adapt is None else prepare_adaptive(sc, setup, adapt, kind, cb)
    timings["mesh"] = time.perf_counter() - t
    warnings = folder_warnings(folder) + _doubtful_inputs(sc, kind, plan.overrides, setup, adapt is not None)
    summary = describe_run(run_id, sc, kind, settings, setup, mesh_name, plan.overrides)
    if folder is not None:
        folder.open()  # the folder and its RUNNING marker

    # solve, then summarise the state
    solved = Solved(setup.mesh, setup.fixed, np.zeros((setup.mesh.n_nodes, 6)))
    if kind != "none":
        try:
            solved = _solve(plan, setup, arun, cb, timings)
        except BaseException:
            # bad input found by the solver, a solver error before any state, Ctrl-C with no state
            # returned: nothing of this run is written and the earlier run's files stay as they were
            if folder is not None:
                folder.abandon()
            raise
        warnings += record_state(summary, sc, solved)

    # write: this run's files beside the earlier run's, swapped in at the end (solidshell.rundir)
    t = time.perf_counter()
    try:
        with _undisturbed(kind):
            files, snap_warnings = write_run(folder, sc, kind, mesh_name, solved, summary, cb)
            if folder is not None:
                timings["write_results"] = time.perf_counter() - t
            timings["total"] = time.perf_counter() - t_start
            boundary = close_summary(summary, timings, warnings + snap_warnings)
            if folder is not None:
                summary["files"] = sorted({Path(f).name for f in files} | {"summary.json"})
                folder.finish(summary)
                files = [folder.path / n for n in summary["files"] if n != "summary.json"]
                files.append(folder.path / "summary.json")
    except BaseException as e:
        if folder is not None:
            folder.abandon()  # the earlier run stays as it was
            if isinstance(e, OSError) and kind != "none":
                raise _results_lost(e, folder, solved, summary) from None
        raise
    cb(1.0, "interrupted" if summary["interrupted"] else "done")
    return RunOutput(
        summary=sio.to_jsonable(summary),
        U=solved.U,
        mesh=solved.mesh,
        out_dir=folder.path if folder else None,
        scene=sc,
        result=solved.result,
        files=[Path(f) for f in files],
        run_id=run_id,
        series=solved.series,
        projected_boundary=boundary,
        problem=solved.problem,
    )


def _solve(plan: RunPlan, setup, arun, cb, timings: dict) -> Solved:
    """The solve step: the scene's problem on the built mesh and the solver on it -- a static
    solve through the recipe's coarse meshes first (solvers/sequence.py), a dynamic one directly,
    or the §5.5 adaptive driver ``arun``."""
    sc, kind = plan.scene, plan.kind
    cb(0.05, "setting up")
    t = time.perf_counter()
    try:
        fn = solvers.get(kind)
    except ImportError as e:
        raise SolverError(f"solver {kind!r} is not available in this installation ({e})") from None
    if arun is not None:
        timings["setup"] = time.perf_counter() - t
        t = time.perf_counter()
        out = arun.run()
        timings["solve"] = time.perf_counter() - t
        return Solved(
            out.mesh,
            support_mask(sc, out.mesh),
            _state(out.result, out.mesh),
            out.result,
            arun.integ.problem,
            out.series,
        )
    problem = build_problem(sc, setup.mesh, setup.fixed)
    timings["setup"] = time.perf_counter() - t
    t = time.perf_counter()
    progress = _phase(cb, 0.08, 0.9)
    if kind == "static":
        from ..solvers.sequence import solve_sequenced

        result = solve_sequenced(
            fn,
            problem,
            dict(setup.solver_settings),
            progress,
            sc,
            setup.mesh_name,
            lambda d: build_problem(sc, build_scene_mesh(sc, d, kind, plan.allow_large)[0], kind=kind),
        )
    else:
        result = fn(problem, dict(setup.solver_settings), progress)
    timings["solve"] = time.perf_counter() - t
    return Solved(setup.mesh, setup.fixed, _state(result, setup.mesh), result, problem)


def _state(result, mesh) -> np.ndarray:
    return np.asarray(result.U, float).reshape(mesh.n_nodes, 6)


@contextmanager
def _undisturbed(kind: str):
    """The write phase runs to its end: a Ctrl-C or SIGTERM meanwhile waits for it, as during a
    solver's step (solidshell.interrupts.deferred_interrupt), so it cannot leave the results
    half written; the run then ends as it would have.  A mesh-only run writes in a moment (and
    need not import the solvers)."""
    if kind == "none":
        yield
        return
    from ..interrupts import deferred_interrupt

    with deferred_interrupt():
        yield


def _results_lost(e: OSError, folder, solved: Solved, summary: dict) -> IOFailure:
    """The IOFailure of a results write that failed (full disk, ...): the folder holds the earlier
    run unchanged (the staging folder is gone), and the solved state (U, the mesh, the summary) is
    saved to a file in the system's temporary folder, named in the one-line message with the run's
    checkpoint when it has one."""
    where = getattr(e, "path", None) or getattr(e, "filename", None) or folder.path
    reason = getattr(e, "reason", None) or e.strerror or str(e)
    keep = Path(tempfile.gettempdir()) / f"solidshell-{folder.run_id[:12]}-state.npz"
    mesh = solved.mesh
    try:
        with sio.atomic_path(keep) as tmp, open(tmp, "wb") as fh:
            np.savez(
                fh,
                U=np.asarray(solved.U, float),
                nodes=np.asarray(mesh.nodes, float),
                quads=np.asarray(mesh.quads),
                tris=np.asarray(mesh.tris),
                summary=np.asarray(json.dumps(sio.to_jsonable(summary))),
            )
        saved = f"the solved state (U, mesh, summary) was saved to {keep}"
    except OSError as e2:
        saved = f"the solved state could not be saved to {keep} either ({e2.strerror or e2})"
    ck = summary.get("checkpoint")
    ck_note = f"; the run's last checkpoint is {ck}" if isinstance(ck, str) and Path(ck).is_file() else ""
    return IOFailure(
        where, f"{reason}; results not written ({folder.path} holds the earlier run unchanged); {saved}{ck_note}"
    )


def _doubtful_inputs(sc: Scene, kind: str, overrides, setup, adaptive: bool) -> list[str]:
    """Warnings for inputs that are legal but likely not what was meant (issue 39): solver keys
    given (--set) for another solver than the one that runs, adapt keys on a run that is not
    adaptive, a scene without a [material] table (the sheet is then the library's wool), and
    clamped nodes that start inside a contact body (they cannot be pushed out, so the body's
    check of the free nodes does not refuse them: a pedestal whose top stands above the clamped
    rim)."""
    out = []
    given = list(overrides or {})
    if kind != "none":
        other = sorted({k.split(".")[1] for k in given if k.count(".") >= 2 and k.startswith("solver.")} - {kind})
        other = [o for o in other if o in solvers.KINDS]
        if other:
            keys = ", ".join(k for k in given if any(k.startswith(f"solver.{o}.") for o in other))
            out.append(f"{keys} set, but this run uses the {kind} solver: ignored")
        if not adaptive:
            keys = ", ".join(k for k in given if k.startswith("adapt.") and k != "adapt.enabled")
            if keys:
                out.append(f"{keys} set, but this run is not adaptive (--adaptive or adapt.enabled = true): ignored")
    if "material" not in (sc.raw or {"material": None}):
        out.append(f"{sc.source}: no [material] table: the sheet is the library's wool (material.fabric = 'wool')")
    out += _embedded_clamps(sc, setup)
    return out


def _embedded_clamps(sc: Scene, setup) -> list[str]:
    """A warning when nodes whose translations are all fixed start inside a contact body deeper
    than round-off (scenes.build.check_initial_contact checks the free nodes only)."""
    from ..contact import initial_penetration
    from ..scenes.build import contact_bodies

    try:
        bodies = contact_bodies(sc)
    except Exception:  # noqa: BLE001 - a body the build step accepted; a warning must not fail the run
        return []
    fixed = np.asarray(setup.fixed, bool).reshape(setup.mesh.n_nodes, -1)[:, :3].all(axis=1)
    if not bodies or not fixed.any():
        return []
    hits = initial_penetration(bodies, np.asarray(setup.mesh.nodes, float), free=fixed)
    return [
        f"{n} clamped node(s) start inside contact body {i} ({body.__class__.__name__}), deepest {depth:.4g} cm "
        f"(its offset included): they stay there; is the body's top above the clamped edge?"
        for i, body, n, depth in hits
    ]
