"""A run's summary (summary.json): what was run (:func:`describe_run`), the solved state and its drape
measures (:func:`record_state`, :func:`analyse`), the contact contract's measure (:func:`contact_check`:
``summary["penetration"]``), the runner's own warnings, and the closing
timings and warnings (:func:`close_summary`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import io as sio
from ..scenes import Scene, load


def pedestal_area(scene: Scene) -> float | None:
    """The area of the scene's pedestal top [cm^2] (None: no pedestal)."""
    p = scene.pedestal()
    if p is None:
        return None
    return p["size"] ** 2 if p["shape"] == "square" else np.pi * p["diameter"] ** 2 / 4.0


def _peak_memory_mb() -> float:
    """Peak resident memory of this process so far [MiB] (Linux reports ru_maxrss in KiB)."""
    import resource

    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)


def _supports(table: dict) -> dict:
    """[supports] as lists of node-set names ([supports.static] nested the same way)."""
    return {k: (_supports(v) if isinstance(v, dict) else list(v)) for k, v in table.items()}


def _material_summary(m) -> dict:
    return {
        "type": type(m).__name__,
        "name": m.name,
        "C_m": np.asarray(m.C_m).tolist(),
        "C_b": np.asarray(m.C_b).tolist(),
        "C_t": np.asarray(m.C_t).tolist(),
        "E_z": float(m.E_z),
        "thickness": float(m.thickness),
        "mass_per_area": float(m.mass_per_area),
        "weight_per_area": float(m.weight_per_area),
        "warp_angle_deg": float(np.degrees(m.warp_angle_rad)),
    }


def describe_run(
    run_id: str, sc: Scene, kind: str, settings: dict | None, setup, mesh_name: str, overrides: dict | None
) -> dict:
    """The summary of a run before it solves: the scene, mesh, solver settings, section, supports,
    contact, units and versions.  ``setup``: the scenes.build.SceneSetup of the run."""
    mesh = setup.mesh
    summary = {
        "run_id": run_id,
        "scene": sc.name,
        "title": sc.title,
        "paper_section": sc.paper_section,
        "scene_file": sc.source,
        "mesh": mesh_name,
        "recipe": sc.recipe,
        "geometry": {k: (str(v) if isinstance(v, Path) else v) for k, v in sc.geometry.items()},
        "solver": kind,
        "settings": settings,
        "counts": sio.mesh_counts(mesh, setup.fixed),
        "area": float(mesh.area()),
        "pedestal_area": pedestal_area(sc),
        "material": _material_summary(setup.material),
        "model": dict(sc.model),
        "supports": _supports(sc.supports),
        "contact": [dict(c) for c in sc.contact],
        "units": dict(sio.UNITS),
        "versions": sio.package_versions(),
        "converged": None,
        "interrupted": False,
        "message": "mesh only" if kind == "none" else "",
    }
    summary["total_weight"] = float(setup.material.weight_per_area * summary["area"])
    summary["overrides"] = dict(overrides or {})
    summary["scene_inputs"] = sc.summary()  # the resolved scene, to reproduce the run
    if setup.perturbed:
        summary["perturbation"] = dict(sc.perturbation)
    for key in ("checkpoint", "restart"):
        if settings and settings.get(key):
            summary[key] = str(settings[key])
    return summary


def record_state(summary: dict, sc: Scene, solved) -> list[str]:
    """Enter a solved run (driver.Solved) into its summary: the final mesh's counts, memory,
    convergence, the state's extent, the solver's info and the drape measures.  Returns the
    warnings: the solver's, then the runner's own about the state."""
    mesh, result, U = solved.mesh, solved.result, solved.U
    summary["counts"] = sio.mesh_counts(mesh, solved.fixed)  # an adaptive run's final mesh
    summary["area"] = float(mesh.area())
    summary["peak_memory_mb"] = _peak_memory_mb()
    info = dict(result.info or {})
    summary["converged"] = bool(result.converged)
    summary["message"] = str(result.message or "")
    summary["interrupted"] = info.get("status") == "interrupted"
    finite = bool(np.all(np.isfinite(U)))
    summary["finite"] = finite
    if finite:
        summary["max_displacement"] = float(np.max(np.linalg.norm(U[:, :3], axis=1)))
        summary["min_z"] = float(np.min(mesh.nodes[:, 2] + U[:, 2]))
    warnings = [str(w) for w in (info.pop("warnings", None) or [])]
    for k, v in info.items():
        if k in summary and (summary[k] == v or k in ("solver", "converged")):
            continue  # already said (the info repeats it)
        summary[k if k not in summary else f"solver_{k}"] = v
    summary["frames"] = len(result.frames or [])
    if finite:
        try:
            a = analyse(sc, mesh, U, solved.problem.model)
        except Exception as e:  # analysis must never lose a solved state
            summary["analysis_error"] = f"{type(e).__name__}: {e}"
        else:
            for k, v in a.items():
                summary.setdefault(k, v)
        warnings += contact_check(summary, sc, solved)
        warnings += layers_check(summary, solved)
    return warnings + _state_warnings(summary, info)


def layers_check(summary: dict, solved) -> list[str]:
    """Enter the sheet-against-itself measures (solidshell.layers.report: ``self_intersections``,
    ``min_layer_gap``, ``layer_pairs_close``) into the summary for a sheet of known thickness;
    returns their warnings."""
    h = (summary.get("material") or {}).get("thickness")
    if not isinstance(h, (int, float)) or not h > 0.0:
        return []
    from .. import layers

    try:
        entry = layers.report(solved.mesh, solved.U, float(h))
    except Exception as e:  # the check must never lose a solved state
        summary["layers_error"] = f"{type(e).__name__}: {e}"
        return [f"the self-intersection check failed ({type(e).__name__}: {e})"]
    summary.update(entry)
    return layers.warnings(entry)


def contact_tables(scene: Scene) -> list[dict]:
    """The scene's resolved contact tables, one per contact body of its problem (``Scene.bodies()``:
    the implied pedestal included)."""
    return [dict(c) for c in scene.bodies()]


def contact_check(summary: dict, sc: Scene, solved) -> list[str]:
    """Enter the contact contract's measure (solidshell.penetration.report: per body the deepest
    node and face point and the counts beyond ``contact.PENETRATION_TOL * h``) as
    ``summary["penetration"]`` (no key: the problem has no contact body); returns its warnings."""
    bodies = list(solved.problem.contact)
    if not bodies:
        return []
    from .. import penetration

    try:
        entry = penetration.report(solved.mesh, solved.U, bodies, contact_tables(sc), summary["material"]["thickness"])
    except Exception as e:  # the check must never lose a solved state
        summary["penetration_error"] = f"{type(e).__name__}: {e}"
        return [f"the contact penetration check failed ({type(e).__name__}: {e})"]
    summary["penetration"] = entry
    return penetration.warnings(entry)


def analyse(scene: Scene, mesh, U, model=None) -> dict:
    """Drape measures (analysis.drape_summary: drape coefficient, folds, outline) of the state U
    (N,6) on ``mesh`` for scenes with a pedestal or a sphere; the strip's tip position; with
    ``model``, the interpenetrated nodes (Section 4.3) for all.  The measures a run's summary
    holds, for a state computed elsewhere (verification/drape_states.py).  ``scene``: a Scene or
    anything scenes.load takes."""
    scene = load(scene)
    out = {}
    if model is not None:
        out["interpenetrated_nodes"] = int(np.count_nonzero(model.interpenetrated_nodes(U)))
    if "tip" in mesh.node_sets and len(mesh.node_sets["tip"]):
        # the strip's free end: mean deformed position of its nodes [cm] (Fig. 4 side view)
        tip = mesh.node_sets["tip"]
        out["tip_position"] = (mesh.nodes[tip] + U[tip, :3]).mean(0).tolist()
    ped = pedestal_area(scene)
    if ped is None and not any(c["type"] == "sphere" for c in scene.contact):
        return out
    from .. import analysis

    kw = {"pedestal_area": ped or 0.0}
    if ped is None:  # cloth on a sphere: the sheet is whole; measure about the sphere's axis
        c = next(c for c in scene.contact if c["type"] == "sphere")
        kw["center"] = (c["centre"][0], c["centre"][1])
    d = analysis.drape_summary(mesh, U, **kw)
    out["projected_boundary"] = d.pop("projected_boundary")
    out.update(d)
    return out


def _state_warnings(summary: dict, info: dict) -> list[str]:
    """The runner's own warnings about a solved state (one line each)."""
    out = []
    n_end = summary.get("interpenetrated_nodes")
    if n_end:
        out.append(
            f"{n_end} node(s) interpenetrated at the end (n_p . d_p < 0, Section 4.3): the "
            f"director is turned through the mid-surface there (the shell's two faces cross); refine "
            f"the mesh or check the result"
        )
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


def close_summary(summary: dict, timings: dict, warnings: list) -> np.ndarray | None:
    """The summary's closing entries: timings [s] and the warnings, in order, each once.  Takes
    the projected boundary out (it goes to its own file) and returns it (None: not a drape)."""
    summary["timings"] = {k: round(v, 4) for k, v in timings.items()}
    summary["warnings"] = list(dict.fromkeys(warnings))
    boundary = summary.pop("projected_boundary", None)
    return None if boundary is None else np.asarray(boundary, float)
