"""The state maps between solidshell and the DOLFINx cross-check (verification/fenicsx/state.py),
without DOLFINx: the restarts of the cross-check exchange states through them."""

import numpy as np

from solidshell.meshing import build_mesh
from solidshell.solvers.static import solve_static
from verification.checks.strips import strip_problem
from verification.fenicsx.state import from_fenicsx_state, max_translation_change, to_fenicsx_state

EPS = np.finfo(float).eps


def test_solidshell_state_round_trips_through_the_dolfinx_format():
    mesh = build_mesh("square_on_square", "12x4x4", sheet=20.0, pedestal=10.0)
    rng = np.random.default_rng(7)
    U = rng.normal(scale=[3.0, 3.0, 3.0, 0.5, 0.5, 0.5], size=(mesh.n_nodes, 6))
    st = to_fenicsx_state(mesh, U)
    assert st["lambda"] == 1.0 and np.asarray(st["U"]).shape == (mesh.n_nodes, 3)
    back = from_fenicsx_state(mesh, st["U"], st["director"])
    # translations are copied; U_n goes through (X_n + U_n) - X_n, exact up to one rounding of each
    # operation: |error| <= 2 eps max(|X_n|, |U_n|) per component (|X_n| = 1)
    assert np.array_equal(back[:, :3], U[:, :3])
    assert np.max(np.abs(back[:, 3:] - U[:, 3:])) <= 2 * EPS * max(1.0, np.max(np.abs(U[:, 3:])))
    # the director handed to DOLFINx is solidshell's current director x_n = X_n + U_n (Eq. 1)
    assert np.allclose(np.asarray(st["director"]), mesh.directors + U[:, 3:], rtol=0, atol=1e-15)


def test_unit_dolfinx_director_means_no_thickness_stretch():
    mesh = build_mesh("square_on_square", "12x4x4", sheet=20.0, pedestal=10.0)
    rng = np.random.default_rng(3)
    d = rng.normal(size=(mesh.n_nodes, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    U = from_fenicsx_state(mesh, np.zeros((mesh.n_nodes, 3)), d)
    # x_n = X_n + U_n is DOLFINx's unit director: |x_n| = 1 to round-off (a few ulp of a unit vector)
    assert np.max(np.abs(np.linalg.norm(mesh.directors + U[:, 3:], axis=1) - 1.0)) < 8 * EPS


def test_solidshell_restarted_from_a_dolfinx_format_state_returns_to_its_equilibrium():
    """The strip's solidshell equilibrium, sent to the DOLFINx format and brought back with its
    directors made unit (what the inextensible DOLFINx director is), is a start from which the
    static solver returns to the same equilibrium in a few iterations: the dof layout [U_o | U_n]
    and the director convention of the map are the solver's (a swapped or mis-scaled director would
    start the strip far from equilibrium)."""
    mesh, model, fixed, loads = strip_problem(10, "warp")
    ref = solve_static(model, fixed, loads)
    assert ref.converged
    st = to_fenicsx_state(mesh, ref.U)
    d = np.asarray(st["director"])
    stretch = np.max(np.abs(np.linalg.norm(d, axis=1) - 1.0))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    U0 = from_fenicsx_state(mesh, st["U"], d)
    r = solve_static(model, fixed, loads, U0=U0, predictor=False)
    assert r.converged
    # the start differs from the equilibrium only by the thickness stretch of the directors (1.1e-4
    # here, a stiff local mode): Newton removes it in 3 iterations (measured), against 83 from flat
    # and 45 from the right translations with the directors left at X_n (a lost director map)
    assert 0.0 < stretch < 1e-2
    assert r.info["iterations"] <= 6 < ref.info["iterations"]
    # the same equilibrium: solve_static stops at a correction below 1e-10 max|D|; 1e-8 cm on a
    # 3.5 cm tip travel leaves room for the different last iterate
    assert max_translation_change(r.U, ref.U) < 1e-8
