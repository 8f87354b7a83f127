"""A run's pictures drawn in a child process (solidshell/render/server.py, issue 41 item 3): the
same pixels as drawn in the run's own process, stamped with the run id; a child that cannot draw
leaves the pictures to the run's process, which still writes them."""

import sys

import matplotlib.image as mimg
import numpy as np
import pytest

from solidshell import io as sio
from solidshell.render import server, vtk_backend
from solidshell.run import run_scene

STRIP = dict(mesh="10x1", progress=False, overrides={"output.pictures": ["top", "iso"]})


def _run(path, monkeypatch, child: bool):
    monkeypatch.setenv("SOLIDSHELL_RENDER_SERVER", "1" if child else "0")
    sent = []
    real = server.RenderServer.submit

    def spy(self, p, *a, **kw):
        ok = real(self, p, *a, **kw)
        sent.append(ok)
        return ok

    monkeypatch.setattr(server.RenderServer, "submit", spy)
    out = run_scene("strip-warp", out_dir=path, **STRIP)
    return out, sent


def _stamped(path, run_id) -> bool:
    return sio._png_text(path.read_bytes()).get(sio.PNG_RUN_ID_KEY) == run_id.encode()


@pytest.mark.skipif(not vtk_backend.available()[0], reason="VTK cannot render off-screen here")
def test_child_pictures_are_the_in_process_pictures(tmp_path, monkeypatch):
    a, sent = _run(tmp_path / "child", monkeypatch, True)
    assert sent == [True, True]  # both went to the child
    b, none = _run(tmp_path / "here", monkeypatch, False)
    assert none == []
    for view in ("top", "iso"):
        pa, pb = (tmp_path / d / f"{view}.png" for d in ("child", "here"))
        # the same renderer, window size and figure: the same pixels (only the run id differs)
        assert np.array_equal(mimg.imread(pa), mimg.imread(pb)), view
        assert _stamped(pa, a.run_id) and _stamped(pb, b.run_id)
    assert server.current() is None  # the run's child was closed with the run


def test_a_child_that_cannot_draw_leaves_the_pictures_to_the_run(tmp_path, monkeypatch):
    monkeypatch.setattr(server, "CHILD", [sys.executable, "-c", "import sys; sys.exit(3)"])
    out, sent = _run(tmp_path / "o", monkeypatch, True)
    for view in ("top", "iso"):
        p = tmp_path / "o" / f"{view}.png"
        assert mimg.imread(p).shape[0] > 100 and _stamped(p, out.run_id)
    assert "top.png" in out.summary["files"] and "iso.png" in out.summary["files"]


def test_no_child_when_turned_off_or_matplotlib_is_asked_for(monkeypatch):
    monkeypatch.setenv("SOLIDSHELL_RENDER_SERVER", "0")
    assert server.start() is None
    monkeypatch.setenv("SOLIDSHELL_RENDER_SERVER", "1")
    monkeypatch.setenv("SOLIDSHELL_RENDERER", "matplotlib")
    assert server.start() is None


def test_a_run_that_stops_on_bad_input_ends_its_pictures_child(tmp_path, monkeypatch):
    """The CLI starts the pictures' child before it reads the scene; a run refused as bad input
    (exit 2, nothing written) ends that child at once instead of leaving it to finish its imports
    for nobody."""
    from solidshell.cli import main
    from solidshell.render import server

    started = []
    real = server.RenderServer

    class Recorded(real):
        def __init__(self):
            super().__init__()
            started.append(self)

    monkeypatch.setattr(server, "RenderServer", Recorded)
    monkeypatch.setattr(server, "enabled", lambda: True)
    code = main(["run", "strip-warp", "--set", "material.no_such_key=1", "--out", str(tmp_path / "out"), "-q"])
    assert code == 2 and not (tmp_path / "out").exists()
    assert len(started) == 1 and started[0].proc.poll() is not None  # ended, not idling
    assert server.current() is None and "server" not in server._LIVE
