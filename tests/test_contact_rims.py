"""Rim-to-face contact (solidshell/contact_rims.py, issue 36): a body's sharp edge, sampled by rim
points, against the sheet's element faces.  The closest points are those of a brute-force search,
the penalty law is C2 and its forces are the gradient of its energy, and a sheet folded over a sharp
pedestal edge keeps the edge out of its faces between the face points, where the face points alone
let it in.

Depths over the edge are measured on a 33 x 33 lattice per element (solidshell.penetration), finer
than the contract's 5 x 5: between the lattice points of the contract is where a sharp edge gets in."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from solidshell import Fabric
from solidshell.contact import Pedestal
from solidshell.contact_faces import FacePoints
from solidshell.contact_rims import Rims, closest_on_quad, closest_on_tri, ramped, rim_points, rim_terms, update
from solidshell.mesh import ShellMesh
from solidshell.meshing import build_mesh
from solidshell.model import Model
from solidshell.penetration import check
from solidshell.problem import Problem
from solidshell.solvers import explicit

G0 = 980.665
H = Fabric.wool().thickness
FINE = 33  # lattice points per element edge of the depth check over a sharp edge

_coord = st.floats(-1.0, 1.0, allow_nan=False)


def _brute(xa, p, tri, n=401):
    """Squared distance of p to the face by dense sampling of its parameters (quad: bilinear on
    [0, 1]^2; triangle: the barycentric lattice)."""
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n), indexing="ij")
    u, v = u.ravel(), v.ravel()
    if tri:
        keep = u + v <= 1.0
        u, v = u[keep], v[keep]
        N = np.column_stack([1 - u - v, u, v])
        x = N @ xa[:3]
    else:
        N = np.column_stack([(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v])
        x = N @ xa
    return float(np.min(np.sum((x - p) ** 2, axis=1)))


@settings(max_examples=60, deadline=None)  # the first example compiles the kernels
@given(st.lists(_coord, min_size=12, max_size=12), st.lists(_coord, min_size=3, max_size=3), st.booleans())
def test_closest_point_is_the_brute_force_one(jitter, point, tri):
    """On a unit square (a triangle: its half) with corners moved by up to 0.2 in each direction
    (sheared, warped out of plane: a draped element's distortion and more), the closest point's
    squared distance is the dense search's to within the search's resolution (a 401^2 lattice
    over a face of side ~1: its spacing 1/400 puts the lattice point within 1/566 of the true
    point, so |d_lattice - d| <= 1.8e-3 and d2 differs by <= 2 d 1.8e-3 + 3.1e-6), and never
    below it (the lattice's points are on the face)."""
    xa = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    xa += 0.2 * np.asarray(jitter).reshape(4, 3)
    if tri:
        xa[3] = xa[0]
    p = np.array([0.5, 0.5, 0.0]) + np.asarray(point)
    d2, N = (closest_on_tri if tri else closest_on_quad)(xa, p[0], p[1], p[2])
    ref = _brute(xa, p, tri)
    assert np.all(N >= -1e-12) and abs(N.sum() - 1.0) < 1e-12
    assert d2 == pytest.approx(float(np.sum((N @ xa - p) ** 2)), rel=1e-12, abs=1e-15)
    d = np.sqrt(ref)
    assert ref - (2 * d * 1.8e-3 + 3.1e-6) <= d2 <= ref + 1e-12


def test_penalty_is_c2_and_its_derivatives_consistent():
    """psi(p) = k p^3 / (6 c) below the slack c, the shifted 1/2 k p^2 above: energy, force and
    stiffness continuous at p = c (to round-off) and each the derivative of the one before (central
    differences, step 1e-7 c: truncation ~1e-14 relative, so 1e-6 relative is round-off's margin)."""
    k, c = 3.0e4, 2.0e-4
    below, above = ramped(k, c * (1 - 1e-12), c), ramped(k, c * (1 + 1e-12), c)
    for a, b in zip(below, above):
        assert a == pytest.approx(b, rel=1e-9)
    assert ramped(k, c, c)[2] == pytest.approx(k)
    eps = 1e-7 * c
    for p in (0.3 * c, 0.999 * c, 1.7 * c, 25 * c):
        e_m, f_m, k_m = ramped(k, p - eps, c)
        e_p, f_p, k_p = ramped(k, p + eps, c)
        _, f, kk = ramped(k, p, c)
        assert (e_p - e_m) / (2 * eps) == pytest.approx(f, rel=1e-6)
        assert (f_p - f_m) / (2 * eps) == pytest.approx(kk, rel=1e-6)


def test_rim_points_follow_the_sharp_edges_only():
    """A sharp box: its top and base rectangles and four vertical edges, spaced <= s; a sharp
    cylinder: its two circles; rounded edges: none (the face points' business)."""
    s = 0.1
    box = Pedestal((0, 0, 0), half_widths=(1.0, 0.5), edge_radius=0.0, height=2.0)
    P = rim_points(box, s)
    assert len(P) == 2 * round(2 * (2.0 + 1.0) / s) + 4 * (round(2.0 / s) - 1)
    on_top = np.isclose(P[:, 2], 0.0)
    assert np.all(np.isclose(np.abs(P[on_top, 0]), 1.0) | np.isclose(np.abs(P[on_top, 1]), 0.5))
    cyl = Pedestal((0, 0, 0), radius=1.5, edge_radius=0.0, height=2.0)
    P = rim_points(cyl, s)
    assert np.allclose(np.hypot(P[:, 0], P[:, 1]), 1.5) and set(np.round(P[:, 2], 12)) == {0.0, -2.0}
    gaps = np.linalg.norm(np.diff(P[P[:, 2] == 0.0], axis=0), axis=1)
    assert gaps.max() <= s
    assert len(rim_points(Pedestal((0, 0, 0), radius=1.5, edge_radius=0.2, height=2.0), s)) == 0


def _flat(kind):
    """A 4 x 4 cm sheet of 1 cm quads, or of their halves as triangles, at z = 0."""
    mesh = build_mesh("square", "4x4", size=4.0)
    if kind == "quads":
        return mesh
    q = mesh.quads
    return ShellMesh(mesh.nodes, tris=np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]))


def _rims(mesh, ped):
    return Rims([ped], FacePoints(mesh, Model(mesh, Fabric.wool()).nodal_areas(), 3), H)


# a sharp box whose top rim lies 0.004 cm inside the sheet's face layer below a sheet at z = 0
_PED = Pedestal((0.3, 0.2, -H / 2 + 0.004), half_widths=(1.0, 1.0), edge_radius=0.0, height=2.0, offset=H / 2)


@pytest.mark.parametrize("kind", ["quads", "tris"])
def test_rim_forces_are_the_gradient_of_the_rim_energy(kind):
    """The sheet warped by a random displacement over the box's rim pressing into it: the rim forces
    (faces, sides and nodes) are minus the gradient of the rim energy -- central differences of step
    1e-7 cm on the energy (psi is C2 and the distances C1 away from the medial set, so the
    difference is exact to O(eps^2) ~ 1e-14 relative; round-off on an energy of ~1e-2 over 2e-7:
    ~1e-10): agreement to 1e-6 of the largest force."""
    mesh = _flat(kind)
    rims = _rims(mesh, _PED)
    kr = np.full(len(rims.conn4), 5.0e3)
    rng = np.random.default_rng(3)
    D = np.zeros(6 * mesh.n_nodes)
    D.reshape(-1, 6)[:, :3] = 0.003 * rng.standard_normal((mesh.n_nodes, 3))
    e, G = rim_terms(rims, mesh.nodes, D, kr)
    assert e > 0 and np.abs(G).max() > 0
    eps, fd = 1e-7, np.zeros_like(G)
    for a in range(mesh.n_nodes):
        for i in range(3):
            Dp, Dm = D.copy(), D.copy()
            Dp[6 * a + i] += eps
            Dm[6 * a + i] -= eps
            ep, em = (rim_terms(rims, mesh.nodes, Dx, kr)[0] for Dx in (Dp, Dm))
            fd[a, i] = (ep - em) / (2 * eps)
    assert np.abs(fd - G).max() <= 1e-6 * np.abs(G).max()


@pytest.mark.parametrize("kind", ["quads", "tris"])
def test_a_flat_sheet_sliding_over_the_rim_feels_each_rim_point_once(kind):
    """The flat sheet slid in its plane over the rim by 24 random offsets (rim points under faces,
    sides and nodes in turn): the rim energy does not change -- each rim point counted once at its
    depth o - c - d, by the faces less the sides plus the nodes (module docstring) -- to 1e-9 of
    itself (round-off of ~100 terms).  A plain sum over the elements would count a point under a
    side twice, under a node four times (quads) or six (triangles)."""
    mesh = _flat(kind)
    rims = _rims(mesh, _PED)
    kr = np.full(len(rims.conn4), 5.0e3)
    D = np.zeros(6 * mesh.n_nodes)
    e0 = rim_terms(rims, mesh.nodes, D, kr)[0]
    on = np.abs(rims.points[:, 2] - _PED.top_center[2]) < 1e-12
    p = H / 2 - rims.slack - (0.0 - _PED.top_center[2])  # every top rim point's depth
    assert e0 == pytest.approx(on.sum() * ramped(5.0e3, p, rims.slack)[0], rel=1e-12)
    rng = np.random.default_rng(7)
    for tx, ty in rng.uniform(-0.5, 0.5, (24, 2)):
        D.reshape(-1, 6)[:, 0], D.reshape(-1, 6)[:, 1] = tx, ty
        assert rim_terms(rims, mesh.nodes, D, kr)[0] == pytest.approx(e0, rel=1e-9)


def test_update_shifts_each_rim_point_by_its_depth():
    """The Uzawa update (contact_rims.update) on a 4 x 4 sheet over a sharp box edge: each rim point's
    new shift is max(0, o - c - d) with d its distance to the sheet found by brute force over every
    element (the 401^2 lattice of each face, its edges included: a lattice point lies within
    delta = 0.0025 / sqrt 2 cm of the closest point, along the face, where the distance is
    stationary, so d is overestimated by <= delta^2 / (2 d) = 6e-5 cm at d ~ 0.026 cm: tolerance
    1e-4 cm), the reported depth o - min d; with those shifts in place a second update adds the
    same raw depths again (the state has not moved: s + p)."""
    mesh = build_mesh("square", "4x4", size=4.0)
    mesh.nodes[:, 2] += 0.002 * np.sin(mesh.nodes[:, 0]) * np.cos(mesh.nodes[:, 1])
    ped = _PED
    rims = _rims(mesh, ped)
    D = np.zeros(6 * mesh.n_nodes)
    depth, shift = update(rims, mesh.nodes, D)
    xa = mesh.nodes[mesh.quads]
    u, v = (a.ravel() for a in np.meshgrid(np.linspace(0, 1, 401), np.linspace(0, 1, 401), indexing="ij"))
    N = np.column_stack([(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v])
    lattice = np.einsum("pa,eak->epk", N, xa).reshape(-1, 3)
    near = np.abs(rims.points[:, 2] - ped.top_center[2]) < 0.1  # the top rim: the base is 2 cm away
    d = np.array([np.min(np.linalg.norm(lattice - P, axis=1)) for P in rims.points[near]])
    want = np.maximum(H / 2 - rims.slack - d, 0.0)
    assert np.abs(shift[near] - want).max() <= 1e-4 and np.all(shift[~near] == 0.0)
    assert (shift > 0).sum() > 10 and depth == pytest.approx(H / 2 - d.min(), abs=1e-4)
    again = update(rims, mesh.nodes, D, shift)[1]
    assert np.allclose(again[shift > 0], 2 * shift[shift > 0], rtol=1e-12, atol=1e-15)


def _over_a_sharp_box():
    """A 6 x 6 cm wool sheet (0.5 cm elements) held at its centre node on a sharp 2 x 2 cm box
    pedestal, its lower face on the top: the overhang folds down over the box's edges and corners."""
    mesh = build_mesh("square", "12x12", size=6.0)
    mesh.nodes[:, 2] += H / 2
    model = Model(mesh, Fabric.wool())
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[np.linalg.norm(mesh.nodes[:, :2], axis=1) < 1e-9] = True
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -model.lumped_mass()[:, 0] * G0
    ped = Pedestal((0, 0, 0), half_widths=(1.0, 1.0), edge_radius=0.0, offset=H / 2, height=3.0)
    return mesh, model, fixed, loads, ped


def test_relaxed_sharp_edge_kept_out_of_the_faces_with_rims():
    """Relaxation (FIRE, director masses x100, the rims switched on): measured 0.060 h deep
    without the rims (under the box's corners, where the sheet's weight gathers on a point), 0.0078
    h with the rims and their updates.  Asserted: <= 0.01 h with (the updates' target, half the
    contract) and >= 0.045 h without (the rims, not chance, keep the edge out: 3/4 of the depth
    measured without them)."""
    mesh, model, fixed, loads, ped = _over_a_sharp_box()
    prob = Problem(model, fixed, loads, contact=[ped])
    s = {"damping": "fire", "mass_scaling": 100.0, "mass_scaling_mode": "director"}
    deep = {}
    for rims in (False, True):
        res = explicit.run_relax(prob, {**s, "contact_rims": rims})
        assert res.converged, res.message
        deep[rims] = check(mesh, res.U, [ped], H, grid=FINE)[0]["deepest_face_point_cm"] / H
    assert deep[True] <= 0.01 and deep[False] >= 0.045, deep


def test_relaxation_restarted_after_a_rim_update_is_bit_for_bit(tmp_path, restart_after_contact_update):
    """The rim points' shifts are checkpointed with the others: the sheet over the sharp box, stopped
    two progress reports after its first contact update and restarted from its last checkpoint
    (written after the update), ends on exactly the state and books of the uninterrupted run."""
    from solidshell.solvers.explicit import checkpoint

    mesh, model, fixed, loads, ped = _over_a_sharp_box()
    prob = Problem(model, fixed, loads, contact=[ped])
    s = {"damping": "fire", "mass_scaling": 100.0, "mass_scaling_mode": "director", "sample_every": 7}
    s["contact_rims"] = True

    def shifted(ck):  # the update shifted rim points
        assert np.asarray(checkpoint.load(ck)[0].shift_r).max() > 0

    restart_after_contact_update(prob, s, str(tmp_path / "rims.npz"), shifted)
