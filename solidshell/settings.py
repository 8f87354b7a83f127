"""Typed solver settings: one declarative schema per solver kind, checked once before any work.

Each solver declares its settings as a pydantic model (a frozen ``SettingsModel`` subclass) next to
the solver that reads them; :func:`parse` turns a plain dict (a scene file's ``[solver.KIND]``
table merged with ``--set`` overrides) into that model or raises one :class:`InputError` line that
names the offending key, what it got and what it accepts.  Unknown keys are refused by name.

Which model belongs to which solver kind is the solver registry's (``solidshell.solvers.KINDS``).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Optional, TypeVar

import numpy as np
from pydantic import AfterValidator, BaseModel, ConfigDict, ValidationError

from .errors import InputError

__all__ = ["SettingsModel", "parse", "Finite", "StateArray"]


def _finite(x: float) -> float:
    if not math.isfinite(x):
        raise ValueError("must be finite")
    return x


Finite = Annotated[float, AfterValidator(_finite)]
"""A float that must be finite (use with pydantic's Field(gt=..., ge=...) for ranges)."""


def _state_array(v: Any) -> Optional[np.ndarray]:
    """A U0 / V0 value: None, or numbers reshapeable to (N, 6) (one row of 6 dofs per node), finite."""
    if v is None:
        return None
    if isinstance(v, (str, bytes, bool)) or np.isscalar(v) and not isinstance(v, (int, float)):
        raise ValueError("must be an array of numbers, 6 per node ((N, 6) dofs)")
    try:
        a = np.array(v, dtype=float)
    except (TypeError, ValueError):
        raise ValueError("must be an array of numbers, 6 per node ((N, 6) dofs)") from None
    if a.size == 0 or a.size % 6:
        raise ValueError(f"must hold 6 numbers per node ((N, 6) dofs), got {a.size} numbers")
    if not np.all(np.isfinite(a)):
        raise ValueError("must be finite")
    a = a.reshape(-1, 6)
    a.flags.writeable = False
    return a


StateArray = Annotated[Any, AfterValidator(_state_array)]
"""A solver state array (U0, V0): None or (N, 6) finite numbers, read-only once parsed."""


class SettingsModel(BaseModel):
    """Base of every solver's settings: frozen, unknown keys refused, strict-ish numbers (a string
    "abc" is refused; "1e-3" from a command line is accepted as 1e-3 by pydantic's lax mode)."""

    model_config = ConfigDict(extra="forbid", frozen=True, arbitrary_types_allowed=True, validate_default=True)

    def as_dict(self) -> dict:
        """The settings as a plain dict (every key, defaults filled in)."""
        return {k: getattr(self, k) for k in type(self).model_fields}


M = TypeVar("M", bound=SettingsModel)


def _one_line(exc: ValidationError, where: str, model: type[SettingsModel]) -> str:
    parts = []
    for e in exc.errors():
        key = ".".join(str(p) for p in e.get("loc", ()))
        msg = e.get("msg", "invalid").replace("Value error, ", "")
        if not key:  # a rule across settings (model validator): its own words
            parts.append(msg)
            continue
        if e.get("type") == "extra_forbidden":
            known = ", ".join(sorted(model.model_fields))
            parts.append(f"unknown setting {key!r} (known: {known})")
            continue
        got = e.get("input")
        got_s = repr(got) if not hasattr(got, "shape") else f"array of shape {got.shape}"
        parts.append(f"setting {key} = {got_s[:60]}: {msg}")
    return f"{where}: " + "; ".join(parts)


def parse(model: type[M], settings: dict | None, where: str = "settings", *, explain=_one_line) -> M:
    """``model`` built from ``settings`` (None: all defaults); InputError (one line) if invalid.
    ``explain(exc, where, model)`` words that line (the scene schema names file and dotted key)."""
    if isinstance(settings, model):
        return settings
    try:
        return model.model_validate(dict(settings or {}))
    except ValidationError as exc:
        raise InputError(explain(exc, where, model)) from None
