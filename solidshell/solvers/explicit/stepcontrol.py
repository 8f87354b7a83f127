"""Critical step of Eq. (23): the start estimate, the re-check at the current state, the reduction.

omega_max of the sheet comes from matrix-free Lanczos on M^-1 K (``..timestep``), after mass scaling;
the penalty springs (normal k and, with friction, tangential k_t) are combined with it
(``contact.combined_critical_time_step``), and dt_crit = (2/omega)(sqrt(1 + xi^2) - xi), xi =
alpha / (2 omega).  Times in seconds, frequencies in rad/s.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...contact import combined_critical_time_step, penalty_stiffness
from ...contact_self_penalty import BUDGET_PAIRS, SELF_SHARE
from ...errors import InputError
from ...interfaces import ContactBody, ExplicitModel
from ...model import Model
from ..timestep import critical_time_step, estimate_omega_max


@dataclass(frozen=True)
class Dynamics:
    """What the critical-step estimates need of one problem."""

    model: ExplicitModel  # its tangent serves method="tangent" (a library Model's only)
    M: np.ndarray  # (N,6) lumped masses after mass scaling
    free_mask: np.ndarray  # (N,6) bool, True on the free dofs
    bodies: list[ContactBody]  # the contact bodies (their penalty springs)
    n_fric: int  # how many of them have friction (their stick springs)
    force: Callable | None = None  # U (N,6) -> internal force to differentiate (None: model.internal_force)
    faces: Any = None  # contact_faces.FacePoints of the mesh (None: contact on the nodes only)
    self_contact: bool = False  # the sheet against itself (contact_self_penalty.py)
    rims: Any = None  # contact_rims.Rims: the bodies' sharp edges against the faces (None: none)


@dataclass
class StepLimit:
    """The critical step of one problem at one state."""

    omega_el: float  # highest frequency of the sheet alone [rad/s]
    omega: float  # with the penalty springs
    dt_crit: float  # [s]
    method: str  # lanczos | power | tangent | given
    k_pen: np.ndarray | None  # (N,) normal penalty stiffness, None without contact
    k_max: np.ndarray | None  # (N,) largest contact Hessian eigenvalue per node
    k_t: np.ndarray | None  # (N,) tangential stick stiffness, None without friction
    k_self: np.ndarray | None = None  # (N,) a self-contact pair's penalty per node, None without
    n_evals: int = 0  # force evaluations spent on the estimate
    seconds: float = 0.0  # wall time of the estimate
    mode: np.ndarray | None = None  # the top mode (warm start of the re-checks)


WARM_TOL = 1e-4
"""Relative tolerance of omega^2 in the estimates warm-started from a known top mode (the mid-run
re-checks, the re-estimate on a new mesh): omega within 5e-5, far inside the step's safety factor."""


def omega_sheet(model, M, free_mask, D, s, force=None, v0=None, difference="central", tol=None):
    """(omega_el, method, force evaluations, mode) at the flat state D: Lanczos (or the method
    asked), or 2 / critical_time_step when the user gave it.  ``force``: the internal force U (N,6)
    -> F to differentiate (default model.internal_force; the integrator passes its fused lane
    kernel, the same force to round-off at a third of the cost); ``v0``: a start vector, e.g. the
    previous mesh's top mode carried over; ``difference``: the directional derivative's
    difference (timestep.estimate_omega_max: "forward" halves the force evaluations); ``tol``:
    instead of the settings' critical_step_tol (WARM_TOL for a warm start)."""
    if s.critical_time_step is not None:
        return 2.0 / s.critical_time_step, "given", 0, None
    try:
        est = estimate_omega_max(
            force or model.internal_force,
            M,
            free_mask,
            D.reshape(M.shape),
            method=s.critical_step_method,
            tol=tol or s.critical_step_tol,
            tangent=model.tangent if isinstance(model, Model) else None,
            v0=v0,
            difference=difference,
        )
    except ValueError as exc:
        raise InputError(f"cannot estimate the critical time step: {exc}") from None
    return est.omega_max, s.critical_step_method, est.n_force_evals, est.mode


def limit(omega_el, method, dyn: Dynamics, s, alpha, n_evals=0, seconds=0.0, mode=None) -> StepLimit:
    """Combine the sheet's omega_el with the penalty springs of ``dyn.bodies`` and of the sheet's
    self-contact into a StepLimit."""
    M, bodies, n_fric = dyn.M, dyn.bodies, dyn.n_fric
    k_pen = k_max = k_t = k_self = None
    omega = omega_el
    if bodies:
        k_pen = penalty_stiffness(M[:, 0], omega_el, s.contact_penalty_factor)
        # the contact Hessian of a node has eigenvalues k (normal) and k_t (tangential, friction);
        # the face points add their row sums to the normal one (contact_faces.py).  The stick
        # springs sit on the nodes and take the normal stiffness a node has when its faces lie flat
        # on the body (its own and the grid points' share): then normal and tangential springs ring
        # in step and a load inside the Coulomb cone stays inside it while they ring
        k_n = k_pen if dyn.faces is None else k_pen + dyn.faces.node_stiffness(dyn.faces.stiffness(k_pen))
        k_max = np.maximum(k_n, s.friction_stiffness * k_n) if n_fric else k_n
        if dyn.rims is not None:  # normal springs only: the stick springs stay the faces' (contact_rims.py)
            k_max = k_max + dyn.rims.node_stiffness(dyn.rims.stiffness(dyn.faces.stiffness(k_pen)))
        omega = 2.0 / combined_critical_time_step(omega_el, k_max, M[:, 0])
        if n_fric:
            k_t = s.friction_stiffness * k_n
    if dyn.self_contact:
        # a pair's spring is SELF_SHARE of a body's; a node budgets BUDGET_PAIRS of them, one body's
        # worth (contact_self_penalty.py)
        k_body = penalty_stiffness(M[:, 0], omega_el, s.contact_penalty_factor)
        k_self = SELF_SHARE * k_body
        k_max = BUDGET_PAIRS * k_self + (k_max if k_max is not None else 0.0)
        omega = 2.0 / combined_critical_time_step(omega_el, k_max, M[:, 0])
    return StepLimit(
        omega_el, omega, critical_time_step(omega, alpha), method, k_pen, k_max, k_t, k_self, n_evals, seconds, mode
    )


def estimate(dyn: Dynamics, D, s, alpha, v0=None, difference="central", tol=None) -> StepLimit:
    """The critical step at the flat state D (the start estimate); ``v0``, ``difference``, ``tol``
    as in omega_sheet."""
    t0 = time.perf_counter()
    w, method, n_ev, mode = omega_sheet(dyn.model, dyn.M, dyn.free_mask, D, s, dyn.force, v0, difference, tol)
    return limit(w, method, dyn, s, alpha, n_ev, time.perf_counter() - t0, mode)


def initial_step(lim: StepLimit, s, alpha, info: dict) -> float:
    """The step [s] of a new run: safety x dt_crit, or the user's dt if stable; a dt above dt_crit is
    refused (InputError with the numbers) or reduced when allow_reduce (noted in ``info``)."""
    dt_crit = lim.dt_crit
    if s.dt is None:
        return s.safety * dt_crit
    if s.dt > dt_crit and not s.allow_unstable:
        if not s.allow_reduce:
            raise InputError(
                f"dt = {s.dt:.6g} s exceeds the critical time step {dt_crit:.6g} s "
                f"(omega_max = {lim.omega:.6g} rad/s, alpha = {alpha:g} 1/s, mass scaling {s.mass_scaling:g} "
                f"{s.mass_scaling_mode}); use dt <= {s.safety * dt_crit:.6g} s, mass scaling, or allow_reduce=True"
            )
        info["dt_requested"] = s.dt
        return s.safety * dt_crit
    return s.dt


def landing_step(dt: float, t_now: float, t_end: float) -> float:
    """The largest step <= dt that lands an integer number of steps from t_now exactly on t_end."""
    return (t_end - t_now) / int(math.ceil((t_end - t_now) / dt * (1.0 - 1e-12)))


def recheck(dyn: Dynamics, D, mode, lim: StepLimit, alpha):
    """(dt_crit now, top mode) at the flat state D, warm-started from ``mode``; (None, mode) when the
    estimate fails (e.g. an indefinite state: keep the step, the energy check still watches)."""
    M = dyn.M
    try:
        est = estimate_omega_max(
            dyn.force or dyn.model.internal_force,
            M,
            dyn.free_mask,
            D.reshape(M.shape),
            tol=WARM_TOL,
            v0=mode if np.any(mode) else None,
        )
    except ValueError:
        return None, mode
    w = est.omega_max
    if lim.k_max is not None:
        w = 2.0 / combined_critical_time_step(w, lim.k_max, M[:, 0])
    return critical_time_step(w, alpha), est.mode
