"""solidshell: fabric drape with ANS solid-shell elements (Xie, Sze & Zhou, FEAD 106 (2015) 85-102)."""

from .errors import InputError, SolverError
from .material import Fabric, IsotropicShell
from .mesh import ShellMesh

__version__ = "0.1.0"

__all__ = ["ShellMesh", "Fabric", "IsotropicShell", "InputError", "SolverError", "__version__"]
