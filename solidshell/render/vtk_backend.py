"""VTK renderer through PyVista, off-screen: z-buffered, lit, anti-aliased pictures.

PyVista is a dependency, but VTK may still be unable to render (no GL library).  Whether VTK can
render on this machine is asked once per process in a child process (:func:`available`): a VTK
build that finds no OpenGL (no X server, no EGL or OSMesa library) can crash its process outright
instead of raising, so the probe must not run in ours.  A run that will draw pictures starts the
probe before it meshes (:func:`start_probe`), so that its ~2 s are not waited for at the end.
With no X display the EGL window is chosen (then OSMesa), which renders headless where the system
has libEGL.
"""

from __future__ import annotations

import os
import subprocess
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # NumPy is loaded where a picture is drawn: the pictures' process is started without it
    import numpy as np

    from .geometry import Camera

_STATE: dict = {}  # {"ok": bool, "why": str}: the probe's answer for this process

_PROBE = r"""
import numpy as np, pyvista as pv
pv.OFF_SCREEN = True
p = pv.Plotter(off_screen=True, window_size=(48, 48))
p.set_background("white")
p.add_mesh(pv.PolyData(np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]]), faces=[3, 0, 1, 2]), color="red")
p.camera_position = "xy"
img = p.screenshot(return_img=True)
p.close()
assert img.shape[0] == 48 and (img[..., 1] < 128).any(), "rendered nothing"
print("solidshell-vtk-ok")
"""


def _windows():
    """OpenGL window classes to try: VTK's default with an X display, else EGL then OSMesa."""
    if os.environ.get("VTK_DEFAULT_OPENGL_WINDOW"):
        return [os.environ["VTK_DEFAULT_OPENGL_WINDOW"]]
    if os.environ.get("DISPLAY") or sys.platform in ("darwin", "win32"):
        return [None]
    return ["vtkEGLRenderWindow", "vtkOSOpenGLRenderWindow"]


def _launch(win):
    """The probe in a child process, with VTK's window class ``win`` (None: VTK's default)."""
    env = dict(os.environ)
    if win:
        env["VTK_DEFAULT_OPENGL_WINDOW"] = win
    return subprocess.Popen(
        [sys.executable, "-c", _PROBE], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def _pyvista_missing() -> bool:
    try:
        import importlib.util

        return importlib.util.find_spec("pyvista") is None
    except (ImportError, ValueError):
        return True


def start_probe() -> None:
    """Start :func:`available`'s probe now, in the background: its child process (VTK's import
    and a first off-screen render, ~2 s) then overlaps the caller's work -- a run's meshing and
    set-up -- and available() waits for its answer.  Nothing when the answer is known, a probe
    is already running, PyVista is missing or SOLIDSHELL_RENDERER asks for matplotlib."""
    if "ok" in _STATE or "pending" in _STATE or _pyvista_missing():
        return
    if os.environ.get("SOLIDSHELL_RENDERER", "auto").strip().lower() in ("matplotlib", "mpl"):
        return
    win = _windows()[0]
    try:
        _STATE["pending"] = (win, _launch(win))
    except OSError:
        pass


def available(timeout: float = 180.0) -> tuple[bool, str]:
    """(True, "") when PyVista imports and renders off-screen here, else (False, why)."""
    if "ok" in _STATE:
        return _STATE["ok"], _STATE["why"]
    if _pyvista_missing():
        _STATE.update(ok=False, why="PyVista is not installed (pip install pyvista)")
        return False, _STATE["why"]
    why = "VTK found no OpenGL to render with"
    pending = _STATE.pop("pending", None)
    for win in _windows():
        try:
            proc = pending[1] if pending is not None and pending[0] == win else _launch(win)
            pending = None
            out, err = proc.communicate(timeout=timeout)
        except OSError as e:
            why = f"VTK probe failed ({type(e).__name__})"
            continue
        except subprocess.TimeoutExpired as e:
            proc.kill()
            proc.communicate()
            why = f"VTK probe failed ({type(e).__name__})"
            continue
        if proc.returncode == 0 and "solidshell-vtk-ok" in out:
            if win:
                os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = win
            _STATE.update(ok=True, why="")
            return True, ""
        tail = (err.strip().splitlines() or [f"exit status {proc.returncode}"])[-1]
        why = f"VTK cannot render off-screen ({' '.join(tail.split())[:120]})"
    _STATE.update(ok=False, why=why)
    return False, why


def _polydata(s):
    import numpy as np
    import pyvista as pv

    parts = []
    if len(s.quads):
        parts.append(np.column_stack([np.full(len(s.quads), 4), s.quads]).ravel())
    if len(s.tris):
        parts.append(np.column_stack([np.full(len(s.tris), 3), s.tris]).ravel())
    faces = np.concatenate(parts) if parts else np.zeros(0, int)
    return pv.PolyData(np.asarray(s.points, float), faces=faces)


def render_image(
    surfaces, camera: Camera, extent, norm, cmap, height_px: int = 900, edge_width: float = 0.6
) -> np.ndarray:
    """RGB image (H,W,3) uint8 of the surfaces seen by ``camera``, framing exactly the screen
    rectangle ``extent`` = (xmin, xmax, ymin, ymax) [cm] (orthographic), white background."""
    import numpy as np
    import pyvista as pv

    pv.OFF_SCREEN = True
    x0, x1, y0, y1 = extent
    aspect = (x1 - x0) / (y1 - y0)
    H = int(height_px)
    W = int(round(H * aspect))
    if W > 2400:  # very wide views: cap the width instead
        W, H = 2400, int(round(2400 / aspect))
    from vtkmodules.vtkRenderingCore import vtkMapper

    # mesh lines are separate line actors (VTK's shader-drawn show_edges vanish on a sheet seen
    # edge-on, as in a side view of a flat sheet); polygons are pushed back so the lines on them win
    vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()
    vtkMapper.SetResolveCoincidentTopologyPolygonOffsetParameters(2.0, 8.0)
    p = _plotter(W, H)
    try:
        for s in surfaces:
            poly = _polydata(s)
            # per-node normals (Gouraud): flat shading lit each warped quad's two render triangles
            # differently, a zig-zag on every element of a coarse mesh; bodies keep their edges sharp
            # render=False: the reused window would render again at each actor added (pyvista renders
            # a shown plotter on add_actor); the screenshot renders once
            kw = dict(show_edges=False, smooth_shading=True, ambient=0.18, diffuse=0.85, render=False)
            if s.scalars is None:
                kw["split_sharp_edges"] = True
            if s.scalars is not None:
                poly.point_data["z"] = np.asarray(s.scalars, float)
                p.add_mesh(
                    poly, scalars="z", cmap=cmap, clim=(norm.vmin, norm.vmax), show_scalar_bar=False, specular=0.1, **kw
                )
            else:
                p.add_mesh(poly, color=s.color, specular=0.25, specular_power=20.0, **kw)
            if s.edges:
                p.add_mesh(
                    poly.extract_all_edges(),
                    color=(0.05, 0.05, 0.05),
                    line_width=edge_width,
                    lighting=False,
                    opacity=0.75,
                    render=False,
                )
            if s.scalars is not None and s.edges:
                # the sheet's rim, a thicker dark line: a sheet seen edge-on still reads as a curve
                rim = poly.extract_feature_edges(
                    boundary_edges=True, feature_edges=False, manifold_edges=False, non_manifold_edges=False
                )
                if rim.n_points:
                    p.add_mesh(
                        rim,
                        color=(0.05, 0.05, 0.05),
                        line_width=max(1.6, 2.0 * edge_width),
                        lighting=False,
                        render=False,
                    )
        r, u, d = camera.frame()
        cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        pts = np.concatenate([s.points for s in surfaces])
        depth = pts @ d
        cd = 0.5 * (depth.min() + depth.max())
        focal = cx * r + cy * u + cd * d
        dist = float(depth.max() - depth.min()) + (x1 - x0) + (y1 - y0) + 1.0
        cam = p.camera
        cam.focal_point = tuple(focal)
        cam.position = tuple(focal - dist * d)
        cam.up = tuple(u)
        p.enable_parallel_projection()
        cam.parallel_scale = 0.5 * (y1 - y0)
        cam.clipping_range = (1e-3 * dist, 3.0 * dist)
        if not getattr(p, "_first_time", True):
            p.render()  # pyvista's screenshot renders a plotter's first picture only
        img = p.screenshot(return_img=True)
    except BaseException:
        _drop_plotter()  # a window in an unknown state is not drawn in again
        raise
    return np.asarray(img)[..., :3]


_PLOTTER: dict = {}  # {"p": the off-screen Plotter this process draws in}


def _plotter(W: int, H: int):
    """The process's one off-screen Plotter, resized to W x H px and emptied: one window and one
    OpenGL context for all its pictures, so the shaders are compiled once (a new window per picture
    took ~0.4 s of compiling in each Render with Mesa's software GL)."""
    import pyvista as pv

    p = _PLOTTER.get("p")
    if p is None or getattr(p, "render_window", None) is None:
        p = pv.Plotter(off_screen=True, window_size=[W, H], lighting="light_kit")
        p.set_background("white")
        _PLOTTER["p"] = p
        import atexit

        atexit.register(_drop_plotter)
    else:  # VTK's own calls: pyvista's clear_actors and window_size setter each render once more
        p.renderer.RemoveAllViewProps()
        p.render_window.SetSize(W, H)
    return p


def _drop_plotter() -> None:
    p = _PLOTTER.pop("p", None)
    if p is not None:
        try:
            p.close()
        except Exception:  # noqa: BLE001, S110 - closing a broken window at exit
            pass
