"""Picture fixes of issue 40 item 5: the strip's side view carries its reference curve and no
colour bar that colours nothing."""

from __future__ import annotations

import numpy as np

from solidshell.plotting import _facing_fraction
from solidshell.render.geometry import CAMERAS


def _strip(twist=0.0):
    from solidshell import ShellMesh

    x, y = np.meshgrid(np.linspace(0, 5, 11), np.linspace(-0.5, 0.5, 2), indexing="ij")
    X = np.column_stack([x.ravel(), y.ravel(), -0.2 * x.ravel() ** 2])
    i = np.arange(len(X)).reshape(11, 2)
    q = np.column_stack([i[:-1, 0], i[1:, 0], i[1:, 1], i[:-1, 1]])
    return ShellMesh(X, quads=q), X


def test_a_strip_seen_from_the_side_is_edge_on_and_from_above_is_not():
    # the side camera looks along y, in the strip's plane: nothing faces it (round-off only); the
    # top and iso cameras see most of it (5 %: the threshold below which render drops the colour bar)
    mesh, X = _strip()
    assert _facing_fraction(mesh, X, CAMERAS["side"]) < 1e-12
    assert _facing_fraction(mesh, X, CAMERAS["top"]) > 0.3 and _facing_fraction(mesh, X, CAMERAS["iso"]) > 0.05


def test_strip_run_side_picture_draws_the_heavy_elastica(tmp_path, monkeypatch):
    # the run passes the stored curve of the strip it is to the side picture
    from solidshell import plotting
    from solidshell.run import run_scene

    seen = {}
    real = plotting.render

    def spy(path, *a, **kw):
        seen[kw.get("view")] = kw.get("reference")
        return real(path, *a, **kw)

    monkeypatch.setattr(plotting, "render", spy)
    monkeypatch.setenv("SOLIDSHELL_RENDER_SERVER", "0")  # drawn here, where the spy is (not in the child)
    run_scene("strip-warp", mesh="10x1", out_dir=tmp_path, progress=False)
    ref = seen["side"]
    assert ref is not None and ref["label"] == "heavy elastica"
    assert ref["z"][-1] < -4.3 and abs(ref["x"][0]) < 1e-12  # the warp strip's droop, from the clamp


def test_fieldview_draws_a_field_from_the_files_and_refuses_an_unknown_one(tmp_path, capsys):
    # python -m solidshell.render.fieldview on a run folder: a PNG of the requested cell field,
    # exit 2 with the known fields named for a missing one
    import pytest

    from solidshell.render import fieldview, vtk_backend
    from solidshell.run import run_scene

    if not vtk_backend.available()[0]:
        pytest.skip("VTK cannot render here")
    run_scene("strip-warp", mesh="10x1", out_dir=tmp_path / "run", progress=False)
    png = tmp_path / "m.png"
    assert fieldview.main([str(tmp_path / "run"), "--field", "M_xx", "--out", str(png)]) == 0
    assert png.read_bytes().startswith(b"\x89PNG") and png.stat().st_size > 5000
    assert fieldview.main([str(tmp_path / "run"), "--field", "nope", "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert "no field 'nope'" in err and "M_xx" in err and not (tmp_path / "x.png").exists()
