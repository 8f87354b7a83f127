"""Mesh bodies (issue 38): [[contact]] type = "mesh" (solidshell/contact_mesh.py, contact_shapes.py and
the MESH code of contact_kernels).  The grid distance is checked against the analytic box and sphere
distances, its Lipschitz bound against random pairs, its forces against the energy they come from,
the face points' skip bound against the unskipped sum, and bad input against the CLI's exit 2."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
import pytest

from solidshell import contact as C
from solidshell import contact_kernels as ck
from solidshell.contact_mesh import MeshBody, mesh_body
from solidshell.errors import InputError

ROOT = Path(__file__).resolve().parents[1]

# a 4 x 6 x 2 box (corner at the origin) as 12 outward triangles
BOX_V = np.array([[x, y, z] for x in (0.0, 4.0) for y in (0.0, 6.0) for z in (0.0, 2.0)])
BOX_F = np.array(
    [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5],  # x = 0, x = 4
        [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],  # y = 0, y = 6
        [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],  # z = 0, z = 2
    ]
)  # fmt: skip


def _box_analytic():
    """The same box as the compiled BOX body (top centre (2, 3, 2), height 2, half widths 2, 3)."""
    return C.Pedestal((2.0, 3.0, 2.0), half_widths=(2.0, 3.0), height=2.0)


def _write(path, V, F):
    meshio.write(path, meshio.Mesh(V, [("triangle", F)]), binary=True)
    return path


def test_box_grid_matches_the_analytic_box():
    """Near a face (its middle, off the edges by more than two grid cells) the exact distance is
    linear, which trilinear interpolation reproduces to round-off; so grid, libigl and the compiled
    BOX body agree there to 1e-9 cm.  Near an edge the exact distance bends (outside) or kinks
    (inside, on the medial planes): there the grid differs by at most the interpolation error of a
    kink, a few tenths of a cell (bound asserted: 0.5 spacing)."""
    b = MeshBody(BOX_V, BOX_F, spacing=0.1, band=0.8)
    rng = np.random.default_rng(0)
    top = np.column_stack([rng.uniform(1, 3, 500), rng.uniform(1, 5, 500), rng.uniform(1.5, 2.6, 500)])
    g, n = b.signed_distance(top)
    ga, na = _box_analytic().signed_distance(top)
    ge, _ = b.exact_distance(top)
    np.testing.assert_allclose(ge, ga, atol=1e-12)
    np.testing.assert_allclose(g, ga, atol=1e-9)
    np.testing.assert_allclose(n, na, atol=1e-9)
    anywhere = rng.uniform(-0.7, 6.7, (4000, 3))
    g, _ = b.signed_distance(anywhere)
    ga, _ = _box_analytic().signed_distance(anywhere)
    inband = np.abs(ga) < 0.6  # (beyond the band the grid holds +-band)
    assert np.max(np.abs(g - ga)[inband]) < 0.5 * b.spacing
    # beyond the band: the kernels hold +-band; signed_distance gives, outside, a lower bound of the
    # exact g less sqrt(3) spacing, at least band (what the candidate selection needs), inside -band
    far_pts = rng.uniform(-30, 36, (4000, 3))
    g, _ = b.signed_distance(far_pts)
    ga, _ = _box_analytic().signed_distance(far_pts)
    gk, _ = ck.distances(b.code, b.params, far_pts, b.grid)
    far = np.abs(ga) > b.band + math.sqrt(3) * b.spacing
    np.testing.assert_array_equal(gk[far], b.band * np.sign(ga[far]))
    out, inn = far & (ga > 0), far & (ga < 0)
    assert np.all(g[out] >= b.band) and np.all(g[out] <= np.maximum(b.band, ga[out] - math.sqrt(3) * b.spacing) + 1e-12)
    assert np.mean(g[out] > 2 * b.band) > 0.5  # the bound grows with the distance (not stuck at the band)
    np.testing.assert_array_equal(g[inn], -b.band)


def test_sharp_edges_and_corners_are_exact():
    """Near the box's edges and corners, where a trilinear interpolant would round them off by up to
    ~spacing / 4 (0.03 cm here: half a wool thickness), the kernels evaluate the exact distance from
    the triangles (contact_kernels.exact_cell): within one spacing of the surface the compiled g
    equals the analytic box's to 1e-12 (round-off), inside and out, at a spacing that puts the edges
    off the lattice; outside, its gradient is the analytic one (1e-9).  The exact cells are those
    along the edges (48 cm of edge / 0.23 x ~4 x 4 cells of the cross-section), not the faces'
    middles: under half of the cells within (1 + sqrt 3) spacings of the surface (~40 % here)."""
    b = MeshBody(BOX_V, BOX_F, spacing=0.23, band=1.6)
    rng = np.random.default_rng(5)
    pts = []
    for ex, ez in ((0.0, 0.0), (4.0, 2.0), (0.0, 2.0), (4.0, 0.0)):  # the four edges along y
        t = rng.uniform(-0.2, 0.2, (3000, 2))
        pts.append(np.column_stack([ex + t[:, 0], rng.uniform(-0.2, 6.2, 3000), ez + t[:, 1]]))
    x = np.concatenate(pts)
    g, n = b.signed_distance(x)
    ga, na = _box_analytic().signed_distance(x)
    near = np.abs(ga) < b.spacing
    np.testing.assert_allclose(g[near], ga[near], atol=1e-12)
    out = near & (ga > 1e-6)
    np.testing.assert_allclose(n[out], na[out], atol=1e-9)
    cells_near = 2 * (2 * (4 * 6 + 4 * 2 + 6 * 2)) / b.spacing**2 * (1 + math.sqrt(3))  # area x thickness / h^3
    assert 0 < b.n_exact < 0.5 * cells_near


def test_sphere_grid_error_and_lipschitz_bound():
    """A gmsh sphere (R = 5 cm, triangles 0.15 cm): the grid's distance against |x| - R near the
    surface within the tessellation's sagitta (e^2 / (8 R) for the longest edge e) plus the
    interpolation error (spacing^2 / (4 R)) plus libigl's own exactness; |g(x) - g(y)| <= sqrt(3)
    |x - y| for random pairs (the face points' skip bound and the candidates rely on it) and the
    gradient's norm near 1 (within 3 %: the trilinear gradient of a curved face)."""
    b = mesh_body(primitives=[{"sphere": [0.0, 0.0, 0.0, 5.0]}], mesh_size=0.15, spacing=0.1)
    e = np.linalg.norm(b.V[b.F] - b.V[np.roll(b.F, -1, axis=1)], axis=-1).max()
    rng = np.random.default_rng(1)
    d = rng.normal(size=(20000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    x = d * rng.uniform(4.5, 5.5, len(d))[:, None]
    g, n = b.signed_distance(x)
    bound = e**2 / (8 * 5.0) + b.spacing**2 / (4 * 5.0) + 1e-9
    assert np.max(np.abs(g - (np.linalg.norm(x, axis=1) - 5.0))) < bound
    L = np.linalg.norm(n, axis=1)
    assert 0.97 < L.min() and L.max() < 1.03
    assert np.min(np.einsum("ij,ij->i", n / L[:, None], d)) > math.cos(math.radians(3.0))
    y = x + rng.normal(scale=0.3, size=x.shape)
    gy, _ = b.signed_distance(y)
    assert np.all(np.abs(g - gy) <= ck.MESH_LIPSCHITZ * np.linalg.norm(x - y, axis=1) + 1e-12)
    assert b.lipschitz == ck.MESH_LIPSCHITZ
    assert abs(b.curvature_radius - 5.0) < 0.5  # the face points' spacing rule sees the sphere (estimate: 10 %)


def test_forces_are_minus_the_energy_gradient():
    """The grid body's force k p grad g is exactly minus the gradient of 1/2 k p^2 of the same g
    (the gradient is not normalised): central differences agree to 1e-6 relative (their own
    truncation error inside one grid cell, where g is a polynomial)."""
    b = MeshBody(BOX_V, BOX_F, spacing=0.25, band=1.0)
    rng = np.random.default_rng(2)
    x = np.column_stack([rng.uniform(0.5, 3.5, 50), rng.uniform(0.5, 5.5, 50), rng.uniform(1.85, 1.99, 50)])
    x[:, 0] += rng.uniform(-0.4, 0.4, 50)  # some off the face's middle
    k = 100.0
    f, _ = b.forces(x, k)
    eps = 1e-6
    for i in range(0, 50, 7):
        for c in range(3):
            xp, xm = x[i : i + 1].copy(), x[i : i + 1].copy()
            xp[0, c] += eps
            xm[0, c] -= eps
            de = (b.forces(xp, k)[1] - b.forces(xm, k)[1]) / (2 * eps)
            assert abs(-de - f[i, c]) <= 1e-6 * max(1.0, abs(f[i, c]))


def test_analytic_bodies_same_bits_with_a_grid():
    """The analytic bodies' kernels give the same bits whether the shared grid is None (no mesh
    body: the code they ran before) or an array (a mesh body elsewhere in the scene)."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-6, 6, (3000, 3))
    bodies = [
        C.Sphere((0.0, 0.0, -1.0), 5.0),
        C.Pedestal((0.0, 0.0, 0.0), radius=3.0, edge_radius=0.2),
        C.Pedestal((0.0, 0.0, 0.0), half_widths=(2.0, 3.0)),
        C.CusickSupport((0.0, 0.0, 0.0), 9.0, 0.5, 2.0),
        C.Plane((0.0, 0.0, -2.0)),
    ]
    grid = np.arange(10.0)
    for b in bodies:
        g0, n0 = ck.distances(b.code, b.params, x)
        g1, n1 = ck.distances(b.code, b.params, x, grid)
        assert np.array_equal(g0, g1) and np.array_equal(n0, n1)


def test_face_pass_skip_bound_is_safe_for_a_mesh_body():
    """The compiled face pass (which skips an element when g(centre) - sqrt(3) r > reach) gives the
    same energy, count and forces as the numpy sum over every face point (contact_faces.contact_terms,
    no skipping), for a sheet pressed onto a box mesh body with some elements straddling its edge."""
    from solidshell.contact_faces import FacePoints, contact_terms, face_pass, reach
    from solidshell.contact_mesh import pack_grid
    from solidshell.meshing import build_mesh

    mesh = build_mesh("square", "12x12", size=6.0)
    b = MeshBody(BOX_V, BOX_F, spacing=0.1, band=0.8, offset=0.05)
    x = np.asarray(mesh.nodes, float) + np.array([2.5, 3.0, 2.0])
    rng = np.random.default_rng(4)
    x[:, 2] += rng.uniform(-0.04, 0.3, len(x))
    fp = FacePoints(mesh, np.ones(mesh.n_nodes), 3)  # (the points' stiffness kq is given below)
    kq = np.full(len(fp), 50.0)
    e_ref, F_ref, _ = contact_terms(fp, [b], x, kq)
    params = np.array([b.params])
    grid = pack_grid([b], params)
    D = np.zeros(6 * mesh.n_nodes)
    D.reshape(-1, 6)[:, :3] = x - mesh.nodes
    Ff = np.zeros((mesh.n_nodes, 3))
    ec, nact, _ = face_pass(
        np.array([b.code]), params, np.array([b.offset]), np.zeros(1), np.ascontiguousarray(mesh.nodes, float),
        D, np.arange(len(fp.conn4)), fp.estart, fp.nodes, fp.w, kq, np.arange(mesh.n_nodes), np.zeros((0, mesh.n_nodes)),
        Ff, np.zeros((0, 0)), reach([b], np.zeros((0, 0))), grid,
    )  # fmt: skip
    assert nact > 0
    np.testing.assert_allclose(ec, e_ref, rtol=1e-12)
    np.testing.assert_allclose(Ff, -F_ref, rtol=1e-10, atol=1e-12)


def test_units_scale_rotate_translate_and_inward_surface(tmp_path):
    """A box written in mm, turned inside out (triangles reversed), read back with units = "mm",
    turned 90 degrees about z and moved: its distances are the analytic box's at the turned and moved
    place (the inward surface turned outward, the grid exact on the face middles as above)."""
    f = _write(tmp_path / "box_mm.stl", 10.0 * BOX_V, BOX_F[:, ::-1])
    b = mesh_body(file=f.name, base_dir=tmp_path, units="mm", rotate=(0, 0, 90), translate=(10, 0, 0), spacing=0.1)
    # turned about z by 90: x -> -y, y -> x; the box [0,4]x[0,6]x[0,2] becomes [-6,0]x[0,4]x[0,2], moved by 10
    ref = C.Pedestal((10.0 - 3.0, 2.0, 2.0), half_widths=(3.0, 2.0), height=2.0)
    x = np.column_stack([np.full(5, 7.0), np.linspace(1, 3, 5), np.linspace(2.1, 2.5, 5)])
    np.testing.assert_allclose(b.signed_distance(x)[0], ref.signed_distance(x)[0], atol=1e-9)


@pytest.mark.parametrize(
    "case, words",
    [("open", "open (3 boundary edge(s))"), ("nonmanifold", "not manifold"), ("flipped", "not consistently oriented")],
)
def test_bad_surfaces_are_refused(tmp_path, case, words):
    """An open surface, an edge of three triangles, a triangle turned against its neighbours: one
    line naming the file and what is wrong."""
    F = BOX_F.copy()
    V = BOX_V.copy()
    if case == "open":
        F = F[:-1]
    elif case == "nonmanifold":
        V = np.vstack([V, [[2.0, -3.0, 1.0]]])
        F = np.vstack([F, [[0, 4, 8]], [[4, 0, 8]]])  # a fin on the edge 0-4 (a closed pair of sides)
    else:
        F[0] = F[0, ::-1]
    f = _write(tmp_path / "bad.stl", V, F)
    with pytest.raises(InputError) as e:
        mesh_body(file=str(f), where="contact[0]")
    msg = str(e.value)
    assert words in msg and "contact[0].file" in msg and "bad.stl" in msg and "\n" not in msg


SCENE = """
name = "mesh-box"
title = "a small sheet on a box mesh body"
[geometry]
recipe = "square"
size = 10.0
[mesh]
density = "6x6"
[material]
fabric = "wool"
[loads]
gravity = true
[[contact]]
type = "mesh"
{body}
offset = 0.03
[solver]
kind = "relax"
[solver.relax]
preset = "fast"
max_steps = 200
[output]
pictures = []
"""


def _cli(tmp_path, body, name="scene.toml"):
    scene = tmp_path / name
    scene.write_text(SCENE.format(body=body))
    out = tmp_path / "out"
    r = subprocess.run(
        [sys.executable, "-m", "solidshell", "run", str(scene), "--out", str(out), "--no-progress"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    return r, out


@pytest.mark.parametrize(
    "body, words",
    [
        ('file = "missing.stl"', ["contact[0].file", "missing.stl", "not found"]),
        ('file = "garbage.stl"', ["contact[0].file", "garbage.stl", "cannot read"]),
        ('file = "open.stl"', ["contact[0].file", "open.stl", "open"]),
        ('file = "box.stl"\ntranslate = [-2.0, -3.0, -1.0]', ["contact[0]", "box.stl", "start inside the body"]),
        ('file = "box.stl"\nunits = "furlong"', ["contact[0].units", "furlong"]),
        ("primitives = [{cone = [1, 2]}]", ["contact[0].primitives[0]"]),
    ],
)
def test_cli_bad_mesh_body_exit_2_nothing_written(tmp_path, body, words):
    """A missing file, an unreadable one, an open surface, a body through the sheet, an unknown
    unit, a bad primitive: exit 2, one line on stderr naming the key (and the file), no output."""
    (tmp_path / "garbage.stl").write_bytes(b"solid x\n this is not an stl\n")
    _write(tmp_path / "open.stl", BOX_V, BOX_F[:-2])
    _write(tmp_path / "box.stl", BOX_V, BOX_F)
    r, out = _cli(tmp_path, body)
    assert r.returncode == 2, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, r.stderr
    assert all(w in lines[0] for w in words), lines[0]
    assert not out.exists()


def test_cli_mesh_body_run(tmp_path):
    """A small sheet dropped on a box body read from an STL runs (exit 0 or 1: relaxed or stopped at
    max_steps, state written) and ends on the box: no node below its top face by more than the
    contact tolerance (2 % of h) beyond the offset."""
    _write(tmp_path / "box.stl", BOX_V, BOX_F)
    r, out = _cli(tmp_path, 'file = "box.stl"\ntranslate = [-2.0, -3.0, -2.1]')
    assert r.returncode in (0, 1), r.stderr
    assert json.loads((out / "summary.json").read_text())
    pts = np.asarray(meshio.read(out / "result.vtu").point_data["position"])
    above = (np.abs(pts[:, 0]) < 2.0) & (np.abs(pts[:, 1]) < 3.0)
    assert np.all(pts[above, 2] >= -0.1 + 0.03 - 0.02 * 0.0593 - 1e-9)


EXAMPLES = {"tablecloth": "16x16", "skirt": "6x40", "scarf": "16x16"}


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_example_scenes_build_and_start_clear(name):
    """The example scenes' bodies are built from their primitives (closed, outward: the checks of
    contact_mesh pass), and their sheets start clear of them on the default mesh (no node or face
    point inside: check_initial_contact raises otherwise); the tablecloth's and the scarf's bodies
    reach exactly to the sheet's lower face (h/2 below the flat mid-surface)."""
    from solidshell.scenes import load
    from solidshell.scenes.build import build_scene_mesh, check_initial_contact, contact_bodies, support_mask

    sc = load(name)
    (body,) = contact_bodies(sc)
    assert body.code == ck.MESH and body.n_triangles > 1000
    if name != "skirt":  # (the skirt's torso rises through its waist hole)
        assert body.V[:, 2].max() == pytest.approx(-body.offset, abs=1e-9)
    m, _ = build_scene_mesh(sc)
    check_initial_contact(sc, m, support_mask(sc, m), [body])


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_example_scenes_run(tmp_path, name):
    """Each example runs from `solidshell run NAME` on a coarse mesh to a steady state (exit 0) with
    its pictures, and verification/penetration_check finds it clean: no node or face point deeper in
    the body than 2 % of h, by its own exact distance to the rebuilt triangles."""
    out = tmp_path / name
    r = subprocess.run(
        [sys.executable, "-m", "solidshell", "run", name, "--mesh", EXAMPLES[name], "--out", str(out), "--no-progress"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    assert all((out / f"{v}.png").is_file() for v in ("iso", "side", "top"))
    c = subprocess.run(
        [sys.executable, "-m", "verification.penetration_check", str(out)], capture_output=True, text=True, cwd=ROOT
    )
    assert c.returncode == 0, c.stdout + c.stderr


def test_updates_measure_against_the_triangles():
    """The augmented-Lagrangian updates measure a mesh body's raw penetration with the exact distance
    (contact_augment.raw_penetration -> MeshBody.exact_penetration); at a sharp edge the kernels'
    distance is exact as well (its exact cells), so both see the true depth.  Exact to 1e-12
    against the analytic box (round-off of the closest-point arithmetic)."""
    from solidshell.contact_augment import raw_penetration

    b = MeshBody(BOX_V, BOX_F, spacing=0.23, band=1.6, offset=0.03)  # (0.23: the edge off the lattice)
    t = np.linspace(-0.15, 0.15, 31)
    x = np.column_stack([4.0 + t, np.full_like(t, 3.0), 2.0 + t[::-1] * 0.5])  # across the edge x = 4, z = 2
    p = raw_penetration([b], x)[0]
    ga, _ = _box_analytic().signed_distance(x)
    np.testing.assert_allclose(p, b.offset - ga, atol=1e-12)
    g_grid, _ = b.signed_distance(x)
    np.testing.assert_allclose(g_grid, ga, atol=1e-12)  # (the kernels' exact cells there: same depth)


def test_grid_disk_cache(tmp_path, monkeypatch):
    """A built grid is kept on disk under the hash of the surface and the grid's parameters: the
    second build of the same body reads it (the same floats, bit for bit), another spacing or a
    moved body builds anew, an unreadable entry is rebuilt (and replaced), and
    SOLIDSHELL_GRID_CACHE=off keeps nothing."""
    from solidshell import contact_mesh as cm

    monkeypatch.setenv("SOLIDSHELL_GRID_CACHE", str(tmp_path / "grids"))
    a = MeshBody(BOX_V, BOX_F, spacing=0.23, band=1.0)
    files = sorted((tmp_path / "grids").glob("*.npz"))
    assert len(files) == 1
    calls = []
    real = cm.build_grid
    monkeypatch.setattr(cm, "build_grid", lambda *args, **kw: calls.append(1) or real(*args, **kw))
    b = MeshBody(BOX_V, BOX_F, spacing=0.23, band=1.0)
    assert not calls
    np.testing.assert_array_equal(a.grid, b.grid)
    np.testing.assert_array_equal(a.params, b.params)
    assert (a.n_blocks, a.n_exact) == (b.n_blocks, b.n_exact)
    MeshBody(BOX_V, BOX_F, spacing=0.25, band=1.0)
    MeshBody(BOX_V + 1.0, BOX_F, spacing=0.23, band=1.0)
    assert len(calls) == 2 and len(list((tmp_path / "grids").glob("*.npz"))) == 3
    files[0].write_bytes(b"not a grid")
    c = MeshBody(BOX_V, BOX_F, spacing=0.23, band=1.0)
    assert len(calls) == 3
    np.testing.assert_array_equal(a.grid, c.grid)
    monkeypatch.setenv("SOLIDSHELL_GRID_CACHE", "off")
    MeshBody(BOX_V, BOX_F, spacing=0.31, band=1.0)
    assert len(calls) == 4 and len(list((tmp_path / "grids").glob("*.npz"))) == 3
