"""A run's adaptive subdivision (paper §5): the scene's adapt settings, the true curves of its
curved boundaries, and the §5.5 driver (solidshell.adapt.driver.AdaptiveRun) built for the run."""

from __future__ import annotations

import numpy as np

from .. import solvers
from ..errors import InputError
from ..scenes import Scene
from ..scenes.build import build_problem
from .progress import _phase


def adapt_settings(scene: Scene, kind: str):
    """The scene's AdaptSettings when adaptivity is on (None when off); InputError when it is asked
    of a solver that cannot host it (§5.5: remeshing happens between the steps of a dynamic run)."""
    if not scene.adapt.get("enabled", False):
        return None
    from ..adapt.settings import parse_adapt

    adapt = parse_adapt(scene.adapt, f"{scene.source}: adapt")
    if not solvers.dynamic(kind):
        raise InputError(
            f"adaptive subdivision runs inside a dynamic run (--solver explicit or relax, "
            f"paper §5.5); the {kind} solver is not adaptive"
        )
    return adapt


def level0_mesh(scene: Scene, mesh):
    """The mesh an adaptive run starts from: ``mesh`` when given, else the scene's
    ``mesh.adaptive_level0`` or its density."""
    return mesh if mesh is not None else scene.mesh["adaptive_level0"] or scene.density


def prepare(sc: Scene, setup, adapt, kind: str, cb):
    """(the §5.5 driver, the summary's mesh name) of an adaptive run on the built level-0 mesh
    (``setup``: scenes.build.SceneSetup).  Building the background mesh checks it (quads only,
    memory) before anything is written."""
    run = _adaptive_run(sc, setup.mesh, setup.solver_settings, adapt, kind, cb)
    guard = f" + {adapt.guard_levels} guard" if adapt.guard_levels else ""
    return run, f"{setup.mesh_name} adaptive ({adapt.levels}{guard} levels)"


def boundary_curves(scene: Scene):
    """The true curves of a recipe's curved boundaries (circles about the origin), for placing new
    boundary nodes on them (§5.1); None for straight-sided sheets."""
    from ..adapt import circle_projector

    g = scene.geometry
    if scene.recipe == "disc_on_disc":
        return circle_projector((0.0, 0.0), (g["pedestal_diameter"] / 2.0, g["diameter"] / 2.0))
    if scene.recipe == "square_on_disc":
        return circle_projector((0.0, 0.0), g["pedestal_diameter"] / 2.0)
    return None


def _adaptive_run(sc: Scene, level0, settings: dict, adapt, kind: str, cb):
    """The §5.5 driver for this scene, built (background mesh and all) but not started."""
    from ..adapt.driver import AdaptiveRun
    from ..model import ElementConstants
    from ..solvers.explicit import Integrator, parse_settings

    s = dict(settings)
    restart = s.pop("restart", None)
    constants = ElementConstants()  # most elements survive a remesh: fold each one once

    def make_problem(mesh, coarse_quads=None):
        # coarse_quads: quads below the finest level, given "ans" membranes (adapt.coarse_membrane)
        membrane = (
            None if coarse_quads is None else np.where(coarse_quads, "ans", sc.model.get("membrane", "full")).tolist()
        )
        return build_problem(sc, mesh, membrane=membrane, constants=constants)

    return AdaptiveRun(
        level0,
        make_problem,
        Integrator,
        parse_settings(s, kind == "relax"),
        adapt,
        relax=kind == "relax",
        curves=boundary_curves(sc),
        progress=_phase(cb, 0.08, 0.9),
        restart=restart,
    )
