"""Settings of the explicit solver (Eq. 23, Section 4.1) and of dynamic relaxation (Section 4.2).

Two frozen pydantic models on :class:`solidshell.settings.SettingsModel`, parsed and checked once
before any work: every value typed and range-checked, unknown keys refused by name.  Units: times
in seconds, frequencies (alpha) in 1/s, everything else dimensionless or a count of steps.  The
defaults are those of the solver since its first version (docs/explicit.md lists what each means).
"""

from __future__ import annotations

import os
from typing import Annotated, Any, Literal, Optional

import numpy as np
from pydantic import AfterValidator, BeforeValidator, Field, ValidationInfo, field_validator, model_validator

from ...contact_augment import DEFAULT_UPDATES
from ...contact_faces import DEFAULT_FACE_POINTS, MAX_FACE_POINTS
from ...errors import InputError
from ...settings import Finite, SettingsModel, StateArray, parse

__all__ = [
    "ExplicitSettings",
    "RelaxSettings",
    "parse_settings",
    "RUN_KEYS",
    "RELAX_KEYS",
    "RESTART_NEUTRAL",
    "RELAX_PRESETS",
]

Pos = Annotated[Finite, Field(gt=0)]
NonNeg = Annotated[Finite, Field(ge=0)]
PosInt = Annotated[int, Field(gt=0)]
NonNegInt = Annotated[int, Field(ge=0)]


def _path(v: Any) -> Optional[str]:
    """A checkpoint / restart path: a string or os.PathLike, not a number."""
    if v is None:
        return None
    if not isinstance(v, (str, os.PathLike)):
        raise ValueError("must be a file path (a string), not a number")
    s = os.fspath(v)
    if not isinstance(s, str) or not s.strip():
        raise ValueError("must be a non-empty file path")
    return s


def _times(v: Any) -> Any:
    return [float(x) for x in np.ravel(v)] if isinstance(v, np.ndarray) else v


PathStr = Annotated[Any, AfterValidator(_path)]


FIRE_ALPHA_START = 0.1
"""FIRE's velocity mixing a after a freeze (Bitzek et al. 2006): RelaxSettings.fire_alpha_start's
default, and the (unused) state.fire_a of an explicit run, which has no FIRE settings."""


class _Common(SettingsModel):
    """Settings shared by run (explicit) and run_relax."""

    dt: Optional[Pos] = None  # [s]; default safety x the critical step
    allow_unstable: bool = False  # only for stability studies
    safety: Pos = 0.9  # dt = safety x dt_crit; < 1 unless allow_unstable
    allow_reduce: bool = False  # a dt above dt_crit is reduced (else refused)
    alpha: NonNeg = 5.0  # [1/s] Rayleigh mass-proportional damping, Eq. (20)
    mass_scaling: Pos = 1.0
    mass_scaling_mode: Literal["uniform", "director"] = "uniform"
    sample_every: Optional[PosInt] = None  # steps between energy samples
    U0: StateArray = None  # (N, 6) initial displacements
    V0: StateArray = None  # (N, 6) initial velocities
    critical_time_step: Optional[Pos] = None  # [s]: skip the estimate
    critical_step_method: Literal["lanczos", "power", "tangent"] = "lanczos"
    critical_step_tol: Pos = 1e-6
    contact_penalty_factor: Pos = 0.1
    contact_face_points: Annotated[int, Field(ge=0, le=MAX_FACE_POINTS)] = DEFAULT_FACE_POINTS  # per element edge
    contact_rims: bool = False  # the bodies' sharp edges against the faces (contact_rims.py; opt-in)
    checkpoint: PathStr = None
    checkpoint_every: Optional[PosInt] = None  # steps; default every checkpoint_wall seconds
    checkpoint_wall: Pos = 60.0  # [s] of wall time
    restart: PathStr = None
    max_wall_time: Optional[Pos] = None  # [s]
    frame_every: Optional[PosInt] = None  # steps
    frame_interval: Optional[NonNeg] = None  # [s] simulated; relax 0.05, explicit 0 (off)
    max_frames: PosInt = 100
    progress_every: Optional[PosInt] = None  # steps (the callback is also called every ~0.5 s)
    threads: Optional[PosInt] = None
    max_energy_error: Pos = 0.5
    recheck_every: NonNegInt = 10000  # steps; 0 = never
    friction_stiffness: Pos = 1.0  # k_t / k

    @field_validator("safety")
    @classmethod
    def _stable(cls, v: float, info: ValidationInfo) -> float:
        if v >= 1.0 and not info.data.get("allow_unstable", False):
            raise ValueError("must be below 1 (the step would reach the stability limit) unless allow_unstable = true")
        return v

    @property
    def relax(self) -> bool:
        return False


class ExplicitSettings(_Common):
    """Settings of ``explicit.run``: t_end [s] is required."""

    t_end: Optional[Pos] = None
    snapshots: Annotated[Optional[list[NonNeg]], BeforeValidator(_times)] = None  # [s]

    @field_validator("t_end")
    @classmethod
    def _needed(cls, v):
        if v is None:
            raise ValueError("the explicit solver needs t_end [s] (the simulated time)")
        return v


RELAX_PRESETS = {
    # Section 4.2 exactly: Rayleigh mass damping alpha = 5 1/s, every nodal mass x100 (weight unchanged)
    "paper": {"damping": "rayleigh", "alpha": 5.0, "mass_scaling": 100.0, "mass_scaling_mode": "uniform"},
    # the scenes' default: FIRE with only the director masses x100 -- past x100 the thickness mode no
    # longer limits the step and more director inertia slows the slowest drape mode (docs/explicit.md,
    # "Relaxation": sqrt(kappa) 2571 against 20620 for the paper's masses on square-pedestal 24x8x4)
    "fast": {"damping": "fire", "mass_scaling": 100.0, "mass_scaling_mode": "director"},
}
"""preset name -> the relaxation settings it stands for (keys given alongside a preset win)."""


class RelaxSettings(_Common):
    """Settings of ``explicit.run_relax`` (dynamic relaxation, Section 4.2).  ``preset`` fills the
    keys of RELAX_PRESETS[preset] that are not given; the bare defaults are the paper's."""

    preset: Optional[Literal[tuple(RELAX_PRESETS)]] = None
    mass_scaling: Pos = 100.0
    damping: Literal["rayleigh", "kinetic", "fire", "modal"] = "rayleigh"
    # FIRE (damping = "fire"; Bitzek et al. 2006, their defaults; dt_max = the scheme's stable step)
    fire_alpha_start: Annotated[Finite, Field(gt=0, lt=1)] = FIRE_ALPHA_START  # velocity mixing a after a freeze
    fire_f_alpha: Annotated[Finite, Field(gt=0, le=1)] = 0.99  # a <- f_alpha a while P >= 0
    fire_f_inc: Annotated[Finite, Field(ge=1)] = 1.1  # dt <- f_inc dt while P >= 0
    fire_f_dec: Annotated[Finite, Field(gt=0, le=1)] = 0.5  # dt <- f_dec dt at a freeze
    fire_n_min: NonNegInt = 5  # steps with P >= 0 before dt grows
    fire_dt_min: Annotated[Finite, Field(gt=0, le=1)] = 0.02  # floor of dt / dt_max
    # modal damping (damping = "modal"): alpha = 2 zeta omega_min of M^-1 K at the current state
    modal_zeta: Pos = 1.0  # damping ratio of the slowest mode (1: critical)
    modal_every: PosInt = 2000  # steps between estimates of omega_min
    tol_kinetic: Pos = 1e-6  # E_kin / W_ext
    tol_residual: Pos = 1e-3  # |P - F + C|_free / |P|_free
    check_every: PosInt = 100  # steps between steady-state tests
    # augmented-Lagrangian updates of the contact at steady states (contact_augment.py; 0: plain penalty)
    contact_augment: NonNegInt = DEFAULT_UPDATES
    t_max: Pos = 60.0  # [s] simulated
    max_steps: Optional[PosInt] = None

    @model_validator(mode="before")
    @classmethod
    def _preset(cls, data: Any) -> Any:
        if isinstance(data, dict) and data.get("preset") is not None:
            name = data["preset"]
            if name not in RELAX_PRESETS:
                return data  # the field's own check names the choices
            data = {**RELAX_PRESETS[name], **data}
        return data

    @property
    def relax(self) -> bool:
        return True


RUN_KEYS = frozenset(ExplicitSettings.model_fields)
RELAX_KEYS = frozenset(RelaxSettings.model_fields)
RESTART_NEUTRAL = frozenset(
    {"checkpoint", "checkpoint_every", "checkpoint_wall", "restart", "progress_every", "max_wall_time", "threads"}
)
"""Settings that do not shape the computed run (a restart may change them)."""


def parse_settings(settings, relax: bool):
    """The settings model of run (relax=False) or run_relax; InputError (one line) if invalid."""
    model = RelaxSettings if relax else ExplicitSettings
    if isinstance(settings, model):
        return settings
    d = dict(settings or {})
    name = "relax" if relax else "explicit"
    unknown = sorted(str(k) for k in d if k not in model.model_fields)
    if unknown:
        raise InputError(
            f"unknown {name} setting(s): {', '.join(unknown)}; known: {', '.join(sorted(model.model_fields))}"
        )
    return parse(model, d, f"solver.{name}")
