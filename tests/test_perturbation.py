"""The [perturbation] scene setting: a seeded starting state U0 (solidshell.perturbation)."""

import numpy as np
import pytest

from solidshell.analysis import projected_boundary
from solidshell.errors import InputError
from solidshell.meshing import build_mesh
from solidshell.perturbation import initial_state
from solidshell.run import run_scene
from solidshell.scenes import load
from solidshell.scenes.build import support_mask


@pytest.fixture(scope="module")
def pedestal():
    sc = load("square-pedestal")
    mesh = build_mesh(sc.recipe, "12x4x4", sheet=20.0, pedestal=10.0)
    return sc, mesh, support_mask(sc, mesh)


@pytest.mark.parametrize(
    "table",
    [{"shape": "random", "amplitude": 0.4, "seed": 7}, {"shape": "folds", "amplitude": 0.4, "folds": 6, "phase": 15.0}],
)
def test_amplitude_clamp_and_directors(pedestal, table):
    sc, mesh, fixed = pedestal
    U = initial_state(table, mesh, fixed, centre=(0.0, 0.0, 0.0))
    # max |w| is the amplitude by construction (scaled to it): exact to round-off
    assert np.abs(U[:, 2]).max() == pytest.approx(0.4, rel=1e-12)
    # flat sheet, directors along z: the start moves nodes along their directors only
    assert np.abs(U[:, :2]).max() == 0.0
    assert np.all(U[fixed] == 0.0)
    # the turned director stays a unit vector (no thickness change at the start)
    n = mesh.directors + U[:, 3:]
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    # ... and is normal to the perturbed surface: along every element edge the mean director is
    # orthogonal to the deformed edge up to the edge's chord error, O((k h)^2) of the tilt; the
    # largest tilt here is ~0.2 rad, so 0.02 (a tenth of it) separates "turned with the surface"
    # from "left vertical" (which gives the tilt itself)
    q = mesh.quads
    x = mesh.nodes + U[:, :3]
    worst, tilt = 0.0, np.abs(mesh.directors + U[:, 3:] - mesh.directors).max()
    for a, b in ((0, 1), (1, 2), (2, 3), (3, 0)):
        e = x[q[:, b]] - x[q[:, a]]
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        nm = 0.5 * (n[q[:, a]] + n[q[:, b]])
        worst = max(worst, np.abs(np.sum(nm * e, axis=1)).max())
    assert tilt > 0.05 and worst < 0.1 * tilt


def test_seeded_and_zero(pedestal):
    sc, mesh, fixed = pedestal
    a = initial_state({"amplitude": 0.3, "seed": 1}, mesh, fixed)
    b = initial_state({"amplitude": 0.3, "seed": 1}, mesh, fixed)
    c = initial_state({"amplitude": 0.3, "seed": 2}, mesh, fixed)
    assert np.array_equal(a, b) and not np.allclose(a, c)
    assert initial_state({"amplitude": 0.0, "seed": 1}, mesh, fixed) is None


def test_folds_shape_has_n_crests(pedestal):
    sc, mesh, fixed = pedestal
    U = initial_state({"shape": "folds", "amplitude": 0.5, "folds": 8}, mesh, fixed, centre=(0, 0, 0))
    _, ring = projected_boundary(mesh, None, return_nodes=True)  # the outer rim, in order
    th = np.arctan2(mesh.nodes[ring, 1], mesh.nodes[ring, 0])
    # on the outer rim w ~ cos(8 theta) times a positive taper: the sign pattern has 16 changes
    order = np.argsort(th)
    s = np.sign(U[ring[order], 2])
    s = s[s != 0]
    assert np.count_nonzero(s != np.roll(s, 1)) == 16


@pytest.mark.parametrize(
    "over, words",
    [
        ({"perturbation.amplitude": -1.0}, "amplitude"),
        ({"perturbation.shape": "folds", "perturbation.amplitude": 1.0}, "perturbation.folds"),
        ({"perturbation.wobble": 1}, "wobble"),
        ({"perturbation.shape": "spiral"}, "shape"),
        ({"perturbation.seed": "x"}, "seed"),
    ],
)
def test_bad_settings_one_line(over, words):
    with pytest.raises(InputError, match=words) as e:
        load("square-pedestal").with_overrides(over)
    assert "\n" not in str(e.value) and "perturbation" in str(e.value)


def test_folds_need_a_centre():
    with pytest.raises(InputError, match="pedestal or sphere"):
        run_scene(
            "strip-warp",
            mesh="10x1",
            progress=False,
            overrides={"perturbation.shape": "folds", "perturbation.folds": 4, "perturbation.amplitude": 0.1},
        )


def test_start_not_imperfection():
    """The strip has one equilibrium: a perturbed start must reach the unperturbed drape (the
    perturbation is a starting state of the same model, not a change of its geometry).  Newton
    stops at a 1e-8 relative residual, so the tip agrees to ~1e-7 of its deflection; 1e-6 allows
    for the two different iteration paths."""
    a = run_scene("strip-warp", mesh="10x1", progress=False, overrides={"solver.static.check_stability": False})
    b = run_scene(
        "strip-warp",
        mesh="10x1",
        progress=False,
        overrides={"solver.static.check_stability": False, "perturbation.amplitude": 0.3, "perturbation.seed": 4},
    )
    assert a.converged and b.converged
    assert b.summary["perturbation"]["amplitude"] == 0.3 and "perturbation" not in a.summary
    assert b.summary["iterations"] != a.summary["iterations"]  # it did start elsewhere
    ta, tb = np.array(a.summary["tip_position"]), np.array(b.summary["tip_position"])
    assert np.abs(ta - tb).max() < 1e-6 * np.abs(ta - [5.0, 0.5, 0.0]).max()
