"""The lane (structure-of-arrays) quad kernel and the fused explicit step against the reference path.

elements/lanes.py must give core.energy_force's forces and energies to round-off, solvers/explicit/
fused.py must assemble them in scatter_add_vec's order (bitwise equal to Model.energy_and_force when
fed the same element forces), and the integrator's fused step must follow the previous path
(Model.internal_force + kernels.central_step) to round-off, on any thread count bit for bit."""

import numba
import numpy as np
import pytest

from solidshell import Fabric, ShellMesh
from solidshell.contact import Plane
from solidshell.elements import core, lanes
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers.explicit import Integrator
from solidshell.solvers.explicit.fused import FusedForces


def warped_mesh(nx=7, ny=5, n_quads=25):
    """A doubly curved sheet: the first n_quads cells as quads, the rest split into triangles
    (35 cells: 25 quads, not a multiple of LANES, so the last block is padded)."""
    x = np.linspace(0, 3, nx + 1)
    y = np.linspace(0, 2, ny + 1)
    X, Y = np.meshgrid(x, y)
    P = np.column_stack([X.ravel(), Y.ravel(), 0.1 * np.sin(X.ravel()) * Y.ravel()])
    a = (np.arange(nx)[None, :] + (nx + 1) * np.arange(ny)[:, None]).ravel()
    q = np.column_stack([a, a + 1, a + nx + 2, a + nx + 1])
    t = q[n_quads:]
    tris = np.vstack([t[:, [0, 1, 2]], t[:, [0, 2, 3]]]) if len(t) else np.zeros((0, 3), int)
    return ShellMesh(P, quads=q[:n_quads], tris=tris)


@pytest.mark.parametrize("thickness", ["green", "quasi"])
def test_lane_kernel_matches_core(thickness):
    """Same operations, grouped and contracted differently: agreement to a few units of round-off
    of the largest element force (1e-13 relative allows ~500 ulps over sums of ~100 products).
    The large random U (5 % of the sheet) reaches both branches of Eq. (24)."""
    mesh = warped_mesh()
    model = Model(mesh, Fabric.wool(), thickness_strain=thickness)
    b = model.blocks[0]
    U = 0.05 * np.random.default_rng(3).standard_normal((mesh.n_nodes, 6))
    xo, xn, Uc = model._current(U)
    M = len(b.conn)
    fe = np.empty((M, 4, 6))
    we = np.empty(M)
    core.energy_force(*b.args(xo, xn, Uc, model.quasi, model.mu), fe, we, 1)
    pk = lanes.pack(b.conn, b.c, b.c["r_zq"])
    L = lanes.LANES
    fs = np.full((pk["B"], 24 * L), np.nan)
    ws = np.full((pk["B"], L), np.nan)
    lanes.quad_forces(
        mesh.nodes,
        mesh.directors,
        Uc,
        pk["conn"],
        pk["Cmb"],
        pk["Cs"],
        pk["Cz"],
        pk["r_z"],
        model.quasi,
        model.mu,
        np.empty((pk["B"], 48 * L)),
        fs,
        ws,
    )
    assert pk["B"] * L > M  # a padded block is exercised
    scale = np.abs(fe).max()
    assert np.abs(lanes.unpack_forces(fs, M) - fe).max() <= 1e-13 * scale
    assert np.abs(ws.ravel()[:M] - we).max() <= 1e-13 * np.abs(we).max()
    # padded lanes: zero rigidity, zero force and energy (never scattered, but finite)
    assert np.all(fs.reshape(-1, 24, L).transpose(0, 2, 1).reshape(-1, 24)[M:] == 0.0)
    assert np.all(ws.ravel()[M:] == 0.0)


def test_node_assembly_is_the_scatter_order_bitwise():
    """With the reference element kernel for every block (use_lanes=False) the node pass must
    reproduce Model.energy_and_force exactly: each dof sums its elements in the same order, quads
    first, then triangles."""
    mesh = warped_mesh()
    model = Model(mesh, Fabric.wool())
    U = 0.05 * np.random.default_rng(4).standard_normal((mesh.n_nodes, 6))
    E0, F0 = model.energy_and_force(U)
    F1, E1 = FusedForces(model, use_lanes=False).internal(U.ravel(), True)
    assert np.array_equal(F1, F0.ravel())
    assert E1 == E0


def test_element_and_node_passes_do_not_depend_on_threads():
    """Blocks are the unit of work and every sum has a fixed order: 1 and 2 threads bit for bit."""
    mesh = warped_mesh(12, 10, 100)
    model = Model(mesh, Fabric.wool(), thickness_strain="quasi")
    U = 0.05 * np.random.default_rng(5).standard_normal((mesh.n_nodes, 6))
    ff = FusedForces(model)
    old = numba.get_num_threads()
    try:
        out = []
        for th in (1, min(2, numba.config.NUMBA_NUM_THREADS)):
            numba.set_num_threads(th)
            out.append(ff.internal(U.ravel(), True))
    finally:
        numba.set_num_threads(old)
    assert np.array_equal(out[0][0], out[1][0]) and out[0][1] == out[1][1]


def test_fused_step_follows_the_previous_path():
    """60 steps of a sheet falling onto a plane (contact in R = P - F + C), quads and triangles,
    quasi thickness strain: the fused step and Model.internal_force + central_step agree to
    round-off (1e-11 relative: per-step differences of 1e-16 grown by 60 steps of a stable scheme
    and the contact's on/off switch staying on the same side)."""
    mesh = warped_mesh()
    fused_follows_previous_path(Model(mesh, Fabric.wool(), thickness_strain="quasi"), z_plane=0.02)


def fused_follows_previous_path(model, z_plane):
    """The sheet of ``model``, clamped at x = 0, falls under gravity onto the plane z = z_plane
    (nodes below it start in contact): 60 fused steps and 60 of Model.internal_force +
    central_step agree to 1e-11 relative, with the same nodes in contact."""
    mesh = model.mesh
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[mesh.nodes[:, 0] == 0.0] = True
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -980.665 * model.lumped_mass()[:, 0]
    prob = Problem(model, fixed, loads, contact=[Plane(point=(0.0, 0.0, z_plane), normal=(0.0, 0.0, 1.0))])
    s = {"t_end": 1.0, "sample_every": 7, "mass_scaling": 100.0}
    a, b = Integrator(prob, s), Integrator(prob, s)
    b.forces.fused = None
    assert a.forces.fused is not None
    for it in (a, b):
        assert it.advance(60) == "running"
    D0 = b.state.D
    assert np.max(np.abs(a.state.D - D0)) <= 1e-11 * np.max(np.abs(D0))
    assert a.state.max_contact == b.state.max_contact > 0


def fused_force_matches_model(ff, model, U):
    """FusedForces ``ff`` of ``model`` at U (N,6): force and energy equal Model.energy_and_force's to
    1e-13 relative (the same element terms, summed in the lane kernels' and chunks' grouping), and
    on two threads the same bits (blocks are the unit of work)."""
    F1, E1 = ff.internal(U.ravel(), True)
    E0, F0 = model.energy_and_force(U)
    assert np.abs(F1 - F0.ravel()).max() <= 1e-13 * np.abs(F0).max()
    assert abs(E1 - E0) <= 1e-13 * abs(E0)
    old = numba.get_num_threads()
    try:
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        F2, E2 = ff.internal(U.ravel(), True)
    finally:
        numba.set_num_threads(old)
    assert np.array_equal(F1, F2) and E1 == E2


def test_fused_step_with_the_reference_kernel_is_the_previous_path_bitwise():
    """With core.energy_force for every block, the fused step performs the previous path's
    operations in the same order (scatter order, central_step's update and v.M.v sum): 30 steps
    of the warped sheet must give identical states."""
    mesh = warped_mesh()
    model = Model(mesh, Fabric.wool())
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[mesh.nodes[:, 0] == 0.0] = True
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -980.665 * model.lumped_mass()[:, 0]
    prob = Problem(model, fixed, loads)
    s = {"t_end": 1.0, "sample_every": 7}
    a, b = Integrator(prob, s), Integrator(prob, s)
    a.forces.fused = FusedForces(model, use_lanes=False)
    b.forces.fused = None
    for it in (a, b):
        it.advance(30)
    assert np.array_equal(a.state.D, b.state.D) and np.array_equal(a.state.D_prev, b.state.D_prev)


def test_chunked_scatter_is_the_scatter_order_but_at_chunk_boundaries():
    """The lane pass scatters each chunk's blocks into the dofs its nodes own and into slots for
    nodes an earlier chunk owns (fused.chunk_plan): every (element, node) pair exactly once, and
    the sum in scatter_add_vec's order bit for bit at every node with no slot; at slot nodes
    (a chunk sum added to another) agreement to 1e-15 of the largest force (two partial sums of
    at most ~8 terms each, regrouped)."""
    from solidshell.assembly import scatter_add_vec
    from solidshell.solvers.explicit.fused import CHUNKS

    mesh = warped_mesh(30, 20, 600)  # 600 quads = 38 blocks, padded; 0 triangles
    model = Model(mesh, Fabric.wool())
    U = 0.05 * np.random.default_rng(6).standard_normal((mesh.n_nodes, 6))
    ff = FusedForces(model)
    F, _ = ff.internal(U.ravel(), False)
    (kind, b, pk, _, _), (fe, _) = ff.parts[0], ff.views[0]
    assert kind == "lanes" and pk["bounds"].size == CHUNKS + 1
    ref = np.zeros(6 * mesh.n_nodes)
    scatter_add_vec(b.dofs, lanes.unpack_forces(fe, pk["M"]).reshape(pk["M"], -1), ref)
    slot = np.zeros(mesh.n_nodes, bool)
    slot[pk["slot_node"]] = True
    assert slot.any() and not slot.all()
    free = np.repeat(~slot, 6)
    assert np.array_equal(F[free], ref[free])
    assert np.abs(F - ref).max() <= 1e-15 * np.abs(ref).max()
