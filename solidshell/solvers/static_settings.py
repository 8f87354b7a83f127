"""Typed settings of the static solver (``[solver.static]`` of a scene, ``--set solver.static.KEY``).

Every setting of :func:`solidshell.solvers.static.solve_static` that a scene can set, with its type,
range and default (the defaults are the solver's own).  ``solidshell.solvers.settings_model("static")``
returns :class:`StaticSettings`; the static ``run`` parses its settings with it, so a bad value is one
InputError line naming the key before any work starts.
"""

from __future__ import annotations

import math
from typing import Literal, Optional, Union

from pydantic import Field, field_validator, model_validator

from ..settings import Finite, SettingsModel, StateArray
from .linear import FACTORIZATIONS

__all__ = ["StaticSettings"]

_METHODS = ("newton", "paper", "arclength")      # = static.METHODS (kept import-free: no numba here)


class StaticSettings(SettingsModel):
    """Settings of the static solver; units are the scene's (length for L_f, max_step, ...)."""

    method: Literal["newton", "paper", "arclength"] = "newton"
    tol: Finite = Field(1e-8, gt=0.0, lt=1.0, description="relative residual tolerance")
    energy_tol: Finite = Field(1e-12, gt=0.0, lt=1.0, description="energy-norm tolerance (ratio)")
    disp_tol: Finite = Field(1e-10, gt=0.0, lt=1.0,
                             description="Newton correction / displacement (positive-definite K_t)")
    max_iter: Optional[int] = Field(None, ge=1, description="iterations per load step")
    load_steps: Optional[int] = Field(None, ge=1, description="n equal load steps 1/n ... 1")
    load_factors: Optional[list[Finite]] = Field(None, min_length=1)
    c: Finite = Field(1e-2, gt=0.0, description="the paper's multiplier constant (Eq. 18)")
    L_f: Optional[Finite] = Field(None, gt=0.0, description="free-hanging length [length]")
    max_step: Optional[Finite] = Field(None, gt=0.0, description="cap on max|dD| per update [length]")
    predictor: bool = True
    increment: Finite = Field(1.0, gt=0.0, le=1.0)
    min_increment: Finite = Field(1e-6, gt=0.0, le=1.0)
    max_cutbacks: int = Field(8, ge=0)
    line_search: Literal["trust", "armijo", "none"] = "trust"
    trust_radius: Finite = Field(0.02, gt=0.0)
    curvilinear: bool = False
    arc_length_initial: Finite = Field(0.1, gt=0.0)
    max_arc_step: Optional[Finite] = Field(None, gt=0.0,
                                           description="largest arc-length load step, fraction of the target")
    max_arc_steps: int = Field(500, ge=1)
    check_stability: bool = True
    eig_max_dofs: int = Field(60000, ge=0)
    max_saddle_escapes: int = Field(5, ge=0, description="saddles left before giving up")
    saddle_step: Finite = Field(0.05, gt=0.0, description="largest escape step, fraction of L_f")
    contact_stiffness: Optional[Finite] = Field(None, gt=0.0)
    factorization: Literal[FACTORIZATIONS] = "auto"
    pcg_iterations: int = Field(
        0, ge=0, description="CG iterations preconditioned by the last factor before a new "
        "factorisation (0: exact Newton steps; unset: 6 on a sequenced fine mesh, else 0)")
    sequence: Union[Literal["auto"], int] = Field(
        0, description="coarse meshes solved first (solvers/sequence.py): 'auto' or a count >= 0")
    U0: StateArray = None     # (N, 6) starting state [length] (e.g. a scene's [perturbation])

    @field_validator("sequence", mode="before")
    @classmethod
    def _sequence(cls, v):
        if v != "auto" and (isinstance(v, bool) or not isinstance(v, int) or v < 0):
            raise ValueError("must be 'auto' or an integer >= 0")
        return v

    @field_validator("load_factors")
    @classmethod
    def _factors(cls, v):
        if v is not None and not all(math.isfinite(x) for x in v):
            raise ValueError("must be a non-empty list of finite numbers")
        return v

    @model_validator(mode="after")
    def _one_of_steps(self):
        if self.load_steps is not None and self.load_factors is not None:
            raise ValueError("give load_steps or load_factors, not both")
        return self

    def solver_kwargs(self) -> dict:
        """Keyword arguments of solve_static (load_steps turned into load_factors)."""
        d = self.as_dict()
        d.pop("sequence")               # a run-level setting (solvers/sequence.py)
        steps = d.pop("load_steps")
        if steps is not None:
            d["load_factors"] = [(i + 1) / steps for i in range(steps)]
        return d
