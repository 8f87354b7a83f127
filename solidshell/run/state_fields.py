"""The fields written with a run's states (solidshell.fields): the final state's and each series
frame's, on the mesh of that frame, with the sheet's clamped, unmeshed parts as patches.

A fixed-mesh run's frames share the solver's problem; an adaptive run's frames lie on the active
meshes of their times, each posed again with ``build_problem`` (its quads' membranes from the
mesh's ``assumed_membrane`` tag, as the adaptive driver posed it)."""

from __future__ import annotations

import numpy as np

from .. import fields, solvers


def load_factor(kind: str, t: float) -> float:
    """The load factor of a frame: a static run's frame parameter, 1 for the dynamic solvers
    (their loads are applied whole)."""
    return 1.0 if solvers.dynamic(kind) else float(t)


def final_load_factor(kind: str, result) -> float:
    """The final state's load factor: the last converged load step's of a static run, else 1."""
    frames = getattr(result, "frames", None) or []
    return load_factor(kind, frames[-1][0]) if (frames and not solvers.dynamic(kind)) else 1.0


def of_problem(problem, U, fixed, lam: float = 1.0):
    """(fields, patches) for :func:`solidshell.io.write_mesh_file` of the state U of ``problem``."""
    return fields.state_fields(problem, U, lam), fields.clamped_patches(problem.model.mesh, fixed)


def series_fields(sc, kind: str, solved):
    """fields_of(t, mesh, U) -> (fields, patches) for the frames of a solved run; None without a
    problem (a mesh-only run) or with a model of the user's own (interfaces.ExplicitModel: no
    element blocks to read strains from)."""
    if solved.problem is None or not hasattr(solved.problem.model, "blocks"):
        return None
    from ..model import ElementConstants
    from ..scenes.build import build_problem, support_mask

    cache: dict[int, tuple] = {id(solved.mesh): (solved.problem, solved.fixed)}
    constants = ElementConstants()  # an adaptive run's frames share most elements: fold each once

    def fields_of(t, mesh, U):
        if id(mesh) not in cache:
            tags = getattr(mesh, "cell_tags", None) or {}
            ans = tags.get("assumed_membrane")
            membrane = None
            if ans is not None:
                base = sc.model.get("membrane", "full")
                membrane = np.where(np.asarray(ans)[: len(mesh.quads)] > 0, "ans", base).tolist()
            fixed = support_mask(sc, mesh, kind)
            cache[id(mesh)] = (build_problem(sc, mesh, fixed, membrane=membrane, constants=constants, kind=kind), fixed)
        problem, fixed = cache[id(mesh)]
        lam = load_factor(kind, t)
        # the final state is written first (result.*, deformed.vtu) and again as the series' last
        # frame, after the earlier frames: its fields are kept (pinned) and computed once
        for key, hit in kept:
            if key == (id(mesh), lam) and np.array_equal(hit[0], U):
                return hit[1]
        out = of_problem(problem, U, fixed, lam)
        entry = ((id(mesh), lam), (np.array(U, copy=True), out))
        kept[:] = [kept[0], entry] if kept else [entry]
        return out

    kept: list[tuple] = []  # [the first state asked for (the final one), the latest other]
    return fields_of
