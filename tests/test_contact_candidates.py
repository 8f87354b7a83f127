"""Contact evaluated at the candidate nodes only (solvers/explicit/candidates.py) must give the run
that evaluates every node, bit for bit: the proof (a non-candidate's gap stays > 0 while no node
has moved margin / L) leaves nothing to round-off, and the energy sums run over the nodes in
contact only (contact_kernels.body_forces, candidates.contact_power)."""

import numpy as np
import pytest

from solidshell import Fabric
from solidshell.contact import Pedestal, Plane, Sphere
from solidshell.meshing import build_mesh
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers.explicit import Integrator
from solidshell.solvers.explicit.candidates import Candidates, moved_beyond


def drop(body, n=12, size=8.0):
    """An n x n wool sheet (mid-surface z = 0) falling onto ``body`` under its weight."""
    mesh = build_mesh("square", f"{n}x{n}", size=size)
    model = Model(mesh, Fabric.wool())
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -980.665 * model.lumped_mass()[:, 0]
    return Problem(model, np.zeros((mesh.n_nodes, 6), bool), loads, contact=[body])


@pytest.mark.parametrize(
    "body",
    [
        Sphere(center=(0.0, 0.0, -2.0), radius=2.0, friction=0.3),
        Sphere(center=(0.0, 0.0, -2.0), radius=2.0),
        Pedestal(top_center=(0.0, 0.0, -0.0002), radius=2.0, edge_radius=0.3, friction=0.2),
        Plane(point=(-4.0, 0.0, -0.0005), normal=(0.3, 0.0, 1.0), friction=0.1),
    ],
)
def test_candidate_contact_is_every_node_contact_bitwise(body):
    """200 steps of the sheet thrown at the body at 20 cm/s (it moves ~0.3 cm), the candidates
    re-selected many times (a 0.01 cm margin): state, anchors and every contact book identical to
    the run that checks every node."""
    prob = drop(body)
    V0 = np.zeros((prob.model.n_nodes, 6))
    V0[:, 2] = -20.0
    s = {"t_end": 1.0, "mass_scaling": 100.0, "sample_every": 1, "V0": V0}
    a, b = Integrator(prob, s), Integrator(prob, s)
    a.cand = Candidates(prob.contact, prob.model.mesh.nodes, 0.01, a.faces)
    b.cand = None
    for it in (a, b):
        assert it.advance(200) == "running"
    sa, sb = a.state, b.state
    assert a.cand.selections > 5  # re-selected as nodes moved
    assert a.cand.nodes.size < prob.model.n_nodes  # a proper subset
    assert sb.max_contact > 0  # the sheet did touch
    assert sb.max_slip > 0 or body.friction == 0.0  # and slipped
    assert np.array_equal(sa.D, sb.D) and np.array_equal(sa.D_prev, sb.D_prev)
    assert np.array_equal(sa.anchors, sb.anchors, equal_nan=True)
    for k in ("contact_work", "fric_work", "max_contact", "max_pen", "max_slip", "balance_err", "damp_sum"):
        assert getattr(sa, k) == getattr(sb, k), k
    assert sa.last == sb.last


def test_moved_beyond_checks_every_node_and_nan():
    D = np.zeros(6 * 3)
    Dsel = np.zeros((3, 3))
    D[6 * 2 + 1] = 0.5
    assert not moved_beyond(D, Dsel, 0.25)  # |dx| = 0.5 = sqrt(0.25): not beyond
    assert moved_beyond(D, Dsel, 0.2499)
    D[6 * 2 + 1] = np.nan
    assert moved_beyond(D, Dsel, 1e300)
    D[:] = 0.0
    D[6 * 1 + 3] = 10.0  # a director dof is not a move
    assert not moved_beyond(D, Dsel, 0.0)


def test_bodies_without_a_lipschitz_bound_use_every_node():
    class Bowl(Sphere):
        lipschitz = None

    c = Candidates([Bowl(center=(0, 0, -1), radius=1.0)], np.zeros((4, 3)), 0.1)
    assert not c.enabled and not c.update(np.zeros(24)) and c.nodes.size == 4


@pytest.mark.parametrize(
    "body",
    [
        Sphere(center=(0.0, 0.0, -2.0), radius=2.0, friction=0.3),
        Pedestal(top_center=(0.0, 0.0, -0.0002), half_widths=(2.0, 1.5), edge_radius=0.3, friction=0.2),
    ],
)
def test_compiled_contact_pass_is_the_per_body_path(body):
    """The explicit solver's one compiled pass over the candidates (contact_kernels.contact_pass)
    against the per-body path a user's own body takes (contact.frictional_contact / forces, the same
    per-node laws): 200 steps of the thrown sheet give the same state, anchors and books bit for
    bit; the deepest penetration, which the per-body path takes from f - f_t, to round-off.  Nodes
    only (a user's body has no face points, contact_faces.py)."""
    prob = drop(body)
    V0 = np.zeros((prob.model.n_nodes, 6))
    V0[:, 2] = -20.0
    s = {"t_end": 1.0, "mass_scaling": 100.0, "sample_every": 1, "V0": V0, "contact_face_points": 0}
    a, b = Integrator(prob, s), Integrator(prob, s)
    assert a.forces.compiled
    b.forces.compiled = False
    for it in (a, b):
        assert it.advance(200) == "running"
    sa, sb = a.state, b.state
    assert sb.max_contact > 0 and sb.max_slip > 0
    assert np.array_equal(sa.D, sb.D) and np.array_equal(sa.anchors, sb.anchors, equal_nan=True)
    for k in ("contact_work", "fric_work", "max_contact", "max_slip", "balance_err", "damp_sum"):
        assert getattr(sa, k) == getattr(sb, k), k
    assert sa.max_pen == pytest.approx(sb.max_pen, rel=1e-12)


def test_a_second_contact_call_leaves_the_steps_friction_forces():
    """The step's friction forces (returned as a view of a reused buffer) survive another contact
    evaluation before the step books their work -- the modal damper differentiates the contact
    force in between (damping/modal.contact_blocks)."""
    prob = drop(Sphere(center=(0.0, 0.0, -2.0), radius=2.0, friction=0.3))
    it = Integrator(prob, {"t_end": 1.0, "mass_scaling": 100.0})
    D = np.zeros(6 * it.N)
    D[2::6] = -0.5  # the sheet's middle pressed into the sphere
    anchors = it.forces.contact_friction(D, np.full((1, it.N, 3), np.nan))[6]
    D[0::6] += 1e-4  # then moved sideways: stick forces
    new = np.full_like(anchors, np.nan)
    FT, nodes = it.forces.contact_friction(D, anchors, np.arange(it.N), np.zeros(6 * it.N), new)[4]
    keep = FT.copy()
    assert np.count_nonzero(np.any(keep != 0.0, axis=2)) > 4
    it.forces.contact_friction(D + 1e-3, anchors)
    np.testing.assert_array_equal(FT, keep)
