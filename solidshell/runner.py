"""run_scene: scene -> mesh -> model + problem -> solver -> files.

    out = run_scene("square-pedestal", mesh="48x16x4", solver="static", out_dir="runs/sp")
    out.summary["converged"], out.U, out.mesh, out.out_dir

The model, boundary, contact, analysis and solver modules are imported only when a solver runs,
so building and writing a mesh (``solver="none"``, what ``solidshell mesh`` does) stays fast.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import io as sio
from .errors import InputError, SolverError
from .scenes import Scene, check_density, load

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

    @property
    def converged(self):
        return self.summary.get("converged")


# --------------------------------------------------------------------------- progress
class _Bar:
    """progress(fraction, text) drawn as a tqdm bar on stderr, shown only after one second and
    only when stderr is a terminal (logs and pipes stay clean)."""

    def __init__(self, label: str):
        from tqdm import tqdm

        tty = hasattr(sys.stderr, "isatty") and sys.stderr.isatty()
        self.bar = tqdm(total=1000, desc=label, file=sys.stderr, delay=1.0, leave=False, disable=not tty,
                        bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining} {postfix}")

    def __call__(self, fraction: float, text: str = "") -> None:
        try:
            n = int(round(1000 * min(max(float(fraction), 0.0), 1.0)))
        except (TypeError, ValueError):
            return
        if self.bar.disable:
            return
        if text:
            self.bar.set_postfix_str(str(text)[:60], refresh=False)
        if n != self.bar.n:
            self.bar.update(n - self.bar.n)     # update() honours the 1 s delay

    def close(self):
        self.bar.close()


def _phase(cb, lo, hi):
    """A progress callback mapping [0,1] onto [lo,hi] of the outer one."""
    return lambda f, text="": cb(lo + (hi - lo) * float(f), text)


# --------------------------------------------------------------------------- building blocks
def build_scene_mesh(scene: Scene, mesh=None):
    """(ShellMesh, mesh name) for a scene: ``mesh`` None (the scene's density), a density string,
    a mesh/geometry file path or a ShellMesh."""
    from .mesh import ShellMesh

    if isinstance(mesh, ShellMesh):
        return mesh, "user ShellMesh"
    from . import meshing

    def read(p: Path):
        try:
            return meshing.from_file(p), str(p)
        except InputError as e:
            msg = str(e)
            raise InputError(msg if p.name in msg else f"mesh file {p}: {msg}") from None

    if mesh is not None and (isinstance(mesh, Path) or str(mesh).lower().endswith(MESH_SUFFIXES)):
        return read(Path(mesh))
    if "file" in scene.geometry:
        if mesh is not None:
            raise InputError(f"scene {scene.name!r} reads its mesh from {scene.geometry['file']}; "
                             f"a density ({mesh!r}) applies to recipe geometries only")
        return read(Path(scene.geometry["file"]))
    density = scene.density if mesh is None else check_density(str(mesh), scene.recipe, "--mesh")
    params = {k: v for k, v in scene.geometry.items() if k != "recipe"}
    return meshing.build_mesh(scene.recipe, density, **params), density


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


def _peak_memory_mb() -> float:
    """Peak resident memory of this process so far [MiB] (Linux reports ru_maxrss in KiB)."""
    import resource

    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)


def _pedestal_area(scene: Scene) -> float | None:
    p = scene.pedestal()
    if p is None:
        return None
    return p["size"] ** 2 if p["shape"] == "square" else np.pi * p["diameter"] ** 2 / 4.0


def _analyse(scene: Scene, mesh, U, model=None) -> dict:
    """Drape measures for scenes with a pedestal or a sphere; interpenetrated nodes for all."""
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
def run_scene(scene, mesh=None, solver=None, out_dir=None, progress=True, overrides=None,
              **settings) -> RunOutput:
    """Run a scene (a name, a .toml path or a Scene).

    mesh      : None (the scene's density), a density like "24x8x4", a mesh file, or a ShellMesh
    solver    : None (the scene's [solver] kind), "static" | "explicit" | "relax", or "none"
                (build and write the mesh only)
    out_dir   : directory for the files (created); None writes nothing
    progress  : True (a tqdm bar on stderr after 1 s), False, or a callback(fraction, text)
    overrides : dotted scene keys, e.g. {"solver.static.c": 2e-3, "material.warp_angle": 90}
    settings  : overrides of the chosen solver's settings (e.g. t_end=0.4, alpha=1.0)
    """
    t_start = time.perf_counter()
    timings = {}
    sc = load(scene)
    sc = sc.with_overrides(overrides)
    kind = sc.solver["kind"] if solver is None else str(solver)
    if kind not in ("none", "static", "explicit", "relax"):
        raise InputError(f"unknown solver {kind!r}; choose one of: static, explicit, relax, none")

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
        return _run(sc, kind, mesh, out_dir, cb, settings, timings, t_start, overrides)
    finally:
        if bar is not None:
            bar.close()


def _run(sc, kind, mesh_arg, out_dir, cb, settings, timings, t_start, overrides=None) -> RunOutput:
    files = []
    out = Path(out_dir) if out_dir is not None else None
    if out is not None:
        if out.exists() and not out.is_dir():
            raise InputError(f"output path {out} exists and is not a directory")
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(f"cannot create output directory {out}: {e.strerror or e}") from None

    # mesh -----------------------------------------------------------------------------------
    cb(0.0, "meshing")
    t = time.perf_counter()
    mesh, mesh_name = build_scene_mesh(sc, mesh_arg)
    fixed = support_mask(sc, mesh)            # unknown / empty node sets fail here, before solving
    material = sc.material_object()
    check_load_sets(sc, mesh)
    timings["mesh"] = time.perf_counter() - t

    summary = {
        "scene": sc.name, "title": sc.title, "paper_section": sc.paper_section,
        "scene_file": sc.source, "mesh": mesh_name, "recipe": sc.recipe,
        "geometry": {k: (str(v) if isinstance(v, Path) else v) for k, v in sc.geometry.items()},
        "solver": kind, "settings": None, "counts": sio.mesh_counts(mesh, fixed),
        "area": float(mesh.area()), "pedestal_area": _pedestal_area(sc),
        "material": _material_summary(material), "model": dict(sc.model),
        "supports": {k: list(v) for k, v in sc.supports.items()},
        "contact": [dict(c) for c in sc.contact],
        "units": dict(sio.UNITS), "versions": sio.package_versions(),
        "converged": None, "message": "mesh only" if kind == "none" else "",
    }
    summary["total_weight"] = float(material.weight_per_area * summary["area"])
    summary["overrides"] = dict(overrides or {})
    summary["scene_inputs"] = sc.summary()          # the resolved scene, to reproduce the run

    if out is not None:
        cb(0.03, "writing mesh")
        t = time.perf_counter()
        for name in ("mesh.xdmf", "mesh.vtu"):
            files.append(sio.write_mesh_file(out / name, mesh))
        timings["write_mesh"] = time.perf_counter() - t

    U = np.zeros((mesh.n_nodes, 6))
    result = None
    model = None
    if kind != "none":
        cb(0.05, "setting up")
        t = time.perf_counter()
        try:
            from . import solvers
            from .model import Model
            from .problem import Problem
            fn = solvers.get(kind)
        except ImportError as e:
            raise SolverError(f"solver {kind!r} is not available in this installation ({e}); "
                              f"the mesh is written") from None

        model = Model(mesh, material, thickness_strain=sc.model["thickness_strain"], mu=sc.model["mu"],
                      membrane=sc.model.get("membrane", "full"))
        problem = Problem(model, fixed, scene_loads(sc, model), contact=contact_bodies(sc), name=sc.name)
        s = sc.solver_settings(kind)
        s.update(settings)
        summary["settings"] = s
        timings["setup"] = time.perf_counter() - t
        t = time.perf_counter()
        result = fn(problem, dict(s), _phase(cb, 0.08, 0.9))
        timings["solve"] = time.perf_counter() - t
        summary["peak_memory_mb"] = _peak_memory_mb()
        U = np.asarray(result.U, float).reshape(mesh.n_nodes, 6)
        summary["converged"] = bool(result.converged)
        summary["message"] = str(result.message or "")
        finite = bool(np.all(np.isfinite(U)))
        summary["finite"] = finite
        if finite:
            summary["max_displacement"] = float(np.max(np.linalg.norm(U[:, :3], axis=1)))
            summary["min_z"] = float(np.min(mesh.nodes[:, 2] + U[:, 2]))
        for k, v in (result.info or {}).items():
            if k in summary and (summary[k] == v or k in ("solver", "converged")):
                continue                        # already said (the info repeats it)
            summary[k if k not in summary else f"solver_{k}"] = v
        summary["frames"] = len(result.frames or [])
        if finite:
            try:
                a = _analyse(sc, mesh, U, model)
            except Exception as e:      # analysis must never lose a solved state
                summary["analysis_error"] = f"{type(e).__name__}: {e}"
            else:
                boundary = a.pop("projected_boundary", None)
                for k, v in a.items():
                    summary.setdefault(k, v)
                if boundary is not None and out is not None:
                    p = out / "projected_boundary.csv"
                    with sio.atomic_write(p) as f:
                        f.write("# projected boundary of the draped sheet on the X-Y plane [cm]\nx,y\n")
                        f.writelines(f"{x:.6g},{y:.6g}\n" for x, y in boundary)
                    files.append(p)

    # files ----------------------------------------------------------------------------------
    if out is not None:
        cb(0.9, "writing results")
        t = time.perf_counter()
        if result is not None:
            files.append(sio.write_mesh_file(out / "result.xdmf", mesh, U))
            files.append(sio.write_mesh_file(out / "result.vtu", mesh, U))
            if np.all(np.isfinite(U)):
                files.append(sio.write_mesh_file(out / "deformed.vtu", mesh, U, deformed=True))
            frames = [(float(tf), Uf) for tf, Uf in (result.frames or [])]
            if len(frames) > 1:
                files.append(sio.write_time_series(out / "series.xdmf", mesh, frames))
                summary["series_parameter"] = "time [s]" if kind in ("explicit", "relax") else "load factor"
        state = U if (result is not None and np.all(np.isfinite(U))) else None
        sub = _subtitle(sc, mesh_name, mesh, kind, summary)
        from .plotting import render
        for i, view in enumerate(sc.output["pictures"]):
            cb(0.92 + 0.08 * i / max(1, len(sc.output["pictures"])), f"{view} picture")
            files.append(render(out / f"{view}.png", mesh, state, view=view, title=sc.title, scene=sc,
                                subtitle=sub))
        if result is not None and kind in ("explicit", "relax") and sc.output["snapshots"] and result.frames:
            times = np.array([float(tf) for tf, _ in result.frames])
            for ts in sc.output["snapshots"]:
                j = int(np.argmin(np.abs(times - ts)))
                if abs(times[j] - ts) <= 1e-6 + 1e-3 * max(ts, 1.0) and np.all(np.isfinite(result.frames[j][1])):
                    files.append(render(out / f"iso_t{ts:.3f}.png", mesh, result.frames[j][1], view="iso",
                                        title=sc.title, scene=sc, subtitle=f"t = {times[j]:.3f} s"))
        timings["write_results"] = time.perf_counter() - t
        timings["total"] = time.perf_counter() - t_start
        summary["timings"] = {k: round(v, 4) for k, v in timings.items()}
        summary["files"] = sorted({Path(f).name for f in files} | {"summary.json"})
        sio.write_json(out / "summary.json", summary)
        files.append(out / "summary.json")
    else:
        timings["total"] = time.perf_counter() - t_start
        summary["timings"] = {k: round(v, 4) for k, v in timings.items()}
    cb(1.0, "done")
    summary = sio.to_jsonable(summary)
    return RunOutput(summary=summary, U=U, mesh=mesh, out_dir=out, scene=sc, result=result,
                     files=[Path(f) for f in files])


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
