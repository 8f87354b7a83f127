"""The explicit integrator: central differences, Eq. (23), with the damping of ``damping/`` (Rayleigh,
kinetic, FIRE or modal).

``Integrator(problem, settings)`` estimates the critical step and sets up the start state;
``advance(n)`` takes up to n steps (all remaining when None) and returns the status word;
``state`` is everything that changes (``state.State``); ``result()`` is the SolveResult.
``Integrator.from_state(problem, state, settings)`` continues a state, possibly on another mesh of
the same sheet (the caller transfers D, D_prev and the friction anchors to the new dofs).

Statuses: running (more steps to go), done (t_end reached), steady (relaxation converged),
diverged (the energy balance error exceeded max_energy_error), nonfinite, failed (the force
kernel raised), walltime, interrupted (Ctrl-C).
"""

from __future__ import annotations

import math
import time

import numpy as np

from ... import contact_augment as augment
from ...contact_faces import FacePoints, spacing
from ...contact_kernels import friction_work
from ...contact_rims import NONE as NO_RIM_SHIFT
from ...contact_rims import Rims
from ...contact_self_penalty import SelfPenalty
from ...errors import InputError, SolverError
from ...interfaces import ExplicitModel, SolverProblem
from ...interrupts import deferred_interrupt
from ...model import Model
from ...problem import SolveResult, no_progress
from . import checkpoint, damping, kernels, ledger, observers, report, stepcontrol
from .candidates import Candidates, contact_power, default_margin
from .forces import Forces
from .fused import FusedForces
from .kernels import Coefficients, Dofs, dot, norm
from .settings import FIRE_ALPHA_START, RESTART_NEUTRAL, ExplicitSettings, RelaxSettings, parse_settings
from .state import State

STATUSES = ("running", "done", "steady", "diverged", "nonfinite", "failed", "walltime", "interrupted")
"""The status words of advance() and info["status"]."""


def scaled_mass(model: ExplicitModel, scaling: float = 1.0, mode: str = "uniform") -> np.ndarray:
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


class Integrator:
    """See the module docstring.  ``settings``: an ExplicitSettings / RelaxSettings, or a dict
    (``relax`` says which); ``progress(fraction, text)`` is called within a second and then at least
    every 0.5 s while stepping."""

    def __init__(self, problem: SolverProblem, settings, progress=no_progress, *, relax: bool = False, _start=True):
        self.s = s = (
            parse_settings(settings, relax) if not isinstance(settings, (ExplicitSettings, RelaxSettings)) else settings
        )
        self.relax = s.relax
        self.progress_cb = progress or no_progress
        self.wall0 = time.perf_counter()
        self.status, self.message, self.warnings, self.info_dt = "running", "", [], {}
        self.restarted_from, self.steps_done, self.t_loop = None, 0, 0.0
        self.checkpoint_extra = None  # callable -> dict of arrays saved with each checkpoint
        self.snaps = None  # the snapshot times kept (_snap_filter), None until _prepare
        self._setup(problem)
        if _start:
            self.progress_cb(0.0, "estimating the critical time step")
            lim = stepcontrol.estimate(self.dynamics, self._D0(), s, self.alpha)
            self._bind(lim)
            self.state = self._initial_state(self._first_step(lim), lim)
            self._prepare(fresh=True)

    # ------------------------------------------------------------------ set-up
    def _setup(self, problem: SolverProblem) -> None:
        """Everything fixed for one problem: masses, loads, supports, contact bodies."""
        s = self.s
        self.problem, self.model = problem, problem.model
        # the library's Model: its mesh (contact candidates, throughput) and the fused passes;
        # any other model (interfaces.ExplicitModel) through its own methods
        mesh = self.model.mesh if isinstance(self.model, Model) else None
        self.N = self.model.n_nodes
        self.shape = (self.N, 6)
        self.n_elem = mesh.n_elements if mesh is not None else 0
        self.damping = s.damping if self.relax else "rayleigh"
        self.damper = damping.make(self.damping)
        self.damper_rewrites = bool(self.damper.rewrites_step)
        self.damper_power = bool(self.damper.wants_power)
        self.step_power = None  # (P, v.M.v, R.M^-1.R) of this step when the fused pass formed them
        self.M = M = scaled_mass(self.model, s.mass_scaling, s.mass_scaling_mode)
        self.free_mask = ~problem.fixed
        if np.any(M[self.free_mask] <= 0.0):
            raise InputError(
                f"{int(np.sum(M[self.free_mask] <= 0))} free dof(s) have zero mass: the explicit scheme needs M > 0"
            )
        self.P = problem.loads.ravel().copy()
        self.fixed_idx = np.flatnonzero(problem.fixed.ravel())
        self.free_idx = np.flatnonzero(self.free_mask.ravel())
        self.presc = problem.prescribed.ravel()[self.fixed_idx].copy()
        self.fixed_mask = np.ascontiguousarray(problem.fixed.ravel(), dtype=np.bool_)
        self.presc_full = np.zeros(6 * self.N)
        self.presc_full[self.fixed_idx] = self.presc
        self.bodies = list(problem.contact or [])
        self.fric_of = [float(b.friction) for b in self.bodies]
        self.n_fric = sum(1 for mu in self.fric_of if mu > 0.0)  # 0: the frictionless path
        # the sheet against itself (contact_self_penalty.py): a library Model's mesh only
        self.self_contact = bool(getattr(problem, "self_contact", False)) and mesh is not None
        self.contacting = bool(self.bodies) or self.self_contact  # any contact forces at all
        # the step's contact only at the nodes near a body (candidates.py), into buffers of its own
        self.faces = (
            FacePoints(
                mesh,
                self.model.nodal_areas(),
                s.contact_face_points,
                spacing(self.bodies, self.model.material.thickness),
            )
            if self.bodies and mesh is not None and all(b.code >= 0 for b in self.bodies)
            else None
        )
        # the bodies' sharp edges against the faces (contact_rims.py; opt-in): where the bodies have any
        self.rims = (
            Rims(self.bodies, self.faces, self.model.material.thickness)
            if self.faces is not None and len(self.faces) and s.contact_rims
            else None
        )
        if self.rims is not None and not len(self.rims):
            self.rims = None
        self.cand = (
            Candidates(self.bodies, mesh.nodes, default_margin(mesh), self.faces)
            if self.bodies and mesh is not None
            else None
        )
        self._C = np.zeros(6 * self.N)
        self._anchor_bufs = [np.full((self.n_fric, self.N, 3), np.nan) for _ in range(2)]
        self._all_nodes = np.arange(self.N)
        self.Mf = M.ravel()
        self.invM = np.zeros_like(self.Mf)
        self.invM[self.free_idx] = 1.0 / self.Mf[self.free_idx]
        self.Pn = norm(self.P[self.free_idx])
        self.dofs = Dofs(
            Mf=self.Mf,
            invM=self.invM,
            P=self.P,
            fixed_idx=self.fixed_idx,
            presc=self.presc,
            fixed_mask=self.fixed_mask,
            presc_full=self.presc_full,
            free_idx=self.free_idx,
        )
        self.alpha = self.damper.alpha0(s)  # the viscous alpha [1/s] of Eq. (23) at the start
        self.damping_view = _DampingView(self)
        # the preallocated element/node passes for the library's Model (fused.py), also the force
        # the critical-step estimates differentiate; other models (e.g. a user's with its own
        # internal_force) go through their methods
        self.fused = FusedForces(self.model) if mesh is not None else None
        self.force_fn = self._fused_force if self.fused is not None else self.model.internal_force
        self.dynamics = stepcontrol.Dynamics(
            self.model,
            M,
            self.free_mask,
            self.bodies,
            self.n_fric,
            self.force_fn,
            self.faces,
            self.self_contact,
            self.rims,
        )
        shaping = {k: v for k, v in s.as_dict().items() if k not in RESTART_NEUTRAL}
        self.fingerprint = checkpoint.fingerprint(problem, shaping, M)

    def _fused_force(self, U):
        """Internal force (6N,) at U (N,6) by the fused lane kernel (a new array)."""
        return self.fused.internal(U, False)[0]

    def _bind(self, lim) -> None:
        """Attach a critical-step estimate: penalty stiffness, forces, the energy floor."""
        self.lim = lim
        selfc = SelfPenalty(self.model.mesh, self.model.material.thickness, lim.k_self) if self.self_contact else None
        self.forces = Forces(self.problem, lim.k_pen, lim.k_t, self.fric_of, self.fused, self.faces, selfc, self.rims)
        self.quasi = self.forces.quasi
        self.E_floor = ledger.energy_floor(self.P, self.Mf, self.free_idx, self.forces.X0, lim.omega_el)

    def _state_array(self, a, name):
        if a is None:
            return np.zeros(self.shape)
        if a.size != 6 * self.N:
            raise InputError(f"setting {name} has {a.shape[0]} rows, the mesh has {self.N} nodes ((N, 6) dofs)")
        return np.array(a, dtype=float).reshape(self.shape)

    def _D0(self):
        D0 = self._state_array(self.s.U0, "U0").ravel().copy()
        D0[self.fixed_idx] = self.presc
        return D0

    def _first_step(self, lim) -> float:
        """The start step [s]; an explicit run lands an integer number of steps on t_end."""
        dt = stepcontrol.initial_step(lim, self.s, self.alpha, self.info_dt)
        if not self.relax:
            dt = self.s.t_end / int(math.ceil(self.s.t_end / dt * (1.0 - 1e-12)))
        return dt

    def _initial_state(self, dt, lim) -> State:
        """D_0 from U0 and D_-1 = D_0 - dt V_0 + dt^2/2 A_0, A_0 = M^-1 (P - F_0 + C_0) - alpha V_0."""
        D0 = self._D0()
        V0 = self._state_array(self.s.V0, "V0").ravel().copy()
        V0[self.fixed_idx] = 0.0
        F0, Es0 = self.forces.internal(D0, True)
        anchors0 = np.full((self.n_fric, self.N, 3), np.nan)
        C0, Ec0, _ = self.forces.contact_energy(D0, anchors0)
        Ek0 = 0.5 * dot(self.Mf * V0, V0)
        A0 = self.invM * (self.P - F0 + C0) - self.alpha * V0
        A0[self.fixed_idx] = 0.0
        Dm = D0 - dt * V0 + 0.5 * dt * dt * A0
        Dm[self.fixed_idx] = self.presc
        mi0, qf0 = self.forces.interp_flags(D0)
        quasi = self.quasi
        st = State(
            D=D0.copy(),
            D_prev=Dm,
            step=0,
            dt=dt,
            n_base=0,
            t_base=0.0,
            omega_el=lim.omega_el,
            method=lim.method,
            dt_initial=dt,
            mode=(lim.mode if lim.mode is not None else np.zeros(6 * self.N)),
            rechecks=0,
            reductions=0,
            dtc_min=lim.dt_crit,
            D0=D0,
            Ek0=Ek0,
            Es0=Es0,
            Ec0=Ec0,
            E_init=Ek0 + Es0,
            closed_change=0.0,
            w_ext_closed=0.0,
            remesh_energy_jump=0.0,
            segments=0,
            close_E=Ek0 + Es0 + Ec0,
            close_W=0.0,
            close_PD=dot(self.P, D0),
            damp_sum=0.0,
            ekin_max=Ek0,
            balance_err=0.0,
            contact_work=0.0,
            w_int=0.0,
            w_int_prev=0.0,
            es_prev=Es0,
            qflags=qf0,
            q_jump=0.0,
            q_samples=0,
            q_corners=0,
            q_F=(F0.copy() if quasi else np.zeros(0)),
            q_D=(D0.copy() if quasi else np.zeros(0)),
            anchors=anchors0,
            fric_work=0.0,
            max_slip=0,
            shift_n=augment.NONE,
            shift_q=augment.NONE,
            shift_r=NO_RIM_SHIFT,
            augment_updates=0,
            augment_jump=0.0,
            augment_depth=-1.0,
            augment_best=math.inf,
            augment_stalls=0,
            max_interp=mi0,
            t_max_interp=0.0,
            max_contact=0,
            max_self=0,
            max_pen=0.0,
            ek_prev_half=0.0,
            resets=0,
            last_ekin=Ek0,
            fire_a=float(self.s.fire_alpha_start if self.relax else FIRE_ALPHA_START),
            fire_n=0,
            damper_alpha=float(self.alpha),
            last_rel_res=(norm((self.P - F0 + C0)[self.free_idx]) / self.Pn if self.Pn > 0 else 0.0),
            frame_dt=self._frame_interval(),
        )
        st.fingerprint = self.fingerprint
        return st

    def _frame_interval(self) -> float:
        # a relaxation keeps a frame every 0.05 s of simulated time by default (a time series to
        # watch it settle); max_frames bounds the memory (thinning, observers.keep_frame)
        fi = self.s.frame_interval
        return fi if fi is not None else (0.05 if (self.relax and self.s.frame_every is None) else 0.0)

    def _prepare(self, fresh: bool) -> None:
        """Derived per-run counts and buffers (after the state is set)."""
        s, st = self.s, self.state
        self.fresh = fresh
        n_steps = self._n_steps(st.dt_initial)
        self.sample_every = s.sample_every or max(1, min(100, n_steps // 100))
        self.check_every = s.check_every if self.relax else max(1, n_steps // 100)
        self.frame_every = s.frame_every
        prog_every = s.progress_every or max(1, n_steps // 100)
        self.progress = observers.Progress(self.progress_cb, prog_every, s)
        self.ckpt = observers.Checkpointer(
            s.checkpoint,
            s.checkpoint_every,
            s.checkpoint_wall,
            lambda: self.checkpoint_extra() if self.checkpoint_extra else {},
            self.warnings,
        )
        self.recheck_margin = 0.5 * (1.0 + s.safety)
        self._set_step(st.dt)
        self._snap_filter()
        if fresh and (0 in self.snap_steps or self.relax or not self.snap_steps):
            self._keep(0.0, st.D, -1)
        self.frame_next_t = observers.next_frame_time(st)
        self._Dn1, self._R = np.empty_like(st.D), np.empty_like(st.D)
        self.forces.shift_n, self.forces.shift_q, self.forces.shift_r = st.shift_n, st.shift_q, st.shift_r
        self._widen_candidates()  # a restart after an update selects as the uninterrupted run did
        if st.good_D is None or st.good_D.size != st.D.size:
            st.good_D, st.good_t = st.D.copy(), st.t

    def _n_steps(self, dt) -> int:
        if self.relax:
            return self.s.max_steps if self.s.max_steps is not None else int(math.ceil(self.s.t_max / dt))
        return int(math.ceil(self.s.t_end / dt * (1.0 - 1e-12)))

    def _snap_filter(self) -> None:
        """Snapshot times after t_end are dropped with a warning (e.g. a scene's times with a shorter
        t_end from the command line)."""
        snaps = sorted(self.s.snapshots or []) if not self.relax else []
        late = [x for x in snaps if x > self.s.t_end * (1 + 1e-9)]
        self.snaps = [x for x in snaps if x <= self.s.t_end * (1 + 1e-9)] if late else snaps
        if late and "snapshots_after_t_end_dropped" not in self.info_dt:
            self.info_dt["snapshots_after_t_end_dropped"] = late
            self.warnings.append(
                f"snapshot time(s) {', '.join(f'{x:g}' for x in late)} s after t_end = {self.s.t_end:g} s dropped"
            )
        self.end_step, self.snap_steps = self._schedule()

    def _schedule(self):
        """(end step, {step: snapshot time}) for the current step dt from step n_base at time t_base."""
        st, s = self.state, self.s
        if self.relax:
            if s.max_steps is not None:
                return s.max_steps, {}
            return st.n_base + int(math.ceil((s.t_max - st.t_base) / st.dt * (1.0 - 1e-12))), {}
        return (
            st.n_base + int(round((s.t_end - st.t_base) / st.dt)),
            {st.n_base + int(round((x - st.t_base) / st.dt)): x for x in self.snaps if x >= st.t_base - 0.5 * st.dt},
        )

    def _set_step(self, dt) -> None:
        self.state.dt = dt
        self.coef = Coefficients.of(self.invM, dt, self.alpha)
        if self.snaps is not None:
            self.end_step, self.snap_steps = self._schedule()

    def _keep(self, t, D, k) -> None:
        observers.keep_frame(self.state, t, D, k, self.shape, self.s.max_frames)

    def time_of(self, n: int) -> float:
        st = self.state
        return st.t_base + (n - st.n_base) * st.dt

    # ------------------------------------------------------------------ stepping
    def advance(self, n_steps: int | None = None) -> str:
        """Take up to ``n_steps`` steps (None: to the end); the status word.  A split run
        (advance(a), advance(b)) is bit for bit the run advance(a + b)."""
        if self.status != "running":
            return self.status
        st = self.state
        stop_at = math.inf if n_steps is None else st.step + int(n_steps)  # end_step may move (re-checks)
        t0 = time.perf_counter()
        with np.errstate(over="ignore", invalid="ignore"), deferred_interrupt() as sigint:
            try:
                status = self._loop(stop_at, sigint)
            except KeyboardInterrupt:  # raised outside the loop's own handler (e.g. a callback)
                status = "interrupted"
        self.t_loop += time.perf_counter() - t0
        if status == "running" and st.step >= self.end_step:
            status = "done"
        self.status = status
        self._on_stop(status)
        return status

    def _loop(self, stop_at: int, sigint) -> str:
        st, relax = self.state, self.relax
        D, Dp, Dn1, R = st.D, st.D_prev, self._Dn1, self._R
        while st.step < stop_at and st.step < self.end_step:
            n = st.step
            sample = (n % self.sample_every == 0) or n == self.end_step - 1
            check = relax and (n % self.check_every == 0)
            f, vMv, finite = self._forces_and_step(n, D, Dp, Dn1, sample, R)
            if f is None:
                return "failed"
            vMv, finite_d = self.damper.correct(self.damping_view, n, D, Dp, Dn1, R, vMv)
            finite = finite and finite_d
            if not finite:
                return self._nonfinite(n)
            self._work(n, vMv, f, Dn1, Dp)
            if sample and self._sample(n, D, vMv, f):
                return "diverged"
            if check or (not relax and n == self.end_step - 1):
                # relative to the loads; without loads (prescribed displacements only) relative to
                # the internal forces including the reactions
                st.last_rel_res = norm(R[self.free_idx]) / (self.Pn if self.Pn > 0 else max(norm(f["F"]), 1e-300))
            self._frames(n, D)
            if check and n > 0 and self._steady(n, vMv) and not self._augment(D):
                return "steady"
            self.damper.after(self.damping_view, n, D, Dn1, R, vMv)
            if self.n_fric:
                self._friction_work(f, Dn1, Dp)
            Dp, D, Dn1 = D, Dn1, Dp
            st.D, st.D_prev, st.step = D, Dp, n + 1
            self._Dn1 = Dn1
            self.steps_done += 1
            status = self._after_step(sigint)
            if status != "running":
                return status
        return "running"

    def _forces_and_step(self, n, D, Dp, Dn1, sample, R):
        """Forces at D_n (R = P - F + C) and the step of Eq. (23) into Dn1: (dict of what the step's
        books need, v_n.M.v_n, finite); (None, 0, True) if the force kernel failed.  With the fused
        evaluator (fused.py) force, assembly and update are two compiled passes; contact comes first
        (it depends on D_n only) and is added in the node pass as R = (P - F) + C."""
        st, fused = self.state, self.forces.fused
        try:
            if fused is None:
                F, Es = self.forces.internal(D, sample)
            else:
                f = {}
                C = self._contact(n, D, f)
                # a damper that rewrites the whole step (FIRE) needs only R, except on a fresh
                # run's first step, which is the scheme's own
                r_only = self.damper_rewrites and not (n == 0 and self.fresh)
                vMv, finite, Es = fused.step(
                    D, Dp, Dn1, R, C, self.dofs, self.coef, sample, r_only, r_only and self.damper_power
                )
                F = fused.F
                self.step_power = fused.last_power
        except (FloatingPointError, ZeroDivisionError, SolverError) as exc:
            self.message = f"internal force failed at step {n} (t = {self.time_of(n):.6g} s): {exc}"
            return None, 0.0, True
        if fused is None:
            np.subtract(self.P, F, out=R)
            f = {}
            C = self._contact(n, D, f)
            if C is not None:
                R += C
            vMv, finite = kernels.step(Dn1, D, Dp, R, self.dofs, self.coef)
        f["F"], f["Es"] = F, Es
        if self.quasi and n > 0:
            # work of the internal forces along the path actually taken, trapezoidal rule per
            # step: sum 1/2 (F_m-1 + F_m).(D_m - D_m-1) up to D_n (the same end points as
            # E(D_n) - E(D_0), so that it differs from them only where the energy jumps)
            st.w_int += 0.5 * float(np.add.reduce((F + st.q_F) * (D - st.q_D)))
            st.q_F[:] = F
            st.q_D[:] = D
        return f, vMv, finite

    def _contact(self, n, D, f):
        """Contact (and friction) forces at D_n, their books into f; C (6N,) or None without bodies.
        With candidates (candidates.py) only the nodes near a body are evaluated, C is the step's
        buffer (valid until the next step) and the new anchors go into the buffer st.anchors is
        not: the same forces, anchors and books as evaluating every node."""
        st, cand = self.state, self.cand
        if not self.bodies:
            return self._self_contact(D, f, None) if self.self_contact else None
        nodes, C, new, elements = None, None, None, None
        if cand is not None and cand.enabled:
            if cand.update(D):
                self._C.fill(0.0)  # the previous candidates' entries
            nodes, C, elements = cand.nodes, self._C, cand.elements
            new = self._anchor_bufs[1] if st.anchors is self._anchor_bufs[0] else self._anchor_bufs[0]
        if self.n_fric:
            C, f["Ec"], f["nact"], pen, f["fr"], f["Et"], f["anchors"], f["nslip"] = self.forces.contact_friction(
                D, st.anchors, nodes, C, new, elements
            )
        else:
            C, f["Ec"], f["nact"], pen = self.forces.contact(D, nodes, C, elements)
        f["C"] = C
        f["cnodes"] = self._all_nodes if nodes is None else nodes
        if pen > st.max_pen:
            st.max_pen = pen
        return self._self_contact(D, f, C) if self.self_contact else C

    def _self_contact(self, D, f, C):
        """C (None: no body forces) plus the sheet's self-contact forces at D_n, their energy into
        f["Ec"] and the pairs in contact into f["nself"]."""
        Cs, es, f["nself"] = self.forces.with_self(D, C)
        f["Ec"] = f.get("Ec", 0.0) + es
        f.setdefault("nact", 0)
        if Cs is not C:  # self-contact forces added: non-zero anywhere
            f["C"], f["cnodes"] = Cs, self._all_nodes
        f.setdefault("C", None)  # no bodies, no pair: no contact force at all
        return Cs

    def _nonfinite(self, n) -> str:
        st = self.state
        self.message = (
            f"the solution became non-finite at step {n + 1} (t = {self.time_of(n + 1):.6g} s) with "
            f"dt = {st.dt:.6g} s, critical step {self.lim.dt_crit:.6g} s; returning the last good "
            f"(finite, energy-balanced) state, t = {st.good_t:.6g} s"
        )
        return "nonfinite"

    def _work(self, n, vMv, f, Dn1, Dp) -> None:
        """Damping dissipation (trapezoidal in time) and contact work of step n."""
        st = self.state
        dd = self.alpha * st.dt * vMv
        if n == 0 and self.fresh:
            dd *= 0.5  # trapezoidal rule: the first and last samples weigh half
        st.damp_sum += dd
        if self.contacting and f["C"] is not None:
            st.contact_work += 0.5 * contact_power(f["C"], Dn1, Dp, f["cnodes"])

    def _sample(self, n, D, vMv, f) -> bool:
        """The energy balance at t_n (ledger.py); True when it exceeds max_energy_error."""
        st, t = self.state, self.time_of(n)
        Ek, Es = 0.5 * vMv, f["Es"]
        st.ekin_max = max(st.ekin_max, Ek)
        Wext = ledger.external_work(st, self.P, D)
        # the trapezoidal sum up to t_n: the n-th term weighs half (at n = 0 too: E_damp(0) = 0)
        Edamp = st.damp_sum - 0.5 * self.alpha * st.dt * vMv
        Ecn = f["Ec"] if self.contacting else 0.0
        if self.quasi:
            n_int, qf = self.forces.interp_and_branches(D)
            ledger.book_jumps(st, Es, qf)
        Efric = -st.fric_work if self.n_fric else 0.0  # work done against friction (>= 0 in slip)
        err = ledger.balance_error(st, Ek, Es, Wext, Edamp, Ecn, Efric, self.E_floor)
        if err > self.s.max_energy_error:
            self.message = (
                f"energy balance error {err:.3g} > {self.s.max_energy_error:g} at step {n} (t = {t:.6g} "
                f"s): the run is creating energy (unstable step {st.dt:.6g} s vs critical "
                f"{self.lim.dt_crit:.6g} s, or a non-physical state); returning the last good state, "
                f"t = {st.good_t:.6g} s"
            )
            return True
        st.good_t = t
        st.good_D[:] = D
        ni = n_int if self.quasi else self.forces.interp_count(D)
        if ni > st.max_interp:
            st.max_interp, st.t_max_interp = ni, t
        if self.bodies:
            st.max_contact = max(st.max_contact, f["nact"])
        if self.self_contact:
            st.max_self = max(st.max_self, f["nself"])
        if self.n_fric:
            st.max_slip = max(st.max_slip, f["nslip"])
        st.last_ekin = Ek
        st.last = dict(
            Ek=Ek,
            Es=Es,
            Wext=Wext,
            Edamp=Edamp,
            Ec=Ecn,
            t=t,
            Efric=Efric,
            Et=(f["Et"] if self.n_fric else 0.0),
            interp=ni,
        )
        return False

    def _frames(self, n, D) -> None:
        t = self.time_of(n)
        if n in self.snap_steps and n > 0:
            self._keep(t, D, -1)
        elif self.frame_every and n > 0 and n % self.frame_every == 0:
            self._keep(t, D, -1)
        elif t >= self.frame_next_t:  # inf without interval frames; >= the interval > 0 else
            self._keep(t, D, int(t / self.state.frame_dt))
            self.frame_next_t = observers.next_frame_time(self.state)

    def _steady(self, n, vMv) -> bool:
        st = self.state
        rel_ke = observers.steady(st, self.s, self.P, vMv, self.E_floor)
        if rel_ke is None:
            return False
        self.message = (
            f"steady state at t = {self.time_of(n):.6g} s after {n} steps: E_kin/W_ext = {rel_ke:.3g} "
            f"< {self.s.tol_kinetic:g}, residual {st.last_rel_res:.3g} < {self.s.tol_residual:g}"
        )
        return True

    def _augment(self, D) -> bool:
        """At a steady state: one augmented-Lagrangian update of the contact (contact_augment.py)
        when a node, face point or rim point lies deeper than the target and updates are left; True
        when it updated (the relaxation goes on)."""
        st, forces = self.state, self.forces
        if not (self.relax and self.bodies and forces.augmentable):
            return False
        limit = augment.target(self.model.material.thickness) if isinstance(self.model, Model) else 0.0
        depth, s_n, s_q, s_r = forces.augment(D)
        st.augment_depth = depth
        stop, st.augment_best, st.augment_stalls = augment.tally(
            depth, st.augment_best, st.augment_stalls, st.augment_updates, self.s.contact_augment, limit
        )
        if stop:
            return False
        anchors = st.anchors
        e_old = forces.contact_energy(D, anchors)[1]
        st.shift_n, st.shift_q, st.shift_r = forces.shift_n, forces.shift_q, forces.shift_r = s_n, s_q, s_r
        jump = forces.contact_energy(D, anchors)[1] - e_old  # the potential changed, no work done
        st.augment_jump += jump
        st.Ec0 += jump
        st.augment_updates += 1
        self._widen_candidates()
        self.progress_cb(
            self.progress.fraction(st, st.step, self.end_step),
            f"contact update {st.augment_updates}: deepest {depth:.3g} > {limit:.3g}, relaxing on",
        )
        return True

    def _widen_candidates(self) -> None:
        """A point feels a body while its gap is below its shift: the candidates reach that far."""
        st = self.state
        if self.cand is not None and (st.shift_n.size or st.shift_q.size or st.shift_r.size):
            self.cand.widen(max(float(np.max(a, initial=0.0)) for a in (st.shift_n, st.shift_q, st.shift_r)))

    def _friction_work(self, f, Dn1, Dp) -> None:
        """Friction work by the scheme's own central rule f_t,n.(x_n+1 - x_n-1)/2; new anchors."""
        st = self.state
        FT, nodes = f["fr"]
        st.fric_work += 0.5 * friction_work(FT, nodes, Dn1, Dp)
        st.anchors = f["anchors"]

    def _after_step(self, sigint) -> str:
        """Re-check, checkpoint, progress, wall time and Ctrl-C after step n -> n + 1."""
        st, s = self.state, self.s
        n = st.step
        if s.recheck_every and n % s.recheck_every == 0 and not s.allow_unstable and n < self.end_step:
            self._recheck()
        if self.ckpt.due(n):
            self.ckpt.write(st)
        if self.progress.due(n):
            self.progress.report(st, n, self.end_step, self.time_of(n))
        if s.max_wall_time is not None and n % 100 == 0 and time.perf_counter() - self.wall0 > s.max_wall_time:
            self.message = f"stopped at t = {self.time_of(n):.6g} s: wall-time limit {s.max_wall_time:g} s reached"
            return "walltime"
        if sigint[0]:
            return "interrupted"
        return "running"

    def _recheck(self) -> None:
        """Re-estimate the critical step at the current state; when dt exceeds (1 + safety)/2 of it,
        shorten the step to safety x it, keeping the velocity v_n-1/2."""
        st = self.state
        dtc_now, mode = stepcontrol.recheck(self.dynamics, st.D, st.mode, self.lim, self.alpha)
        if dtc_now is None:
            return
        st.rechecks += 1
        st.mode = mode
        st.dtc_min = min(st.dtc_min, dtc_now)
        if st.dt > self.recheck_margin * dtc_now:
            self._change_step(self.s.safety * dtc_now)
            st.reductions += 1

    def _change_step(self, new: float) -> None:
        """Continue with step ``new`` (an explicit run re-spaced to land on t_end) from the current
        state, keeping the half-step velocity: D_n-1 := D_n - dt_new/dt_old (D_n - D_n-1)."""
        st = self.state
        t_now = self.time_of(st.step)
        if not self.relax and self.s.t_end > t_now:
            new = stepcontrol.landing_step(new, t_now, self.s.t_end)
        st.D_prev[:] = st.D - (new / st.dt) * (st.D - st.D_prev)
        st.t_base, st.n_base = t_now, st.step
        self._set_step(new)

    # ------------------------------------------------------------------ ends
    def _on_stop(self, status: str) -> None:
        """End-of-run bookkeeping: messages, the last frame, the final checkpoint, the books."""
        st = self.state
        if status == "done":
            if self.relax:
                self.message = (
                    f"no steady state within {self.end_step} steps (t = {self.time_of(self.end_step):.6g} "
                    f"s): last residual {st.last_rel_res:.3g} (tol {self.s.tol_residual:g})"
                )
            else:
                self.message = (
                    f"reached t_end = {self.time_of(self.end_step):.6g} s in {self.end_step} steps of "
                    f"{st.dt:.6g} s"
                    + (
                        f" ({st.reductions} step reduction(s) after re-checking the critical step)"
                        if st.reductions
                        else ""
                    )
                )
                self._keep(self.time_of(self.end_step), st.D, -1)
                self.ckpt.write(st)
        elif status == "steady":
            if not st.frame_t or st.frame_t[-1] != self.time_of(st.step):
                self._keep(self.time_of(st.step), st.D, -1)
        elif status == "interrupted":
            self.message = (
                f"interrupted at t = {self.time_of(st.step):.6g} s after {st.step} steps; returning "
                f"the last completed step"
            )
            self.ckpt.write(st)
        if status in ("running", "done", "steady", "walltime", "interrupted"):
            self._read_books()

    def _read_books(self) -> None:
        """The energies now (close_E = E_kin + E_strain + E_contact), the run's external work and the
        loads' P.D (minus their potential), the end readings of the ledger segment should the next
        advance happen on another mesh."""
        try:
            e = self.energies()
        except (FloatingPointError, ZeroDivisionError, SolverError, ValueError):
            return
        self.state.close_E = e["kinetic_central"] + e["strain"] + e["contact"]
        self.state.close_W = e["external_work"]
        self.state.close_PD = dot(self.P, self.state.D)

    def energies(self) -> dict:
        """Energies at the current state D_n: kinetic 1/2 v.M.v with the half-step velocity
        v_n-1/2 = (D_n - D_n-1)/dt, and ``kinetic_central`` with the central velocity v_n = (D_n+1 -
        D_n-1)/(2 dt) of a trial step (the measure of the ledger's samples), strain, contact (penalty,
        incl. friction stick springs), the run's external work and damping dissipation so far.
        Nothing of the state changes."""
        st = self.state
        v = (st.D - st.D_prev) / st.dt
        F, Es = self.forces.internal(st.D, True)
        C, Ec, _ = self.forces.contact_energy(st.D, st.anchors)
        return {
            "kinetic": 0.5 * dot(self.Mf * v, v),
            "kinetic_central": 0.5 * self._trial_vMv(F, C),
            "strain": float(Es),
            "contact": float(Ec),
            "external_work": ledger.external_work(st, self.P, st.D),
            "damping_dissipation": float(st.damp_sum),
        }

    def _trial_vMv(self, F, C) -> float:
        """v_n.M.v_n of the central velocity of the step the scheme would take from D_n (Eq. 23),
        without taking it.  Right after a mesh change the out-of-balance force is large and the
        half-step and central velocities differ by its impulse over dt/2; the segment's reference
        kinetic energy must be measured as the samples measure it."""
        st = self.state
        R = self.P - F
        if np.size(C) == R.size:
            R += np.asarray(C).ravel()
        vMv, _ = kernels.step(np.empty_like(st.D), st.D, st.D_prev, R, self.dofs, self.coef)
        return float(vMv)

    def result(self) -> SolveResult:
        """The SolveResult of the run so far (U, converged, message, info, frames)."""
        st, status = self.state, self.status
        D = st.good_D if status in ("nonfinite", "diverged") else st.D
        ok = (status == "done" and not self.relax) or status == "steady"
        info = report.info(self, ok)
        self.progress_cb(1.0, self.message.replace("\n", " "))
        return SolveResult(
            U=D.reshape(self.shape).copy(),
            converged=bool(ok),
            message=self.message,
            info=info,
            frames=list(zip(st.frame_t, st.frame_U)),
        )

    # ------------------------------------------------------------------ continuing a state
    @classmethod
    def from_state(
        cls,
        problem: SolverProblem,
        state: State,
        settings,
        *,
        reestimate_step: bool = True,
        new_segment: bool = True,
        progress=no_progress,
        relax: bool = False,
    ) -> Integrator:
        """Continue ``state`` on ``problem`` (possibly another mesh: D, D_prev and anchors already on
        its dofs).  reestimate_step: the critical step is estimated anew at the state (Lanczos) and,
        when dt changes, the velocity kept; else state.dt is reused exactly.  new_segment: the ledger
        references are taken at the state (totals carry over; the energy change since the last
        reading is booked as remesh_energy_jump); False only to continue the very same run (a
        restart).  ``state`` is taken over, not copied."""
        integ = cls(problem, settings, progress, relax=relax, _start=False)
        integ._adopt(state, reestimate_step, new_segment)
        return integ

    @classmethod
    def resume(
        cls,
        problem: SolverProblem,
        state: State,
        settings,
        *,
        source="the checkpoint",
        progress=no_progress,
        relax: bool = False,
    ) -> Integrator:
        """Continue a checkpointed ``state`` (``checkpoint.load``) bit for bit: refused (InputError
        naming the differing items) unless it was written by a run of this very problem and these
        settings (``state.fingerprint``)."""
        integ = cls(problem, settings, progress, relax=relax, _start=False)
        checkpoint.check_fingerprint(state.fingerprint, integ.fingerprint, source)
        integ._adopt(state, reestimate_step=False, new_segment=False)
        integ.restarted_from = state.step
        return integ

    def _adopt(self, st: State, reestimate_step: bool, new_segment: bool) -> None:
        self._check_sizes(st)
        self.progress_cb(0.0, f"continuing at t = {st.t:.4g} s, step {st.step}")
        self.state = st
        if self.damper.varies_alpha:
            self.alpha = float(st.damper_alpha)  # the estimate the run had reached
        if reestimate_step:
            # warm-started from the state's top mode when it has one (e.g. carried over a remesh),
            # then to the re-checks' tolerance; forward differences from the state's force, half
            # the evaluations of the central ones: this estimate was 30-43 % of the remeshing
            # (docs/adaptivity.md)
            warm = bool(np.any(st.mode))
            lim = stepcontrol.estimate(
                self.dynamics,
                st.D,
                self.s,
                self.alpha,
                v0=st.mode if warm else None,
                difference="forward",
                tol=stepcontrol.WARM_TOL if warm else None,
            )
        else:
            lim = stepcontrol.limit(st.omega_el, st.method, self.dynamics, self.s, self.alpha)
        self._bind(lim)
        if reestimate_step:
            # dtc_min is the smallest critical step of the problem being stepped (FIRE's dt_max is
            # safety x it): a new segment is a new mesh, whose estimate at this state replaces the
            # earlier meshes' (an earlier, stiffer mesh's limit capped the adaptive square-pedestal
            # FIRE run at 0.81 x its own stable step: docs/adaptivity.md)
            st.omega_el, st.method = lim.omega_el, lim.method
            st.dtc_min = lim.dt_crit if new_segment else min(st.dtc_min, lim.dt_crit)
            st.mode = lim.mode if lim.mode is not None else np.zeros(6 * self.N)
        self._prepare(fresh=False)
        if reestimate_step:
            new = stepcontrol.initial_step(lim, self.s, self.alpha, self.info_dt)
            if new != st.dt:
                self._change_step(new)
        if new_segment:
            self._open_segment()
        st.fingerprint = self.fingerprint

    def _check_sizes(self, st: State) -> None:
        n6 = 6 * self.N
        bad = [k for k, a in (("D", st.D), ("D_prev", st.D_prev)) if np.asarray(a).size != n6]
        if not self.n_fric:
            st.anchors = np.zeros((0, self.N, 3))  # nothing to remap without a frictional body
        elif np.asarray(st.anchors).shape != (self.n_fric, self.N, 3):
            bad.append(f"anchors {np.asarray(st.anchors).shape} (want {(self.n_fric, self.N, 3)})")
        if bad:
            raise InputError(
                f"the state does not fit this problem ({self.N} nodes, {self.n_fric} frictional "
                f"bodies): {', '.join(bad)}"
            )
        st.D = np.array(st.D, dtype=float).ravel()
        st.D_prev = np.array(st.D_prev, dtype=float).ravel()
        if np.asarray(st.mode).size != n6:
            st.mode = np.zeros(n6)
        nb, P = len(self.bodies), (len(self.faces) if self.faces is not None else 0)
        R = len(self.rims) if self.rims is not None else 0
        if np.shape(st.shift_n) != (nb, self.N) or np.shape(st.shift_q) != (nb, P) or st.shift_r.size not in (0, R):
            # another mesh: the updates start over
            st.shift_n, st.shift_q, st.shift_r, st.augment_updates = augment.NONE, augment.NONE, NO_RIM_SHIFT, 0
            st.augment_best, st.augment_stalls = math.inf, 0

    def _open_segment(self) -> None:
        """A new ledger segment at the current state (ledger.py), and the quasi-strain work and
        branch references there."""
        st = self.state
        ledger.close_segment(st)
        st.D0 = st.D.copy()  # the new segment's external work starts here
        e = self.energies()
        ledger.open_segment(st, e["kinetic_central"], e["strain"], e["contact"], st.D, dot(self.P, st.D))
        F, Es = self.forces.internal(st.D, True)
        st.es_prev, st.w_int_prev = Es, st.w_int
        st.q_F = F.copy() if self.quasi else np.zeros(0)
        st.q_D = st.D.copy() if self.quasi else np.zeros(0)
        n_int, st.qflags = self.forces.interp_flags(st.D)
        st.good_D, st.good_t = st.D.copy(), st.t
        self._read_books()


class _DampingView:
    """What the damper sees of its run (interfaces.DampingView): the settings, the dof arrays, the
    state, the critical step and the few operations a damper performs on the scheme -- the
    integrator itself stays out of its reach."""

    __slots__ = ("_integ", "dofs", "settings")

    def __init__(self, integ: Integrator):
        self._integ = integ
        self.settings = integ.s
        self.dofs = integ.dofs

    @property
    def state(self) -> State:
        return self._integ.state

    @property
    def fresh(self) -> bool:
        return self._integ.fresh

    @property
    def step_power(self):
        return self._integ.step_power

    @property
    def dt_crit(self) -> float:
        return self._integ.lim.dt_crit

    def time_of(self, n: int) -> float:
        return self._integ.time_of(n)

    def change_step(self, n: int, dt: float) -> None:
        """The steps from t_n on are dt: t_n stays where it is."""
        integ = self._integ
        st = integ.state
        st.t_base, st.n_base = integ.time_of(n), n
        integ._set_step(dt)

    def set_alpha(self, alpha: float) -> None:
        """The viscous alpha from now on: Eq. (23)'s coefficients re-formed at the current step."""
        integ = self._integ
        integ.alpha = alpha
        integ.state.damper_alpha = alpha
        integ._set_step(integ.state.dt)

    def central_step(self, Dn1, D, Dp, R):
        return kernels.step(Dn1, D, Dp, R, self.dofs, self._integ.coef)

    def stiffness(self, D):
        """The model's tangent at D plus the contact (and stick) springs, (6N, 6N) CSR."""
        import scipy.sparse as sp

        integ = self._integ
        K = integ.model.tangent(D.reshape(integ.shape)).tocsr()
        cb = integ.forces.contact_stiffness(D, integ.state.anchors)
        if cb is not None:
            K = K + sp.csr_matrix((cb[2], (cb[0], cb[1])), shape=K.shape)
        return K
