"""The explicit integrator as a component: split runs, continuing a state on a renumbered mesh,
relaxation restarts, checkpoints (extra arrays, fingerprints, damaged files), Ctrl-C, progress and
bad settings.  Tiny meshes (a few dozen quads): the file runs in well under a minute."""

import math
import os
import signal
import time

import numpy as np
import pytest
from test_explicit import ISO, cantilever, incline, plate

from solidshell import Fabric, InputError, IsotropicShell
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers import explicit, validate
from solidshell.solvers.explicit import Integrator, checkpoint
from solidshell.units import G0

# keys that measure the machine, not the run
CLOCK = ("wall_time_s", "element_steps_per_second", "time_step_estimate_s")


def same_run(a, b):
    """Bit-for-bit the same state, frames and info (clock readings aside)."""
    sa, sb = a.state, b.state
    assert np.array_equal(sa.D, sb.D) and np.array_equal(sa.D_prev, sb.D_prev)
    assert sa.frame_t == sb.frame_t and all(np.array_equal(x, y) for x, y in zip(sa.frame_U, sb.frame_U))
    ia, ib = a.result().info, b.result().info
    assert {k: v for k, v in ia.items() if k not in CLOCK} == {k: v for k, v in ib.items() if k not in CLOCK}


CASES = {
    # snapshots, thinned interval frames and critical-step re-checks on a hanging strip
    "explicit": (
        lambda: cantilever(gravity=0.01),
        dict(
            t_end=0.05,
            alpha=5.0,
            snapshots=[0.01, 0.03],
            sample_every=7,
            frame_interval=0.002,
            max_frames=8,
            recheck_every=150,
        ),
        False,
    ),
    # kinetic damping resets and the steady-state test
    "relax": (
        lambda: cantilever(Fabric.wool(), nx=6, ny=1, L=3.0, W=0.5, gravity=1.0),
        dict(damping="kinetic", mass_scaling=1e4, mass_scaling_mode="director", max_steps=3000),
        True,
    ),
    # Coulomb friction anchors
    "friction": (lambda: incline(30.0, 0.55)[0], dict(t_end=0.02, alpha=1.0, sample_every=7), False),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_split_advance_is_bit_for_bit(case):
    make, s, relax = CASES[case]
    prob = make()
    whole = Integrator(prob, s, relax=relax)
    whole.advance()
    n = whole.state.step
    assert n > 30
    split = Integrator(prob, s, relax=relax)
    assert split.advance(n // 3) == "running" and split.state.step == n // 3
    split.advance(1)
    split.advance()
    assert split.status == whole.status
    same_run(split, whole)


def renumbered(prob, perm):
    """The same problem with node i of ``prob`` as node inv[i] (perm: new -> old)."""
    m = prob.model.mesh
    inv = np.argsort(perm)
    mesh = type(m)(m.nodes[perm], quads=inv[m.quads])
    return Problem(Model(mesh, prob.model.material), prob.fixed[perm], prob.loads[perm], prob.prescribed[perm])


def to_new(D, perm):
    return D.reshape(-1, 6)[perm].ravel().copy()


@pytest.mark.parametrize("reestimate", [False, True])
def test_from_state_on_a_renumbered_mesh_continues_the_run(reestimate):
    """The hanging strip's state moved mid-run onto the same mesh with its nodes renumbered: the
    continued run is the same motion (the force sums run in another order: round-off only when the
    step is kept; with the step re-estimated, 1e-6 relative Lanczos accuracy changes dt and the path
    by ~1e-6), the remesh jump is zero to round-off and the ledger stays closed across the change."""
    prob = cantilever(gravity=0.01)
    s = dict(t_end=0.05, alpha=5.0, sample_every=7)
    ref = Integrator(prob, s)
    ref.advance()
    a = Integrator(prob, s)
    a.advance(ref.state.step // 2)
    e_before = a.energies()
    perm = np.random.default_rng(1).permutation(prob.model.n_nodes)
    st = a.state
    st.D, st.D_prev = to_new(st.D, perm), to_new(st.D_prev, perm)
    new = renumbered(prob, perm)
    b = Integrator.from_state(new, st, s, reestimate_step=reestimate)
    e_after = b.energies()
    W = e_before["external_work"]
    # same state on the same sheet: energies agree to round-off (1e-9 of the work done so far)
    for k in ("strain", "external_work", "damping_dissipation"):
        assert e_after[k] == pytest.approx(e_before[k], abs=1e-9 * W), k
    b.advance()
    r, i = b.result(), b.result().info
    assert r.converged and i["t_final"] == pytest.approx(0.05, rel=1e-12)
    assert i["ledger_segments"] == 2 and abs(i["remesh_energy_jump"]) < 1e-6 * W
    U = r.U[np.argsort(perm)]
    moved = np.max(np.abs(ref.state.D))
    tol = 1e-6 if reestimate else 1e-10
    assert np.max(np.abs(U.ravel() - ref.state.D)) < tol * moved
    # the balance reads the whole run: as small as the uninterrupted run's (which is ~1e-5)
    assert i["energy_balance_error"] < 2 * ref.result().info["energy_balance_error"] + 1e-6
    assert i["steps"] == ref.state.step or reestimate
    with pytest.raises(InputError, match="does not fit"):
        Integrator.from_state(cantilever(nx=4), b.state, s)


def falling_plate(n):
    mesh = plate(n, n, 1.0, 1.0)
    model = Model(mesh, ISO)
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -model.lumped_mass()[:, 0] * G0
    return Problem(model, np.zeros((mesh.n_nodes, 6), bool), loads)


def test_from_state_onto_a_refined_mesh_of_a_falling_sheet():
    """A free-falling plate moves rigidly (no strain), so its state transfers exactly to a refined
    mesh (every node the same translation).  With the director masses x1e4 the membrane mode limits
    the step, so halving the elements about halves it: the step is re-estimated and the half-step
    velocity v kept.  From then on the scheme moves the sheet exactly as w + v tau + a tau (tau +
    dt)/2 (central differences are exact for constant acceleration: round-off, 1e-9 allowed); the
    remesh keeps the total mass and v_n-1/2.  Keeping v_n-1/2 (read at t_n - dt_old/2, used at
    t_n - dt_new/2) is a first-order jolt, a change of the central velocity v_n = v_n-1/2 + a dt/2 by
    dv = a (dt_new - dt_old)/2 and of the kinetic energy by m v dv: the ledger measures both sides of
    the change with the central velocity of its samples, so it books exactly that as the remesh
    jump (to 2 %: m v dv is its first-order term) and the balance stays at round-off (1e-9 allowed)."""
    s = dict(t_end=0.1, alpha=0.0, sample_every=5, mass_scaling=1e4, mass_scaling_mode="director")
    a = Integrator(falling_plate(2), s)
    a.advance(a.end_step // 2)
    st, t_mid, n_mid, dt_old = a.state, a.state.t, a.state.step, a.state.dt
    w, wp = st.D[2], st.D_prev[2]
    assert np.all(st.D.reshape(-1, 6)[:, 2] == w)  # rigid: every node the same
    fine = falling_plate(4)
    N = fine.model.n_nodes
    st.D, st.D_prev = np.zeros((N, 6)), np.zeros((N, 6))
    st.D[:, 2], st.D_prev[:, 2] = w, wp
    b = Integrator.from_state(fine, st, s)
    dt = b.state.dt
    assert dt < 0.75 * dt_old and b.state.t == t_mid
    v = (w - wp) / dt_old
    assert (b.state.D[2] - b.state.D_prev[2]) / dt == pytest.approx(v, rel=1e-12)  # velocity kept
    b.advance()
    r = b.result()
    i = r.info
    assert r.converged and i["t_final"] == pytest.approx(0.1, rel=1e-12)
    tau, acc = 0.1 - t_mid, -G0
    assert np.allclose(r.U[:, 2], w + v * tau + 0.5 * acc * tau * (tau + dt), rtol=1e-9, atol=0)
    assert np.max(np.abs(r.U[:, [0, 1, 3, 4, 5]])) < 1e-12 * G0
    dv = G0 * (dt_old - dt) / 2
    mass = fine.model.lumped_mass()[:, 0].sum()
    assert i["ledger_segments"] == 2
    assert -i["remesh_energy_jump"] == pytest.approx(mass * abs(v) * dv, rel=0.02)
    assert i["energy_balance_error"] < 1e-9 and i["steps"] > 2 * n_mid


def relax_whole_and_restarted(prob, s, ck):
    """(the uninterrupted relaxation, the same run stopped past half-way by its progress callback
    and restarted from the checkpoint ``ck`` it wrote every 37 steps)."""
    full = explicit.run_relax(prob, s)
    cks = dict(checkpoint=ck, checkpoint_every=37, progress_every=50)

    class Stop(Exception):
        pass

    def stop(frac, text):
        if 0.5 < frac < 1.0:
            raise Stop("stopped by the progress callback")

    with pytest.raises(Stop, match="stopped by the progress callback"):
        explicit.run_relax(prob, {**s, **cks}, progress=stop)
    return full, explicit.run_relax(prob, {**s, **cks, "restart": ck})


def test_relaxation_restart_bit_for_bit(tmp_path):
    prob = cantilever(Fabric.wool(), nx=6, ny=1, L=3.0, W=0.5, gravity=1.0)
    s = dict(
        damping="kinetic",
        mass_scaling=1e4,
        mass_scaling_mode="director",
        tol_residual=1e-4,
        tol_kinetic=1e-8,
        sample_every=7,
    )
    full, again = relax_whole_and_restarted(prob, s, str(tmp_path / "relax.npz"))
    assert full.converged and full.info["kinetic_resets"] > 0
    assert 0 < again.info["restarted_from_step"] < full.info["steps"]
    assert np.array_equal(again.U, full.U) and again.message == full.message
    for k in ("steps", "energy_balance_error", "kinetic_resets", "final_relative_residual", "damping_dissipation"):
        assert again.info[k] == full.info[k], k
    assert [t for t, _ in again.frames] == [t for t, _ in full.frames]


def test_checkpoint_keeps_extra_arrays_and_is_atomic(tmp_path):
    integ = Integrator(cantilever(gravity=0.01), dict(t_end=0.01))
    integ.advance(20)
    p = tmp_path / "c.npz"
    levels = np.arange(12).reshape(3, 4)
    checkpoint.save(p, integ.state, {"levels": levels})
    assert os.listdir(tmp_path) == ["c.npz"]  # no temporary file left behind
    st, extra = checkpoint.load(p)
    assert np.array_equal(extra["levels"], levels) and st.step == 20
    assert np.array_equal(st.D, integ.state.D) and st.fingerprint == integ.fingerprint
    # a cut file (an interrupted copy) is one line of InputError, not a traceback
    data = p.read_bytes()
    p.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match="cannot read restart file"):
        checkpoint.load(p)
    with pytest.raises(InputError, match="does not exist"):
        checkpoint.load(tmp_path / "none.npz")


def test_restart_of_another_run_is_refused_naming_what_differs(tmp_path):
    """A 100x heavier sheet has a 10x longer critical step: continuing its checkpoint would run this
    one 10x above its stability limit.  The refusal names the differing items."""
    s = dict(t_end=0.01, alpha=5.0, checkpoint=str(tmp_path / "c.npz"), checkpoint_every=20)
    explicit.run(cantilever(gravity=0.01), s)
    heavy = IsotropicShell(E=1e5, nu=0.3, h=0.1, density=100.0)
    with pytest.raises(InputError, match="masses") as e:
        explicit.run(cantilever(heavy, gravity=0.01), {**s, "restart": s["checkpoint"]})
    assert "material" in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(InputError, match="setting t_end"):
        explicit.run(cantilever(gravity=0.01), {**s, "t_end": 0.02, "restart": s["checkpoint"]})
    # the restart-neutral settings may change (checkpoint interval, wall-time limit, threads)
    r = explicit.run(
        cantilever(gravity=0.01),
        {**s, "checkpoint_every": 7, "max_wall_time": 100.0, "threads": 1, "restart": s["checkpoint"]},
    )
    assert r.converged and r.info["restarted_from_step"] > 0


@pytest.mark.parametrize("how", ["signal", "raise"])
def test_ctrl_c_returns_the_last_completed_step(tmp_path, how):
    """Ctrl-C: converged False, status interrupted, the state of a completed step, a checkpoint of
    it; resumed from that checkpoint the run is bit for bit the uninterrupted one."""
    prob = cantilever(gravity=0.01)
    s = dict(t_end=0.03, alpha=5.0, sample_every=7, progress_every=40)
    full = explicit.run(prob, s)
    ck = str(tmp_path / "c.npz")

    def ctrl_c(frac, text):
        if 0.3 < frac < 1.0:
            if how == "signal":
                os.kill(os.getpid(), signal.SIGINT)
            else:
                raise KeyboardInterrupt

    r = explicit.run(prob, {**s, "checkpoint": ck}, progress=ctrl_c)
    assert not r.converged and r.info["status"] == "interrupted" and "interrupted" in r.message
    assert 0 < r.info["steps"] < full.info["steps"]
    st, _ = checkpoint.load(ck)
    assert st.step == r.info["steps"] and np.array_equal(st.D.reshape(-1, 6), r.U)
    again = explicit.run(prob, {**s, "checkpoint": ck, "restart": ck})
    assert np.array_equal(again.U, full.U) and again.info["energy_balance_error"] == full.info["energy_balance_error"]


def test_late_snapshots_warn_and_progress_is_prompt_monotone_and_clean():
    calls = []
    t0 = time.perf_counter()
    r = explicit.run(
        cantilever(gravity=0.01),
        dict(t_end=0.01, snapshots=[0.004, 0.5, 0.7]),
        progress=lambda f, t: calls.append((time.perf_counter() - t0, f, t)),
    )
    (w,) = r.info["warnings"]
    assert "0.5" in w and "0.7" in w and "\n" not in w and r.info["snapshots_after_t_end_dropped"] == [0.5, 0.7]
    assert calls[0][0] < 1.0  # the first call before any real work
    fr = [f for _, f, _ in calls]
    assert fr == sorted(fr) and fr[-1] == 1.0 and all("\n" not in t for _, _, t in calls)
    # a relaxation's fraction moves with the residual, not with t / t_max (t_max = 60 s, the
    # strip settles in ~1-3 s): the last fraction before the end is far above t / t_max
    calls.clear()
    rr = explicit.run_relax(
        cantilever(Fabric.wool(), nx=6, ny=1, L=3.0, W=0.5, gravity=1.0),
        dict(damping="kinetic", mass_scaling=1e4, mass_scaling_mode="director", progress_every=50),
        progress=lambda f, t: calls.append((0, f, t)),
    )
    fr = [f for _, f, _ in calls]
    assert rr.converged and fr == sorted(fr)
    assert fr[-2] > 0.5 and fr[-2] > 10 * rr.info["t_final"] / 60.0


@pytest.mark.parametrize(
    "key,value,match",
    [
        ("U0", "abc", "U0"),
        ("U0", np.zeros((3, 6)), "U0 has 3 rows"),
        ("V0", [np.nan] * 6, "finite"),
        ("checkpoint", 5, "checkpoint"),
        ("restart", 5.0, "restart"),
        ("safety", 1.2, "safety"),
        ("t_end", -1.0, "t_end"),
        ("sample_every", 2.5, "sample_every"),
        ("recheck_every", -1, "recheck_every"),
        ("critical_step_method", "qr", "critical_step_method"),
        ("snapshots", ["a"], "snapshots"),
        ("alpha", math.inf, "alpha"),
        ("max_frames", 0, "max_frames"),
        ("tend", 1.0, "unknown explicit setting"),
    ],
)
def test_bad_settings_are_one_line_input_errors(key, value, match):
    s = {"t_end": 1e-4, key: value}
    with pytest.raises(InputError, match=match) as e:
        explicit.run(cantilever(), s)
    assert "\n" not in str(e.value)


def test_settings_schema_defaults_and_registry():
    ex = validate("explicit", {"t_end": 1.0})
    rx = validate("relax", {})
    assert (ex.alpha, ex.mass_scaling, ex.safety, ex.recheck_every, ex.max_frames) == (5.0, 1.0, 0.9, 10000, 100)
    assert (rx.mass_scaling, rx.damping, rx.tol_kinetic, rx.tol_residual, rx.t_max, rx.check_every) == (
        100.0,
        "rayleigh",
        1e-6,
        1e-3,
        60.0,
        100,
    )
    assert validate("explicit", {"t_end": 1.0, "safety": 1.5, "allow_unstable": True}).safety == 1.5
    with pytest.raises(InputError, match="t_end"):
        validate("explicit", {})
    with pytest.raises(InputError, match="max_steps"):
        validate("relax", {"max_steps": "abc"})


def test_fire_on_a_new_mesh_steps_at_that_mesh_s_own_stable_step():
    """FIRE's largest step is safety x the smallest critical step of the problem it steps
    (state.dtc_min).  A state moved from a fine mesh onto a coarser one (an adaptive merge) gets
    the coarse mesh's estimate there, not the fine mesh's smaller one: on the falling plate (no
    freeze: gravity's power F.v stays positive) the step stays at safety x the coarse critical step
    (exactly: FIRE's growth is capped at it) and is more than 1.5 x the fine mesh's (halving the
    elements about halves the membrane-limited step: 1.48e-3 against 7.48e-4 s).  Before, dtc_min carried the fine mesh's limit
    over and FIRE cut the coarse mesh's step back to it at its first growth."""
    s = dict(damping="fire", mass_scaling=1e4, mass_scaling_mode="director", max_steps=400)
    a = Integrator(falling_plate(4), s, relax=True)
    a.advance(100)
    st, dtc_fine = a.state, a.lim.dt_crit
    w, wp, resets = st.D[2], st.D_prev[2], st.resets  # (the start on the fine mesh froze thrice)
    coarse = falling_plate(2)
    N = coarse.model.n_nodes
    st.D, st.D_prev = np.zeros((N, 6)), np.zeros((N, 6))
    st.D[:, 2], st.D_prev[:, 2] = w, wp
    b = Integrator.from_state(coarse, st, s, relax=True)
    assert b.lim.dt_crit > 1.5 * dtc_fine
    assert b.state.dtc_min == b.lim.dt_crit
    b.advance(100)
    assert b.state.resets == resets and b.state.fire_n > 50
    assert b.state.dt == 0.9 * b.lim.dt_crit


def test_fingerprint_tells_per_quad_membranes_apart():
    """A model with one membrane per quad (an adaptive mesh's coarse "ans" and finest "full") is
    fingerprinted by its membrane array: the same choice gives the same digest, one quad changed
    another (a restart on another mesh's membranes is refused), and one value for all quads keeps
    the digest of the plain string (uniform runs' checkpoints still continue)."""
    mesh = plate(2, 2, 1.0, 1.0)
    n = len(mesh.quads)

    def fp(membrane):
        m = Model(mesh, ISO, membrane=membrane)
        return checkpoint.fingerprint(
            Problem(m, np.zeros((mesh.n_nodes, 6), bool), np.zeros((mesh.n_nodes, 6))), {}, m.lumped_mass()
        )["material"]

    mixed = ["ans"] + ["full"] * (n - 1)
    assert fp(tuple(mixed)) == fp(list(mixed))
    assert fp(tuple(mixed)) != fp(tuple(["full"] * n)) != fp("full")
    assert fp("full") == checkpoint.digest([ISO, False, 0.5, "full"])
