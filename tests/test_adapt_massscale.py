"""Selective mass scaling of adapted meshes (adapt.step_level; solidshell/adapt/massscale.py) and the
per-dof damping that goes with it (solvers/explicit/integrator.py, Problem.mass_weights)."""

from __future__ import annotations

import numpy as np
import pytest

from solidshell import Fabric, ShellMesh, run_scene
from solidshell.adapt import AdaptiveMesh, BackgroundMesh
from solidshell.adapt.massscale import characteristic_lengths, level_length, step_weights
from solidshell.errors import InputError
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers.explicit import Integrator, scaled_mass
from solidshell.solvers.explicit import stepcontrol
from solidshell.solvers.explicit.settings import parse_settings

WOOL = Fabric.wool()


def grid(n, size=10.0):
    x, y = np.meshgrid(np.linspace(0, size, n + 1), np.linspace(0, size, n + 1))
    a = (np.arange(n)[None, :] + (n + 1) * np.arange(n)[:, None]).ravel()
    q = np.column_stack([a, a + 1, a + n + 2, a + n + 1])
    return ShellMesh(np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)]), quads=q,
                     directors=np.tile([0.0, 0.0, 1.0], ((n + 1) ** 2, 1)))


def adapted():
    """A 4x4 level-0 grid (2.5 cm quads), 2 levels, the 2x2 block at one corner split twice: quads
    of 2.5, 1.25 and 0.625 cm with transition patches between them."""
    am = AdaptiveMesh(BackgroundMesh.from_level0(grid(4), 2))
    am.split([[0, 0], [0, 1], [0, 4], [0, 5]])
    am.split([[1, 0], [1, 1], [1, 2], [1, 3]])
    return am, am.active_mesh(check=True)


def test_characteristic_lengths_are_the_explicit_codes():
    X = np.array([[0.0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]])
    # a 2x1 rectangle: area / longest side = its short side; a right triangle with unit legs: its
    # smallest altitude, 1/sqrt(2)
    assert characteristic_lengths(X, [[0, 1, 2, 3]]) == pytest.approx([1.0], rel=1e-14)
    Y = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert characteristic_lengths(Y, [[0, 1, 2]]) == pytest.approx([2 ** -0.5], rel=1e-14)


def test_weights_lift_the_finer_elements_to_the_chosen_level():
    am, a = adapted()
    h1 = level_length(am.bg, 1)
    assert h1 == pytest.approx(1.25, rel=1e-12)
    w = step_weights(a.mesh, h1)
    lvl, kind = a.elem_leaf[:, 0], a.elem_kind
    nq = len(a.mesh.quads)
    plain = kind[:nq] == 0
    # plain quads: level 2 (0.625 cm) get (1.25 / 0.625)^2 = 4, levels 0 and 1 nothing
    assert np.allclose(w[:nq][plain & (lvl[:nq] == 2)], 4.0, rtol=1e-12)
    assert np.all(w[:nq][plain & (lvl[:nq] < 2)] == 1.0)
    # every element ends at least as long as level 1's quads (characteristic length x sqrt(w))
    h = np.concatenate([characteristic_lengths(a.mesh.nodes, c) for c in (a.mesh.quads, a.mesh.tris) if len(c)])
    assert np.all(h * np.sqrt(w) >= h1 * (1 - 1e-12))
    # the transition triangles between levels 1 and 2 are shorter than level-2 quads: heavier
    assert w[nq:].max() > 4.0


def test_weighted_mass_keeps_each_elements_share_and_unit_weights_change_nothing():
    _, a = adapted()
    model = Model(a.mesh, WOOL)
    M = model.lumped_mass()
    assert np.array_equal(model.lumped_mass(np.ones(a.mesh.n_elements)), M)
    w = step_weights(a.mesh, 1.25)
    Mw = model.lumped_mass(w)
    # the total is sum_e w_e mu A_e (exact: the trapezoidal shares of each element add up to its area)
    areas = model.nodal_areas
    per_el = [model.nodal_areas(np.eye(a.mesh.n_elements)[e]).sum() for e in range(a.mesh.n_elements)]
    assert Mw[:, 0].sum() == pytest.approx(WOOL.mass_per_area * np.dot(w, per_el), rel=1e-12)
    assert areas().sum() == pytest.approx(100.0, rel=1e-12)
    with pytest.raises(ValueError, match="mass_weights"):
        Problem(model, np.zeros((a.mesh.n_nodes, 6), bool), np.zeros((a.mesh.n_nodes, 6)), mass_weights=w[:-1])


def _omega(problem, s):
    M = scaled_mass(problem.model, s.mass_scaling, s.mass_scaling_mode, problem.mass_weights)
    D = np.zeros(M.size)
    return stepcontrol.omega_sheet(problem.model, M, ~problem.fixed, D, s)[0]


def _flat(mesh, weights=None):
    z = np.zeros((mesh.n_nodes, 6))
    return Problem(Model(mesh, WOOL), z.astype(bool), z, mass_weights=weights)


def test_with_uniform_mass_scaling_the_top_frequency_does_not_depend_on_the_element_size():
    """The paper's premise (§5): the top frequency of the solid-shell sheet is its thickness mode,
    the same for 2.5 cm and 0.3125 cm quads (measured 2.3478e5 rad/s, unscaled wool, to 1e-13)."""
    s = parse_settings({"mass_scaling": 1.0}, True)
    w = [_omega(_flat(grid(n)), s) for n in (4, 8, 16, 32)]
    assert np.ptp(w) <= 1e-9 * w[0], w


def test_weighted_adapted_mesh_has_about_the_step_of_the_coarser_uniform_mesh():
    """With the director masses x10^4 (the scenes' FIRE relaxation) the thickness mode is slowed
    and the membrane mode, c / h, sets the top frequency omega_max (Lanczos on M^-1 K at the flat
    state): 4x4, 8x8, 16x16 uniform grids measured 6078, 12160, 24310 rad/s.  The adapted mesh has
    the 16x16 grid's finest quads (measured 24260); with the weights of step_level 1 it comes down
    to the 8x8 grid's, which has level 1's 1.25 cm quads (measured 12220).  Tolerance 20 %: the
    characteristic length estimates an element's step; quads and triangles differ by ~10-20 %."""
    _, a = adapted()
    s = parse_settings({"mass_scaling": 1e4, "mass_scaling_mode": "director"}, True)
    w_plain = _omega(_flat(a.mesh), s)
    w_weighted = _omega(_flat(a.mesh, step_weights(a.mesh, 1.25)), s)
    w8, w16 = _omega(_flat(grid(8)), s), _omega(_flat(grid(16)), s)
    msg = f"omega plain {w_plain:.4g}, weighted {w_weighted:.4g}, uniform 8x8 {w8:.4g}, 16x16 {w16:.4g} rad/s"
    assert w16 == pytest.approx(2.0 * w8, rel=0.05), msg      # membrane-governed: omega ~ 1 / h
    assert w_plain == pytest.approx(w16, rel=0.05), msg
    assert 0.8 * w8 <= w_weighted <= 1.2 * w8, msg


def test_weighted_dofs_are_damped_by_their_unweighted_mass():
    """Rayleigh damping C = alpha M_0: a weighted dof's alpha in Eq. (23) is alpha M_0 / M, and the
    ledger's dissipation uses M_0 -- so the damping force, and with it the overdamped creep, do not
    change with the weights."""
    _, a = adapted()
    fixed = np.zeros((a.mesh.n_nodes, 6), bool)
    fixed[0] = True
    w = step_weights(a.mesh, 1.25)
    loads = np.zeros((a.mesh.n_nodes, 6))
    loads[:, 2] = -1e-3
    settings = {"damping": "rayleigh", "alpha": 5.0, "mass_scaling": 100.0, "max_steps": 10}
    plain = Integrator(Problem(Model(a.mesh, WOOL), fixed, loads), settings, relax=True)
    weighted = Integrator(Problem(Model(a.mesh, WOOL), fixed, loads, mass_weights=w), settings, relax=True)
    assert plain.damp_idx is None and np.ndim(plain.cD) == 0
    C_plain = plain.alpha * plain.Mf
    C_weighted = weighted._dof_alpha() * weighted.Mf
    free = weighted.free_idx
    assert np.allclose(C_weighted[free], C_plain[free], rtol=1e-13)
    assert np.any(weighted.Mf[free] > 1.5 * plain.Mf[free])
    weighted.advance(10)
    assert weighted.state.damp_sum > 0.0


def test_step_level_doubles_the_step_of_an_adaptive_relaxation():
    """hang-20 on a 4x4 level 0, 2 levels, relaxed with unscaled masses to step 4000: const 0.1
    splits the hung corners at step ~2700 and then the rest, to all of level 2 (289 nodes).
    step_level 1 gives those quads four times their mass, and the last mesh's step doubles
    (measured 7.67e-6 -> 1.53e-5 s) with the energy balanced (measured 1.1e-5)."""
    common = {"adapt.levels": 2, "adapt.const": 0.1, "adapt.eps": 0.05, "adapt.every": 50,
              "output.pictures": [], "output.snapshots": []}
    kw = dict(mesh="4x4", solver="relax", out_dir=None, progress=False, adaptive=True, mass_scaling=1.0,
              max_steps=4000)
    plain = run_scene("hang-20", overrides=common, **kw).summary
    weighted = run_scene("hang-20", overrides={**common, "adapt.step_level": 1}, **kw).summary
    assert plain["max_level_reached"] == weighted["max_level_reached"] == 2
    assert weighted["adapt_step_level"] == 1 and plain["adapt_step_level"] is None
    assert weighted["dt"] == pytest.approx(2.0 * plain["dt"], rel=0.05)
    assert weighted["energy_balance_error"] < 1e-3


def test_step_level_is_refused_where_it_does_not_apply():
    kw = dict(mesh="4x4", out_dir=None, progress=False, adaptive=True)
    with pytest.raises(InputError, match="step_level.*relax"):
        run_scene("hang-20", solver="explicit", overrides={"adapt.step_level": 0}, **kw)
    with pytest.raises(InputError, match="step_level 2 must be below levels"):
        run_scene("hang-20", solver="relax", overrides={"adapt.levels": 2, "adapt.step_level": 2}, **kw)
