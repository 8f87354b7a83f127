"""Static solver robustness (issue 11 parts 1-3): the same answer and iteration count in any unit
system and at any load level, Newton in <= 3 iterations in the linear regime, saddles left for a
minimum, zero load, Ctrl-C, progress, typed settings, and a finely drawn arc-length path checked
against displacement control."""

import re

import numpy as np
import pytest

from solidshell.boundary import clamp, surface_load
from solidshell.errors import InputError
from solidshell.material import IsotropicShell
from solidshell.meshing import build_mesh
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers import validate
from solidshell.solvers.static import run, solve_static
from solidshell.units import GF_IN_N

# (force unit in gf, length unit in cm) of each system: gf-cm, N-m, N-mm
UNITS = {"gf-cm": (1.0, 1.0), "N-m": (1.0 / GF_IN_N, 100.0), "N-mm": (1.0 / GF_IN_N, 0.1)}


def wool_like_strip(units, load, n=10):
    """A 5 x 1 cm cantilever strip with the wool-weight isotropic section of issue 11 (E h = 1118
    gf/cm, D = 0.083 gf cm, weight 0.019 gf/cm^2), clamped at x = 0, under ``load`` times its own
    weight, expressed in ``units``.  Returns (mesh, model, fixed, P, length unit in cm)."""
    fu, lu = UNITS[units]  # 1 force unit = fu gf, 1 length unit = lu cm
    mesh = build_mesh("strip", f"{n}x1", length=5.0 / lu, width=1.0 / lu)
    mat = IsotropicShell(E=37457.0 / fu * lu**2, nu=0.0, h=0.02985 / lu)
    model = Model(mesh, mat)
    P = surface_load(model, load * 0.019 / fu * lu**2)
    return mesh, model, clamp(mesh, "clamped"), P, lu


LOADS = [1e-8, 1e-6, 1e-4, 1e-2, 1.0]


@pytest.fixture(scope="module")
def unit_load_table():
    """{(units, load): (iterations, U with U_o in cm, result)} for every unit system and load."""
    out = {}
    for units in UNITS:
        for load in LOADS:
            mesh, model, fixed, P, lu = wool_like_strip(units, load)
            r = solve_static(model, fixed, P)
            U = r.U.copy()
            U[:, :3] *= lu  # positions in cm; the director dofs are unit-free
            out[units, load] = (r.info["iterations"], U, r)
    return out


def test_every_unit_system_and_load_level_converges(unit_load_table):
    for (units, load), (_, _, r) in unit_load_table.items():
        assert r.converged, (units, load, r.message)
        assert r.info["positive_definite"] is True, (units, load)


def test_same_answer_and_iterations_in_every_unit_system(unit_load_table):
    """The unit change is an exact rescaling of the discrete equations; only round-off differs.
    The displacements (in cm) agree to 1e-8 of the largest one (the issue's bound; measured
    <= 2e-15, verification/static_units.py: every step control is in length units and every
    tolerance relative, so the iterations are the same up to round-off), and the iteration counts
    to 3 (measured: identical)."""
    for load in LOADS:
        it0, U0, _ = unit_load_table["gf-cm", load]
        scale = np.abs(U0).max()
        for units in ("N-m", "N-mm"):
            it, U, _ = unit_load_table[units, load]
            assert abs(it - it0) <= 3, (units, load, it, it0)
            assert np.abs(U - U0).max() <= 1e-8 * scale, (units, load)


def test_linear_regime_is_linear_and_newton_is_fast(unit_load_table):
    """Below 1e-4 of the working load the strip is in its linear regime: U / load is the same at
    1e-8 and 1e-6 to 1e-5 (the quadratic terms are O(deflection / thickness) ~ 1e-2 x load ratio at
    1e-6), and Newton needs at most 3 iterations (1 when the predictor is already linear-exact)."""
    for units in UNITS:
        U8 = unit_load_table[units, 1e-8][1] / 1e-8
        U6 = unit_load_table[units, 1e-6][1] / 1e-6
        assert np.abs(U8 - U6).max() <= 1e-5 * np.abs(U8).max()
        for load in (1e-8, 1e-6):
            assert unit_load_table[units, load][0] <= 3, (units, load)


@pytest.mark.parametrize("units", list(UNITS))
@pytest.mark.parametrize("h", [1e-3, 1e-2])
def test_clamped_plate_linear_regime(units, h):
    """Issue 11's clamped 16x16 square plate (a = 1, E = 1e6, nu = 0.3) at 1e-6 of a unit pressure
    failed with "line search failed" (strains formed as x.x - X.X lost the digits of U << X):
    now <= 3 Newton iterations in every unit system, and the centre deflection is Kirchhoff's
    0.00126 q a^4 / D within 3 % (16x16 mesh, shear-deformable element; at h = 1e-2 the
    transverse shear adds ~0.2 %)."""
    fu, lu = UNITS[units]
    mesh = build_mesh("square", "16x16", size=1.0 / lu)
    E, nu, q = 1e6 / fu * lu**2, 0.3, 1e-6 / fu * lu**2
    model = Model(mesh, IsotropicShell(E=E, nu=nu, h=h / lu))
    r = solve_static(model, clamp(mesh, "outer"), surface_load(model, q))
    assert r.converged, r.message
    assert r.info["iterations"] <= 3
    D = 1e6 * h**3 / (12 * (1 - nu**2))
    w = np.abs(r.U[:, 2]).max() * lu  # cm
    assert w == pytest.approx(0.00126 * 1e-6 / D, rel=3e-2)


# ----------------------------------------------------------------------------- saddles
def _column(n=8):
    L = 10.0
    mesh = build_mesh("strip", f"{n}x1", length=L, width=1.0)
    mat = IsotropicShell(E=1.2e6, nu=0.0, h=0.1)
    Pcr = np.pi**2 * mat.C_b[0, 0] / (4 * L**2)  # Euler load of a cantilever (width 1)
    return mesh, Model(mesh, mat), Pcr


def test_starts_exactly_at_a_symmetric_saddle_and_ends_at_a_minimum():
    """A perfectly straight cantilever under 1.5 x its Euler load: the straight compressed state is
    an exact equilibrium (found here with the lateral dofs held) and a saddle.  Started exactly
    there, the solver converges at once, finds the negative curvature, leaves along the buckling
    mode and ends on the buckled (elastica) state: positive definite, lower potential, one saddle
    left and reported."""
    mesh, model, Pcr = _column()
    tip = mesh.node_set("tip")
    fixed = clamp(mesh, "clamped")
    P = np.zeros((mesh.n_nodes, 6))
    P[tip, 0] = -1.5 * Pcr / len(tip)
    held = fixed.copy()
    held[:, 2] = held[:, 5] = True  # no lateral motion: the straight branch
    straight = solve_static(model, held, P, check_stability=False)
    assert straight.converged, straight.message
    r = solve_static(model, fixed, P, U0=straight.U)
    assert r.converged, r.message
    assert r.info["saddles_left"] == 1
    assert r.info["saddle_eigenvalues"][0] < 0
    assert len(r.info["warnings"]) == 1 and "saddle" in r.info["warnings"][0]
    assert r.info["positive_definite"] is True and r.info["min_tangent_eigenvalue"] > 0

    def pot(U):
        return model.energy(U) - float(np.sum(P * U))

    assert pot(r.U) < pot(straight.U) - 1e-3 * abs(pot(straight.U))
    # the elastica of a cantilever at 1.5 P_cr deflects its tip by ~0.7 L sideways
    assert np.abs(r.U[tip, 2]).mean() > 0.3 * 10.0
    # with escapes off the same start is reported as it is: converged, not positive definite
    s = solve_static(model, fixed, P, U0=straight.U, max_saddle_escapes=0)
    assert s.converged and s.info["positive_definite"] is False and s.info["saddles_left"] == 0


def test_a_saddle_that_cannot_be_left_is_not_converged():
    """With escapes allowed but a zero escape budget reached, converged=False and status 'saddle'
    (max_saddle_escapes=1 is enough here, so force failure by an escape step too small to lower
    the energy above round-off: 1e-12 of L_f)."""
    mesh, model, Pcr = _column()
    tip = mesh.node_set("tip")
    fixed = clamp(mesh, "clamped")
    P = np.zeros((mesh.n_nodes, 6))
    P[tip, 0] = -1.5 * Pcr / len(tip)
    r = solve_static(model, fixed, P, saddle_step=1e-12)
    assert not r.converged
    assert r.info["status"] == "saddle"
    assert "saddle" in r.message and "\n" not in r.message


# ----------------------------------------------------------------------------- small items
def test_zero_load_is_the_zero_state():
    mesh, model, fixed, P, _ = wool_like_strip("gf-cm", 0.0)
    r = solve_static(model, fixed, P)
    assert r.converged and r.info["iterations"] == 0 and r.info["status"] == "converged"
    assert r.info["criterion"] == "zero load"
    assert not np.any(r.U)


def test_ctrl_c_returns_the_last_iterate():
    mesh, model, fixed, P, _ = wool_like_strip("gf-cm", 1.0)
    calls = []

    def progress(frac, text):
        calls.append(frac)
        if len(calls) == 6:
            raise KeyboardInterrupt

    r = solve_static(model, fixed, P, progress=progress)
    assert not r.converged and r.info["status"] == "interrupted"
    assert np.all(np.isfinite(r.U)) and np.any(r.U)  # a real iterate, not the start
    assert r.info["warnings"]


def test_progress_starts_at_once_and_moves_monotonically():
    mesh, model, fixed, P, _ = wool_like_strip("gf-cm", 1.0)
    seen = []
    r = solve_static(model, fixed, P, progress=lambda f, t: seen.append((f, t)))
    assert r.converged
    assert seen[0][0] == 0.0  # before any assembly
    fr = [f for f, _ in seen]
    assert all(b >= a for a, b in zip(fr, fr[1:])) and fr[-1] == 1.0
    # one call per iteration at least, and intermediate values in between
    assert len(seen) >= r.info["iterations"]
    assert len({round(f, 3) for f in fr if 0.0 < f < 1.0}) >= 5


@pytest.mark.parametrize(
    "bad",
    [
        {"tol": "abc"},
        {"max_iter": "abc"},
        {"load_factors": ["a"]},
        {"tol": -1},
        {"tol": 0},
        {"max_iter": 0},
        {"load_factors": []},
        {"method": "dynamic"},
        {"cc": 0.01},
    ],
)
def test_bad_settings_are_one_line_input_errors(bad):
    mesh, model, fixed, P, _ = wool_like_strip("gf-cm", 1.0)
    # "setting tol = ...", "setting load_factors.0 = ...", "unknown setting 'cc' ..."
    words = rf"^solver\.static: (setting |unknown setting '){re.escape(next(iter(bad)))}\b"
    with pytest.raises(InputError, match=words) as e:
        run(Problem(model, fixed, P), bad)
    assert "\n" not in str(e.value) and next(iter(bad)) in str(e.value)
    with pytest.raises(InputError, match=words):
        validate("static", bad)


@pytest.mark.parametrize(
    "bad", [{"tol": -1}, {"max_iter": 0}, {"load_factors": []}, {"cc": 0.01}, {"line_search": "wolfe"}]
)
def test_solve_static_options_are_the_settings(bad):
    """solve_static's keyword options are StaticSettings' fields, checked by that one model: a bad
    value or an unknown key is one InputError line naming it, before any work."""
    mesh, model, fixed, P, _ = wool_like_strip("gf-cm", 1.0)
    words = rf"^solve_static: (setting |unknown setting '){re.escape(next(iter(bad)))}\b"
    with pytest.raises(InputError, match=words) as e:
        solve_static(model, fixed, P, **bad)
    assert "\n" not in str(e.value)


def test_settings_and_options_give_the_same_solve():
    """The same settings given as keyword options, as a dict or as a parsed StaticSettings give the
    same solve, and an explicit argument overrides ``settings``."""
    mesh, model, fixed, P, _ = wool_like_strip("gf-cm", 1.0)
    a = solve_static(model, fixed, P, method="paper", c=2e-2)
    b = solve_static(model, fixed, P, settings={"method": "paper", "c": 2e-2})
    c = solve_static(model, fixed, P, settings=validate("static", {"c": 2e-2}), method="paper")
    assert a.converged and a.info["method"] == "paper" and a.info["c"] == 2e-2
    for r in (b, c):
        assert r.info["method"] == "paper" and r.info["iterations"] == a.info["iterations"]
        assert np.array_equal(r.U, a.U)
    d = solve_static(model, fixed, P, settings={"method": "paper"}, method="newton")
    assert d.converged and d.info["method"] == "newton"


# ----------------------------------------------------------------------------- arc-length
def _arch():
    from solidshell import ShellMesh

    S, rise, nx = 10.0, 0.15, 10
    x = np.linspace(0.0, S / 2, nx + 1)
    z = rise * (1 - (2 * x / S - 1) ** 2)
    nodes = np.array([[xi, y, zi] for y in (0.0, 1.0) for xi, zi in zip(x, z)])
    quads = np.array([[i, i + 1, nx + 2 + i, nx + 1 + i] for i in range(nx)])
    mesh = ShellMesh(nodes, quads=quads)
    model = Model(mesh, IsotropicShell(E=1.2e6, nu=0.0, h=0.1))
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    end = np.flatnonzero(np.isclose(nodes[:, 0], 0.0))
    mid = np.flatnonzero(np.isclose(nodes[:, 0], S / 2))
    fixed[end, :3] = True
    fixed[:, 1] = fixed[:, 4] = True
    fixed[mid, 0] = fixed[mid, 3] = True
    return mesh, model, fixed, mid


def test_fine_arclength_path_matches_displacement_control():
    """The shallow-arch snap-through of test_static, traced with max_arc_step = 0.02: many more
    points, and at each of ten of them (including the unstable branch) the load is checked against
    a displacement-controlled solve that prescribes the same mid-span deflection (the load is then
    the reaction there).  Both are equilibria of the same discrete system at relative residual
    1e-8, so the loads agree to 1e-5 of the peak load (measured ~1e-8; 1e-5 allows the path
    points' own tolerance, which is relative to the larger reactions at the supports)."""
    mesh, model, fixed, mid = _arch()
    P = np.zeros((mesh.n_nodes, 6))
    P[mid, 2] = -5.0 / len(mid)
    coarse = solve_static(model, fixed, P, method="arclength")
    r = solve_static(model, fixed, P, method="arclength", max_arc_step=0.02)
    assert r.converged, r.message
    assert len(r.path) >= 2 * len(coarse.path) and len(r.path) >= 40
    lam = np.array([l for l, _ in r.path])
    w = np.array([-U[mid, 2].mean() for _, U in r.path])
    k_lim = int(np.flatnonzero(np.diff(lam) < 0)[0])  # the first limit point
    peak = 5.0 * lam[k_lim]
    pick = sorted(set(np.linspace(1, len(r.path) - 2, 9).astype(int)) | {k_lim + 2})
    assert any(i > k_lim for i in pick)  # at least one past the limit point
    dfix = fixed.copy()
    dfix[mid, 2] = True
    for i in pick:
        presc = np.zeros((mesh.n_nodes, 6))
        presc[mid, 2] = -w[i]
        d = solve_static(model, dfix, np.zeros_like(P), prescribed=presc, U0=r.path[i][1], check_stability=False)
        assert d.converged, d.message
        reaction = -float(model.internal_force(d.U)[mid, 2].sum())  # load carried at mid-span
        assert reaction == pytest.approx(5.0 * lam[i], abs=1e-5 * peak), (i, w[i])


def test_extended_shifted_steps_reach_the_same_minimum(monkeypatch):
    """circle-pedestal 10x40 meets shifted Newton steps along which Pi is nearly linear (rho >= 1.8
    at alpha 1): they are doubled while Pi falls (static.newton.EXTEND_RHO).  The run ends on the minimum of
    the run without extensions, in fewer factorisations (measured 84 iterations and 97
    factorisations with 4 extensions, against 86 and 105)."""
    from solidshell.run import run_scene
    from solidshell.solvers.static import newton

    ext = run_scene("circle-pedestal", mesh="10x40", out_dir=None, progress=False)
    monkeypatch.setattr(newton, "EXTEND_RHO", np.inf)
    plain = run_scene("circle-pedestal", mesh="10x40", out_dir=None, progress=False)
    assert ext.converged and plain.converged and ext.summary["positive_definite"]
    assert ext.summary["extended_steps"] > 0 and plain.summary["extended_steps"] == 0
    assert ext.summary["factorizations"] < plain.summary["factorizations"]
    # both stop at the Newton tolerance (relative residual 1e-8) on the same minimum: the states
    # agree far below the 1e-6 of max|U| that separates distinct drapes (different fold patterns)
    du = np.abs(ext.U - plain.U).max() / np.abs(plain.U).max()
    assert du <= 1e-6
    assert ext.summary["fold_count"] == plain.summary["fold_count"]


def test_load_steps_that_stay_slow_snap_to_the_target_instead_of_stalling(monkeypatch):
    """Near a critical point of the path every load step needs >= 12 Newton iterations however
    small it is; the increment halves after each such step, and before the floor on it a geometric
    series of steps converged to a factor short of the target (sphere 60x60 with self-contact:
    0.9165, docs/contact.md section 15).  Here each step of the cantilever strip is charged 20
    iterations more than it took: the increment halves down to ``min_increment``, then one step
    goes to the target, and the state is the direct solve's (the strip has one equilibrium, so
    they agree to the Newton tolerance: 1e-6 of max|U|, like the other same-minimum tests)."""
    from solidshell.solvers.static import driver

    mesh, model, fixed, P, _ = wool_like_strip("gf-cm", 1.0)
    direct = solve_static(model, fixed, P)
    real = driver.newton_level
    calls = []

    def slow(sys, D, lam, o, stats):
        calls.append(lam)
        if len(calls) > 200:  # without the snap the factors would converge short of 1 for ever
            raise RuntimeError("load stepping stalled")
        out = real(sys, D, lam, o, stats)
        stats["iterations"] += 20
        return out

    monkeypatch.setattr(driver, "newton_level", slow)
    r = solve_static(model, fixed, P, increment=0.1, min_increment=1e-4, check_stability=False)
    assert r.converged, r.message
    assert r.info["load_factor"] == 1.0
    # 0.1 halved to the floor 1e-4 (10 halvings), one step at the floor, then the snap
    assert 10 <= r.info["load_steps"] <= 14
    (lam_snap,) = r.info["snapped_from"]
    assert 0.1 < lam_snap < 0.3  # 0.1 + 0.05 + ... + 1e-4: the series' sum, about 0.2
    du = np.abs(r.U - direct.U).max() / np.abs(direct.U).max()
    assert du <= 1e-6
