"""Explicit dynamics (Section 4): central differences with mass-proportional Rayleigh damping,
Eq. (23), and dynamic relaxation (Section 4.2).

Scheme
------
With the lumped (diagonal) mass M of the trapezoidal rule, Eq. (23) is applied literally, dof by dof:

    D_n+1 = [ M^-1 (P_n - F_n + C_n) + 2/dt^2 D_n + (alpha/(2 dt) - 1/dt^2) D_n-1 ]
            / (1/dt^2 + alpha/(2 dt))

(C_n: penalty contact forces on the mid-surface dofs, ``solidshell.contact``).  Fixed dofs are held
at their prescribed values.  The hot path of a step is one ``model.internal_force`` (a compiled
batched kernel), the contact forces when there is a contact body, and a handful of vectorised numpy
operations on (6N,) arrays: no tangent, no sparse matrix, no Python loop over nodes or elements.
The start from (D_0, V_0) uses D_-1 = D_0 - dt V_0 + dt^2/2 A_0, A_0 = M^-1 (P - F_0 + C_0) - alpha V_0.

Critical step
-------------
Estimated at the start state by matrix-free Lanczos on M^-1 K (``timestep.py``), after mass
scaling and including the penalty springs (``contact.combined_critical_time_step``), and re-checked
every ``recheck_every`` steps (default 10^4; 0: never) at the current state, warm-started from the
last top mode (~1-2 % of the run time).  When the state has stiffened so that dt exceeds
(1 + safety)/2 of the new critical step, the step is shortened to safety x the new one, keeping the
half-step velocity (D_n-1 := D_n - dt_new/dt_old (D_n - D_n-1)); an explicit run then re-spaces its
remaining steps to land on t_end.  The step is never lengthened.  The default step is ``safety``
(0.9) × dt_crit; a user ``dt`` above dt_crit is refused with the numbers (InputError), or reduced
to safety × dt_crit when ``allow_reduce=True``.  Measured (verification/dynamic_cantilever.py): the
observed stability limit is 0.9999-1.0003 × the Lanczos dt_crit on three strips.

A run that goes non-finite stops at once; so does one whose sampled energy balance error exceeds
``max_energy_error`` (it is creating energy: an instability that has not overflowed yet).  Either
returns converged=False, a message saying when and why, and the last *good* state: the last sample
that was finite and passed the energy check (the state just before the overflow is finite but
already ~1e200).

Energy balance (every ``sample_every`` steps)
---------------------------------------------
E_kin = 1/2 v_n.M.v_n with the central velocity v_n = (D_n+1 - D_n-1)/(2 dt); E_strain =
model energy at D_n; W_ext = P.(D_n - D_0) (dead loads, exact); E_damp = trapezoidal sum over steps
of alpha v_m.M.v_m dt (accumulated every step); E_contact = penalty energy at D_n (the contact is
frictionless and conservative; the work of the contact forces is also accumulated and reported).
energy_balance_error = max over samples of |dE_kin + dE_strain - W_ext + E_damp + dE_contact| /
max(W_ext, max E_kin, initial energy, dE_strain, 1e-9 |P|_1 L, 1/2 sum M (1e-9 L omega_max)^2),
d = change since the start.  All
energies use the (scaled) masses actually integrated.  The central-velocity E_kin misreads a mode of
frequency w by ~(w dt)^2/3 of its energy, so the error is ~1e-6..1e-4 for smooth drapes and a few %
right after a penalty impact (w_c dt ~ 0.5).  With kinetic damping E_damp is the kinetic energy removed at the resets.

Coulomb friction (a contact body with ``friction`` mu > 0; contact.frictional_contact): the stick
springs' anchors are part of the state (checkpointed, so a restart stays bit for bit), their
stiffness k_t = ``friction_stiffness`` x k (default 1) enters the critical step as max(k, k_t), and
the work W_f of the friction forces, accumulated every step by the scheme's own central rule
f_t,n.(x_n+1 - x_n-1)/2 on the nodes in contact, enters the balance as -W_f (reported:
friction_work = -W_f, of it friction_stick_energy still stored, friction_dissipation the rest).
Without a frictional body none of this runs.

Eq. (24) (model thickness_strain = "quasi"): its stored energy jumps where a corner's n_p.d_p
crosses -mu (the nodal strain goes from |x_n| - 1 to -|x_n| - 1: ~2 C_z per corner, with no work
done), which a plain balance reads as energy creation.  So in a quasi run the work of the internal
forces is also accumulated every step (trapezoidal rule, W_int = sum 1/2 (F_m-1 + F_m).(D_m -
D_m-1)), the Eq. (24) branch flags (n_p.d_p <= -mu per element corner) are compared at every
sample, and over a sample interval in which any flag changed the difference (E_strain change -
W_int) is booked as a jump (thickness_strain_energy_jump, with thickness_strain_switch_samples and
thickness_strain_corner_switches counted and reported) instead of entering the balance.  Intervals
without a switch are checked exactly as before, so an unstable step is still caught; a run whose
corners switch in every interval is only checked through the work identity there (see the counts).
The booked energy is real for the dynamics: on the 60 x 60 sphere (verification/dynamic_sphere.py,
Rayleigh alpha 5, director masses x1e4) 41 corner flips booked 35x the work of gravity and the run
went non-finite at t = 2.39 s with the balance still at 0.006; with kinetic damping no corner flipped.

Mass scaling (Section 4.2): ``mass_scaling`` s with ``mass_scaling_mode`` "uniform" (all masses ×s,
the paper's choice; the weight P is unchanged) or "director" (only the U_n masses ×s: the thickness
mode limits the step, so this lengthens it by up to sqrt(s) while leaving translational inertia
unchanged until the membrane/bending modes take over).  It does add rotary inertia: measured on the
hung 20 x 20 cm sheet (verification/dynamic_mass_scaling.py, 20x20 mesh, 0.2 s) the positions move
by <= 0.4 % (x10), <= 1.8 % (x100), <= 10 % (x1000) of the displacement, for 0.46, 0.10, 0.06 of the
wall time; a steady state (relaxation) does not depend on the masses at all.  The penalty stiffness
follows the step (k = factor m omega_max^2, contact.py), so director scaling by s softens the contact
by up to s: on the 30 x 30 cloth over the sphere (20x20 mesh, x1e4) the deepest penetration seen
was 0.037 cm (0.6 h) during the fall; raise ``contact_penalty_factor`` if that matters (the step
shrinks by 1/sqrt(1 + factor)).

Settings (all optional unless said)
-----------------------------------
run:        t_end [s] (required), snapshots (list of times [s] to keep as frames), dt [s],
            safety (0.9), allow_reduce (False), allow_unstable (False: only for stability studies),
            alpha [1/s] (Rayleigh factor of Eq. 20, default 5.0), mass_scaling (1), mass_scaling_mode
            ("uniform"), sample_every (steps between energy/interpenetration samples), U0, V0 ((N,6)
            initial state), critical_time_step [s] (skip the estimate), critical_step_method
            ("lanczos" | "power" | "tangent"), critical_step_tol (1e-6), contact_penalty_factor
            (0.1), checkpoint (path), checkpoint_every (steps; default: every checkpoint_wall = 60 s
            of wall time), restart (path),
            max_wall_time [s] (stop, unconverged, when exceeded), frame_every (steps), frame_interval
            [s] (simulated time between kept frames; relax default 0.05, explicit 0 = off) and
            max_frames (100: past it every other interval frame is dropped and the interval
            doubled), threads
            (numba threads for the force kernel; default 1 below SMALL_MESH_ELEMENTS elements),
            max_energy_error (0.5: a sampled energy balance error above it means the run creates
            energy -- an instability -- and stops it, returning the last good state),
            recheck_every (steps between critical-step re-checks, 10000; 0 = never),
            friction_stiffness (1.0: tangential stick stiffness k_t / normal penalty k, with friction).
run_relax:  the same keys (alpha default 5.0, mass_scaling default 100) plus damping ("rayleigh" |
            "kinetic"), tol_kinetic (1e-6: E_kin / W_ext), tol_residual (1e-3: |P - F + C|_free /
            |P|_free, or / |F| without loads), check_every (steps, 100), t_max [s] (default 60) or
            max_steps.  With
            damping="kinetic", alpha is ignored (set to 0).  Measured on square-pedestal 24x8x4
            (benchmarks/explicit_relaxation.py): the paper's alpha = 5, masses x100 needs 31 s of
            simulated time (402k steps, 247 s wall); kinetic damping with the director masses x1e4
            reaches the same drape (DC 0.6790 vs 0.6795) in 28.5k steps, 29 s wall.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np
from numba import njit

from ..contact import combined_critical_time_step, contact_forces, frictional_contact, penalty_stiffness
from ..errors import InputError, SolverError
from ..problem import Problem, SolveResult, no_progress
from .blas import single_threaded_blas
from .timestep import critical_time_step, estimate_omega_max

_CHECKPOINT_VERSION = 1

_RUN_KEYS = {"t_end", "snapshots", "dt", "safety", "allow_reduce", "allow_unstable", "alpha",
             "mass_scaling", "mass_scaling_mode", "sample_every", "U0", "V0", "critical_time_step",
             "critical_step_method", "critical_step_tol", "contact_penalty_factor", "checkpoint",
             "checkpoint_every", "checkpoint_wall", "restart", "max_wall_time", "frame_every", "frame_interval", "max_frames", "progress_every", "threads", "max_energy_error", "recheck_every",
             "friction_stiffness"}
_RELAX_KEYS = _RUN_KEYS - {"t_end", "snapshots"} | {"damping", "tol_kinetic", "tol_residual",
                                                     "check_every", "t_max", "max_steps"}


# ============================================================================ small helpers
# Vector reductions on the hot path avoid BLAS (np.dot, np.linalg.norm of 1-D arrays): a threaded
# OpenBLAS on a busy machine was measured at 3-15 ms for one 10^4-long dot product, against 25 us
# for the plain pairwise sum below.
def _dot(a, b) -> float:
    return float(np.add.reduce(a * b))


def _norm(a) -> float:
    return math.sqrt(float(np.add.reduce(a * a)))


@njit(cache=True)
def _central_step(Dn1, D, Dp, R, cF, cD, cDp, fixed_idx, presc, Mf, inv2dt):
    """Eq. (23) for every dof, D_n+1 = cF R + cD D_n + cDp D_n-1 (the same operation order as the
    numpy expression), the prescribed values, and in the same pass the finiteness of D_n+1 and
    v_n.M.v_n with v_n = (D_n+1 - D_n-1) / (2 dt).  Fusing these saves ~8 passes over 6N doubles
    per step (25 % of a 1600-quad step once the force kernel got fast)."""
    n = D.size
    for i in range(n):
        Dn1[i] = cF[i] * R[i] + cD * D[i] + cDp * Dp[i]
    for k in range(fixed_idx.size):
        Dn1[fixed_idx[k]] = presc[k]
    vMv = 0.0
    finite = True
    for i in range(n):
        x = Dn1[i]
        if x - x != 0.0:  # inf - inf and nan - nan are nan
            finite = False
        w = (x - Dp[i]) * inv2dt
        vMv += Mf[i] * w * w
    return vMv, finite


# ============================================================================ settings helpers
def _num(settings, key, default, *, positive=False, nonneg=False, integer=False):
    v = settings.get(key, default)
    if v is None:
        return None
    try:
        x = int(v) if integer else float(v)
    except (TypeError, ValueError):
        raise InputError(f"setting {key} must be a number, got {v!r}") from None
    if integer and float(v) != x:
        raise InputError(f"setting {key} must be an integer, got {v!r}")
    if not math.isfinite(x) or (positive and x <= 0) or (nonneg and x < 0):
        kind = "positive" if positive else "non-negative" if nonneg else "finite"
        raise InputError(f"setting {key} must be {kind}, got {v!r}")
    return x


def _check_keys(settings, allowed, name):
    unknown = sorted(set(settings) - allowed)
    if unknown:
        raise InputError(f"unknown {name} setting(s): {', '.join(unknown)}; known: {', '.join(sorted(allowed))}")


def scaled_mass(model, scaling: float = 1.0, mode: str = "uniform") -> np.ndarray:
    """(N,6) lumped mass after mass scaling (Section 4.2): "uniform" multiplies every mass by
    ``scaling``; "director" only the U_n masses."""
    M = np.asarray(model.lumped_mass(), dtype=float).copy()
    if mode == "uniform":
        M *= scaling
    elif mode == "director":
        M[:, 3:] *= scaling
    else:
        raise InputError(f"mass_scaling_mode must be 'uniform' or 'director', got {mode!r}")
    return M


# ============================================================================ the integrator
class _State:
    """Everything that changes during the run: saved in checkpoints, restored on restart."""

    FIELDS = ("D", "Dp", "step", "damp_sum", "ekin_max", "balance_err", "max_interp", "contact_work",
              "max_contact", "max_pen", "ek_prev_half", "resets", "last_ekin", "last_rel_res", "frame_t", "frame_U",
              "dt_cur", "n_base", "t_base", "mode", "rechecks", "reductions", "dtc_min",
              # Coulomb friction (empty / zero without a frictional body)
              "anchors", "fric_work", "max_slip",
              # Eq. (24) energy jumps (zero / empty unless thickness_strain = "quasi")
              "w_int", "w_int_prev", "es_prev", "qflags", "q_jump", "q_samples", "q_corners",
              "q_F", "q_D", "t_max_interp",
              # interval frames: per frame its interval index (-1: t = 0, a snapshot or the end), the interval
              "frame_k", "frame_dt")
    # fields a checkpoint written before they existed may lack (a frictionless, Green-strain run)
    DEFAULTS = dict(anchors=lambda n: np.zeros((0, n, 3)), fric_work=lambda n: 0.0, max_slip=lambda n: 0,
                    w_int=lambda n: 0.0, w_int_prev=lambda n: 0.0, es_prev=lambda n: 0.0,
                    qflags=lambda n: np.zeros(0, bool), q_jump=lambda n: 0.0, q_samples=lambda n: 0,
                    q_corners=lambda n: 0, q_F=lambda n: np.zeros(0), q_D=lambda n: np.zeros(0),
                    t_max_interp=lambda n: 0.0, frame_dt=lambda n: 0.0)

    def __init__(self, **kw):
        self.__dict__.update(kw)


def _keep_frame(st: _State, t: float, D: np.ndarray, k: int, shape, max_frames: int) -> None:
    """Append the frame (t, D) with its interval index k (-1: not an interval frame); past
    ``max_frames`` interval frames, keep the even-indexed ones and double the interval."""
    st.frame_t.append(float(t))
    st.frame_U.append(D.reshape(shape).copy())
    st.frame_k.append(int(k))
    if sum(1 for kk in st.frame_k if kk >= 0) > max_frames:
        keep = [i for i, kk in enumerate(st.frame_k) if kk < 0 or kk % 2 == 0]
        st.frame_t = [st.frame_t[i] for i in keep]
        st.frame_U = [st.frame_U[i] for i in keep]
        st.frame_k = [kk if kk < 0 else kk // 2 for kk in (st.frame_k[i] for i in keep)]
        st.frame_dt *= 2.0


def _next_frame_time(st: _State) -> float:
    """Simulated time [s] of the next interval frame (inf without interval frames)."""
    if st.frame_dt <= 0.0:
        return math.inf
    last = next((k for k in reversed(st.frame_k) if k >= 0), 0)
    return (last + 1) * st.frame_dt


def _save_checkpoint(path, st: _State, fixed_info: dict):
    tmp = f"{path}.tmp{os.getpid()}.npz"
    arrays = {k: np.asarray(getattr(st, k)) for k in _State.FIELDS if k not in ("frame_t", "frame_U", "frame_k")}
    arrays["frame_k"] = np.asarray(st.frame_k, dtype=np.int64)
    arrays["frame_t"] = np.asarray(st.frame_t, dtype=float)
    arrays["frame_U"] = (np.stack(st.frame_U) if st.frame_U else np.zeros((0,) + st.D.shape))
    for k, v in fixed_info.items():
        arrays["fix_" + k] = np.asarray(v)
    arrays["version"] = np.asarray(_CHECKPOINT_VERSION)
    with open(tmp, "wb") as fh:
        np.savez(fh, **arrays)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)  # atomic: a reader sees the old or the new checkpoint, never half of one


def _load_checkpoint(path, fixed_info: dict) -> _State:
    try:
        z = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot read restart file {path}: {exc}") from None
    with z:
        if int(z["version"]) != _CHECKPOINT_VERSION:
            raise InputError(f"restart file {path} has version {int(z['version'])}, expected {_CHECKPOINT_VERSION}")
        for k, v in fixed_info.items():
            if "fix_" + k not in z.files:
                raise InputError(f"restart file {path} does not match this run: it has no {k} (written by a run "
                                 f"without it)")
            saved = z["fix_" + k]
            if not np.array_equal(saved, np.asarray(v)):
                raise InputError(f"restart file {path} does not match this run: {k} was {saved.tolist() if saved.size < 8 else '...'}, "
                                 f"now {np.asarray(v).tolist() if np.asarray(v).size < 8 else '...'}")
        n_nodes = int(fixed_info["n_nodes"])
        kw = {k: (z[k].copy() if k in z.files else _State.DEFAULTS[k](n_nodes)) for k in _State.FIELDS
              if k != "frame_k"}
        kw["frame_k"] = [int(k) for k in z["frame_k"]] if "frame_k" in z.files else [-1] * len(z["frame_t"])
    for k in ("step", "max_interp", "max_contact", "resets", "n_base", "rechecks", "reductions", "max_slip",
              "q_samples", "q_corners"):
        kw[k] = int(kw[k])
    for k in ("dt_cur", "t_base", "dtc_min", "damp_sum", "max_pen", "ekin_max", "balance_err", "contact_work", "ek_prev_half", "last_ekin", "last_rel_res",
              "fric_work", "w_int", "w_int_prev", "es_prev", "q_jump", "t_max_interp", "frame_dt"):
        kw[k] = float(kw[k])
    kw["frame_t"] = [float(t) for t in kw["frame_t"]]
    kw["frame_U"] = [u for u in kw["frame_U"]]
    return _State(**kw)


def _integrate(problem: Problem, settings: dict, progress, relax: bool) -> SolveResult:
    wall0 = time.perf_counter()
    settings = dict(settings or {})
    _check_keys(settings, _RELAX_KEYS if relax else _RUN_KEYS, "relax" if relax else "explicit")
    model = problem.model
    N = model.n_nodes
    shape = (N, 6)
    n_elem = int(getattr(getattr(model, "mesh", None), "n_elements", 0))

    # ------------------------------------------------------------------ settings
    alpha = _num(settings, "alpha", 5.0, nonneg=True)
    damping = settings.get("damping", "rayleigh") if relax else "rayleigh"
    if damping not in ("rayleigh", "kinetic"):
        raise InputError(f"damping must be 'rayleigh' or 'kinetic', got {damping!r}")
    if damping == "kinetic":
        # Cundall's kinetic damping replaces the viscous damping: a scene file's alpha is meant for
        # damping="rayleigh" (with both, the relaxation measured 4x more steps on the wool strip)
        alpha = 0.0
    ms = _num(settings, "mass_scaling", 100.0 if relax else 1.0, positive=True)
    ms_mode = settings.get("mass_scaling_mode", "uniform")
    safety = _num(settings, "safety", 0.9, positive=True)
    if safety >= 1.0 and not settings.get("allow_unstable", False):
        raise InputError(f"safety must be below 1 (the step would reach the stability limit), got {safety}")
    allow_reduce = bool(settings.get("allow_reduce", False))
    allow_unstable = bool(settings.get("allow_unstable", False))
    pen_factor = _num(settings, "contact_penalty_factor", 0.1, positive=True)
    kt_ratio = _num(settings, "friction_stiffness", 1.0, positive=True)
    max_wall = _num(settings, "max_wall_time", None, positive=True)

    M = scaled_mass(model, ms, ms_mode)
    fixed = problem.fixed
    free_mask = ~fixed
    if np.any(M[free_mask] <= 0.0):
        raise InputError(f"{int(np.sum(M[free_mask] <= 0))} free dof(s) have zero mass: the explicit scheme needs M > 0")
    P = problem.loads.ravel().copy()
    fixed_idx = np.flatnonzero(fixed.ravel())
    free_idx = np.flatnonzero(free_mask.ravel())
    presc = problem.prescribed.ravel()[fixed_idx].copy()
    X0 = model.mesh.nodes if hasattr(model, "mesh") else np.zeros((N, 3))
    bodies = list(problem.contact or [])
    fric_of = [float(getattr(b, "friction", 0.0)) for b in bodies]
    n_fric = sum(1 for mu in fric_of if mu > 0.0)   # 0: the frictionless path, exactly as before
    quasi = bool(getattr(model, "quasi", False)) and hasattr(model, "interpenetration")
    q_mu = float(getattr(model, "mu", 0.5))

    U0 = np.zeros(shape) if settings.get("U0") is None else np.asarray(settings["U0"], float).reshape(shape).copy()
    V0 = np.zeros(shape) if settings.get("V0") is None else np.asarray(settings["V0"], float).reshape(shape).copy()
    D0 = U0.ravel().copy()
    D0[fixed_idx] = presc
    V0f = V0.ravel().copy()
    V0f[fixed_idx] = 0.0

    # ------------------------------------------------------------------ restart: dt as saved
    restart = settings.get("restart")
    saved = None
    if restart:
        try:
            with np.load(restart, allow_pickle=False) as z:
                saved = dict(dt=float(z["fix_dt"]), omega=float(z["fix_omega"]),
                             omega_el=float(z["fix_omega_el"]), method=str(z["fix_method"]))
        except (OSError, ValueError, KeyError) as exc:
            raise InputError(f"cannot read restart file {restart}: {exc}") from None

    # ------------------------------------------------------------------ critical step
    t_est = time.perf_counter()
    dt_crit_user = _num(settings, "critical_time_step", None, positive=True)
    method = settings.get("critical_step_method", "lanczos")
    n_est_evals = 0
    mode0 = None
    if saved is not None:  # a restart reuses the step of the run it continues (bit-for-bit)
        omega_el, method = saved["omega_el"], saved["method"]
    elif dt_crit_user is None:
        try:
            est = estimate_omega_max(model.internal_force, M, free_mask, D0.reshape(shape), method=method,
                                     tol=_num(settings, "critical_step_tol", 1e-6, positive=True),
                                     tangent=getattr(model, "tangent", None))
        except ValueError as exc:
            raise InputError(f"cannot estimate the critical time step: {exc}") from None
        omega_el = est.omega_max
        n_est_evals = est.n_force_evals
        mode0 = est.mode
    else:
        omega_el = 2.0 / dt_crit_user
        method = "given"
    k_pen = None
    omega = omega_el
    k_t = None
    if bodies:
        k_pen = penalty_stiffness(M[:, 0], omega_el, pen_factor)
        # the contact Hessian of a node has eigenvalues k (normal) and k_t (tangential, friction)
        k_max = k_pen * max(1.0, kt_ratio) if n_fric else k_pen
        omega = 2.0 / combined_critical_time_step(omega_el, k_max, M[:, 0])
        if n_fric:
            k_t = kt_ratio * k_pen
    dt_crit = critical_time_step(omega, alpha)
    t_est = time.perf_counter() - t_est

    dt_req = _num(settings, "dt", None, positive=True)
    info_dt = {}
    if saved is not None:
        dt = saved["dt"]
    elif dt_req is None:
        dt = safety * dt_crit
    elif dt_req > dt_crit and not allow_unstable:
        if not allow_reduce:
            raise InputError(
                f"dt = {dt_req:.6g} s exceeds the critical time step {dt_crit:.6g} s "
                f"(omega_max = {omega:.6g} rad/s, alpha = {alpha:g} 1/s, mass scaling {ms:g} {ms_mode}); "
                f"use dt <= {safety * dt_crit:.6g} s, mass scaling, or allow_reduce=True")
        dt = safety * dt_crit
        info_dt["dt_requested"] = dt_req
    else:
        dt = dt_req

    # ------------------------------------------------------------------ step counts
    if relax:
        t_max = _num(settings, "t_max", 60.0, positive=True)
        max_steps = _num(settings, "max_steps", None, positive=True, integer=True)
        n_steps = max_steps if max_steps is not None else int(math.ceil(t_max / dt))
        snap_steps = {}
        tol_ke = _num(settings, "tol_kinetic", 1e-6, positive=True)
        tol_res = _num(settings, "tol_residual", 1e-3, positive=True)
        check_every = _num(settings, "check_every", 100, positive=True, integer=True)
    else:
        if "t_end" not in settings:
            raise InputError("the explicit solver needs t_end [s] (the simulated time)")
        t_end = _num(settings, "t_end", None, positive=True)
        n_steps = int(math.ceil(t_end / dt * (1.0 - 1e-12)))
        if saved is None:
            dt = t_end / n_steps  # land exactly on t_end; never longer than the requested/default step
        snaps = settings.get("snapshots") or []
        try:
            snaps = sorted(float(s) for s in snaps)
        except (TypeError, ValueError):
            raise InputError(f"snapshots must be a list of times [s], got {settings.get('snapshots')!r}") from None
        if snaps and snaps[0] < 0.0:
            raise InputError(f"snapshot times must not be negative, got {snaps}")
        late = [x for x in snaps if x > t_end * (1 + 1e-9)]
        if late:  # a scene's snapshots with a shorter t_end from the command line: keep the rest
            info_dt["snapshots_after_t_end_dropped"] = late
            snaps = [x for x in snaps if x <= t_end * (1 + 1e-9)]
        snap_steps = {min(n_steps, int(round(s / dt))): s for s in snaps}
        check_every = max(1, n_steps // 100)
    recheck_every = _num(settings, "recheck_every", 10000, nonneg=True, integer=True)
    if not relax:
        t_max = max_steps = None
    else:
        t_end = None
        snaps = []

    def schedule(n_base, t_base, dt):
        """(end step, {step: snapshot time}) for the step dt taken from step n_base at time t_base."""
        if relax:
            if max_steps is not None:
                return max_steps, {}
            return n_base + int(math.ceil((t_max - t_base) / dt * (1.0 - 1e-12))), {}
        return (n_base + int(round((t_end - t_base) / dt)),
                {n_base + int(round((s - t_base) / dt)): s for s in snaps if s >= t_base - 0.5 * dt})

    sample_every = _num(settings, "sample_every", max(1, min(100, n_steps // 100)), positive=True, integer=True)
    frame_every = _num(settings, "frame_every", None, positive=True, integer=True)
    # a relaxation keeps a frame every frame_interval of simulated time by default (a time series
    # to watch it settle); max_frames bounds the memory: beyond it every other interval frame is
    # dropped and the interval doubled, so a run of any length keeps 1/2..1 x max_frames of them
    frame_iv = _num(settings, "frame_interval", 0.05 if (relax and frame_every is None) else 0.0, nonneg=True)
    max_frames = _num(settings, "max_frames", 100, positive=True, integer=True)

    def keep_frame(st, t, D, k):
        _keep_frame(st, t, D, k, shape, max_frames)
    ckpt_path = settings.get("checkpoint")
    # by steps when asked; otherwise every checkpoint_wall seconds of wall time (a checkpoint holds
    # the kept frames too: tens of MB on a big mesh, too much to write every few thousand steps)
    ckpt_every = _num(settings, "checkpoint_every", None, positive=True, integer=True)
    ckpt_wall = _num(settings, "checkpoint_wall", 60.0, positive=True)
    prog_every = _num(settings, "progress_every", max(1, n_steps // 100), positive=True, integer=True)

    # ------------------------------------------------------------------ coefficients of Eq. (23)
    Mf = M.ravel()
    invM = np.zeros_like(Mf)
    invM[free_idx] = 1.0 / Mf[free_idx]

    def coefficients(dt):
        lhs = 1.0 / dt**2 + alpha / (2.0 * dt)
        return (invM / lhs,                                   # multiplies (P - F + C)
                (2.0 / dt**2) / lhs,                          # multiplies D_n
                (alpha / (2.0 * dt) - 1.0 / dt**2) / lhs)     # multiplies D_n-1

    cF, cD, cDp = coefficients(dt)

    Pn = _norm(P[free_idx])
    has_energy_force = hasattr(model, "energy_and_force")

    def force_and_energy(D, want_energy):
        if want_energy:
            if has_energy_force:
                E, F = model.energy_and_force(D.reshape(shape))
            else:
                F = model.internal_force(D.reshape(shape))
                E = model.energy(D.reshape(shape))
            return np.asarray(F, float).reshape(-1), float(E)
        return np.asarray(model.internal_force(D.reshape(shape)), float).reshape(-1), None

    def contact(D):
        x = X0 + D.reshape(shape)[:, :3]
        fc, ec, nact = contact_forces(bodies, x, k_pen)
        C = np.zeros(6 * N)
        C.reshape(shape)[:, :3] = fc
        pen = float(np.max(np.linalg.norm(fc, axis=1) / k_pen)) if nact else 0.0
        return C, ec, nact, pen

    def contact_friction(D, anchors):
        """As contact(), with Coulomb friction on the bodies with mu > 0 (contact.frictional_contact):
        also [(idx, f_t)] per frictional body, the stick energy, the new anchors and the slip count.
        ``anchors`` is not modified (a restart must see the saved ones)."""
        x = X0 + D.reshape(shape)[:, :3]
        fc = np.zeros_like(x)
        ec = et = pen = 0.0
        nact = nslip = 0
        fr = []
        new = np.empty_like(anchors)
        j = 0
        for b, mu in zip(bodies, fric_of):
            if mu > 0.0:
                fb, eb, idx, ft, etb, new[j], ns = frictional_contact(b, x, k_pen, k_t, anchors[j])
                j += 1
                fr.append((idx, ft))
                et += etb
                nslip += ns
                if idx.size:
                    fn = fb[idx] - ft
                    pen = max(pen, float(np.max(np.sqrt(np.einsum("ij,ij->i", fn, fn)) / k_pen[idx])))
                    nact += idx.size
            else:
                fb, eb = b.forces(x, k_pen)
                act = np.any(fb != 0.0, axis=1)
                if np.any(act):
                    nact += int(np.count_nonzero(act))
                    pen = max(pen, float(np.max(np.linalg.norm(fb[act], axis=1) / k_pen[act])))
            fc += fb
            ec += eb
        C = np.zeros(6 * N)
        C.reshape(shape)[:, :3] = fc
        return C, ec, nact, pen, fr, et, new, nslip

    def interp_count(D):
        if hasattr(model, "interpenetrated_nodes"):
            return int(np.count_nonzero(model.interpenetrated_nodes(D.reshape(shape))))
        return 0

    def interp_and_branches(D):
        """(interpenetrated node count n_p.d_p < 0, Eq. (24) branch flags n_p.d_p <= -mu per element
        corner) from one evaluation of model.interpenetration."""
        nds = model.interpenetration(D.reshape(shape))
        flag = np.zeros(N, dtype=bool)
        for b, nd in zip(model.blocks, nds):
            flag[b.conn[nd < 0.0]] = True
        return int(np.count_nonzero(flag)), np.concatenate([nd.ravel() <= -q_mu for nd in nds])

    # ------------------------------------------------------------------ initial state
    F0, Es0 = force_and_energy(D0, True)
    anchors0 = np.full((n_fric, N, 3), np.nan)
    if n_fric:
        C0, Ec0, _, _, _, _, _, _ = contact_friction(D0, anchors0)
    elif bodies:
        C0, Ec0, _, _ = contact(D0)
    else:
        C0, Ec0 = np.zeros(6 * N), 0.0
    Ek0 = 0.5 * _dot(Mf * V0f, V0f)
    E_init = Ek0 + Es0  # energy scale for a free vibration started from an initial state
    # floor of the energy scale: the work of the loads over 1e-9 of the mesh size, so that the first
    # samples (all energies ~0, imbalance ~round-off) do not read as a 100 % error
    L_char = float(np.ptp(X0, axis=0).max()) if N > 1 else 1.0
    # (and, with no load at all, the energy of a 1e-9 L vibration at omega_max: far above round-off)
    E_floor = max(1e-9 * float(np.abs(P).sum()) * L_char,
                  0.5 * float(Mf[free_idx].sum()) * (1e-9 * L_char * omega_el) ** 2, 1e-300)
    fixed_info = dict(n_nodes=N, dt=dt, alpha=alpha, mass_scaling=ms, mode=ms_mode, damping=damping,
                      n_fixed=fixed_idx.size, D0=D0, omega=omega, omega_el=omega_el, method=method)
    if n_fric:  # (only then: frictionless checkpoints stay as they were)
        fixed_info.update(friction=np.asarray(fric_of), friction_stiffness=kt_ratio)

    if restart:
        st = _load_checkpoint(restart, fixed_info)
        restarted_from = st.step
    else:
        A0 = invM * (P - F0 + C0) - alpha * V0f
        A0[fixed_idx] = 0.0
        Dm = D0 - dt * V0f + 0.5 * dt * dt * A0
        Dm[fixed_idx] = presc
        if quasi:
            mi0, qf0 = interp_and_branches(D0)
        else:
            mi0, qf0 = interp_count(D0), np.zeros(0, bool)
        st = _State(D=D0.copy(), Dp=Dm, step=0, damp_sum=0.0, ekin_max=Ek0, balance_err=0.0,
                    anchors=anchors0, fric_work=0.0, max_slip=0, w_int=0.0, w_int_prev=0.0, es_prev=Es0,
                    qflags=qf0, q_jump=0.0, q_samples=0, q_corners=0, t_max_interp=0.0,
                    q_F=(F0.copy() if quasi else np.zeros(0)), q_D=(D0.copy() if quasi else np.zeros(0)),
                    max_interp=mi0, contact_work=0.0, max_contact=0, max_pen=0.0, ek_prev_half=0.0,
                    resets=0, last_ekin=Ek0, last_rel_res=(_norm((P - F0 + C0)[free_idx]) / Pn
                                                         if Pn > 0 else 0.0),
                    frame_t=[], frame_U=[], frame_k=[], frame_dt=frame_iv, dt_cur=dt, n_base=0, t_base=0.0,
                    mode=(mode0 if mode0 is not None else np.zeros(6 * N)), rechecks=0, reductions=0, dtc_min=dt_crit)
        if 0 in snap_steps or relax or (not snap_steps):
            keep_frame(st, 0.0, D0, -1)
        restarted_from = None

    D, Dp = st.D.copy(), st.Dp.copy()
    dt = st.dt_cur
    cF, cD, cDp = coefficients(dt)
    end_step, snap_steps = schedule(st.n_base, st.t_base, dt)

    def time_of(n):
        return st.t_base + (n - st.n_base) * dt

    good_D, good_t = D.copy(), time_of(st.step)  # the last state that passed the sample checks
    frame_next_t = _next_frame_time(st)
    ckpt_t = time.perf_counter()
    max_err = _num(settings, "max_energy_error", 0.5, positive=True)
    Dn1 = np.empty_like(D)
    R = np.empty_like(D)
    status = "running"
    message = ""
    last = {}
    steps_done = 0
    t_loop = time.perf_counter()
    n = st.step
    recheck_margin = 0.5 * (1.0 + safety)

    with np.errstate(over="ignore", invalid="ignore"):
        while n < end_step:
            sample = (n % sample_every == 0) or n == end_step - 1
            check = relax and (n % check_every == 0)
            # ---------------------------------------------------- forces at D_n
            try:
                F, Es = force_and_energy(D, sample)
            except (FloatingPointError, ZeroDivisionError, SolverError) as exc:
                status, message = "failed", f"internal force failed at step {n} (t = {time_of(n):.6g} s): {exc}"
                break
            np.subtract(P, F, out=R)
            if quasi and n > 0:
                # work of the internal forces along the path actually taken, trapezoidal rule per
                # step: sum 1/2 (F_m-1 + F_m).(D_m - D_m-1) up to D_n (the same end points as
                # E(D_n) - E(D_0), so that it differs from them only where the energy jumps)
                st.w_int += 0.5 * float(np.add.reduce((F + st.q_F) * (D - st.q_D)))
                st.q_F[:] = F
                st.q_D[:] = D
            if n_fric:
                C, Ec, nact, pen, fr, Et, new_anchors, nslip = contact_friction(D, st.anchors)
                R += C
                if pen > st.max_pen:
                    st.max_pen = pen
            elif bodies:
                C, Ec, nact, pen = contact(D)
                R += C
                if pen > st.max_pen:
                    st.max_pen = pen
            # ---------------------------------------------------- Eq. (23)
            # one fused pass: D_n+1, the fixed dofs, the finiteness check and v_n.M.v_n
            vMv, finite = _central_step(Dn1, D, Dp, R, cF, cD, cDp, fixed_idx, presc, Mf, 0.5 / dt)
            if not finite:
                status = "nonfinite"
                message = (f"the solution became non-finite at step {n + 1} (t = {time_of(n + 1):.6g} s) with "
                           f"dt = {dt:.6g} s, critical step {dt_crit:.6g} s; returning the last good (finite, "
                           f"energy-balanced) state, t = {good_t:.6g} s")
                break
            # ---------------------------------------------------- central velocity, damping work
            dd = alpha * dt * vMv
            if n == 0 and restarted_from is None:
                dd *= 0.5  # trapezoidal rule: the first and last samples weigh half
            st.damp_sum += dd
            if bodies:
                st.contact_work += 0.5 * _dot(C, Dn1 - Dp)
            # ---------------------------------------------------- samples at t_n
            if sample:
                Ek = 0.5 * vMv
                st.ekin_max = max(st.ekin_max, Ek)
                Wext = _dot(P, D - D0)
                Edamp = st.damp_sum - (0.5 * alpha * dt * vMv if n > 0 else 0.0)
                Ecn = Ec if bodies else 0.0
                if quasi:
                    # Eq. (24) is discontinuous where a corner's n_p.d_p crosses -mu: the stored
                    # thickness energy jumps with no work done.  Over a sample interval in which a
                    # branch flag changed, the jump is the change of the strain energy minus the
                    # work of the internal forces (trapezoidal rule, accumulated every step);
                    # it is booked as a jump (counted, reported) and kept out of the balance.  In
                    # intervals without a switch the energy is smooth and is checked as usual.
                    n_int, qf = interp_and_branches(D)
                    nsw = int(np.count_nonzero(qf != st.qflags))
                    if nsw:
                        st.q_jump += (Es - st.es_prev) - (st.w_int - st.w_int_prev)
                        st.q_samples += 1
                        st.q_corners += nsw
                        st.qflags = qf
                    st.es_prev, st.w_int_prev = Es, st.w_int
                Efric = -st.fric_work if n_fric else 0.0   # work done against friction (>= 0 in slip)
                bal = (Ek - Ek0) + (Es - Es0 - st.q_jump) - Wext + Edamp + (Ecn - Ec0) + Efric
                scale = max(abs(Wext), st.ekin_max, E_init, abs(Es - Es0), E_floor)
                err = abs(bal) / scale
                st.balance_err = max(st.balance_err, err)
                if err > max_err:
                    status = "diverged"
                    message = (f"energy balance error {err:.3g} > {max_err:g} at step {n} (t = {time_of(n):.6g} s): the "
                               f"run is creating energy (unstable step {dt:.6g} s vs critical {dt_crit:.6g} s, or "
                               f"a non-physical state); returning the last good state, t = {good_t:.6g} s")
                    break
                good_t = time_of(n)
                good_D[:] = D
                ni = n_int if quasi else interp_count(D)
                if ni > st.max_interp:
                    st.max_interp, st.t_max_interp = ni, time_of(n)
                if bodies:
                    st.max_contact = max(st.max_contact, nact)
                if n_fric:
                    st.max_slip = max(st.max_slip, nslip)
                st.last_ekin = Ek
                last = dict(Ek=Ek, Es=Es - Es0, Wext=Wext, Edamp=Edamp, Ec=Ecn - Ec0, t=time_of(n),
                            Efric=Efric, Et=(Et if n_fric else 0.0), interp=ni)
            if check or (not relax and n == end_step - 1):
                # relative to the loads; without loads (prescribed displacements only) relative to
                # the internal forces including the reactions
                st.last_rel_res = _norm(R[free_idx]) / (Pn if Pn > 0 else max(_norm(F), 1e-300))
            # ---------------------------------------------------- frames
            if n in snap_steps and n > 0:
                keep_frame(st, time_of(n), D, -1)
            elif frame_every and n > 0 and n % frame_every == 0:
                keep_frame(st, time_of(n), D, -1)
            elif time_of(n) >= frame_next_t:   # inf without interval frames; >= the interval > 0 else
                keep_frame(st, time_of(n), D, int(time_of(n) / st.frame_dt))
                frame_next_t = _next_frame_time(st)
            # ---------------------------------------------------- steady state?
            if check and n > 0:
                Wext_c = _dot(P, D - D0)
                Ek_c = 0.5 * vMv
                rel_ke = Ek_c / max(abs(Wext_c), abs(last.get("Es", 0.0)), E_floor)
                if rel_ke < tol_ke and st.last_rel_res < tol_res:
                    status = "steady"
                    st.last_ekin = Ek_c
                    message = (f"steady state at t = {time_of(n):.6g} s after {n} steps: E_kin/W_ext = {rel_ke:.3g} "
                               f"< {tol_ke:g}, residual {st.last_rel_res:.3g} < {tol_res:g}")
                    break
            # ---------------------------------------------------- kinetic damping (Cundall)
            if damping == "kinetic":
                dh = Dn1 - D
                ek_half = 0.5 * _dot(Mf * dh, dh) / dt**2
                if ek_half < st.ek_prev_half:
                    # kinetic-energy peak passed (between v_n-1/2 and v_n+1/2, i.e. at D_n): restart
                    # from D_n at rest with the start rule of t = 0, D_n+1 = D_n + dt^2/2 M^-1 R_n.
                    # (Simply zeroing v_n+1/2 at D_n+1 turns repeated resets near equilibrium into
                    # steepest descent with step dt^2 M^-1, unstable above omega dt = sqrt(2); the
                    # half-step restart is stable up to omega dt = 2 like the scheme itself.)
                    st.damp_sum += 0.5 * vMv
                    np.multiply(invM, R, out=Dn1)
                    Dn1 *= 0.5 * dt * dt
                    Dn1 += D
                    Dn1[fixed_idx] = presc
                    dh = Dn1 - D
                    ek_half = 0.5 * _dot(Mf * dh, dh) / dt**2
                    st.resets += 1
                st.ek_prev_half = ek_half
            # ---------------------------------------------------- path-dependent work of step n
            if n_fric:
                # friction work, by the same central rule as the scheme: f_t,n.(x_n+1 - x_n-1)/2
                D6, Dp6 = Dn1.reshape(shape), Dp.reshape(shape)
                for idx, ft in fr:
                    if idx.size:
                        st.fric_work += 0.5 * float(np.add.reduce((ft * (D6[idx, :3] - Dp6[idx, :3])).ravel()))
                st.anchors = new_anchors
            # ---------------------------------------------------- advance
            Dp, D, Dn1 = D, Dn1, Dp
            n += 1
            st.step = n
            steps_done += 1
            # ---------------------------------------------------- re-check the critical step
            if recheck_every and n % recheck_every == 0 and not allow_unstable and n < end_step:
                try:
                    est = estimate_omega_max(model.internal_force, M, free_mask, D.reshape(shape), tol=1e-4,
                                             v0=st.mode if np.any(st.mode) else None)
                except ValueError:
                    est = None  # e.g. an indefinite state: keep the step, the energy check still watches
                if est is not None:
                    st.rechecks += 1
                    st.mode = est.mode
                    w = est.omega_max
                    if bodies:
                        w = 2.0 / combined_critical_time_step(w, k_max, M[:, 0])
                    dtc_now = critical_time_step(w, alpha)
                    st.dtc_min = min(st.dtc_min, dtc_now)
                    if dt > recheck_margin * dtc_now:
                        # the state has stiffened: shorten the step, keeping the velocity v_n-1/2
                        t_now = time_of(n)
                        new = safety * dtc_now
                        if not relax:
                            new = (t_end - t_now) / int(math.ceil((t_end - t_now) / new * (1.0 - 1e-12)))
                        Dp[:] = D - (new / dt) * (D - Dp)
                        st.t_base, st.n_base, dt = t_now, n, new
                        st.dt_cur = dt
                        st.reductions += 1
                        cF, cD, cDp = coefficients(dt)
                        end_step, snap_steps = schedule(st.n_base, st.t_base, dt)
            if ckpt_path and (st.step % ckpt_every == 0 if ckpt_every else
                              (st.step % 100 == 0 and time.perf_counter() - ckpt_t >= ckpt_wall)):
                st.D, st.Dp = D, Dp
                _save_checkpoint(ckpt_path, st, fixed_info)
                st.D, st.Dp = None, None
                ckpt_t = time.perf_counter()
            if st.step % prog_every == 0:
                frac = st.step / max(end_step, 1)
                if relax and st.last_rel_res > 0:
                    frac = max(frac, min(0.99, math.log(max(st.last_rel_res, tol_res) / 1.0) / math.log(tol_res)))
                progress(min(frac, 1.0), f"t = {time_of(st.step):.4g} s, E_kin = {st.last_ekin:.3g}, "
                                         f"residual {st.last_rel_res:.2e}")
            if max_wall is not None and st.step % 100 == 0 and time.perf_counter() - wall0 > max_wall:
                status = "walltime"
                message = f"stopped at t = {time_of(st.step):.6g} s: wall-time limit {max_wall:g} s reached"
                break
    t_loop = time.perf_counter() - t_loop

    if status == "running":
        status = "done"
    if status == "done":
        if relax:
            message = (f"no steady state within {end_step} steps (t = {time_of(end_step):.6g} s): last residual "
                       f"{st.last_rel_res:.3g} (tol {tol_res:g})")
        else:
            message = (f"reached t_end = {time_of(end_step):.6g} s in {end_step} steps of {dt:.6g} s"
                       + (f" ({st.reductions} step reduction(s) after re-checking the critical step)"
                          if st.reductions else ""))
            keep_frame(st, time_of(end_step), D, -1)
            if ckpt_path:
                st.D, st.Dp = D, Dp
                _save_checkpoint(ckpt_path, st, fixed_info)
    if status == "steady":
        if not st.frame_t or st.frame_t[-1] != time_of(st.step):
            keep_frame(st, time_of(st.step), D, -1)

    if status in ("nonfinite", "diverged"):
        D = good_D
    U = D.reshape(shape).copy()
    ok_run = status == "done" and not relax
    steady = status == "steady"
    wall = time.perf_counter() - wall0
    info = {
        "steps": int(st.step),
        "dt": float(dt),
        "dt_initial": float(fixed_info["dt"]),
        "critical_time_step": float(dt_crit),
        "critical_time_step_min": float(st.dtc_min),
        "time_step_rechecks": int(st.rechecks),
        "time_step_reductions": int(st.reductions),
        "critical_time_step_sheet": float(critical_time_step(omega_el, alpha)),
        "critical_step_method": method,
        "omega_max": float(omega),
        "time_step_estimate_s": float(t_est),
        "time_step_force_evals": int(n_est_evals),
        "safety": float(safety),
        "t_final": float(time_of(st.step)),
        "alpha": float(alpha),
        "damping": damping,
        "mass_scaling": float(ms),
        "mass_scaling_mode": ms_mode,
        "energy_balance_error": float(st.balance_err),
        "max_interpenetrated_nodes": int(st.max_interp),
        "wall_time_s": float(wall),
        "element_steps_per_second": float(n_elem * steps_done / t_loop) if t_loop > 0 and steps_done else 0.0,
        "converged": bool(ok_run or steady),
        "steady_state_reached": bool(steady),
        "final_kinetic_energy": float(st.last_ekin),
        "final_relative_residual": float(st.last_rel_res),
        "kinetic_energy": float(last.get("Ek", 0.0)),
        "strain_energy": float(last.get("Es", 0.0)),
        "external_work": float(last.get("Wext", 0.0)),
        "damping_dissipation": float(last.get("Edamp", 0.0)),
        "contact_energy": float(last.get("Ec", 0.0)),
        "contact_work": float(st.contact_work),
        "max_contact_nodes": int(st.max_contact),
        "max_contact_penetration": float(st.max_pen),  # deepest, over every step (p = |f|/k)
        "kinetic_resets": int(st.resets),
        "max_interpenetration_time": float(st.t_max_interp),
        "interpenetrated_nodes_last_sample": int(last.get("interp", 0)),
        "status": status,
    }
    if n_fric:
        info.update({
            "friction": [float(m) for m in fric_of],
            "friction_stiffness_ratio": float(kt_ratio),
            "friction_work": float(-st.fric_work),              # energy taken out by friction
            "friction_stick_energy": float(last.get("Et", 0.0)),  # of it, still stored in the stick springs
            "friction_dissipation": float(-st.fric_work - last.get("Et", 0.0)),
            "max_slipping_nodes": int(st.max_slip),
        })
    if quasi:
        info.update({
            "thickness_strain_energy_jump": float(st.q_jump),
            "thickness_strain_switch_samples": int(st.q_samples),
            "thickness_strain_corner_switches": int(st.q_corners),
        })
    info.update(info_dt)
    if restarted_from is not None:
        info["restarted_from_step"] = int(restarted_from)
    frames = list(zip(st.frame_t, st.frame_U))
    progress(1.0, message)
    return SolveResult(U=U, converged=bool(ok_run or steady), message=message, info=info, frames=frames)


SMALL_MESH_ELEMENTS = 1000
"""Below this many elements the loop runs the force kernel on one thread by default: a step then
takes microseconds and starting/joining the kernel's worker threads every step costs more than it
saves.  Measured on the quiet 2-core machine (benchmarks/explicit_throughput.py --threads 1|2, two
passes, load ~1): 400 quads 1.18/1.20 M element-steps/s on 1 thread vs 0.45/1.83 M on 2; 900 quads
1.27/1.23 M vs 1.87/1.48 M; 1600 quads 1.30/1.21 M vs 2.09/1.56 M; 2500 quads 1.18/1.19 M vs
1.98/2.31 M (benchmarks/dynamic_speed.py).  The results are bitwise the same on any number of
threads (element forces in parallel, one serial scatter).  On a machine whose cores are busy with
other jobs, two threads are much slower (a worker waits a whole time slice for a core: 0.31 M vs
1.76 M at 2500 quads under load 5); pass ``threads=1`` there."""


def _with_threads(problem, settings, progress, relax):
    settings = dict(settings or {})
    threads = settings.get("threads")
    n_elem = int(getattr(getattr(problem.model, "mesh", None), "n_elements", 0))
    try:
        import numba
    except ImportError:  # pragma: no cover - numba is a dependency
        return _integrate(problem, settings, progress, relax)
    old = numba.get_num_threads()
    if threads is None:
        new = 1 if n_elem < SMALL_MESH_ELEMENTS else old
    else:
        new = int(_num(settings, "threads", None, positive=True, integer=True))
        new = min(new, numba.config.NUMBA_NUM_THREADS)
    try:
        numba.set_num_threads(new)
        res = _integrate(problem, settings, progress, relax)
    finally:
        numba.set_num_threads(old)
    res.info["threads"] = int(new)
    return res


@single_threaded_blas
def run(problem: Problem, settings: dict | None = None, progress=no_progress) -> SolveResult:
    """Dynamic drape (Section 4.1): integrate Eq. (23) from t = 0 to ``settings["t_end"]``.
    converged = True when t_end was reached with a finite state.  See the module docstring."""
    return _with_threads(problem, settings, progress, relax=False)


@single_threaded_blas
def run_relax(problem: Problem, settings: dict | None = None, progress=no_progress) -> SolveResult:
    """Dynamic relaxation (Section 4.2): damped explicit dynamics with scaled masses (default α = 5 1/s,
    masses ×100) that stops itself once E_kin / W_ext < tol_kinetic and the relative residual force
    |P - F + C|_free / |P|_free < tol_residual.  ``damping="kinetic"`` uses Cundall's kinetic damping
    (all velocities zeroed at each kinetic-energy peak; ``alpha`` is then ignored: no viscous damping).
    converged = steady_state_reached."""
    return _with_threads(problem, settings, progress, relax=True)
