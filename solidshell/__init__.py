"""solidshell: fabric drape with ANS solid-shell elements (Xie, Sze & Zhou, FEAD 106 (2015) 85-102).

Public face (DESIGN.md): ShellMesh, Fabric, IsotropicShell, Model, solve_static, run_scene,
build_problem.
Model (numba kernels), solvers and scene entry points are imported on first use, so ``import
solidshell`` -- and ``solidshell scenes`` / ``solidshell mesh`` -- stay light.
"""

from .errors import InputError, IOFailure, SolverError
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
    "build_problem",
    "InputError",
    "SolverError",
    "IOFailure",
    "__version__",
]

_LAZY = {
    "Model": "solidshell.model",
    "solve_static": "solidshell.solvers.static",
    "run_scene": "solidshell.run.driver",
    "build_problem": "solidshell.scenes.build",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'solidshell' has no attribute {name!r}")
