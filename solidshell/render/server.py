"""A run's pictures drawn in a child process that starts with the run: VTK's and matplotlib's
imports, the OpenGL context and the first shader compiles (~1.5-2.5 s) happen there while the run
meshes and solves, and the pictures are drawn there while the run writes its other files.

    pictures = server.start()          # when the run starts (solidshell.run.outputs.prepare_folder)
    ...
    pictures.submit(path, (mesh, U), dict(view="iso", ...), run_id)   # non-blocking
    ...                                 # the run writes its VTU/XDMF files meanwhile
    failed = pictures.collect()        # {path: reason} of pictures the child could not draw

The child (``python -m solidshell.render.server``) first renders a triangle off-screen (the
probe of solidshell.render.vtk_backend: a VTK build without OpenGL may crash its process, which
must not be ours), then imports solidshell.plotting and draws one small picture to warm it, then
draws each job with solidshell.plotting.render and stamps it with the run id.  Jobs and replies are
pickled frames on its stdin and on a duplicate of its stdout (C-level prints go to its stderr).  A
child that fails its probe, crashes or is missing leaves the caller to draw in its own process
(``collect`` names what is left).  ``SOLIDSHELL_RENDER_SERVER=0`` turns the child off (pictures in
the run's process, as before; benchmarks/picture_speed.py compares the two).
"""

from __future__ import annotations

import os
import pickle
import queue
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

_LIVE: dict = {}  # {"server": RenderServer}: the one started for the current run of this process


def enabled() -> bool:
    """Whether a run's pictures go to a child process: VTK asked for (not SOLIDSHELL_RENDERER=
    matplotlib), VTK installed, SOLIDSHELL_RENDER_SERVER not 0, and VTK not already known to
    fail here (solidshell.render.vtk_backend's answer)."""
    from . import vtk_backend

    if os.environ.get("SOLIDSHELL_RENDER_SERVER", "1").strip().lower() in ("0", "false", "no", "off"):
        return False
    if os.environ.get("SOLIDSHELL_RENDERER", "auto").strip().lower() in ("matplotlib", "mpl"):
        return False
    if vtk_backend._STATE.get("ok") is False or vtk_backend._vtk_missing():
        return False
    return True


def _send(stream, obj) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(struct.pack("<Q", len(data)) + data)
    stream.flush()


def _recv(stream):
    """The next frame, or None at the end of the stream."""
    head = stream.read(8)
    if len(head) < 8:
        return None
    (n,) = struct.unpack("<Q", head)
    data = stream.read(n)
    return pickle.loads(data) if len(data) == n else None


CHILD = [sys.executable, "-m", "solidshell.render.server"]
"""The child's command line (tests replace it with one that fails)."""


class RenderServer:
    """The parent's handle on one child (module docstring)."""

    def __init__(self):
        from .vtk_backend import _windows

        env = dict(os.environ)
        win = _windows()[0]
        if win and "VTK_DEFAULT_OPENGL_WINDOW" not in env:
            env["VTK_DEFAULT_OPENGL_WINDOW"] = win  # headless: EGL first (vtk_backend._windows)
        self.win = env.get("VTK_DEFAULT_OPENGL_WINDOW")
        self._err = tempfile.TemporaryFile()
        self.proc = subprocess.Popen(
            list(CHILD),
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=None if os.environ.get("SOLIDSHELL_RENDER_DEBUG") else self._err,
        )
        self.replies: queue.Queue = queue.Queue()
        # jobs are sent by a thread: a job larger than the pipe's buffer would otherwise hold the
        # run until the child, still importing, reads it
        self.jobs: queue.Queue = queue.Queue()
        self._writer = threading.Thread(target=self._write, name="solidshell-render-jobs", daemon=True)
        self._writer.start()
        self.pending: list[Path] = []
        self.used = False  # a picture was asked for
        self.ready: bool | None = None  # the probe's answer, once read
        self.why = ""
        self._reader = threading.Thread(target=self._read, name="solidshell-render-replies", daemon=True)
        self._reader.start()

    def _read(self) -> None:
        while True:
            try:
                msg = _recv(self.proc.stdout)
            except Exception:  # noqa: BLE001 - a broken frame ends the child's answers
                msg = None
            self.replies.put(msg)
            if msg is None:
                return

    def _write(self) -> None:
        while True:
            job = self.jobs.get()
            if job is None:
                break
            try:
                self.proc.stdin.write(struct.pack("<Q", len(job)) + job)
                self.proc.stdin.flush()
            except (OSError, ValueError):  # the child is gone: collect() finds out from its replies
                break
        try:
            self.proc.stdin.close()  # the child leaves its loop once every job is read
        except OSError:
            pass

    def alive(self) -> bool:
        return self.proc.poll() is None and self.ready is not False

    def submit(self, path, args: tuple, kwargs: dict, run_id: str | None) -> bool:
        """Ask the child to draw ``plotting.render(path, *args, **kwargs)`` and stamp it; False when
        the child is gone (the caller draws it)."""
        if not self.alive():
            return False
        try:  # pickled here: what cannot be sent is drawn by the caller
            job = pickle.dumps(("render", str(path), args, kwargs, run_id), protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, TypeError, AttributeError):
            return False
        self.jobs.put(job)
        self.used = True
        self.pending.append(Path(path))
        return True

    def _next(self, timeout: float):
        try:
            return self.replies.get(timeout=timeout)
        except queue.Empty:
            return None

    def collect(self, timeout: float = 120.0) -> dict:
        """Wait for the submitted pictures: {path: reason} of those the child did not draw (its
        probe failed, it died or stopped answering for ``timeout`` s, or the picture raised there:
        ``OSError: ...`` for a write failure)."""
        left = set(self.pending)
        self.pending = []
        _say(f"parent waits for {len(left)} picture(s)")
        failed: dict = {}
        while left:
            msg = self._next(timeout)
            if msg is None:  # the child ended (or hangs): what is left is the caller's to draw
                why = self.why or self._tail() or "the picture process ended"
                failed.update({p: why for p in left})
                self.ready = False if self.ready is None else self.ready
                break
            if msg[0] == "ready":
                self.ready = True
            elif msg[0] == "fail":
                self.ready, self.why = False, msg[1]
            elif msg[0] in ("done", "error"):
                p = Path(msg[1])
                left.discard(p)
                if msg[0] == "error":
                    failed[p] = msg[2]
        _say("parent has them")
        return failed

    def _tail(self) -> str:
        try:
            self._err.seek(0)
            lines = self._err.read().decode(errors="replace").strip().splitlines()
        except (OSError, ValueError):
            return ""
        return " ".join(lines[-1].split())[:160] if lines else ""

    def close(self) -> None:
        """End the child (its stdin closed: it leaves its loop) and forget it."""
        self.jobs.put(None)  # the writer closes the child's stdin after the last job
        self._writer.join(5.0)
        try:
            self.proc.wait(5.0)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self._err.close()
        if self.ready and self.win:
            os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", self.win)  # this process renders alike
        if _LIVE.get("server") is self:
            _LIVE.pop("server")


def start() -> RenderServer | None:
    """The child for the run starting now (module docstring); None when :func:`enabled` says no or
    it cannot be started.  A child started and not yet given a picture (the CLI starts one before
    its imports) is kept; one of an earlier run still open is closed first."""
    old = _LIVE.get("server")
    if old is not None and old.alive() and not old.used:
        return old
    _LIVE.pop("server", None)
    if old is not None:
        old.close()
    if not enabled():
        return None
    try:
        _LIVE["server"] = RenderServer()
    except OSError:
        return None
    return _LIVE["server"]


def discard() -> None:
    """End the child of a run that stopped before its pictures were collected (bad input, a solver
    error, Ctrl-C): killed at once -- nothing of the run is there -- instead of finishing its
    imports and probe (1-2 s of a core) for nobody.  Nothing when there is none."""
    s = _LIVE.pop("server", None)
    if s is None:
        return
    try:
        s.proc.kill()
    except OSError:
        pass
    s.jobs.put(None)  # the writer thread ends (the child's stdin is closed or already broken)
    s.proc.wait()
    s._err.close()


def current() -> RenderServer | None:
    """The child started for this run, when it is still alive."""
    s = _LIVE.get("server")
    return s if s is not None and s.alive() else None


# ----------------------------------------------------------------------------- the child
def _probe() -> None:
    """A small height-coloured sheet with its mesh lines rendered off-screen in the process's
    reused window (vtk_backend.render_image): the probe of solidshell.render.vtk_backend, and the
    first compile of the shaders the run's pictures use.  Raises when nothing was drawn."""
    import matplotlib.colors as mcolors
    import numpy as np

    from .geometry import CAMERAS, Surface
    from .vtk_backend import render_image

    P = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0.2]])
    s = Surface(P, np.array([[0, 1, 2, 3]]), np.zeros((0, 3), int), scalars=P[:, 2], edges=True)
    img = render_image([s], CAMERAS["iso"], (-1.0, 1.0, -1.0, 1.0), mcolors.Normalize(0.0, 0.2), "viridis", 48)
    if not (img.shape[0] == 48 and (img.min(axis=2) < 200).any()):
        raise RuntimeError("rendered nothing")


def _warm(plotting, stop=lambda: False) -> None:
    """Two small pictures drawn and thrown away, a top view (ticks, axis labels, colour bar) and an
    oblique one (the orientation triad) at the runs' resolution: matplotlib's fonts at the
    pictures' sizes and the renderers' first calls are paid before the run's pictures are asked
    for.  ``stop()`` true before a picture: the rest is left (a job waits)."""
    import numpy as np

    from ..mesh import ShellMesh
    from .panel import SceneLook

    s = np.linspace(-6.0, 6.0, 3)
    X, Y = np.meshgrid(s, s)
    nodes = np.column_stack([X.ravel(), Y.ravel(), -0.05 * X.ravel() ** 2])
    q = np.array([[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]])
    mesh, scene = ShellMesh(nodes, quads=q), SceneLook((), 0.0)
    with tempfile.TemporaryDirectory() as d:
        for view in ("top", "iso"):
            if stop():
                return
            plotting.render(Path(d) / f"{view}.png", mesh, None, view=view, title="warm", scene=scene)


def _jobs_waiting(stream) -> bool:
    """Whether a job is already there to read (then warming would only delay it); False where
    pipes cannot be polled (Windows)."""
    try:
        import select

        return bool(select.select([stream], [], [], 0)[0])
    except (ImportError, OSError, ValueError):
        return False


def _say(what: str, t0: float = time.perf_counter()) -> None:
    """SOLIDSHELL_RENDER_DEBUG=1: the child's phases with their times on its stderr."""
    if os.environ.get("SOLIDSHELL_RENDER_DEBUG"):
        print(
            f"render child {time.time():.3f} (+{time.perf_counter() - t0:.2f} s): {what}", file=sys.stderr, flush=True
        )


def main() -> int:
    _say("started")
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # whatever a library prints goes to stderr, not into the frames
    sys.stdout = sys.stderr
    try:
        _probe()
    except Exception as e:  # noqa: BLE001 - the answer is the parent's to act on
        _send(out, ("fail", f"VTK cannot render off-screen ({type(e).__name__}: {' '.join(str(e).split())[:120]})"))
        return 1
    from . import vtk_backend

    vtk_backend._STATE.update(ok=True, why="")
    _send(out, ("ready",))
    _say("probe rendered")
    from .. import io as sio
    from .. import plotting

    if not _jobs_waiting(sys.stdin):
        try:
            _warm(plotting, lambda: _jobs_waiting(sys.stdin))
        except Exception:  # noqa: BLE001, S110 - warming is an optimisation only
            pass
    _say("warm")
    inp = sys.stdin.buffer
    while True:
        job = _recv(inp)
        if job is None:
            return 0
        _, path, args, kwargs, run_id = job
        try:
            plotting.render(path, *args, **kwargs)
            if run_id:
                sio.stamp_png(path, run_id)
        except Exception as e:  # noqa: BLE001 - reported to the parent, which draws it itself
            _send(out, ("error", path, f"{type(e).__name__}: {' '.join(str(e).split())[:200]}"))
            continue
        _send(out, ("done", path))
        _say(f"drew {Path(path).name}")


if __name__ == "__main__":
    code = main()
    sys.stderr.flush()
    # every picture is written and answered: leave without the interpreter's teardown (VTK's window
    # and OpenGL context closed, every module freed), which the run waits for in RenderServer.close
    os._exit(code)
