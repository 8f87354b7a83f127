"""Typed settings of the static solver: the one place each option and its default is written.

``[solver.static]`` of a scene, ``--set solver.static.KEY``, the options of
:func:`solidshell.solvers.static.solve_static` and the settings dict of the registry entry
``run`` are all this model; a bad value or an unknown key is one InputError line naming it before
any work starts (``solidshell.solvers.settings_model("static")`` returns :class:`StaticSettings`).
A default that depends on the mesh or the method (``max_iter``, ``L_f``, ``max_step``,
``contact_stiffness``) is ``None`` here and resolved where the mesh is known
(:meth:`StaticSettings.level`, ``system.System``).  Imports neither numba nor scipy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Optional, Union, get_args

from pydantic import Field, field_validator, model_validator

from ...contact_augment import DEFAULT_UPDATES
from ...contact_faces import DEFAULT_FACE_POINTS, MAX_FACE_POINTS
from ...settings import Finite, SettingsModel, StateArray
from ..linear import FACTORIZATIONS

__all__ = ["METHODS", "RUN_SETTINGS", "LevelOptions", "StaticSettings"]

Method = Literal["newton", "paper", "arclength"]
METHODS = get_args(Method)

RUN_SETTINGS = ("sequence",)
"""Settings of a scene run rather than of one solve (solvers/sequence.py reads them)."""


class StaticSettings(SettingsModel):
    """Settings of the static solver; units are the scene's (length for L_f, max_step, ...)."""

    method: Method = Field(
        "newton",
        description="'newton' (trust-region Newton on the potential), 'paper' (Eqs. 16-18) or 'arclength' (Crisfield)",
    )
    tol: Finite = Field(1e-8, gt=0.0, lt=1.0, description="relative residual tolerance")
    energy_tol: Finite = Field(1e-12, gt=0.0, lt=1.0, description="energy norm of the last update over the first's")
    disp_tol: Finite = Field(
        1e-10,
        gt=0.0,
        lt=1.0,
        description="newton also stops when the Newton correction of a "
        "positive-definite, unshifted K_t is below disp_tol max|D| (scale-free)",
    )
    max_iter: Optional[int] = Field(
        None,
        ge=1,
        description="iterations per load step (None: 1000 for newton and arclength -- "
        "newton then cuts the step back --, 5000 for paper; well above what the trust-region "
        "Newton needs on the paper's drapes, since a cap near that count cuts back a converging "
        "run, docs/solvers.md section 8)",
    )
    load_steps: Optional[int] = Field(None, ge=1, description="n equal load steps 1/n ... 1")
    load_factors: Optional[list[Finite]] = Field(
        None,
        min_length=1,
        description="increasing load factors (None: [1.0]); each is a converged "
        "state of the path; loads and prescribed values are scaled by the factor; for arclength "
        "only the last one (the target) matters",
    )
    c: Finite = Field(1e-2, gt=0.0, description="the paper's multiplier constant (Eq. 18, 1e-3..1e-2)")
    L_f: Optional[Finite] = Field(
        None,
        gt=0.0,
        description="free-hanging length [length] (None: the "
        "largest distance from a free node to the nearest fixed one)",
    )
    max_step: Optional[Finite] = Field(None, gt=0.0, description="cap on max|dD| per update [length] (None: L_f / 2)")
    predictor: bool = Field(
        True, description="newton: predict the start of every new load level (tangent or path extrapolation)"
    )
    increment: Finite = Field(
        1.0, gt=0.0, le=1.0, description="newton: first automatic sub-step, fraction of the final load factor"
    )
    min_increment: Finite = Field(1e-6, gt=0.0, le=1.0, description="newton: smallest automatic sub-step (fraction)")
    max_cutbacks: int = Field(8, ge=0, description="newton: consecutive cut-backs of a failed sub-step")
    line_search: Literal["trust", "armijo", "none"] = Field(
        "trust", description="newton's globalisation: trust region, Armijo backtracking or none"
    )
    trust_radius: Finite = Field(0.02, gt=0.0, description="first trust radius, fraction of L_f")
    curvilinear: bool = Field(
        False,
        description="newton: second-order (geodesic acceleration) "
        "correction of the step; did not pay (docs/solvers.md section 2)",
    )
    arc_length_initial: Finite = Field(0.1, gt=0.0, description="first arc-length step, fraction of the target")
    max_arc_step: Optional[Finite] = Field(
        None,
        gt=0.0,
        description="largest arc length, fraction of the linear path length to the "
        "target (None: unlimited; 0.02 draws a load-deflection curve with >= 50 points)",
    )
    max_arc_steps: int = Field(500, ge=1, description="arc-length steps at most")
    check_stability: bool = Field(
        True, description="leave saddles and report positive_definite and min_tangent_eigenvalue of the final state"
    )
    eig_max_dofs: int = Field(60000, ge=0, description="largest free-dof count for the eigenvalue report")
    max_saddle_escapes: int = Field(5, ge=0, description="saddles left before giving up")
    saddle_step: Finite = Field(0.05, gt=0.0, description="largest escape step, fraction of L_f")
    contact_stiffness: Optional[Finite] = Field(
        None, gt=0.0, description="penalty [force/length] (None: 1e4 x heaviest nodal dead load / h, system.py)"
    )
    contact_face_points: int = Field(
        DEFAULT_FACE_POINTS,
        ge=0,
        le=MAX_FACE_POINTS,
        description="contact points per element edge inside each element (contact_faces.py; 0: nodes only)",
    )
    self_contact: bool = Field(
        False,
        description="the barrier between the sheet's layers, steps cut by continuous collision detection "
        "(contact_self.py; method 'newton' only)",
    )
    contact_augment: int = Field(
        DEFAULT_UPDATES,
        ge=0,
        description="augmented-Lagrangian updates of the contact after the solve (contact_augment.py; 0: plain penalty)",
    )
    factorization: Literal[FACTORIZATIONS] = Field(
        "auto",
        description="'auto' (PARDISO where Intel MKL loads and from linear.PARDISO_MIN_DOFS "
        "free dofs, else CHOLMOD), 'cholmod', 'pardiso' or 'superlu' (LDL^T throughout, 3-5 times "
        "slower); info['factorization'] names the one used",
    )
    pcg_iterations: int = Field(
        0,
        ge=0,
        description="CG iterations preconditioned by the last factor before a new "
        "factorisation (0: exact Newton steps; unset: 6 on a sequenced fine mesh, else 0)",
    )
    sequence: Union[Literal["auto"], int] = Field(
        0, description="coarse meshes solved first (solvers/sequence.py): 'auto' or a count >= 0"
    )
    U0: StateArray = None  # (N, 6) starting state [length] (e.g. a scene's [perturbation])

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

    def factors(self) -> list[float]:
        """The load factors to reach in turn: ``load_factors``, n equal steps 1/n ... 1, or [1.0]."""
        if self.load_steps is not None:
            return [(i + 1) / self.load_steps for i in range(self.load_steps)]
        return [1.0] if self.load_factors is None else list(self.load_factors)

    def level(self, L_f: float) -> LevelOptions:
        """The options of one load level with the free-hanging length ``L_f`` [length] resolved."""
        return LevelOptions(
            tol=self.tol,
            energy_tol=self.energy_tol,
            disp_tol=self.disp_tol,
            max_iter=self.max_iter if self.max_iter is not None else (5000 if self.method == "paper" else 1000),
            c=self.c,
            L_f=L_f,
            max_step=self.max_step if self.max_step is not None else 0.5 * L_f,
            curvilinear=self.curvilinear,
            line_search=self.line_search,
            radius0=self.trust_radius * L_f,
            radius_min=1e-9 * L_f,
            pcg_iterations=self.pcg_iterations,
        )


@dataclass(frozen=True)
class LevelOptions:
    """What a load level (newton.newton_level, paper.paper_level, arclength) reads: the settings
    with their lengths in the mesh's unit (``radius0`` the first trust radius, ``radius_min`` the
    smallest, 1e-9 L_f)."""

    tol: float
    energy_tol: float
    disp_tol: float
    max_iter: int
    c: float
    L_f: float
    max_step: float
    curvilinear: bool
    line_search: str
    radius0: float
    radius_min: float
    pcg_iterations: int
