"""Run pictures mark where the sheet passes through itself (issue 37 item 4): the elements whose
mid-surface triangles cross another's sharing no node (solidshell/layers.py) drawn red, the
interpenetrated nodes (n_p . d_p < 0) ringed red, a legend line each with the count; nothing is
marked, and nothing is computed, when summary.json counts neither."""

import numpy as np
import pytest

from solidshell import Fabric, Model, plotting
from solidshell.layers import self_intersections
from solidshell.mesh import ShellMesh
from solidshell.render import vtk_backend


def _pierced_sheet():
    """A flat 4x4 sheet of unit quads on [-2, 2]^2 and a separate vertical quad (no shared node)
    through the middle of its element [0, 1] x [0, 1] (element 10), clear of every other one."""
    s = np.linspace(-2.0, 2.0, 5)
    Xg, Yg = np.meshgrid(s, s)  # node r*5 + c at (s[c], s[r])
    nodes = np.column_stack([Xg.ravel(), Yg.ravel(), np.zeros(Xg.size)])
    i, j = np.meshgrid(np.arange(4), np.arange(4), indexing="ij")
    a = (i * 5 + j).ravel()
    quads = np.column_stack([a, a + 1, a + 6, a + 5])
    wall = np.array([[0.5, 0.2, -0.5], [0.5, 0.8, -0.5], [0.5, 0.8, 0.5], [0.5, 0.2, 0.5]])
    nodes = np.vstack([nodes, wall])
    quads = np.vstack([quads, 25 + np.arange(4)[None]])
    return ShellMesh(nodes, quads=quads)


def _red_pixels(path) -> int:
    """Pixels of the marks' red (shaded): red well above green and blue.  Viridis (the heights),
    the bodies' grey and the black mesh lines have none."""
    import matplotlib.image as mimg

    img = mimg.imread(path)[..., :3]
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return int(np.count_nonzero((r > 0.45) & (r > 2.5 * g) & (r > 2.5 * b)))


def _backends():
    return ["matplotlib"] + (["vtk"] if vtk_backend.available()[0] else [])


@pytest.mark.parametrize("backend", _backends())
def test_crossing_elements_and_interpenetrated_nodes_are_marked_red(backend, tmp_path, monkeypatch):
    monkeypatch.setenv("SOLIDSHELL_RENDERER", backend)
    mesh = _pierced_sheet()
    model = Model(mesh, Fabric.wool())
    U = np.zeros((mesh.n_nodes, 6))
    U[0, 3:] = -2.0 * mesh.directors[0]  # node 0's director turned through the mid-surface: n . d < 0
    pairs = len(self_intersections(mesh, U))
    assert pairs > 0
    summary = {"self_intersections": pairs, "interpenetrated_nodes": 1}
    marks = plotting.crossing_marks(model, U, summary)
    # exactly the pierced element and the wall, and node 0 (the crossing is built in: no tolerance)
    assert np.flatnonzero(marks["cells"]).tolist() == [10, 16]
    assert marks["points"].tolist() == [0] and marks["pairs"] == pairs
    labels = [h.get_label() for h in plotting._mark_handles(marks)]
    assert labels == [
        f"2 element(s) through the sheet itself ({pairs} crossing triangle pairs)",
        "1 interpenetrated node(s) (n$_p$·d$_p$ < 0)",
    ]
    on = plotting.render(tmp_path / "on.png", mesh, U, view="iso", marks=marks)
    off = plotting.render(tmp_path / "off.png", mesh, U, view="iso")
    # the marked element is 1/16 of the sheet: thousands of red pixels at 130 dpi; none unmarked
    assert _red_pixels(on) > 500 and _red_pixels(off) == 0


def test_nothing_marked_or_computed_when_the_summary_counts_nothing(monkeypatch):
    mesh = _pierced_sheet()
    model = Model(mesh, Fabric.wool())

    def boom(*a, **kw):
        raise AssertionError("flags computed for a clean state")

    monkeypatch.setattr("solidshell.fields.flag_fields", boom)
    U = np.zeros((mesh.n_nodes, 6))
    assert plotting.crossing_marks(model, U, {"self_intersections": 0, "interpenetrated_nodes": 0}) is None
    assert plotting._mark_handles(None) == []


@pytest.mark.slow
def test_a_run_through_itself_gets_its_crossings_marked(tmp_path):
    """square-on-disc 10x80, static, self-contact off (issue 37's example: the sheet passes
    through itself in its folds): its pictures mark the crossing elements (16 of them, 24 pairs
    when measured); with self-contact none crosses and no element is marked.  Both states have
    20 nodes with n_p . d_p < 0 (a separate measure, ringed in both pictures), so the crossing run's
    picture has more red: its elements' and its caption's (~15-30 s a run on a loaded 2-core machine)."""
    from solidshell.run import run_scene

    runs = {}
    for on in (False, True):
        out = run_scene(
            "square-on-disc",
            mesh="10x80",
            out_dir=tmp_path / str(on),
            progress=False,
            overrides={"self_contact.enabled": on, "output.pictures": ["iso"], "output.snapshots": []},
        )
        marks = plotting.crossing_marks(out.problem.model, out.U, out.summary)
        cells = 0 if marks is None else int(np.count_nonzero(marks["cells"]))
        runs[on] = (out.summary["self_intersections"], cells, _red_pixels(tmp_path / str(on) / "iso.png"))
    (pairs, cells, red), (pairs_on, cells_on, red_on) = runs[False], runs[True]
    assert pairs > 0 and cells > 0  # every crossing pair marks its two elements (sharing no node)
    assert pairs_on == 0 and cells_on == 0
    assert red > red_on
