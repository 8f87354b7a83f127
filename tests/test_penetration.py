"""The contact contract's measure: solidshell.penetration (the run reports on itself) against the
independent verification/penetration_check.py (its own face points and geometry, from the files),
on cases with closed-form answers.

Tolerances: both sides evaluate the same mathematical points with different formulas on
coordinates of at most ~100 cm, so depths agree to round-off (~1e-13 cm); 1e-10 cm is far below
the contract's tolerance (1.2e-3 cm for wool) and far above that round-off.  Closed forms are
compared at 1e-12 cm for the same reason (a few operations on numbers of size ~5 cm)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from solidshell import io as sio
from solidshell import penetration
from solidshell.contact import PENETRATION_TOL, Pedestal, Plane, Sphere
from solidshell.errors import InputError
from solidshell.mesh import ShellMesh
from verification import penetration_check as pc

H = 0.0593  # the paper's wool [cm]
OFF = H / 2  # the scenes' offset: the lower face h/2 below the mid-surface
TOL = PENETRATION_TOL * H
AGREE = 1e-10  # cm: see the module docstring
EXACT = 1e-12  # cm: closed forms, see the module docstring
R = 5.0  # the paper's sphere radius [cm]
RP = R + OFF  # the radius the mid-surface keeps off the sphere's centre


def both(mesh, U, bodies, tables, grid=5):
    """(library rows, checker rows) for the same state."""
    lib = penetration.check(mesh, U, bodies, H, grid)
    x = mesh.nodes + U[:, :3]
    xf = pc.element_points(x, mesh.quads, mesh.tris, grid)
    return lib, [pc.count(t, x, xf, TOL) for t in tables]


def assert_agree(lib, ind):
    assert len(lib) == len(ind)
    for a, b in zip(lib, ind):
        assert (a["nodes_beyond"], a["face_points_beyond"]) == (b["nodes_beyond"], b["face_points_beyond"])
        assert a["deepest_node_cm"] == pytest.approx(b["deepest_node_cm"], abs=AGREE)
        assert a["deepest_face_point_cm"] == pytest.approx(b["deepest_face_point_cm"], abs=AGREE)


def sphere(centre):
    return Sphere(centre, R, offset=OFF), {"type": "sphere", "centre": list(centre), "radius": R, "offset": OFF}


def grid_mesh(x0, x1, y0, y1, nx, ny, z=0.0):
    xs, ys = np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    n0 = (i * (ny + 1) + j).ravel()
    quads = np.column_stack([n0, n0 + ny + 1, n0 + ny + 2, n0 + 1])
    return ShellMesh(nodes, quads=quads)


def state(mesh, lift=0.0, seed=0):
    """U that moves the mesh down by ``lift`` (its nodes were built ``lift`` too high), with
    director displacements that must not matter."""
    U = np.zeros((mesh.n_nodes, 6))
    U[:, 2] = -lift
    U[:, 3:] = np.random.default_rng(seed).normal(0.0, 0.1, (mesh.n_nodes, 3))
    return U


# ---------------------------------------------------------------------------- (a) plane
@pytest.mark.parametrize(("sink", "beyond"), [(0.0, False), (0.5, False), (1.5, True)])
def test_flat_sheet_on_a_plane(sink, beyond):
    """A flat sheet with its lower face on a floor: nothing beyond; sunk by 0.5 tol: still nothing;
    by 1.5 tol: every node and every face point (4x4 quads: 25 nodes, 16 x 25 face points)."""
    m = grid_mesh(-1, 1, -1, 1, 4, 4, z=0.3)
    U = state(m, lift=0.3 + sink * TOL)
    table = {"type": "plane", "point": [0.0, 0.0, -OFF], "normal": [0.0, 0.0, 1.0], "offset": OFF}
    lib, ind = both(m, U, [Plane(table["point"], offset=OFF)], [table])
    assert_agree(lib, ind)
    assert lib[0]["nodes_beyond"] == (25 if beyond else 0)
    assert lib[0]["face_points_beyond"] == (16 * 25 if beyond else 0)
    assert lib[0]["deepest_face_point_cm"] == pytest.approx(sink * TOL, abs=EXACT)


# ---------------------------------------------------------------------------- (b) the chord
def chord_quad(r=0.6, shift=(0.0, 0.0, 0.0)):
    """One flat square quad whose corners (at distance r from the axis) lie on the sphere, the
    lower face touching: the sphere bulges through its middle."""
    a = r / np.sqrt(2.0)
    s = np.sqrt(RP**2 - r**2)  # the corners' height above the centre
    nodes = np.array([[-a, -a, 0.0], [a, -a, 0.0], [a, a, 0.0], [-a, a, 0.0]]) + shift
    return ShellMesh(nodes + [0.0, 0.0, 0.2], quads=[[0, 1, 2, 3]]), np.array([0.0, 0.0, -s]) + shift, a, s


def test_chord_of_a_coarse_quad_on_a_sphere():
    """Nodes exactly on the sphere (clean); the face cuts in: its centre lies R' - sqrt(R'^2 - r^2)
    deep (R' = R + offset), and the face points beyond are those with R' - sqrt(rho^2 + s^2) > tol."""
    m, c, a, s = chord_quad()
    body, table = sphere(c)
    lib, ind = both(m, state(m, 0.2), [body], [table])
    assert_agree(lib, ind)
    r = np.sqrt(2.0) * a
    assert lib[0]["nodes_beyond"] == 0
    assert lib[0]["deepest_node_cm"] < EXACT
    assert lib[0]["deepest_face_point_cm"] == pytest.approx(RP - np.sqrt(RP**2 - r**2), abs=EXACT)
    assert lib[0]["deepest_face_point_cm"] > 0.5 * H  # the chord's sag is no round-off effect
    u = np.linspace(-a, a, 5)
    p = RP - np.sqrt(u[:, None] ** 2 + u[None, :] ** 2 + s**2)
    assert np.min(np.abs(p - TOL)) > 1e-6  # no point near the threshold: the count is no tie-break
    assert lib[0]["face_points_beyond"] == np.count_nonzero(p > TOL) == 21  # all but the corners


# ---------------------------------------------------------------------------- (c) box pedestal
def box():
    table = {"type": "pedestal", "shape": "square", "size": 10.0, "centre": [0.0, 0.0, 0.0], "height": 10.0}
    table["offset"] = OFF
    return Pedestal((0.0, 0.0, 0.0), half_widths=(5.0, 5.0), height=10.0, offset=OFF), table


def test_sheet_through_a_box_pedestal_side():
    """A horizontal strip 2 cm below the top, x in [4.5, 5.5] across the side x = 5 (|y| <= 0.5):
    every point's distance is x - 5 (the side is the nearest face), so a point is beyond when
    x < 5 + offset - tol.  4 x 2 quads: nodes at x = 4.5, 4.75, 5 are beyond (3 x 3 of them);
    face points of an element [x_e, x_e + 0.25] at x_e + k/16, y on 5 rows per element."""
    m = grid_mesh(4.5, 5.5, -0.5, 0.5, 4, 2, z=-2.0 + 0.1)
    body, table = box()
    lib, ind = both(m, state(m, 0.1), [body], [table])
    assert_agree(lib, ind)
    limit = 5.0 + OFF - TOL
    fx = np.array([4.5 + 0.25 * e + 0.0625 * k for e in range(4) for k in range(5)])
    assert lib[0]["nodes_beyond"] == 9
    assert lib[0]["face_points_beyond"] == np.count_nonzero(fx < limit) * 2 * 5
    assert lib[0]["deepest_node_cm"] == pytest.approx(OFF + 0.5, abs=EXACT)


def test_coarse_quad_over_a_box_pedestal_edge():
    """One quad folded over the top edge (x = 5, z = 0): one side lies on the top, the other hangs
    beside the side wall, both at the offset (nodes clean); its straight chord cuts the corner, where
    a point is min(5 - x, -z) inside.  Face-point rows t = 1/4, 1/2, 3/4 of the chord are inside."""
    xa, za, xb, zb = 4.6, OFF, 5.0 + OFF, -0.6
    nodes = np.array([[xa, -0.5, za], [xb, -0.5, zb], [xb, 0.5, zb], [xa, 0.5, za]])
    m = ShellMesh(nodes, quads=[[0, 1, 2, 3]])
    body, table = box()
    lib, ind = both(m, state(m), [body], [table])
    assert_agree(lib, ind)
    t = np.array([0.25, 0.5, 0.75])
    depth = np.minimum(5.0 - (xa + t * (xb - xa)), -(za + t * (zb - za)))
    assert np.all(depth > 0.0)
    assert lib[0]["nodes_beyond"] == 0
    assert lib[0]["deepest_node_cm"] < EXACT
    assert lib[0]["face_points_beyond"] == 3 * 5
    assert lib[0]["deepest_face_point_cm"] == pytest.approx(OFF + depth.max(), abs=EXACT)


# ---------------------------------------------------------------------------- (d) triangles
def chord_tri(r=0.6, shift=(0.0, 0.0, 0.0)):
    """An equilateral triangle with its corners (circumradius r) on the sphere."""
    s = np.sqrt(RP**2 - r**2)
    ang = np.pi / 2 + 2 * np.pi * np.arange(3) / 3
    nodes = np.column_stack([r * np.cos(ang), r * np.sin(ang), np.zeros(3)]) + shift
    return ShellMesh(nodes, tris=[[0, 1, 2]]), np.array([0.0, 0.0, -s]) + shift, s


def test_chord_of_a_triangle_on_a_sphere():
    """The order-4 lattice's points nearest the centroid are (1/2, 1/4, 1/4) and its rotations, at
    r/4 from the axis: the deepest face point is R' - sqrt(r^2/16 + s^2); the 3 interior points
    (at r/4) are beyond, the 3 edge midpoints (at r/2) are too (R' - sqrt(r^2/4 + s^2) = 0.027 cm)."""
    r = 0.6
    m, c, s = chord_tri(r)
    body, table = sphere(c)
    lib, ind = both(m, state(m), [body], [table])
    assert_agree(lib, ind)
    assert lib[0]["nodes_beyond"] == 0
    assert lib[0]["deepest_face_point_cm"] == pytest.approx(RP - np.sqrt(r**2 / 16 + s**2), abs=EXACT)
    # the 15 points' distances from the axis: corners r, edge quarter points r sqrt(7)/4 (6 of
    # them), edge midpoints r/2 (3), interior r/4 (3)
    rho = np.array([r] * 3 + [r * np.sqrt(7) / 4] * 6 + [r / 2] * 3 + [r / 4] * 3)
    p = RP - np.sqrt(rho**2 + s**2)
    assert np.min(np.abs(p - TOL)) > 1e-6
    assert lib[0]["face_points_beyond"] == np.count_nonzero(p > TOL)


def test_mixed_mesh_on_a_rounded_cylinder_pedestal():
    """Quads and triangles in a bumpy state around a cylinder pedestal with a rounded top edge
    (the library's compiled distance against the checker's numpy one): the same counts and depths,
    some points beyond and some not."""
    m0 = grid_mesh(-6.0, 6.0, -6.0, 6.0, 6, 6)
    q = m0.quads
    tris = np.concatenate([q[:18][:, [0, 1, 2]], q[:18][:, [0, 2, 3]]])
    m = ShellMesh(m0.nodes, quads=q[18:], tris=tris)
    rng = np.random.default_rng(3)
    U = np.zeros((m.n_nodes, 6))
    U[:, 2] = rng.uniform(-0.4, 0.2, m.n_nodes)
    body = Pedestal((0.0, 0.0, 0.0), radius=4.5, height=10.0, edge_radius=0.5, offset=OFF)
    table = {"type": "pedestal", "shape": "disc", "diameter": 9.0, "centre": [0.0, 0.0, 0.0], "height": 10.0}
    table.update(edge_radius=0.5, offset=OFF)
    for grid in (2, 5, 7):
        lib, ind = both(m, U, [body], [table], grid)
        assert_agree(lib, ind)
        assert 0 < lib[0]["face_points_beyond"] < m.n_quads * grid**2 + m.n_tris * grid * (grid + 1) // 2


def test_cusick_support_distance():
    """The checker's disc-on-stem (no library body to compare with yet): a point above the disc is
    its height above the top; one beside the stem, under the disc, is the nearer of the stem's
    side and the disc's underside; one inside the stem is minus its distance to the stem's side."""
    t = {"type": "pedestal", "shape": "disc", "diameter": 18.0, "centre": [0.0, 0.0, 0.0], "height": 10.0}
    t.update(support="cusick", disc_thickness=1.0, stem_diameter=4.0)
    x = np.array([[3.0, 0.0, 0.7], [0.0, 2.6, -1.9], [2.3, 0.0, -1.5], [0.0, 0.0, -5.0], [1.5, 0.0, -6.0]])
    expected = [0.7, min(0.6, 0.9), min(0.3, 0.5), -2.0, -0.5]
    np.testing.assert_allclose(pc.signed_distance(t, x), expected, atol=EXACT)


# ---------------------------------------------------------------------------- invariance
@given(st.tuples(*[st.floats(-100.0, 100.0, allow_nan=False) for _ in range(3)]), st.sampled_from(["quad", "tri"]))
def test_translation_leaves_the_counts(shift, kind):
    """Translating the sheet and the body together changes no count and no depth (beyond
    round-off of coordinates up to 100 cm: AGREE)."""
    make = chord_quad if kind == "quad" else chord_tri
    m0, c0 = make()[:2]
    m1, c1 = make(shift=np.array(shift))[:2]
    base = penetration.check(m0, np.zeros((4 if kind == "quad" else 3, 6)), [sphere(c0)[0]], H)
    body, table = sphere(c1)
    lib, ind = both(m1, np.zeros((m1.n_nodes, 6)), [body], [table])
    assert_agree(lib, ind)
    assert_agree(base, lib)


# ---------------------------------------------------------------------------- files and summary
def write_run(folder, mesh, U, bodies, tables, thickness=H):
    folder.mkdir()
    sio.write_mesh_file(folder / "result.vtu", mesh, U)
    summary = {"material": {"thickness": thickness}, "contact": tables}
    if bodies:
        summary["penetration"] = penetration.report(mesh, U, bodies, tables, thickness)
    (folder / "summary.json").write_text(json.dumps(sio.to_jsonable(summary)))
    return summary


def test_checker_on_run_files(tmp_path, capsys):
    """The checker reads result.vtu and summary.json: a clean run exits 0, the chord's run exits 1
    and its line says the summary's own numbers agree; the library's warning names the body."""
    m, c, _, _ = chord_quad()
    body, table = sphere(c)
    s = write_run(tmp_path / "chord", m, state(m, 0.2), [body], [table])
    flat = grid_mesh(-1, 1, -1, 1, 2, 2)
    plane = {"type": "plane", "point": [0.0, 0.0, -OFF], "normal": [0.0, 0.0, 1.0], "offset": OFF}
    write_run(tmp_path / "flat", flat, state(flat), [Plane(plane["point"], offset=OFF)], [plane])
    assert pc.main([str(tmp_path / "flat")]) == 0
    assert pc.main([str(tmp_path / "chord"), str(tmp_path / "flat")]) == 1
    out = capsys.readouterr().out.splitlines()
    assert "clean" in out[0] and "[summary agrees]" in out[0]
    assert "face points beyond 21/25" in out[1] and "BEYOND" in out[1] and "[summary agrees]" in out[1]
    assert "clean" in out[2]
    s["penetration"]["bodies"][0]["face_points_beyond"] -= 1  # a summary that under-reports
    (tmp_path / "chord" / "summary.json").write_text(json.dumps(sio.to_jsonable(s)))
    assert pc.main([str(tmp_path / "chord")]) == 1
    assert "[MISMATCH: summary says 0 nodes, 20 face points]" in capsys.readouterr().out
    s["penetration"]["bodies"][0]["face_points_beyond"] += 1
    (w,) = penetration.warnings(s["penetration"])
    assert w.startswith("contact[0] (sphere): 0 node(s) and 21 face point(s)")


def test_checker_refuses_incomplete_runs(tmp_path, capsys):
    """No thickness in the summary, an unknown body key, a missing result file: exit 2, one line."""
    m = grid_mesh(0, 1, 0, 1, 1, 1)
    plane = {"type": "plane", "point": [0.0, 0.0, -1.0], "normal": [0.0, 0.0, 1.0]}
    s = write_run(tmp_path / "a", m, state(m), [], [plane])
    s["material"] = {}
    (tmp_path / "a" / "summary.json").write_text(json.dumps(s))
    assert pc.main([str(tmp_path / "a")]) == 2
    write_run(tmp_path / "b", m, state(m), [], [dict(plane, spin=1.0)])
    assert pc.main([str(tmp_path / "b")]) == 2
    assert pc.main([str(tmp_path / "none")]) == 2
    err = capsys.readouterr().err.splitlines()
    assert "no material.thickness" in err[0]
    assert "keys this check does not know: spin" in err[1]
    assert "result.vtu does not exist" in err[2] or "summary.json does not exist" in err[2]


def test_library_refuses_bad_input():
    m = grid_mesh(0, 1, 0, 1, 1, 1)
    with pytest.raises(InputError, match="face-point grid must be an integer >= 2"):
        penetration.check(m, np.zeros((4, 6)), [], H, grid=1)
    with pytest.raises(InputError, match="sheet thickness h must be a positive number"):
        penetration.check(m, np.zeros((4, 6)), [], 0.0)
    with pytest.raises(InputError, match="1 contact table"):
        penetration.report(m, np.zeros((4, 6)), [], [{"type": "plane"}], H)


def test_a_run_reports_penetration_and_the_checker_agrees(tmp_path, capsys):
    """The whole path: a short relaxation of the sphere scene writes summary["penetration"] (the
    scene's sphere table with its numbers), a warning exactly when a count is nonzero, and the
    checker recomputes the same numbers from the written files."""
    from solidshell import run_scene

    out = run_scene(
        "sphere", mesh="4x4", solver="relax", out_dir=tmp_path / "r", progress=False,
        overrides={"solver.relax.t_max": 0.05, "output.pictures": [], "output.snapshots": []},
    )  # fmt: skip
    entry = out.summary["penetration"]
    assert entry["tolerance_cm"] == pytest.approx(PENETRATION_TOL * out.summary["material"]["thickness"], rel=1e-15)
    (b,) = entry["bodies"]
    assert b["type"] == "sphere" and b["radius"] == R
    beyond = b["nodes_beyond"] + b["face_points_beyond"] > 0
    assert any(w.startswith("contact[0] (sphere)") for w in out.summary["warnings"]) == beyond
    assert pc.main([str(tmp_path / "r")]) == (1 if beyond else 0)
    assert "[summary agrees]" in capsys.readouterr().out
