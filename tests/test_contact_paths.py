"""Node paths through rigid bodies (solidshell/contact_paths.py): the static solvers' trial steps are
cut before any node's straight path goes deeper than h into a body, and never later than the path's
first entry.  The references are closed forms: a segment's entry into a sphere solves a quadratic."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from solidshell import Fabric
from solidshell.contact import Pedestal, Sphere
from solidshell.contact_paths import REACHED, free_fraction
from solidshell.contact_self import CCD_SAFETY
from solidshell.meshing import build_mesh
from solidshell.model import Model
from solidshell.problem import Problem

H = Fabric.wool().thickness
DEPTH = H  # the depth the static solver passes (System.h)
SPHERE = Sphere((0.0, 0.0, 0.0), 2.0, offset=H / 2)
R_IN = 2.0 + H / 2 - DEPTH  # the forbidden ball: gap g - offset < -depth


def _entry(x0, dx, r=R_IN):
    """The first s in [0, 1] at which x0 + s dx is inside the ball |x| < r (the sphere's centre at 0),
    or None: the smaller root of |x0 + s dx|^2 = r^2."""
    a, b, c = dx @ dx, 2.0 * x0 @ dx, x0 @ x0 - r * r
    disc = b * b - 4 * a * c
    if c <= 0.0 or disc <= 0.0:
        return None if c > 0.0 else 0.0
    s = (-b - math.sqrt(disc)) / (2 * a)
    return s if 0.0 <= s <= 1.0 else None


def test_a_path_through_the_sphere_is_cut_just_before_it_enters():
    """A node 5 cm above the sphere moving 10 cm straight down passes through it.  The fraction is
    at most the exact entry and at most REACHED x depth (over the path's length) short of it: the
    advancement stops once the gap is within REACHED x depth of -depth."""
    x0 = np.array([[0.3, 0.2, 5.0]])
    dx = np.array([[0.0, 0.0, -10.0]])
    s = _entry(x0[0], dx[0])
    t = free_fraction([SPHERE], x0, dx, DEPTH)
    assert t <= s
    # on a path through the centre's vertical the gap falls at most 1 per unit length (Lipschitz 1)
    assert t >= s - REACHED * DEPTH / 10.0 - 1e-12


def test_free_paths_and_deep_starts_are_not_cut():
    """A path beside the sphere, one ending above it, and a node that starts deeper than -depth (the
    penalty is pushing it out already; it is not followed) leave the step whole."""
    x0 = np.array([[3.0, 0.0, 5.0], [0.0, 0.0, 6.0], [0.0, 0.0, 1.0]])
    dx = np.array([[0.0, 0.0, -10.0], [0.0, 0.0, -3.0], [0.0, 0.0, -0.5]])
    assert free_fraction([SPHERE], x0, dx, DEPTH) == 1.0


def test_bodies_without_a_lipschitz_bound_are_skipped():
    """A user's body without ``lipschitz`` gives no bound to advance by: not followed."""

    class Unbounded(Sphere):
        lipschitz = None

    x0, dx = np.array([[0.0, 0.0, 5.0]]), np.array([[0.0, 0.0, -10.0]])
    assert free_fraction([Unbounded((0, 0, 0), 2.0)], x0, dx, DEPTH) == 1.0
    assert free_fraction([Unbounded((0, 0, 0), 2.0), SPHERE], x0, dx, DEPTH) < 1.0


def test_the_earliest_entry_over_nodes_and_bodies():
    """Two bodies, three nodes: the fraction is the earliest entry of all (the box's top at z = 1
    is passed by the first node after 4 cm + depth of its 10 cm path, the sphere by the second after
    3 cm; the third node passes beside both)."""
    box = Pedestal((10.0, 0.0, 1.0), half_widths=(1.0, 1.0), height=2.0)
    x0 = np.array([[10.0, 0.0, 5.0], [0.0, 0.0, 5.0 + H / 2 - DEPTH], [20.0, 0.0, 5.0]])
    dx = np.array([[0.0, 0.0, -10.0], [0.0, 0.0, -10.0], [0.0, 0.0, -10.0]])
    t = free_fraction([box, SPHERE], x0, dx, DEPTH)
    s_sphere = (x0[1, 2] - R_IN) / 10.0  # the second node enters at z = R_IN, 3 cm down its path
    s_box = (5.0 - (1.0 - DEPTH)) / 10.0  # the box's gap is z - 1 above its top: -depth at z = 1 - depth
    assert s_sphere == pytest.approx(0.3) and s_box > 0.4
    assert s_sphere - REACHED * DEPTH / 10.0 - 1e-12 <= t <= s_sphere
    assert free_fraction([box], x0, dx, DEPTH) == pytest.approx(s_box, abs=REACHED * DEPTH / 10.0)


@given(st.lists(st.floats(-6.0, 6.0), min_size=3, max_size=3), st.lists(st.floats(-12.0, 12.0), min_size=3, max_size=3))
def test_never_beyond_the_first_entry(p, d):
    """Any segment: the fraction never passes the exact entry (the guarantee the solver needs), and a
    segment that never enters is cut only where it grazes the forbidden ball (its closest approach
    within the distance the advancement can resolve) -- otherwise it is left whole."""
    x0, dx = np.array([p]), np.array([d])
    if np.linalg.norm(x0) < R_IN or not np.linalg.norm(dx) > 1e-6:
        return  # starts inside (not followed) or does not move
    t = free_fraction([SPHERE], x0, dx, DEPTH)
    assert 0.0 <= t <= 1.0
    s = _entry(x0[0], dx[0])
    if s is not None:
        assert t <= s + 1e-12
        return
    a = float(np.clip(-(x0[0] @ dx[0]) / (dx[0] @ dx[0]), 0.0, 1.0))
    closest = float(np.linalg.norm(x0[0] + a * dx[0]))
    if closest > R_IN + 0.5:  # comfortably clear: 64 advances of >= 0.5 cover any path here
        assert t == 1.0


def test_the_static_system_cuts_a_step_that_would_drop_the_sheet_through_the_sphere():
    """The 8 x 8 cm sheet resting on a 2 cm sphere; a trial step dropping every node 20 cm would
    put the sheet below the sphere, where the penalty sees nothing.  step_cut takes it to where
    the first node has gone no deeper than h (the sheet starts touching: the cut is about h / 20,
    with CCD_SAFETY to spare) and counts the cut; a sideways step of 1 cm is left whole."""
    from solidshell.solvers.static.system import System

    mesh = build_mesh("square", "8x8", size=8.0)
    model = Model(mesh, Fabric.wool())
    sph = Sphere((0.0, 0.0, -2.0 - H / 2), 2.0, offset=H / 2)
    prob = Problem(model, np.zeros((mesh.n_nodes, 6), bool), np.zeros((mesh.n_nodes, 6)), contact=[sph])
    sys_ = System(prob.model, prob.fixed, prob.loads, prob.prescribed, prob.contact, 1.0, "cholmod")
    D0 = np.zeros(6 * mesh.n_nodes)
    D1 = D0.copy()
    D1.reshape(-1, 6)[:, 2] = -20.0
    c = sys_.step_cut(D0, D1)
    assert 0.0 < c * 20.0 <= CCD_SAFETY * H * (1 + 1e-12)  # round-off in s = room / |dx|
    assert c * 20.0 >= CCD_SAFETY * (1.0 - REACHED) * H - 1e-9  # the centre node touches: gap 0 at the start
    assert sys_.body_cuts == 1
    D1 = D0.copy()
    D1.reshape(-1, 6)[:, 0] = 1.0
    assert sys_.step_cut(D0, D1) == 1.0
    assert sys_.body_cuts == 1
