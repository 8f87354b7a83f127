"""The fields written for ParaView (solidshell/fields.py, issue 40 item 1), read back from the files
with meshio and checked against closed forms, a reference elastica and the solver's own state."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from importlib import resources

import meshio
import numpy as np
import pytest

from solidshell import Fabric, Model, ShellMesh, fields, solve_static
from solidshell.contact import Plane
from solidshell.problem import Problem


def _grid(nx, ny, Lx, Ly, tris=False):
    x, y = np.meshgrid(np.linspace(0, Lx, nx + 1), np.linspace(0, Ly, ny + 1), indexing="ij")
    X = np.column_stack([x.ravel(), y.ravel(), 0 * x.ravel()])
    i = np.arange(len(X)).reshape(nx + 1, ny + 1)
    q = np.column_stack([i[:-1, :-1].ravel(), i[1:, :-1].ravel(), i[1:, 1:].ravel(), i[:-1, 1:].ravel()])
    if tris:  # every other quad split in two: both element types in one mesh
        return ShellMesh(X, quads=q[::2], tris=np.vstack([q[1::2][:, [0, 1, 2]], q[1::2][:, [0, 2, 3]]]))
    return ShellMesh(X, quads=q)


def _cells(m, name):
    return np.concatenate([np.asarray(a) for a in m.cell_data[name]])


@pytest.mark.parametrize("tris, membrane", [(False, "full"), (False, "ans"), (True, "full")])
@pytest.mark.parametrize("warp_deg", [0.0, 90.0])
def test_uniform_stretch_gives_the_green_strain_and_c_m_times_it(tris, membrane, warp_deg):
    # U_o = (e x, 0, 0): the Green strain e + e^2/2 along x, exactly, on quads (compatible and
    # assumed membrane: its field passes the patch test) and triangles; with the warp turned 90 deg
    # the same stretch is along the weft (component yy). 1e-12: round-off only.
    mat = Fabric.wool(warp_angle=warp_deg)
    mesh = _grid(4, 3, 2.0, 1.5, tris)
    e = 0.01
    U = np.zeros((mesh.n_nodes, 6))
    U[:, 0] = e * mesh.nodes[:, 0]
    cell = fields.element_fields(Model(mesh, mat, membrane=membrane), U)
    eps = np.zeros(3)
    eps[0 if warp_deg == 0.0 else 1] = e + 0.5 * e * e
    for j, c in enumerate(fields.COMPONENTS):
        np.testing.assert_allclose(cell[f"membrane_strain_{c}"], eps[j], atol=1e-12)
        np.testing.assert_allclose(cell[f"N_{c}"], (mat.C_m @ eps)[j], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(cell[f"curvature_{c}"], 0.0, atol=1e-12)
    np.testing.assert_allclose(cell["Q_xz"], 0.0, atol=1e-12)


@pytest.mark.parametrize("tris", [False, True])
def test_cylinder_curvature_is_one_over_r(tris):
    # a strip rolled to radius R with its directors normal: kappa_xx = 1/R, M_xx = C_b[0,0]/R. The
    # flat elements' chords see 4 sin^2(D/2) / (R D^2) = (1 - D^2/12) / R, D the element's angle:
    # 1.3e-4 here, hence 2e-4. Positive kappa: the sheet bends away from its director side.
    mat = Fabric.wool()
    mesh = _grid(40, 2, 2 * np.pi, 1.0, tris)
    R = 4.0
    th = mesh.nodes[:, 0] / R
    pos = np.column_stack([R * np.sin(th), mesh.nodes[:, 1], -R * (1 - np.cos(th))])
    d = np.column_stack([np.sin(th), 0 * th, np.cos(th)])
    U = np.hstack([pos - mesh.nodes, d - mesh.directors])
    model = Model(mesh, mat)
    cell = fields.element_fields(model, U)
    np.testing.assert_allclose(cell["curvature_xx"], 1 / R, rtol=2e-4)
    np.testing.assert_allclose(cell["M_xx"], mat.C_b[0, 0] / R, rtol=2e-4)
    np.testing.assert_allclose(cell["curvature_yy"], 0.0, atol=1e-12)
    point = fields.nodal_average(model, cell)  # a uniform field stays uniform at the nodes
    np.testing.assert_allclose(point["M_xx"], mat.C_b[0, 0] / R, rtol=2e-4)


def test_contact_pressure_of_a_sheet_on_a_plane_is_its_weight_per_area():
    # a sheet lying on a plane under its weight, solved with the penalty contact: at equilibrium
    # every node's reaction over its area is the weight per area (0.019 gf/cm^2); 1e-4 relative:
    # the static solver's residual tolerance
    mat = Fabric.wool()
    mesh = _grid(4, 4, 10.0, 10.0)
    model = Model(mesh, mat)
    fixed = np.zeros((mesh.n_nodes, 6), bool)
    fixed[:, :2] = True  # no in-plane rigid motion
    loads = np.zeros((mesh.n_nodes, 6))
    loads[:, 2] = -mat.weight_per_area * model.nodal_areas()
    body = Plane((0, 0, 0), (0, 0, 1), offset=mat.thickness / 2)
    res = solve_static(model, fixed, loads, contact=[body])
    assert res.converged
    point, _ = fields.state_fields(Problem(model, fixed, loads, contact=[body]), res.U)
    np.testing.assert_allclose(point["contact_pressure:plane"], mat.weight_per_area, rtol=1e-4)
    assert np.all(point["gap:plane"] < 0) and np.all(point["gap:plane"] > -0.01 * mat.thickness)


def test_self_intersecting_flag_marks_two_crossing_quads():
    X = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [1, -1, -1], [1, 3, -1], [1, 3, 1], [1, -1, 1]], float)
    mesh = ShellMesh(X, quads=[[0, 1, 2, 3], [4, 5, 6, 7]])
    point, cell = fields.flag_fields(Model(mesh, Fabric.wool()), np.zeros((8, 6)))
    assert cell["self_intersecting"].tolist() == [1, 1] and point["self_intersecting"].sum() == 8


def test_layers_close_flags_two_sheets_brought_within_half_a_thickness():
    # two 2x2 sheets 10 cm apart, the upper one moved down to 0.5 h above the lower: every node is
    # a node of a layer closer than 0.9 h (layers.py); no triangle crosses another
    a, b = _grid(2, 2, 2.0, 2.0), _grid(2, 2, 2.0, 2.0)
    mat = Fabric.wool()
    X = np.vstack([a.nodes, b.nodes + [0.0, 0.0, 10.0]])
    mesh = ShellMesh(X, quads=np.vstack([a.quads, b.quads + a.n_nodes]))
    U = np.zeros((mesh.n_nodes, 6))
    U[a.n_nodes :, 2] = -10.0 + 0.5 * mat.thickness
    point, cell = fields.flag_fields(Model(mesh, mat), U)
    assert point["layers_close"].tolist() == [1] * mesh.n_nodes and not cell["self_intersecting"].any()
    point, _ = fields.flag_fields(Model(mesh, mat), np.zeros((mesh.n_nodes, 6)))
    assert not point["layers_close"].any()


def test_strip_root_moment_from_the_file_against_the_heavy_elastica(tmp_path):
    # strip-warp 20x1 static: M_xx read from result.vtu, the first two elements' means extrapolated
    # linearly to the clamp, against the clamp moment of reference/elastica_strip.json (0.1171 gf
    # cm/cm); measured +0.44 %; 1 %: the tip's own agreement on 10x1 (README). The transverse
    # shear at the first element's centre balances the weight beyond it (times the cosine of the
    # chord's slope): measured +1.3 %, the size of (kappa L_e)^2 / 8 with the root element turning
    # kappa L_e = 0.32 rad across its 0.25 cm, hence 2 %.
    from solidshell.run import run_scene

    out = run_scene("strip-warp", mesh="20x1", out_dir=tmp_path, progress=False)
    ref = json.loads(resources.files("reference").joinpath("elastica_strip.json").read_text())["strip"]["warp"]
    m = meshio.read(tmp_path / "result.vtu")
    M = _cells(m, "M_xx")
    xc = np.asarray(m.points)[np.asarray(m.cells[0].data)].mean(1)[:, 0]
    order = np.argsort(xc)
    M0 = 1.5 * M[order[0]] - 0.5 * M[order[1]]  # the element centres at 1/40 and 3/40 of L
    assert M0 == pytest.approx(ref["clamp_moment"], rel=0.01)
    x = np.asarray(m.point_data["position"])
    q = np.asarray(m.cells[0].data)[order[0]]
    d = 0.5 * (x[q[1]] + x[q[2]] - x[q[0]] - x[q[3]])  # the chord along the strip
    dx, dz = abs(d[0]), d[2]
    w_beyond = ref["w"] * (ref["L"] - 0.125)  # the weight beyond the first centre (0.125 cm)
    assert -_cells(m, "Q_xz")[order[0]] == pytest.approx(w_beyond * dx / np.hypot(dx, dz), rel=0.02)
    # the file holds the solver's state's fields, bit for bit
    point, cell = fields.state_fields(out.problem, out.U)
    np.testing.assert_array_equal(_cells(m, "curvature_xx"), cell["curvature_xx"])
    np.testing.assert_array_equal(m.point_data["thickness_strain"], point["thickness_strain"])
    assert m.point_data["clamped"].sum() == 2  # the two clamp nodes
    # series.pvd: the load path from rest (0) to the full weight (1), the last frame the result
    pvd = ET.parse(tmp_path / "series.pvd").getroot()
    steps = [(float(d.get("timestep")), d.get("file")) for d in pvd.iter("DataSet")]
    assert [t for t, _ in steps] == [0.0, 1.0]
    first, last = (meshio.read(tmp_path / f) for _, f in (steps[0], steps[-1]))
    assert np.all(_cells(first, "M_xx") == 0.0)
    np.testing.assert_array_equal(_cells(last, "M_xx"), M)


def test_pedestal_sheet_whole_with_its_clamped_patch(tmp_path):
    # square-pedestal 8x3x4: result.vtu holds the hanging part's quads and the part lying on the
    # pedestal as one polygon (the 32 clamped nodes round the 10 x 10 cm top): the sheet's 400 cm^2
    from solidshell.analysis import polygon_area
    from solidshell.run import run_scene

    out = run_scene("square-pedestal", mesh="8x3x4", out_dir=tmp_path, progress=False)
    for name in ("result.vtu", "deformed.vtu"):
        m = meshio.read(tmp_path / name)
        kinds = {b.type: np.asarray(b.data) for b in m.cells}
        assert set(kinds) == {"quad", "polygon"} and kinds["polygon"].shape == (1, 32)
        top = np.asarray(m.points)[kinds["polygon"][0]]
        assert polygon_area(top[:, :2]) == pytest.approx(100.0) and np.ptp(top[:, 2]) == 0.0
        assert out.mesh.area() + polygon_area(top[:, :2]) == pytest.approx(400.0)
        assert m.cell_data["clamped_part"][1].tolist() == [1] and m.cell_data["M_xx"][1].tolist() == [0.0]
        assert np.all(np.asarray(m.point_data["gap:pedestal"]) > -0.02 * 0.0593)  # the contract's 2 % of h
    x = meshio.read(tmp_path / "result.xdmf")  # XDMF: the solver's mesh and its fields (no polygon cell)
    assert [b.type for b in x.cells] == ["quad"] and "M_xx" in x.cell_data and "gap:pedestal" in x.point_data


def test_adaptive_series_carries_refinement_levels(tmp_path):
    # a short adaptive relaxation of the sphere: every frame of series.pvd on its own mesh with its
    # levels (transition elements between i and i+1 at i + 1/2), assumed-membrane tags and fields
    from solidshell.run import run_scene

    out = run_scene("sphere", solver="relax", adaptive=True, out_dir=tmp_path, progress=False, t_max=0.11)
    pvd = ET.parse(tmp_path / "series.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    assert len(files) >= 2
    last = meshio.read(tmp_path / files[-1])
    lv = _cells(last, "refinement_level")
    assert lv.min() == 0.0 and lv.max() >= 1.0 and np.all(np.isin(lv * 2, np.arange(0, 2 * 4 + 1)))
    assert set(np.unique(_cells(last, "assumed_membrane"))) <= {0, 1}
    m = meshio.read(tmp_path / "result.vtu")
    assert len(m.points) == out.mesh.n_nodes and "contact_pressure:sphere" in m.point_data
    np.testing.assert_array_equal(_cells(m, "refinement_level"), out.mesh.cell_tags["refinement_level"])
