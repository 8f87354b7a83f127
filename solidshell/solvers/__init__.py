"""Solvers by name.  Each entry is a function ``fn(problem, settings, progress) -> SolveResult``
(see solidshell.problem); ``settings`` is the scene's [solver] table with user overrides applied.
Modules are imported only when their solver is asked for, so a static run never loads the explicit
integrator and vice versa."""

from __future__ import annotations

import importlib

from ..errors import InputError

_ENTRIES = {
    "static": ("solidshell.solvers.static", "run"),
    "explicit": ("solidshell.solvers.explicit", "run"),
    "relax": ("solidshell.solvers.explicit", "run_relax"),
}

NAMES = tuple(_ENTRIES)


def get(name: str):
    """The solver function registered under ``name`` (static | explicit | relax)."""
    try:
        mod, fn = _ENTRIES[name]
    except KeyError:
        raise InputError(f"unknown solver {name!r}; choose one of: {', '.join(_ENTRIES)}") from None
    return getattr(importlib.import_module(mod), fn)
