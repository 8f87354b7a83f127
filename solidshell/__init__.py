"""solidshell: fabric drape with ANS solid-shell elements (Xie, Sze & Zhou, FEAD 106 (2015) 85-102).

Public face (DESIGN.md; ``__all__``): ShellMesh, Fabric, IsotropicShell, Model, solve_static,
run_scene (-> RunOutput), build_problem (-> Problem), load_scene (-> Scene), available_scenes,
SolveResult, the errors (InputError, SolverError, IOFailure) and ``__version__``.
Everything but the errors is imported on first use (NumPy included), so ``import solidshell``
-- and ``solidshell scenes`` / ``solidshell mesh`` -- stay light, and ``solidshell run`` starts
its pictures' process (solidshell.render.server) before NumPy is loaded; ``dir(solidshell)``
lists them all the same.
"""

from typing import TYPE_CHECKING

from . import openmp
from .errors import InputError, IOFailure, SolverError

openmp.configure()  # before numba or MKL load the OpenMP runtime (solidshell/openmp.py)

if TYPE_CHECKING:  # the lazy names below, for type checkers
    from .material import Fabric, IsotropicShell
    from .mesh import ShellMesh

__version__ = "0.1.0"

__all__ = [
    "ShellMesh",
    "Fabric",
    "IsotropicShell",
    "Model",
    "solve_static",
    "run_scene",
    "RunOutput",
    "build_problem",
    "Problem",
    "SolveResult",
    "load_scene",
    "available_scenes",
    "Scene",
    "InputError",
    "SolverError",
    "IOFailure",
    "__version__",
]

# name -> (module, attribute there)
_LAZY = {
    "ShellMesh": ("solidshell.mesh", "ShellMesh"),
    "Fabric": ("solidshell.material", "Fabric"),
    "IsotropicShell": ("solidshell.material", "IsotropicShell"),
    "Model": ("solidshell.model", "Model"),
    "solve_static": ("solidshell.solvers.static", "solve_static"),
    "run_scene": ("solidshell.run.driver", "run_scene"),
    "RunOutput": ("solidshell.run.driver", "RunOutput"),
    "build_problem": ("solidshell.scenes.build", "build_problem"),
    "Problem": ("solidshell.problem", "Problem"),
    "SolveResult": ("solidshell.problem", "SolveResult"),
    "load_scene": ("solidshell.scenes", "load"),
    "available_scenes": ("solidshell.scenes", "available"),
    "Scene": ("solidshell.scenes", "Scene"),
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'solidshell' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
