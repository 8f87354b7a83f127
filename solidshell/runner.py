"""run_scene: scene -> mesh -> model + problem -> solver -> files.

    out = run_scene("square-pedestal", mesh="48x16x4", solver="static", out_dir="runs/sp")
    out.summary["converged"], out.U, out.mesh, out.out_dir

The model, boundary, contact, analysis and solver modules are imported only when a solver runs,
so building and writing a mesh (``solver="none"``, what ``solidshell mesh`` does) stays fast.
"""

from __future__ import annotations

import logging
import sys
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import io as sio
from . import solvers
from . import sizing
from .errors import InputError, SolverError
from .rundir import RunFolder
from .scenes import Scene, check_density, load

log = logging.getLogger("solidshell")

MESH_SUFFIXES = (".msh", ".geo", ".vtu", ".vtk", ".xdmf", ".inp", ".med")


@dataclass
class RunOutput:
    """What :func:`run_scene` returns."""

    summary: dict
    U: np.ndarray
    mesh: Any
    out_dir: Path | None
    scene: Scene | None = None
    result: Any = None                      # the solver's SolveResult (None for a mesh-only run)
    files: list = field(default_factory=list)
    run_id: str = ""                        # uuid4 hex, also in summary.json and every file
    series: list | None = None              # adaptive runs: [(t, ShellMesh, U)], each frame on its own mesh
    projected_boundary: np.ndarray | None = None   # the analysed drape's outline (analysis.projected_boundary)
    problem: Any = None                     # the Problem the solver ran (adaptive: on the final mesh, with its
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


# --------------------------------------------------------------------------- progress
class _Bar:
    """progress(fraction, text) drawn as a tqdm bar on stderr, only when stderr is a terminal (logs
    and pipes stay clean).  A ticker thread redraws it every quarter second, so the bar appears
    half a second after the start and its elapsed time and ETA keep moving even while a solver is
    busy between two progress calls (a numba compile, a factorisation)."""

    SHOW_AFTER = 0.5    # s: short runs finish without a bar flashing by
    TICK = 0.25         # s between redraws

    def __init__(self, label: str):
        self.bar = None
        tty = hasattr(sys.stderr, "isatty") and sys.stderr.isatty()
        if not tty:
            return
        from tqdm import tqdm

        # ETA from the average rate since the start (smoothing 0): solver fractions are uneven
        self.bar = tqdm(total=1000, desc=label, file=sys.stderr, delay=self.SHOW_AFTER, leave=False,
                        smoothing=0.0, mininterval=self.TICK,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}{postfix}")
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._tick, name="solidshell-progress", daemon=True)
        self._thread.start()

    def _tick(self):
        if self._stop.wait(self.SHOW_AFTER):
            return
        while not self._stop.is_set():
            self.bar.refresh()
            self._stop.wait(self.TICK)

    def __call__(self, fraction: float, text: str = "") -> None:
        if self.bar is None:
            return
        try:
            n = int(round(1000 * min(max(float(fraction), 0.0), 1.0)))
        except (TypeError, ValueError):
            return
        if text:
            self.bar.set_postfix_str(" ".join(str(text).split())[:60], refresh=False)
        if n > self.bar.n:
            self.bar.update(n - self.bar.n)

    def close(self):
        if self.bar is not None:
            self._stop.set()
            self._thread.join(1.0)
            self.bar.close()


def _phase(cb, lo, hi):
    """A progress callback mapping [0,1] onto [lo,hi] of the outer one."""
    return lambda f, text="": cb(lo + (hi - lo) * float(f), text)


# --------------------------------------------------------------------------- building blocks
def build_scene_mesh(scene: Scene, mesh=None, kind: str = "none", allow_large: bool = False):
    """(ShellMesh, mesh name) for a scene: ``mesh`` None (the scene's density), a density string,
    a mesh/geometry file path or a ShellMesh.

    Size guard (solidshell.sizing): a density is refused *before meshing* when the memory a run of
    ``kind`` needs on it exceeds the machine's available memory; a mesh read from a file is checked
    once read (its size is not known before).  ``allow_large`` skips the guard."""
    from .mesh import ShellMesh

    if isinstance(mesh, ShellMesh):
        return _guard(mesh, "the given mesh", kind, allow_large), "user ShellMesh"
    from . import meshing

    def read(p: Path):
        try:
            m = meshing.from_file(p)
        except InputError as e:
            msg = str(e)
            raise InputError(msg if p.name in msg else f"mesh file {p}: {msg}") from None
        return _guard(m, f"mesh file {p}", kind, allow_large), str(p)

    if mesh is not None and (isinstance(mesh, Path) or str(mesh).lower().endswith(MESH_SUFFIXES)):
        return read(Path(mesh))
    if "file" in scene.geometry:
        if mesh is not None:
            raise InputError(f"scene {scene.name!r} reads its mesh from {scene.geometry['file']}; "
                             f"a density ({mesh!r}) applies to recipe geometries only")
        return read(Path(scene.geometry["file"]))
    where = "--mesh" if mesh is not None else f"{scene.source}: mesh.density"
    density = scene.density if mesh is None else check_density(str(mesh), scene.recipe, "--mesh")
    if density is not None:
        sizing.check(sizing.elements_of_density(density), kind, f"{where} {density}", allow_large)
    params = {k: v for k, v in scene.geometry.items() if k != "recipe"}
    return meshing.build_mesh(scene.recipe, density, **params), density


def _guard(mesh, what, kind, allow_large):
    sizing.check(mesh.n_elements, kind, what, allow_large)
    return mesh


def support_mask(scene: Scene, mesh) -> np.ndarray:
    """(N,6) bool: clamped sets fix all six dofs, fixed_translations sets fix U_o."""
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    for kind, dofs in (("clamped", slice(0, 6)), ("fixed_translations", slice(0, 3))):
        for name in scene.supports.get(kind, ()):
            try:
                idx = mesh.node_set(name)
            except InputError as e:
                raise InputError(f"{scene.source}: supports.{kind}: {e}") from None
            fixed[idx, dofs] = True
    return fixed


def check_load_sets(scene: Scene, mesh) -> None:
    """Fail early (before any solve) on a load that names a missing or empty node set."""
    for kind in ("point", "line"):
        for ld in scene.loads[kind]:
            if "node_set" in ld:
                mesh.node_set(ld["node_set"])


def scene_loads(scene: Scene, model) -> np.ndarray:
    """(N,6) dead loads of the scene [gf]: self-weight, point, line and surface loads, lumped with
    the model's trapezoidal-rule nodal areas (solidshell.boundary)."""
    from . import boundary

    mesh = model.mesh
    P = np.zeros((mesh.n_nodes, 6))
    if scene.loads["gravity"]:
        P += boundary.gravity_loads(model, direction=tuple(scene.loads["gravity_direction"]))
    for ld in scene.loads["point"]:
        if "at" in ld:
            idx = np.array([int(np.argmin(np.linalg.norm(mesh.nodes - np.asarray(ld["at"]), axis=1)))])
        else:
            idx = mesh.node_set(ld["node_set"])
        P += boundary.point_load(mesh.n_nodes, idx, np.asarray(ld["force"], float) / len(idx))
    for ld in scene.loads["line"]:
        try:
            P += boundary.line_load(mesh, ld["node_set"], ld["force"])
        except InputError as e:
            raise InputError(f"line load on node set {ld['node_set']!r}: {e}") from None
    for ld in scene.loads["surface"]:
        f = np.asarray(ld["force"], float)
        n = float(np.linalg.norm(f))
        if n > 0.0:
            P += boundary.surface_load(model, n, direction=f / n)
    return P


def contact_bodies(scene: Scene) -> list:
    """solidshell.contact bodies of the scene's [[contact]] tables (empty: no contact search)."""
    if not scene.contact:
        return []
    from . import contact as C

    out = []
    for c in scene.contact:
        off = c.get("offset", 0.0)
        mu = c.get("friction", 0.0)
        if c["type"] == "sphere":
            out.append(C.Sphere(c["centre"], c["radius"], offset=off, friction=mu))
        elif c["type"] == "plane":
            out.append(C.Plane(c["point"], c["normal"], offset=off, friction=mu))
        else:
            kw = dict(height=c.get("height"), edge_radius=c.get("edge_radius", 0.0), offset=off, friction=mu)
            if c["shape"] == "disc":
                out.append(C.Pedestal(c["centre"], radius=c["diameter"] / 2, **kw))
            else:
                out.append(C.Pedestal(c["centre"], half_widths=(c["size"] / 2, c["size"] / 2), **kw))
    return out


def _body_label(scene: Scene, i: int) -> str:
    c = scene.contact[i]
    where = {"sphere": "centre", "plane": "point", "pedestal": "centre"}[c["type"]]
    return f"contact[{i}] ({c['type']} at {list(c[where])})"


def check_initial_contact(scene: Scene, mesh, fixed, bodies=None, U0=None) -> None:
    """InputError when a node of the sheet starts inside a contact body (solidshell.contact.
    initial_penetration): names the body, the node count and the deepest penetration [cm].
    Nodes with all translations fixed are not checked (they cannot be pushed out, and a clamped
    rim on a pedestal's edge sits exactly on it)."""
    bodies = contact_bodies(scene) if bodies is None else bodies
    if not bodies:
        return
    from .contact import initial_penetration

    x = np.asarray(mesh.nodes, float)
    if U0 is not None:
        u = np.asarray(U0, dtype=float)
        if u.size == 6 * mesh.n_nodes:          # (a wrong shape is the solver's settings' to refuse)
            x = x + u.reshape(-1, 6)[:, :3]
    free = ~np.asarray(fixed, bool)[:, :3].all(axis=1)
    hits = initial_penetration(bodies, x, free=free)
    if hits:
        i, body, n, depth = hits[0]
        more = f"; {len(hits) - 1} more bod{'y' if len(hits) == 2 else 'ies'} too" if len(hits) > 1 else ""
        off = f" (its offset {body.offset:g} cm included)" if body.offset else ""
        raise InputError(f"{scene.source}: {_body_label(scene, i)}: {n} node(s) of the sheet start inside "
                         f"the body, deepest {depth:.4g} cm{off}; move the body or the sheet so that "
                         f"they start apart or just touching{more}")


def build_problem(scene: Scene, mesh, fixed=None, membrane=None, constants=None):
    """The solidshell.problem.Problem of a scene on a mesh: the Model (section, thickness-strain
    model), supports, loads (self-weight, point, line, surface) and contact bodies -- everything a
    solver needs.  Unknown or empty node sets raise InputError.  The adaptive driver calls this for
    every new mesh.  ``membrane``: the quads' membrane strains (Model's argument: one choice or one
    per quad) instead of the scene's ``model.membrane``; ``constants``: a model.ElementConstants
    cache shared by the problems of one adaptive run."""
    from .model import Model
    from .problem import Problem

    sc = load(scene)
    if fixed is None:
        fixed = support_mask(sc, mesh)
    check_load_sets(sc, mesh)
    if membrane is None:
        membrane = sc.model.get("membrane", "full")
    model = Model(mesh, sc.material_object(), thickness_strain=sc.model["thickness_strain"],
                  mu=sc.model["mu"], membrane=membrane, constants=constants)
    return Problem(model, fixed, scene_loads(sc, model), contact=contact_bodies(sc), name=sc.name)


def perturbed_start(scene: Scene, mesh, fixed, settings: dict):
    """The starting state U0 of the scene's ``[perturbation]`` (solidshell.perturbation), or None
    when it has none (or amplitude 0).  A perturbation and a solver U0 together are refused."""
    if not scene.perturbation or not scene.perturbation.get("amplitude"):
        return None
    if settings.get("U0") is not None:
        raise InputError(f"{scene.source}: perturbation and solver setting U0 both give the starting state; "
                         f"keep one")
    from .perturbation import initial_state

    centre = None
    ped = scene.pedestal()
    if ped is not None:
        centre = ped["centre"]
    else:
        centre = next((c["centre"] for c in scene.contact if c["type"] == "sphere"), None)
    try:
        return initial_state(scene.perturbation, mesh, fixed, centre)
    except InputError as e:
        raise InputError(f"{scene.source}: {e}") from None


def check_solver_settings(kind: str, merged: dict):
    """The solver's typed settings (solidshell.solvers.validate) before any work: one-line
    InputError naming the key.  Returns the parsed settings model."""
    return solvers.validate(kind, merged)


def check_restart_file(path) -> None:
    """A restart file must be a complete checkpoint archive (.npz, a zip file): a truncated or
    foreign file is refused before any work, naming it (whether it matches this run -- mesh,
    material, settings -- is the solver's check)."""
    import zipfile

    p = Path(path)
    try:
        with zipfile.ZipFile(p) as z:
            bad = z.testzip()               # reads every member and checks its CRC
    except FileNotFoundError:
        raise InputError(f"restart file {p} not found") from None
    except IsADirectoryError:
        raise InputError(f"restart file {p} is a directory") from None
    except (OSError, zipfile.BadZipFile, EOFError, ValueError) as e:
        raise InputError(f"restart file {p} is not a readable checkpoint ({e}); truncated or not "
                         f"written by solidshell") from None
    if bad is not None:
        raise InputError(f"restart file {p} is damaged (member {bad} fails its checksum)")




def _peak_memory_mb() -> float:
    """Peak resident memory of this process so far [MiB] (Linux reports ru_maxrss in KiB)."""
    import resource

    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)


def _pedestal_area(scene: Scene) -> float | None:
    p = scene.pedestal()
    if p is None:
        return None
    return p["size"] ** 2 if p["shape"] == "square" else np.pi * p["diameter"] ** 2 / 4.0


def analyse(scene: Scene, mesh, U, model=None) -> dict:
    """Drape measures (analysis.drape_summary: drape coefficient, folds, outline) of the state U
    (N,6) on ``mesh`` for scenes with a pedestal or a sphere; the strip's tip position; with
    ``model``, the interpenetrated nodes (Section 4.3) for all.  The measures a run's summary
    holds, for a state computed elsewhere (verification/drape_states.py).  ``scene``: a Scene or
    anything scenes.load takes."""
    scene = load(scene)
    out = {}
    if model is not None and hasattr(model, "interpenetrated_nodes"):
        out["interpenetrated_nodes"] = int(np.count_nonzero(model.interpenetrated_nodes(U)))
    if "tip" in mesh.node_sets and len(mesh.node_sets["tip"]):
        # the strip's free end: mean deformed position of its nodes [cm] (Fig. 4 side view)
        tip = mesh.node_sets["tip"]
        out["tip_position"] = (mesh.nodes[tip] + U[tip, :3]).mean(0).tolist()
    ped = _pedestal_area(scene)
    if ped is None and not any(c["type"] == "sphere" for c in scene.contact):
        return out
    from . import analysis

    kw = {"pedestal_area": ped or 0.0}
    if ped is None:   # cloth on a sphere: the sheet is whole; measure about the sphere's axis
        c = next(c for c in scene.contact if c["type"] == "sphere")
        kw["center"] = (c["centre"][0], c["centre"][1])
    d = analysis.drape_summary(mesh, U, **kw)
    out["projected_boundary"] = d.pop("projected_boundary")
    out.update(d)
    return out


# --------------------------------------------------------------------------- the run
def run_scene(scene, mesh=None, solver=None, out_dir=None, progress=True, overrides=None, *,
              force=False, allow_large=False, adaptive=None, **settings) -> RunOutput:
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
    timings = {}
    sc = load(scene)
    if adaptive is not None:
        overrides = {**(overrides or {}), "adapt.enabled": bool(adaptive)}
    sc = sc.with_overrides(overrides)
    kind = sc.solver["kind"] if solver is None else str(solver)
    if kind != "none":
        solvers.kind(kind)          # the registry's one-line error for an unknown kind

    bar = None
    if callable(progress):
        cb = progress
    elif progress:
        bar = _Bar(sc.name)
        cb = bar
    else:
        from .problem import no_progress
        cb = no_progress
    try:
        out = _run(sc, kind, mesh, out_dir, cb, settings, timings, t_start, overrides, force, allow_large)
    finally:
        if bar is not None:
            bar.close()
    for w in out.summary["warnings"]:      # after the bar is gone: one clean line each
        log.warning(w)
    return out


def _run(sc, kind, mesh_arg, out_dir, cb, settings, timings, t_start, overrides=None, force=False,
         allow_large=False) -> RunOutput:
    run_id = uuid.uuid4().hex
    warnings: list[str] = []

    # every check, before anything is written ---------------------------------------------------
    s = None
    if kind == "static" and ({"checkpoint", "restart"} & set(settings)):
        raise InputError("--checkpoint / --restart apply to the explicit and relax solvers, not static")
    if kind != "none":
        s = sc.solver_settings(kind)
        s.update(settings)
        check_solver_settings(kind, s)
        if isinstance(s.get("restart"), (str, Path)):     # (another type: the schema refuses it)
            check_restart_file(s["restart"])
    folder = None
    if out_dir is not None:
        folder = RunFolder(out_dir, run_id, force=force,
                           keep=[s.get(k) for k in ("checkpoint", "restart")] if s else ())
        folder.check()
        if sc.output["pictures"] or sc.output["snapshots"]:
            # whether VTK can render is asked in a child process (~2 s): it runs while we mesh
            from .render import vtk_backend

            vtk_backend.start_probe()
    adapt = adapt_settings(sc, kind)
    cb(0.0, "meshing")
    t = time.perf_counter()
    if adapt is not None and mesh_arg is None:
        mesh_arg = sc.mesh["adaptive_level0"] or sc.density
    mesh, mesh_name = build_scene_mesh(sc, mesh_arg, kind, allow_large)
    fixed = support_mask(sc, mesh)            # unknown / empty node sets fail here, before solving
    material = sc.material_object()
    check_load_sets(sc, mesh)
    bodies = contact_bodies(sc)
    solver_s = s                  # the solver's settings: s plus a perturbed start (kept out of summary)
    if kind != "none":
        U0 = perturbed_start(sc, mesh, fixed, s)
        if U0 is not None:
            solver_s = {**s, "U0": U0}
        check_initial_contact(sc, mesh, fixed, bodies, U0=solver_s.get("U0"))
    adaptive_run = None
    if adapt is not None:       # builds the background mesh: its checks (quads only, memory) come now
        adaptive_run = _adaptive_run(sc, mesh, solver_s, adapt, kind, cb)
        guard = f" + {adapt.guard_levels} guard" if adapt.guard_levels else ""
        mesh_name = f"{mesh_name} adaptive ({adapt.levels}{guard} levels)"
    timings["mesh"] = time.perf_counter() - t
    if folder is not None and folder.foreign:
        warnings.append(f"output folder {folder.path} holds {len(folder.foreign)} file(s) solidshell did "
                        f"not write, left untouched (--force): {', '.join(folder.foreign[:5])}")

    summary = {
        "run_id": run_id, "scene": sc.name, "title": sc.title, "paper_section": sc.paper_section,
        "scene_file": sc.source, "mesh": mesh_name, "recipe": sc.recipe,
        "geometry": {k: (str(v) if isinstance(v, Path) else v) for k, v in sc.geometry.items()},
        "solver": kind, "settings": s, "counts": sio.mesh_counts(mesh, fixed),
        "area": float(mesh.area()), "pedestal_area": _pedestal_area(sc),
        "material": _material_summary(material), "model": dict(sc.model),
        "supports": {k: list(v) for k, v in sc.supports.items()},
        "contact": [dict(c) for c in sc.contact],
        "units": dict(sio.UNITS), "versions": sio.package_versions(),
        "converged": None, "interrupted": False, "message": "mesh only" if kind == "none" else "",
    }
    summary["total_weight"] = float(material.weight_per_area * summary["area"])
    summary["overrides"] = dict(overrides or {})
    summary["scene_inputs"] = sc.summary()          # the resolved scene, to reproduce the run
    if solver_s is not s:
        summary["perturbation"] = dict(sc.perturbation)
    if s and s.get("checkpoint"):
        summary["checkpoint"] = str(s["checkpoint"])
    if s and s.get("restart"):
        summary["restart"] = str(s["restart"])

    if folder is not None:
        folder.open()                              # the folder and its RUNNING marker

    U = np.zeros((mesh.n_nodes, 6))
    result = None
    model = None
    problem = None
    series = None                                  # adaptive: [(t, mesh, U)] on each frame's own mesh
    if kind != "none":
        try:
            cb(0.05, "setting up")
            t = time.perf_counter()
            try:
                from . import solvers
                fn = solvers.get(kind)
            except ImportError as e:
                raise SolverError(f"solver {kind!r} is not available in this installation ({e})") from None
            if adaptive_run is None:
                problem = build_problem(sc, mesh, fixed)
                model = problem.model
                timings["setup"] = time.perf_counter() - t
                t = time.perf_counter()
                if kind == "static":
                    # coarse meshes of the recipe first (solvers/sequence.py; "sequence" setting)
                    from .solvers.sequence import solve_sequenced
                    result = solve_sequenced(
                        fn, problem, dict(solver_s), _phase(cb, 0.08, 0.9), sc, mesh_name,
                        lambda d: build_problem(sc, build_scene_mesh(sc, d, kind, allow_large)[0]))
                else:
                    result = fn(problem, dict(solver_s), _phase(cb, 0.08, 0.9))
            else:
                timings["setup"] = time.perf_counter() - t
                t = time.perf_counter()
                adaptive_out = adaptive_run.run()
                result, mesh = adaptive_out.result, adaptive_out.mesh
                series = adaptive_out.series
                fixed = support_mask(sc, mesh)
                problem = adaptive_run.integ.problem
                model = problem.model
                summary["counts"] = sio.mesh_counts(mesh, fixed)
                summary["area"] = float(mesh.area())
            timings["solve"] = time.perf_counter() - t
        except BaseException:
            # bad input found by the solver, a solver error before any state, Ctrl-C with no state
            # returned: nothing of this run is written and the earlier run's files stay as they were
            if folder is not None:
                folder.abandon()
            raise
        summary["peak_memory_mb"] = _peak_memory_mb()
        U = np.asarray(result.U, float).reshape(mesh.n_nodes, 6)
        info = dict(result.info or {})
        summary["converged"] = bool(result.converged)
        summary["message"] = str(result.message or "")
        summary["interrupted"] = info.get("status") == "interrupted"
        finite = bool(np.all(np.isfinite(U)))
        summary["finite"] = finite
        if finite:
            summary["max_displacement"] = float(np.max(np.linalg.norm(U[:, :3], axis=1)))
            summary["min_z"] = float(np.min(mesh.nodes[:, 2] + U[:, 2]))
        warnings.extend(str(w) for w in (info.pop("warnings", None) or []))
        for k, v in info.items():
            if k in summary and (summary[k] == v or k in ("solver", "converged")):
                continue                        # already said (the info repeats it)
            summary[k if k not in summary else f"solver_{k}"] = v
        summary["frames"] = len(result.frames or [])
        if finite:
            try:
                a = analyse(sc, mesh, U, model)
            except Exception as e:      # analysis must never lose a solved state
                summary["analysis_error"] = f"{type(e).__name__}: {e}"
            else:
                for k, v in a.items():
                    summary.setdefault(k, v)
        warnings.extend(_state_warnings(summary, info))

    # files: the earlier run's go first (its summary before the rest), then this run's ----------
    snaps = _snapshot_plan(sc, kind, result)
    warnings.extend(w for _, _, w in snaps if w)
    files = []
    if folder is not None:
        cb(0.9, "writing results")
        t = time.perf_counter()
        replaced = folder.clear_stale()
        if replaced:
            summary["replaced_files"] = replaced
        files += _write_outputs(folder, sc, kind, mesh, mesh_name, U, result, summary, snaps, cb, series)
        timings["write_results"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t_start
    summary["timings"] = {k: round(v, 4) for k, v in timings.items()}
    summary["warnings"] = list(dict.fromkeys(warnings))      # in order, each once
    boundary = summary.pop("projected_boundary", None)
    if folder is not None:
        summary["files"] = sorted({Path(f).name for f in files} | {"summary.json"})
        files.append(folder.finish(summary))
    cb(1.0, "interrupted" if summary["interrupted"] else "done")
    summary = sio.to_jsonable(summary)
    return RunOutput(summary=summary, U=U, mesh=mesh, out_dir=folder.path if folder else None, scene=sc,
                     result=result, files=[Path(f) for f in files], run_id=run_id, series=series,
                     projected_boundary=None if boundary is None else np.asarray(boundary, float),
                     problem=problem)


def adapt_settings(scene: Scene, kind: str):
    """The scene's AdaptSettings when adaptivity is on (None when off); InputError when it is asked
    of a solver that cannot host it (§5.5: remeshing happens between the steps of a dynamic run)."""
    if not scene.adapt.get("enabled", False):
        return None
    from .adapt.settings import parse_adapt

    adapt = parse_adapt(scene.adapt, f"{scene.source}: adapt")
    if kind not in ("explicit", "relax"):
        raise InputError(f"adaptive subdivision runs inside a dynamic run (--solver explicit or relax, "
                         f"paper §5.5); the {kind} solver is not adaptive")
    return adapt


def boundary_curves(scene: Scene):
    """The true curves of a recipe's curved boundaries (circles about the origin), for placing new
    boundary nodes on them (§5.1); None for straight-sided sheets."""
    from .adapt import circle_projector

    g = scene.geometry
    if scene.recipe == "disc_on_disc":
        return circle_projector((0.0, 0.0), (g["pedestal_diameter"] / 2.0, g["diameter"] / 2.0))
    if scene.recipe == "square_on_disc":
        return circle_projector((0.0, 0.0), g["pedestal_diameter"] / 2.0)
    return None


def _adaptive_run(sc: Scene, level0, settings: dict, adapt, kind: str, cb):
    """The §5.5 driver for this scene, built (background mesh and all) but not started."""
    from .adapt.driver import AdaptiveRun
    from .solvers.explicit import Integrator, parse_settings

    s = dict(settings)
    restart = s.pop("restart", None)

    from .model import ElementConstants

    constants = ElementConstants()        # most elements survive a remesh: fold each one once

    def make_problem(mesh, coarse_quads=None):
        # coarse_quads: quads below the finest level, given "ans" membranes (adapt.coarse_membrane)
        membrane = None if coarse_quads is None else \
            np.where(coarse_quads, "ans", sc.model.get("membrane", "full")).tolist()
        return build_problem(sc, mesh, membrane=membrane, constants=constants)

    run = AdaptiveRun(level0, make_problem, Integrator, parse_settings(s, kind == "relax"),
                      adapt, relax=kind == "relax", curves=boundary_curves(sc), progress=_phase(cb, 0.08, 0.9),
                      restart=restart)
    return run


def _state_warnings(summary: dict, info: dict) -> list[str]:
    """The runner's own warnings about a solved state (one line each)."""
    out = []
    n_end = summary.get("interpenetrated_nodes")
    if n_end:
        out.append(f"{n_end} node(s) interpenetrated at the end (n_p . d_p < 0, Section 4.3): the "
                   f"sheet passes through itself there; refine the mesh or check the result")
    n_max = info.get("max_interpenetrated_nodes")
    if n_max and not n_end:
        t = info.get("max_interpenetration_time")
        at = f" (at t = {t:.4g} s)" if isinstance(t, (int, float)) else ""
        out.append(f"up to {n_max} node(s) were interpenetrated during the run{at}, none at the end")
    if info.get("positive_definite") is False:
        lmin = info.get("min_tangent_eigenvalue")
        ev = f" (smallest tangent eigenvalue {lmin:.3g})" if isinstance(lmin, (int, float)) else ""
        out.append(f"the final state is not a stable equilibrium{ev}: a saddle, not a drape at rest")
    if summary.get("finite") is False:
        out.append("the final state is not finite; the files hold it as written by the solver")
    return out


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
    said = {float(x) for x in (info.get("snapshots_after_t_end_dropped") or [])}   # the solver's warning
    out = []
    for ts in snaps:
        j = int(np.argmin(np.abs(times - ts))) if len(times) else -1
        if j >= 0 and abs(times[j] - ts) <= 1e-6 + 1e-3 * max(ts, 1.0) and np.all(np.isfinite(frames[j][1])):
            out.append((ts, j, None))
        elif ts in said:
            out.append((ts, None, None))
        else:
            why = (f"after the run's end t = {t_final:.6g} s" if isinstance(t_final, (int, float)) and ts > t_final
                   else "no frame kept at that time")
            out.append((ts, None, f"snapshot t = {ts:g} s dropped: {why}"))
    return out


def _write_outputs(folder, sc, kind, mesh, mesh_name, U, result, summary, snaps, cb, series=None) -> list:
    """Write a run's files (each stamped with the run id) into its folder; returns their paths.
    ``series`` (an adaptive run): [(t, mesh, U)], each frame on its own mesh -> series.pvd of VTUs."""
    rid = folder.run_id
    files = [folder.write(name, sio.write_mesh_file, mesh, run_id=rid) for name in ("mesh.xdmf", "mesh.vtu")]
    finite = result is not None and bool(np.all(np.isfinite(U)))
    if result is not None:
        files.append(folder.write("result.xdmf", sio.write_mesh_file, mesh, U, run_id=rid))
        files.append(folder.write("result.vtu", sio.write_mesh_file, mesh, U, run_id=rid))
        if finite:
            files.append(folder.write("deformed.vtu", sio.write_mesh_file, mesh, U, deformed=True, run_id=rid))
        frames = [(float(tf), Uf) for tf, Uf in (result.frames or [])]
        if series is not None and len(series) > 1:
            files.append(folder.write("series.pvd", sio.write_mesh_series, series, run_id=rid))
            files += sio.series_frame_paths(folder.path / "series.pvd", len(series))
            summary["series_parameter"] = "time [s]"
        elif len(frames) > 1:
            files.append(folder.write("series.xdmf", sio.write_time_series, mesh, frames, run_id=rid))
            summary["series_parameter"] = "time [s]" if kind in ("explicit", "relax") else "load factor"
    boundary = summary.get("projected_boundary")
    if boundary is not None:
        def csv(p):
            with sio.atomic_write(p) as f:
                f.write(f"# projected boundary of the draped sheet on the X-Y plane [cm]\n"
                        f"# solidshell run_id={rid}\nx,y\n")
                f.writelines(f"{x:.6g},{y:.6g}\n" for x, y in boundary)
            return p
        files.append(folder.write("projected_boundary.csv", csv))
    def picture(p, *a, **kw):
        from .plotting import render      # matplotlib only when a picture is drawn

        return sio.stamp_png(render(p, *a, **kw), rid)

    state = U if finite else None
    sub = _subtitle(sc, mesh_name, mesh, kind, summary)
    views = sc.output["pictures"]
    for i, view in enumerate(views):
        cb(0.92 + 0.08 * i / max(1, len(views)), f"{view} picture")
        files.append(folder.write(f"{view}.png", picture, mesh, state, view=view, title=sc.title, scene=sc,
                                  subtitle=sub))
    for ts, j, _ in snaps:
        if j is not None:
            tj = float(result.frames[j][0])
            mj = mesh if series is None else series[j][1]
            sub_j = f"t = {tj:.3f} s" + ("" if series is None else f", {mj.n_nodes} active nodes")
            for view in ("iso", "top") if series is not None else ("iso",):
                files.append(folder.write(f"{view}_t{ts:.3f}.png", picture, mj, result.frames[j][1], view=view,
                                          title=sc.title, scene=sc, subtitle=sub_j))
    return files


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


def _material_summary(m) -> dict:
    d = {"type": type(m).__name__, "name": getattr(m, "name", None),
         "C_m": np.asarray(m.C_m).tolist(), "C_b": np.asarray(m.C_b).tolist(),
         "C_t": np.asarray(m.C_t).tolist(), "E_z": float(m.E_z), "thickness": float(m.thickness),
         "mass_per_area": float(m.mass_per_area), "weight_per_area": float(m.weight_per_area),
         "warp_angle_deg": float(np.degrees(m.warp_angle_rad))}
    return d
