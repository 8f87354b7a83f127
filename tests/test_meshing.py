"""Tests of solidshell.meshing: the paper's meshes (counts, areas, orientation, node sets) and
bad inputs.  Every mesh here is built in well under a second."""

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from solidshell.errors import InputError
from solidshell.mesh import ShellMesh
from solidshell.meshing import RECIPES, build_mesh, from_file, gmsh_initialize, parse_density

# (recipe, density, geometry, quads, nodes): every mesh named in the paper, §3.1-§6.4
PAPER_MESHES = [
    ("strip", "10x1", {}, 10, 22),  # §3.1
    ("strip", "20x1", {}, 20, 42),  # §3.1
    ("square_on_square", "24x8x4", {}, 768, 864),  # §3.2
    ("square_on_square", "48x16x4", {}, 3072, 3264),  # §3.2
    ("square_on_square", "6x2x4", {}, 48, 72),  # §6.1 level 0
    ("square_on_square", "45x15x4", dict(sheet=40.0, pedestal=20.0), 2700, 2880),  # §3.5
    ("square_on_square", "6x2x4", dict(sheet=40.0, pedestal=20.0), 48, 72),  # §6.2 level 0
    ("square_on_square", "96x32x4", {}, 12288, 12672),  # refinement of §3.2
    ("disc_on_disc", "10x40", {}, 400, 440),  # §3.3
    ("disc_on_disc", "20x80", {}, 1600, 1680),  # §3.3
    ("square_on_disc", "30x240", {}, 7200, 7440),  # §3.4
    ("square_on_disc", "4x32", {}, 128, 160),  # §6.3 level 0
    ("square", "40x40", dict(size=20.0), 1600, 1681),  # §4.1
    ("square", "50x50", dict(size=100.0), 2500, 2601),  # §4.1
    ("square", "60x60", dict(size=30.0), 3600, 3721),  # §4.2 sphere
    ("square", "100x100", dict(size=30.0), 10000, 10201),  # §4.3 sphere
    ("square", "16x16", dict(size=30.0), 256, 289),  # §6.4 level 0
]

_cache: dict = {}


def mesh_of(recipe, density, geometry):
    key = (recipe, density, tuple(sorted(geometry.items())))
    if key not in _cache:
        _cache[key] = build_mesh(recipe, density, **geometry)
    return _cache[key]


def ids(params):
    return [f"{p[0]}-{p[1]}-{'-'.join(f'{v:g}' for v in p[2].values())}" for p in params]


@pytest.mark.parametrize("recipe,density,geometry,n_quads,n_nodes", PAPER_MESHES, ids=ids(PAPER_MESHES))
def test_paper_mesh_counts(recipe, density, geometry, n_quads, n_nodes):
    m = mesh_of(recipe, density, geometry)
    assert (m.n_quads, m.n_tris, m.n_nodes) == (n_quads, 0, n_nodes)


def _straight_area(recipe, g):
    return {
        "strip": lambda: g.get("length", 5.0) * g.get("width", 1.0),
        "square_on_square": lambda: g.get("sheet", 20.0) ** 2 - g.get("pedestal", 10.0) ** 2,
        "square": lambda: g.get("size", 20.0) ** 2,
    }[recipe]()


STRAIGHT = [p for p in PAPER_MESHES if p[0] in ("strip", "square_on_square", "square")]


@pytest.mark.parametrize("recipe,density,geometry,n_quads,n_nodes", STRAIGHT, ids=ids(STRAIGHT))
def test_straight_sided_area_is_exact(recipe, density, geometry, n_quads, n_nodes):
    m = mesh_of(recipe, density, geometry)
    # straight sides are meshed exactly; only rounding in gmsh's node coordinates and the
    # summation of <= 1e4 element areas remains (~1e-14), so 1e-10 is a wide margin
    assert m.area() == pytest.approx(_straight_area(recipe, geometry), rel=1e-10)


def _rates(recipe, densities, exact):
    err = [abs(build_mesh(recipe, d).area() - exact) / exact for d in densities]
    return [math.log2(err[i] / err[i + 1]) for i in range(len(err) - 1)]


def test_disc_area_converges_at_second_order():
    exact = math.pi * (12.7**2 - 6.35**2)
    rates = _rates("disc_on_disc", ["2x20", "4x40", "8x80", "16x160"], exact)
    # the polygonal area error is 1 - sin(x)/x = x^2/6 - x^4/120 + ..., x = 2*pi/C: the x^4 term
    # shifts the observed rate below 2 by ~0.002 at C = 20, so 2 +- 0.1 cannot fail by accident
    # yet rejects first-order behaviour
    assert all(abs(r - 2.0) < 0.1 for r in rates), rates


def test_square_on_disc_area_converges_at_second_order():
    exact = 50.0**2 - math.pi * 10.0**2
    rates = _rates("square_on_disc", ["2x16", "4x32", "8x64", "16x128"], exact)
    # same polygon error of the inscribed pedestal circle (x = 2*pi/C); see the disc test
    assert all(abs(r - 2.0) < 0.1 for r in rates), rates


@pytest.mark.parametrize("recipe,density,geometry,n_quads,n_nodes", PAPER_MESHES, ids=ids(PAPER_MESHES))
def test_flat_counter_clockwise_directors_up_no_duplicates(recipe, density, geometry, n_quads, n_nodes):
    m = mesh_of(recipe, density, geometry)
    assert np.all(m.nodes[:, 2] == 0.0)
    assert np.array_equal(m.directors, np.tile([0.0, 0.0, 1.0], (m.n_nodes, 1)))
    P = m.nodes[m.quads]
    normals = np.cross(np.roll(P, -1, axis=1) - P, np.roll(P, 1, axis=1) - P)  # at each corner
    assert np.all(normals[..., 2] > 0.0)
    # nodes closer than 1e-9 of the mesh size would be duplicates (the finest spacing is ~1e-3)
    q = np.round(m.nodes / (1e-9 * m.characteristic_length()))
    assert len(np.unique(q, axis=0)) == m.n_nodes
    assert len(np.unique(m.quads)) == m.n_nodes  # every node belongs to an element


# geometric tolerance for "on the edge": the nodes are placed by gmsh from exact endpoints, so
# rounding is ~1e-15 cm; 1e-9 cm separates on-edge nodes from the next row (>= 0.1 cm away)
TOL = 1e-9


def close(a, b):
    """Coordinates equal within TOL cm (absolute, as for positions)."""
    return np.allclose(a, b, rtol=0.0, atol=TOL)


def test_strip_sets():
    m = build_mesh("strip", "20x1")
    x = m.nodes[:, 0]
    assert np.array_equal(m.node_set("clamped"), np.flatnonzero(np.abs(x) < TOL))
    assert np.array_equal(m.node_set("tip"), np.flatnonzero(np.abs(x - 5.0) < TOL))
    assert len(m.node_set("clamped")) == 2
    assert close(m.nodes.min(0), [0.0, -0.5, 0.0]) and close(m.nodes.max(0), [5.0, 0.5, 0.0])


@pytest.mark.parametrize("sheet,pedestal,density,a", [(20.0, 10.0, "24x8x4", 24), (40.0, 20.0, "45x15x4", 45)])
def test_square_on_square_sets(sheet, pedestal, density, a):
    m = mesh_of("square_on_square", density, dict(sheet=sheet, pedestal=pedestal))
    linf = np.abs(m.nodes[:, :2]).max(axis=1)
    assert np.array_equal(m.node_set("clamped"), np.flatnonzero(np.abs(linf - pedestal / 2) < TOL))
    assert np.array_equal(m.node_set("outer"), np.flatnonzero(np.abs(linf - sheet / 2) < TOL))
    assert len(m.node_set("clamped")) == len(m.node_set("outer")) == 4 * a
    assert np.all(linf >= pedestal / 2 - TOL)  # only the hanging part is meshed
    # the pedestal edge is the boundary: clamped edges are boundary edges of the mesh
    b = m.boundary_edges()
    assert np.isin(b, np.r_[m.node_set("clamped"), m.node_set("outer")]).all()


def test_square_on_square_panels_are_trapezoids_meeting_on_diagonals():
    m = build_mesh("square_on_square", "6x2x4")
    x, y = m.nodes[:, 0], m.nodes[:, 1]
    on_diag = np.abs(np.abs(x) - np.abs(y)) < TOL
    assert on_diag.sum() == 4 * 3  # B + 1 = 3 nodes on each diagonal
    # the warp (X) axis and weft (Y) axis cross the outer edge at nodes because A = 6 is even
    assert np.any((np.abs(y) < TOL) & (np.abs(x - 10.0) < TOL))


@pytest.mark.parametrize("grading", [4.0, 8.0])
def test_square_on_square_grading(grading):
    # the graded mesh has the uniform one's counts, covers the same hanging area exactly (straight
    # sides), keeps the mirror symmetries and grows its elements from the pedestal corners by the
    # requested factor along the diagonals
    m = build_mesh("square_on_square", "24x8x4", grading=grading)
    u = build_mesh("square_on_square", "24x8x4")
    assert (len(m.quads), m.n_nodes) == (len(u.quads), u.n_nodes)
    assert m.area() == pytest.approx(400.0 - 100.0, rel=1e-12)
    x = m.nodes

    def key(p):
        return np.round(p, 9).tolist()

    assert sorted(map(key, x * [-1, 1, 1])) == sorted(map(key, x))
    diag = x[np.abs(x[:, 0] - x[:, 1]) < 1e-9]
    r = np.sort(diag[diag[:, 0] > 0, 0])
    h = np.diff(r)
    assert h[-1] / h[0] == pytest.approx(grading, rel=1e-6)
    with pytest.raises(InputError, match="grading"):
        build_mesh("square_on_square", "24x8x4", grading=0.5)


@pytest.mark.parametrize(
    "recipe,density,inner,outer_r", [("disc_on_disc", "10x40", 6.35, 12.7), ("square_on_disc", "30x240", 10.0, None)]
)
def test_circular_pedestal_sets(recipe, density, inner, outer_r):
    m = mesh_of(recipe, density, {})
    r = np.linalg.norm(m.nodes[:, :2], axis=1)
    c = int(density.split("x")[1])
    assert np.array_equal(m.node_set("clamped"), np.flatnonzero(np.abs(r - inner) < TOL))
    assert len(m.node_set("clamped")) == len(m.node_set("outer")) == c
    assert np.all(r >= inner - TOL)
    out = m.nodes[m.node_set("outer")]
    if outer_r is not None:
        assert close(np.linalg.norm(out[:, :2], axis=1), outer_r)
    else:
        assert close(np.abs(out[:, :2]).max(axis=1), 25.0)
    # clamped nodes are uniform in angle; OpenCASCADE arcs are exact to rounding (~1e-15 rad),
    # 1e-12 rad would catch gmsh's built-in kernel, which is ~1e-9 rad off
    ang = np.sort(np.arctan2(m.nodes[m.node_set("clamped"), 1], m.nodes[m.node_set("clamped"), 0]))
    assert np.allclose(np.diff(ang), 2 * np.pi / c, rtol=0.0, atol=1e-12)


def test_square_on_disc_diagonals_and_axes_are_mesh_lines():
    m = build_mesh("square_on_disc", "4x32")
    x, y = m.nodes[:, 0], m.nodes[:, 1]
    assert (np.abs(np.abs(x) - np.abs(y)) < TOL).sum() == 4 * 5  # R + 1 nodes per diagonal
    assert ((np.abs(x) < TOL) | (np.abs(y) < TOL)).sum() == 4 * 5  # and per half-axis


SYMMETRIC = [p for p in PAPER_MESHES if p[0] != "strip"]


@pytest.mark.parametrize("recipe,density,geometry,n_quads,n_nodes", SYMMETRIC, ids=ids(SYMMETRIC))
def test_mirror_symmetric_about_warp_and_weft_axes(recipe, density, geometry, n_quads, n_nodes):
    # symmetric drapes (Sections 3.2-3.5) need a symmetric mesh: mirroring the nodes about the X
    # axis and about the Y axis gives the same node cloud to rounding (1e-12 cm << spacing)
    from scipy.spatial import cKDTree

    m = mesh_of(recipe, density, geometry)
    tree = cKDTree(m.nodes)
    for flip in ([1, -1, 1], [-1, 1, 1]):
        dist, _ = tree.query(m.nodes * flip)
        assert dist.max() < 1e-12


def test_square_sets():
    m = mesh_of("square", "40x40", dict(size=20.0))
    X = m.nodes
    corner = {"sw": (-10, -10), "se": (10, -10), "ne": (10, 10), "nw": (-10, 10)}
    for k, xy in corner.items():
        (i,) = m.node_set(f"corner_{k}")
        assert close(X[i, :2], xy)
    assert sorted(m.node_set("corners")) == sorted(int(m.node_set(f"corner_{k}")[0]) for k in corner)
    hung = m.node_set("hung")
    assert len(hung) == 2 and close(X[hung, 1], 10.0)
    assert close(abs(X[hung[0], 0] - X[hung[1], 0]), 20.0)  # adjacent corners
    on_edge = np.abs(np.abs(X[:, :2]).max(axis=1) - 10.0) < TOL
    assert np.array_equal(m.node_set("outer"), np.flatnonzero(on_edge)) and on_edge.sum() == 160


def test_rectangular_square_density_and_centring():
    m = build_mesh("square", "4x2", size=2.0)
    assert (m.n_quads, m.n_nodes) == (8, 15)
    assert np.allclose(m.nodes.mean(0), 0.0, rtol=0.0, atol=1e-15)  # mirrored nodes cancel to rounding
    assert close(np.unique(np.round(m.nodes[:, 0], 9)), np.linspace(-1, 1, 5))


def test_deterministic():
    a, b = build_mesh("square_on_disc", "4x32"), build_mesh("square_on_disc", "4x32")
    assert np.array_equal(a.nodes, b.nodes) and np.array_equal(a.quads, b.quads)
    assert all(np.array_equal(a.node_sets[k], b.node_sets[k]) for k in a.node_sets)


def test_default_densities_are_the_papers():
    assert {k: r.density for k, r in RECIPES.items()} == {
        "strip": "10x1",
        "square_on_square": "24x8x4",
        "disc_on_disc": "10x40",
        "square_on_disc": "30x240",
        "square": "40x40",
        "from_file": None,
    }
    assert build_mesh("disc_on_disc").n_quads == 400
    assert build_mesh("square-on-square", "6x2x4").n_quads == 48  # scene-style name


_SIGPIPE_PROBE = """
import signal, sys, threading
from pathlib import Path
from solidshell.meshing import build_mesh

def ignored():  # the kernel's disposition: signal.getsignal only echoes what Python last set
    status = Path("/proc/self/status").read_text()
    mask = int(next(s for s in status.splitlines() if s.startswith("SigIgn:")).split()[1], 16)
    return bool(mask & (1 << (signal.SIGPIPE - 1)))

before = ignored()
if sys.argv[1] == "main":
    build_mesh("strip", "4x1")
else:
    t = threading.Thread(target=build_mesh, args=("strip", "4x1"))
    t.start()
    t.join()
print(before, ignored())
"""


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads the signal mask from /proc")
@pytest.mark.parametrize("where", ["main", "thread"])
def test_meshing_keeps_sigpipe_ignored(where):
    # gmsh's first initialise in a process sets SIGPIPE to "terminate": a later write to a closed
    # socket or pipe (Dask, a subprocess, `| head`) then killed the whole process with exit 141
    # instead of raising BrokenPipeError -- one CI run of the suite died that way.  A fresh
    # interpreter, since only the process's first gmsh session does it.
    out = subprocess.run([sys.executable, "-c", _SIGPIPE_PROBE, where], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "True"], out.stdout + out.stderr


def test_leaves_a_running_gmsh_session_alone():
    import gmsh

    gmsh_initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("users_model")
        build_mesh("strip", "10x1")
        assert gmsh.isInitialized() and gmsh.model.getCurrent() == "users_model"
    finally:
        gmsh.finalize()


# ------------------------------------------------------------------------- densities
@pytest.mark.parametrize(
    "text,n,expected",
    [("24x8x4", 3, (24, 8, 4)), ("24×8×4", 3, (24, 8, 4)), ("24X8X4", 3, (24, 8, 4)), (" 10 x 1 ", 2, (10, 1))],
)
def test_parse_density(text, n, expected):
    assert parse_density(text, n) == expected


@pytest.mark.parametrize(
    "text,n",
    [
        ("24x8", 3),
        ("0x5", 2),
        ("-3x4", 2),
        ("abc", 2),
        ("2.5x4", 2),
        ("", 2),
        ("24x8x", 3),
        ("1e2x4", 2),
        (None, 2),
        ("24x8x4x4", 3),
    ],
)
def test_parse_density_rejects(text, n):
    with pytest.raises(InputError, match="expected"):
        parse_density(text, n)


@pytest.mark.parametrize(
    "recipe,density,match",
    [
        ("square_on_square", "24x8", "AxBx4"),
        ("square_on_square", "24x8x3", "must be 4"),
        ("square_on_square", "0x8x4", "zero"),
        ("strip", "-3x4", "NxM"),
        ("strip", "abc", "NxM"),
        ("disc_on_disc", "10x42", "divisible by 4"),
        ("square_on_disc", "30x244", "divisible by 8"),
    ],
)
def test_build_mesh_rejects_bad_densities(recipe, density, match):
    with pytest.raises(InputError, match=match):
        build_mesh(recipe, density)


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: build_mesh("hexagon"), "unknown mesh recipe 'hexagon'"),
        (lambda: build_mesh("square", "4x4", diameter=3.0), "no geometry keyword 'diameter'"),
        (lambda: build_mesh("square_on_square", sheet=10.0, pedestal=10.0), "smaller"),
        (lambda: build_mesh("disc_on_disc", diameter=-1.0), "positive"),
        (lambda: build_mesh("strip", length="long"), "length"),
        (lambda: build_mesh("from_file"), "path"),
        (lambda: build_mesh("from_file", "4x4", path="x.msh"), "no density"),
    ],
)
def test_build_mesh_rejects_bad_calls(call, match):
    with pytest.raises(InputError, match=match):
        call()


# ------------------------------------------------------------------------- from_file
GEO = """
Point(1) = {0, 0, 0}; Point(2) = {4, 0, 0}; Point(3) = {4, 2, 0}; Point(4) = {0, 2, 0};
Line(1) = {1, 4}; Line(2) = {4, 3}; Line(3) = {3, 2}; Line(4) = {2, 1};   // clockwise loop
Transfinite Curve{1, 3} = 3; Transfinite Curve{2, 4} = 5;
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1}; Transfinite Surface{1};
Physical Curve("clamped") = {1}; Physical Point("corner") = {3}; Physical Curve(7) = {3};
Physical Surface("cloth") = {1};
"""


def _check_geo_mesh(m: ShellMesh):
    assert (m.n_quads, m.n_tris, m.n_nodes) == (8, 0, 15)
    assert m.area() == pytest.approx(8.0, rel=1e-12)  # exact rectangle, rounding only
    assert np.all(m.directors[:, 2] == 1.0)  # clockwise .geo loop turned up
    assert close(m.nodes[m.node_set("clamped"), 0], 0.0) and len(m.node_set("clamped")) == 3
    assert close(m.nodes[m.node_set("corner")], [[4.0, 2.0, 0.0]])
    assert close(m.nodes[m.node_set("curve_7"), 0], 4.0)  # unnamed group: named by tag


def test_from_file_geo(tmp_path):
    (tmp_path / "sheet.geo").write_text(GEO)
    _check_geo_mesh(from_file(tmp_path / "sheet.geo"))
    _check_geo_mesh(build_mesh("from_file", path=str(tmp_path / "sheet.geo")))


def test_from_file_msh(tmp_path):
    import gmsh

    (tmp_path / "sheet.geo").write_text(GEO)
    gmsh_initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(tmp_path / "sheet.geo"))
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(tmp_path / "sheet.msh"))
    finally:
        gmsh.finalize()
    _check_geo_mesh(from_file(tmp_path / "sheet.msh"))


def test_from_file_vtu_keeps_sets_and_directors(tmp_path):
    m = build_mesh("square_on_square", "6x2x4")
    m.to_meshio().write(tmp_path / "m.vtu")
    r = from_file(tmp_path / "m.vtu")
    assert np.array_equal(r.quads, m.quads) and np.array_equal(r.nodes, m.nodes)
    assert all(np.array_equal(r.node_set(k), m.node_set(k)) for k in m.node_sets)


def test_from_file_keeps_stored_directors(tmp_path):
    # an upside-down flat mesh (clockwise from +Z, directors -Z) is consistent: keep it as stored
    m = build_mesh("square", "2x2")
    down = ShellMesh(m.nodes, m.quads[:, ::-1], directors=-m.directors)
    down.to_meshio().write(tmp_path / "down.vtu")
    r = from_file(tmp_path / "down.vtu")
    assert np.array_equal(r.quads, down.quads) and np.array_equal(r.directors, down.directors)


def test_from_file_geo_inside_a_users_gmsh_session(tmp_path):
    import gmsh

    (tmp_path / "sheet.geo").write_text(GEO)
    gmsh_initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        _check_geo_mesh(from_file(tmp_path / "sheet.geo"))
        assert gmsh.option.getNumber("Mesh.RecombineAll") == 0  # the user's option restored
    finally:
        gmsh.finalize()


def test_from_file_unstructured_geo_is_recombined(tmp_path):
    (tmp_path / "disc.geo").write_text(
        "Point(1)={0,0,0,1}; Point(2)={3,0,0,1}; Point(3)={-3,0,0,1};\n"
        "Circle(1)={2,1,3}; Circle(2)={3,1,2}; Curve Loop(1)={1,2}; Plane Surface(1)={1};\n"
        'Physical Curve("rim")={1,2};\n'
    )
    m = from_file(tmp_path / "disc.geo")
    assert m.n_quads > 0 and m.n_quads > m.n_tris
    assert m.area() == pytest.approx(math.pi * 9.0, rel=0.05)  # polygonal disc with h = 1 cm
    assert close(np.linalg.norm(m.nodes[m.node_set("rim"), :2], axis=1), 3.0)


@pytest.mark.parametrize(
    "name,content,match",
    [
        ("missing.msh", None, "does not exist"),
        ("garbage.msh", b"\x00\x01 this is not a mesh", "cannot read"),
        ("empty.msh", b"", "is empty"),
        ("truncated.msh", b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4", "cannot read"),
        ("bad.geo", b"Point(1) = {0, 0, 0\nfoo bar;\n", "gmsh cannot mesh"),
        ("nosurface.geo", b"Point(1) = {0,0,0}; Point(2) = {1,0,0}; Line(1) = {1,2};\n", "no surface"),
        ("lines.vtu", None, "no quad or triangle"),
        ("mesh.txt", b"1 2 3\n", "cannot read"),
    ],
)
def test_from_file_rejects(tmp_path, name, content, match):
    path = tmp_path / name
    if content is not None:
        path.write_bytes(content)
    elif name.endswith(".vtu"):
        import meshio

        meshio.Mesh(np.eye(3), [("line", np.array([[0, 1], [1, 2]]))]).write(path)
    with pytest.raises(InputError, match=match):
        from_file(path)
