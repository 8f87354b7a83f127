"""Run output: atomic writes, XDMF/VTU round trips, time series, summary.json, run_scene wiring
(with a stand-in solver, so these tests stay fast and independent of the real solvers)."""

import json
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from solidshell import InputError, io, meshing
from solidshell.problem import SolveResult


# ----------------------------------------------------------------------------- atomic writes
def _leftovers(d):
    return sorted(p.name for p in d.iterdir())


def test_atomic_write_exception_leaves_nothing(tmp_path):
    p = tmp_path / "summary.json"
    with pytest.raises(RuntimeError, match="crash mid-write"):
        with io.atomic_write(p) as f:
            f.write('{"half": ')
            raise RuntimeError("crash mid-write")
    assert not p.exists()
    assert _leftovers(tmp_path) == []  # no temporary left either


def test_atomic_write_keeps_old_file_on_failure(tmp_path):
    p = tmp_path / "a.txt"
    with io.atomic_write(p) as f:
        f.write("old")
    with pytest.raises(KeyboardInterrupt, match="Ctrl-C mid-write"):
        with io.atomic_write(p) as f:
            f.write("new but unfinished")
            raise KeyboardInterrupt("Ctrl-C mid-write")
    assert p.read_text() == "old" and _leftovers(tmp_path) == ["a.txt"]


def test_atomic_path_exception_leaves_nothing(tmp_path):
    p = tmp_path / "mesh.vtu"
    with pytest.raises(ValueError, match="writer failed"):
        with io.atomic_path(p) as tmp:
            assert tmp.parent == p.parent and tmp.suffix == ".vtu" and tmp != p
            tmp.write_bytes(b"partial")
            raise ValueError("writer failed")
    assert not p.exists() and _leftovers(tmp_path) == []


def test_atomic_write_success_and_mode(tmp_path):
    p = tmp_path / "sub" / "x.txt"
    with io.atomic_write(p) as f:
        f.write("hello")
    assert p.read_text() == "hello" and _leftovers(p.parent) == ["x.txt"]
    umask = os.umask(0)
    os.umask(umask)
    assert p.stat().st_mode & 0o777 == 0o666 & ~umask


def test_write_json_unserialisable_leaves_nothing(tmp_path):
    p = tmp_path / "summary.json"
    with pytest.raises(TypeError, match="summary value of type object is not JSON-serialisable"):
        io.write_json(p, {"ok": 1, "bad": object()})
    assert not p.exists() and _leftovers(tmp_path) == []


def test_write_json_numpy_and_nan(tmp_path):
    p = io.write_json(
        tmp_path / "s.json",
        {"a": np.float64(1.5), "b": np.arange(3), "c": float("nan"), "d": (np.int32(2), np.bool_(True)), "e": tmp_path},
    )
    assert json.loads(p.read_text()) == {"a": 1.5, "b": [0, 1, 2], "c": None, "d": [2, True], "e": str(tmp_path)}


def test_mesh_write_failure_leaves_nothing(tmp_path, monkeypatch):

    from solidshell.mesh import ShellMesh

    mesh = ShellMesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], quads=[[0, 1, 2, 3]])

    def broken(filename, *a, **k):
        with open(filename, "w") as f:
            f.write("<Xdmf half")
        raise OSError("disk full")

    monkeypatch.setattr(io, "_write_xdmf", broken)
    with pytest.raises(OSError, match="disk full"):
        io.write_mesh_file(tmp_path / "mesh.xdmf", mesh)
    assert _leftovers(tmp_path) == []


# ----------------------------------------------------------------------------- meshio files
@pytest.fixture
def small():
    mesh = meshing.build_mesh("square", "4x3", size=8.0)
    U = np.zeros((mesh.n_nodes, 6))
    U[:, 2] = -0.05 * mesh.nodes[:, 0] ** 2
    U[:, 3] = 0.01 * mesh.nodes[:, 1]
    return mesh, U


@pytest.mark.parametrize("name", ["result.xdmf", "result.vtu"])
def test_state_round_trip(tmp_path, small, name):
    mesh, U = small
    p = io.write_mesh_file(tmp_path / name, mesh, U)
    m2, U2 = io.read_state(p)
    np.testing.assert_allclose(m2.nodes, mesh.nodes)
    np.testing.assert_array_equal(m2.quads, mesh.quads)
    np.testing.assert_allclose(U2, U, atol=1e-12)
    assert sorted(m2.node_sets) == sorted(mesh.node_sets)
    np.testing.assert_array_equal(m2.node_set("hung"), mesh.node_set("hung"))


def test_xdmf_is_self_contained_xml(tmp_path, small):
    mesh, U = small
    p = io.write_mesh_file(tmp_path / "result.xdmf", mesh, U)
    root = ET.parse(p).getroot()
    names = {a.get("Name") for a in root.iter("Attribute")}
    assert {"displacement", "director", "director_displacement", "position", "set:hung"} <= names
    assert all(d.get("Format") == "XML" for d in root.iter("DataItem"))
    assert _leftovers(tmp_path) == ["result.xdmf"]


def test_deformed_vtu(tmp_path, small):
    mesh, U = small
    p = io.write_mesh_file(tmp_path / "deformed.vtu", mesh, U, deformed=True)
    import meshio

    m = meshio.read(p)
    np.testing.assert_allclose(m.points, mesh.nodes + U[:, :3])


def test_time_series(tmp_path, small):
    mesh, U = small
    frames = [(0.0, 0 * U), (0.1, 0.5 * U), (0.4, U)]
    p = io.write_time_series(tmp_path / "series.xdmf", mesh, frames)
    root = ET.parse(p).getroot()
    assert [float(t.get("Value")) for t in root.iter("Time")] == [0.0, 0.1, 0.4]
    import meshio

    with meshio.xdmf.TimeSeriesReader(str(p)) as r:
        r.read_points_cells()
        t, pd, _ = r.read_data(2)
    assert t == 0.4
    np.testing.assert_allclose(pd["displacement"], U[:, :3], atol=1e-12)


def test_time_series_text_is_meshios_byte_for_byte(tmp_path, small):
    """write_time_series formats the inline numbers itself (a join instead of np.savetxt's loop);
    the file must be exactly what meshio's own TimeSeriesWriter writes (floats and the int
    topology), so ParaView and meshio read it as before."""
    import filecmp

    import meshio

    mesh, U = small
    frames = [(0.0, 0 * U), (0.1, 0.5 * U), (0.4, U)]
    ours = io.write_time_series(tmp_path / "series.xdmf", mesh, frames)
    ref = tmp_path / "ref.xdmf"
    with meshio.xdmf.TimeSeriesWriter(str(ref), data_format="XML") as w:
        w.write_points_cells(mesh.nodes, [("quad", mesh.quads)] if mesh.n_quads else [])
        for t, Uf in frames:
            w.write_data(t, point_data={"displacement": Uf[:, :3].copy(), "director_displacement": Uf[:, 3:].copy()})
    assert mesh.n_quads and not mesh.n_tris
    assert filecmp.cmp(ours, ref, shallow=False)


@pytest.mark.parametrize("tris", [False, True])
def test_mesh_file_xdmf_text_is_meshios_byte_for_byte(tmp_path, small, tris):
    """write_mesh_file's XDMF formats the inline numbers in one join (io._savetxt_text) instead of
    np.savetxt's loop: the file must be exactly what meshio.xdmf.write writes, for float point
    data (1-D and 2-D), int32 flags and cell data, on quads and on triangles."""
    import filecmp

    import meshio

    mesh, U = small
    if tris:
        q = mesh.quads
        mesh = type(mesh)(mesh.nodes, tris=np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]))
    rng = np.random.default_rng(3)
    point = {"curvature": rng.normal(size=mesh.n_nodes) * 1e-7, "interpenetrated": np.arange(mesh.n_nodes) % 2}
    cell = {"N": rng.normal(size=(mesh.n_elements, 3)), "self_intersecting": np.zeros(mesh.n_elements, np.int8)}
    ours = io.write_mesh_file(tmp_path / "result.xdmf", mesh, U, fields=(point, cell))
    m = io._with_fields(mesh.to_meshio(point_data=io._fields(mesh, U)), mesh, (point, cell), [])
    ref = tmp_path / "ref.xdmf"
    with io._no_h5py_needed():
        meshio.xdmf.write(str(ref), m, data_format="XML")
    assert filecmp.cmp(ours, ref, shallow=False)
    import io as pyio

    for a, fmt in [(np.zeros((0, 3)), "%.16e"), (np.zeros(0, np.int32), "%d"), (rng.normal(size=(4, 2)), "%.16e")]:
        b = pyio.BytesIO()
        np.savetxt(b, a, fmt)
        assert io._savetxt_text(a, fmt) == b.getvalue().decode()


def test_versions_and_counts(small):
    v = io.package_versions()
    assert {"python", "numpy", "scipy", "numba", "gmsh", "meshio"} <= set(v)
    assert v["numpy"] == np.__version__
    mesh, _ = small
    c = io.mesh_counts(mesh, np.zeros((mesh.n_nodes, 6), bool))
    assert c["nodes"] == 20 and c["quads"] == 12 and c["dofs"] == 120 and c["free_dofs"] == 120


# ----------------------------------------------------------------------------- run_scene
def fake_solver(record, converged=True):
    def solve(problem, settings, progress):
        record["settings"] = dict(settings)
        record["problem"] = problem
        X = problem.model.mesh.nodes
        U = np.zeros((len(X), 6))
        U[:, 2] = -0.02 * (X[:, 0] ** 2 + X[:, 1] ** 2)
        U[:, :2] = -0.1 * X[:, :2]
        U[problem.fixed] = 0.0
        progress(0.5, "half way")
        frames = [(0.0, 0 * U), (0.1, 0.3 * U), (0.4, U)]
        return SolveResult(
            U=U,
            converged=converged,
            message="fake solver" if converged else "ran out of steps",
            info={"iterations": 3, "solver": "fake", "residual": 1e-9},
            frames=frames,
        )

    return solve


@pytest.fixture
def fake(monkeypatch):
    from solidshell import solvers

    class Model:  # stands in for solidshell.model.Model (no numba compile here)
        def __init__(self, mesh, material, thickness_strain="green", mu=0.5, membrane="full", constants=None):
            self.mesh, self.material, self.n_nodes = mesh, material, mesh.n_nodes

        def nodal_areas(self):  # equal shares: the wiring, not the lumping, is under test here
            return np.full(self.mesh.n_nodes, self.mesh.area() / self.mesh.n_nodes)

        def interpenetrated_nodes(self, U):  # none: the summary's wiring, not Section 4.3, is under test
            return np.zeros(self.n_nodes, dtype=bool)

    import solidshell.model

    record = {}
    monkeypatch.setattr(solidshell.model, "Model", Model)
    monkeypatch.setattr(solvers, "get", lambda kind: fake_solver(record))
    return record


def test_run_scene_mesh_only(tmp_path):
    from solidshell.run import run_scene

    out = run_scene("strip-warp", mesh="10x1", solver="none", out_dir=tmp_path, progress=False)
    assert out.summary["counts"]["nodes"] == 22 and out.summary["converged"] is None
    assert sorted(out.summary["files"]) == ["iso.png", "mesh.vtu", "mesh.xdmf", "side.png", "summary.json", "top.png"]
    assert _leftovers(tmp_path) == sorted(out.summary["files"])
    assert np.all(out.U == 0)


def test_run_scene_dynamic_outputs(tmp_path, fake):
    from solidshell.run import run_scene

    seen = []
    out = run_scene("hang-20", mesh="4x4", out_dir=tmp_path, progress=lambda f, t="": seen.append(f), t_end=0.4)
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s == out.summary
    assert s["solver"] == "explicit" and s["converged"] is True and s["message"] == "fake solver"
    assert s["iterations"] == 3 and s["residual"] == 1e-9 and "solver_solver" not in s
    assert s["counts"]["nodes"] == 25 and s["counts"]["fixed_dofs"] == 6  # two hung corners, U_o
    assert fake["settings"]["t_end"] == 0.4 and fake["settings"]["alpha"] == 5.0
    assert fake["settings"]["snapshots"] == [0.0, 0.1, 0.4, 2.1]
    assert fake["problem"].loads[:, 2].sum() == pytest.approx(-0.019 * 400.0)  # the weight, gf
    assert s["total_weight"] == pytest.approx(0.019 * 400.0)
    assert (
        {
            "mesh.xdmf",
            "mesh.vtu",
            "result.xdmf",
            "result.vtu",
            "deformed.vtu",
            "series.xdmf",
            "top.png",
            "iso.png",
            "side_yz.png",
            "iso_t0.000.png",
            "iso_t0.100.png",
            "iso_t0.400.png",
            "summary.json",
        }
        == set(s["files"])
        == set(_leftovers(tmp_path))
    )
    assert s["versions"]["meshio"] and s["units"]["length"] == "cm" and s["timings"]["total"] > 0
    assert seen[0] == 0.0 and seen[-1] == 1.0 and seen == sorted(seen)
    _, U = io.read_state(tmp_path / "result.vtu")
    np.testing.assert_allclose(U, out.U, atol=1e-12)


def test_run_scene_pedestal_analysis(tmp_path, fake):
    from solidshell.run import run_scene

    out = run_scene(
        "square-pedestal", mesh="8x3x4", out_dir=tmp_path, progress=False, overrides={"solver.static.c": 2e-3}
    )
    s = out.summary
    assert fake["settings"] == {"c": 2e-3}
    assert s["counts"]["fixed_dofs"] == 6 * 32 and s["pedestal_area"] == 100.0
    assert 0.0 < s["drape_coefficient"] < 1.0 and "fold_count" in s
    assert (tmp_path / "projected_boundary.csv").read_text().startswith("# projected boundary")
    assert "series.xdmf" in s["files"]


def test_run_scene_not_converged(tmp_path, monkeypatch, fake):
    from solidshell import solvers
    from solidshell.run import run_scene

    monkeypatch.setattr(solvers, "get", lambda kind: fake_solver({}, converged=False))
    out = run_scene("strip-warp", mesh="4x1", out_dir=tmp_path, progress=False)
    assert out.summary["converged"] is False and out.summary["message"] == "ran out of steps"
    assert (tmp_path / "result.vtu").exists()


def test_run_scene_bad_inputs(tmp_path):
    from solidshell.run import run_scene

    with pytest.raises(InputError, match="density"):
        run_scene("square-pedestal", mesh="24x8", solver="none", progress=False)
    with pytest.raises(InputError, match="unknown solver"):
        run_scene("square-pedestal", solver="implicit", progress=False)
    with pytest.raises(InputError, match="supports.clamped"):
        run_scene("hang-20", mesh="4x4", solver="none", progress=False, overrides={"supports.clamped": "nowhere"})
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a directory"):
        run_scene("strip-warp", solver="none", out_dir=tmp_path / "file", progress=False)
