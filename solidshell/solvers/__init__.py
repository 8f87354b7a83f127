"""The solver registry: every solver kind by name, with its run function and its settings model.

``KINDS`` is the one list of solver kinds: the CLI's ``--solver`` choices, the scene schema's
``solver.kind`` and ``[solver.KIND]`` tables, the runner and the sweep spec all read it.  Each kind's
run function is ``fn(problem, settings, progress) -> SolveResult`` (solidshell.problem) and its
settings model a ``solidshell.settings.SettingsModel``; both are imported only when that kind is
asked for, so a static run never loads the explicit integrator and importing this module loads
neither (numba stays unloaded until a solver runs).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

from ..errors import InputError

__all__ = ["Kind", "KINDS", "kind", "dynamic", "get", "settings_model", "validate"]


@dataclass(frozen=True)
class Kind:
    """A solver kind: where its run function and its settings model live ("module:attribute"), and
    whether it integrates in time (``dynamic``: frames are times, adaptivity can run inside it)."""

    name: str
    run: str
    settings: str
    dynamic: bool

    @staticmethod
    def _attr(ref: str):
        mod, attr = ref.split(":")
        return getattr(importlib.import_module(mod), attr)

    def run_function(self):
        return self._attr(self.run)

    def settings_model(self):
        return self._attr(self.settings)


KINDS: dict[str, Kind] = {
    k.name: k
    for k in (
        Kind(
            "static", "solidshell.solvers.static.driver:run", "solidshell.solvers.static.settings:StaticSettings", False
        ),
        Kind(
            "explicit", "solidshell.solvers.explicit:run", "solidshell.solvers.explicit.settings:ExplicitSettings", True
        ),
        Kind(
            "relax", "solidshell.solvers.explicit:run_relax", "solidshell.solvers.explicit.settings:RelaxSettings", True
        ),
    )
}


def kind(name: str) -> Kind:
    """The registered kind ``name``; InputError (one line naming the choices) if there is none."""
    try:
        return KINDS[name]
    except KeyError:
        raise InputError(f"unknown solver {name!r}; choose one of: {', '.join(KINDS)}") from None


def dynamic(name: str) -> bool:
    """True when ``name`` is a registered kind that integrates in time ("none", a mesh-only run: False)."""
    return name in KINDS and KINDS[name].dynamic


def get(name: str):
    """The run function of solver kind ``name``."""
    return kind(name).run_function()


def settings_model(name: str):
    """The settings model (a SettingsModel subclass) of solver kind ``name``."""
    return kind(name).settings_model()


def validate(name: str, settings: dict | None, where: str | None = None):
    """Check a solver kind's settings before any work; returns the parsed settings model."""
    from ..settings import parse

    return parse(settings_model(name), settings, where or f"solver.{name}")
