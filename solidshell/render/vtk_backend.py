"""VTK renderer, off-screen: z-buffered, lit, anti-aliased pictures, drawn with VTK's own classes
(vtkmodules: ~0.3 s of imports; PyVista's import, 0.4 s more, is left to the field viewer).

VTK is a dependency, but it may still be unable to render (no GL library).  Whether VTK can
render on this machine is asked once per process in a child process (:func:`available`): a VTK
build that finds no OpenGL (no X server, no EGL or OSMesa library) can crash its process outright
instead of raising, so the probe must not run in ours.  A run that will draw pictures starts the
probe before it meshes (:func:`start_probe`), so that its ~1 s is not waited for at the end.
With no X display the EGL window is chosen (then OSMesa), which renders headless where the system
has libEGL.

Anti-aliasing: the picture is rendered at ``height_px`` (900 px) and drawn into an axes of about
half that height, so matplotlib's resampling averages ~2x2 rendered pixels into each shown one;
VTK's multisampling (PyVista's default, 8 samples) cost 2-3x the render time in Mesa's software
GL for no visible difference after that (:data:`MULTI_SAMPLES`).
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
import vtkmodules.vtkRenderingOpenGL2
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper, vtkRenderer, vtkRenderWindow, vtkWindowToImageFilter
pts = vtkPoints()
for p in ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)):
    pts.InsertNextPoint(p)
tri = vtkCellArray()
tri.InsertNextCell(3, (0, 1, 2))
poly = vtkPolyData()
poly.SetPoints(pts)
poly.SetPolys(tri)
m = vtkPolyDataMapper()
m.SetInputData(poly)
a = vtkActor()
a.SetMapper(m)
a.GetProperty().SetColor(1.0, 0.0, 0.0)
ren = vtkRenderer()
ren.SetBackground(1.0, 1.0, 1.0)
ren.AddActor(a)
rw = vtkRenderWindow()
rw.SetOffScreenRendering(1)
rw.SetSize(48, 48)
rw.AddRenderer(ren)
ren.ResetCamera()
rw.Render()
g = vtkWindowToImageFilter()
g.SetInput(rw)
g.Update()
s = g.GetOutput().GetPointData().GetScalars()
assert any(s.GetTuple(i)[1] < 128 for i in range(s.GetNumberOfTuples())), "rendered nothing"
rw.Finalize()
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


def _vtk_missing() -> bool:
    try:
        import importlib.util

        return importlib.util.find_spec("vtkmodules") is None
    except (ImportError, ValueError):
        return True


def start_probe() -> None:
    """Start :func:`available`'s probe now, in the background: its child process (VTK's import
    and a first off-screen render, ~1 s) then overlaps the caller's work -- a run's meshing and
    set-up -- and available() waits for its answer.  Nothing when the answer is known, a probe
    is already running, VTK is missing or SOLIDSHELL_RENDERER asks for matplotlib."""
    if "ok" in _STATE or "pending" in _STATE or _vtk_missing():
        return
    if os.environ.get("SOLIDSHELL_RENDERER", "auto").strip().lower() in ("matplotlib", "mpl"):
        return
    win = _windows()[0]
    try:
        _STATE["pending"] = (win, _launch(win))
    except OSError:
        pass


def available(timeout: float = 180.0) -> tuple[bool, str]:
    """(True, "") when VTK imports and renders off-screen here, else (False, why)."""
    if "ok" in _STATE:
        return _STATE["ok"], _STATE["why"]
    if _vtk_missing():
        _STATE.update(ok=False, why="VTK is not installed (pip install vtk)")
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
    """A vtkPolyData of the surface's points and polygons (quads, then triangles)."""
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData

    pts = vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(s.points, dtype=float), deep=True))
    parts = []
    if len(s.quads):
        parts.append(np.column_stack([np.full(len(s.quads), 4), s.quads]).ravel())
    if len(s.tris):
        parts.append(np.column_stack([np.full(len(s.tris), 3), s.tris]).ravel())
    conn = np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, np.int64)
    cells = vtkCellArray()
    cells.ImportLegacyFormat(numpy_to_vtkIdTypeArray(conn, deep=True))
    poly = vtkPolyData()
    poly.SetPoints(pts)
    poly.SetPolys(cells)
    return poly


def _lookup_table(cmap, norm):
    """VTK's colour table of the matplotlib colour map ``cmap`` (256 colours) over norm's range."""
    import matplotlib
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkLookupTable

    cmap = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
    rgba = cmap(np.linspace(0.0, 1.0, 256))
    lut = vtkLookupTable()
    lut.SetNumberOfTableValues(256)
    lut.SetTable(numpy_to_vtk(np.ascontiguousarray(np.round(rgba * 255.0), dtype=np.uint8)))
    lut.SetRange(float(norm.vmin), float(norm.vmax))
    return lut


def _actor(source, color=None, **prop):
    """An actor of ``source`` (vtkPolyData or an algorithm's output port) with the given
    vtkProperty settings (names without "Set")."""
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

    m = vtkPolyDataMapper()
    if hasattr(source, "GetOutputPort"):
        m.SetInputConnection(source.GetOutputPort())
    else:
        m.SetInputData(source)
    m.ScalarVisibilityOff()
    a = vtkActor()
    a.SetMapper(m)
    p = a.GetProperty()
    if color is not None:
        p.SetColor(*color)
    for k, v in prop.items():
        getattr(p, "Set" + k)(*(v if isinstance(v, tuple) else (v,)))
    return a


def _add_surface(ren, s, cmap, norm, edge_width: float) -> None:
    """The surface's actors: its polygons lit per pixel (Phong) from per-node normals, its mesh
    lines and, for the sheet, its rim."""
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkFiltersCore import vtkFeatureEdges, vtkPolyDataNormals

    try:
        from vtkmodules.vtkFiltersCore import vtkExtractEdges
    except ImportError:  # older VTK releases kept it with the extraction filters
        from vtkmodules.vtkFiltersExtraction import vtkExtractEdges

    poly = _polydata(s)
    # per-node normals: flat shading lit each warped quad's two render triangles differently, a
    # zig-zag on every element of a coarse mesh; bodies keep their sharp edges (split at 30 deg)
    normals = vtkPolyDataNormals()
    normals.SetInputData(poly)
    normals.ComputeCellNormalsOff()
    normals.ComputePointNormalsOn()
    normals.SetSplitting(s.scalars is None)
    normals.SetFeatureAngle(30.0)
    lit = dict(Ambient=0.18, Diffuse=0.85)
    if s.scalars is not None:
        z = numpy_to_vtk(np.ascontiguousarray(s.scalars, dtype=float), deep=True)
        z.SetName("z")
        poly.GetPointData().SetScalars(z)
        a = _actor(normals, Specular=0.1, **lit)
        m = a.GetMapper()
        m.ScalarVisibilityOn()
        m.SetScalarModeToUsePointData()
        m.SetLookupTable(_lookup_table(cmap, norm))
        m.UseLookupTableScalarRangeOn()
        m.InterpolateScalarsBeforeMappingOn()
    else:
        a = _actor(normals, color=s.color, Specular=0.25, SpecularPower=20.0, **lit)
    a.GetProperty().SetInterpolationToPhong()
    ren.AddActor(a)
    line = dict(LineWidth=float(edge_width), Lighting=False)
    if s.edges:
        e = vtkExtractEdges()
        e.SetInputData(poly)
        ren.AddActor(_actor(e, color=(0.05, 0.05, 0.05), Opacity=0.75, **line))
    if s.scalars is not None and s.edges:
        # the sheet's rim, a thicker dark line: a sheet seen edge-on still reads as a curve
        rim = vtkFeatureEdges()
        rim.SetInputData(poly)
        rim.BoundaryEdgesOn()
        rim.FeatureEdgesOff()
        rim.ManifoldEdgesOff()
        rim.NonManifoldEdgesOff()
        rim.Update()
        if rim.GetOutput().GetNumberOfPoints():
            line["LineWidth"] = max(1.6, 2.0 * edge_width)
            ren.AddActor(_actor(rim, color=(0.05, 0.05, 0.05), **line))


def render_image(
    surfaces, camera: Camera, extent, norm, cmap, height_px: int = 900, edge_width: float = 0.6
) -> np.ndarray:
    """RGB image (H,W,3) uint8 of the surfaces seen by ``camera``, framing exactly the screen
    rectangle ``extent`` = (xmin, xmax, ymin, ymax) [cm] (orthographic), white background."""
    import numpy as np
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
    from vtkmodules.vtkRenderingCore import vtkMapper

    x0, x1, y0, y1 = extent
    aspect = (x1 - x0) / (y1 - y0)
    H = int(height_px)
    W = int(round(H * aspect))
    if W > 2400:  # very wide views: cap the width instead
        W, H = 2400, int(round(2400 / aspect))
    # mesh lines are separate line actors (VTK's shader-drawn edges vanish on a sheet seen edge-on,
    # as in a side view of a flat sheet); polygons are pushed back so the lines on them win
    vtkMapper.SetResolveCoincidentTopologyToPolygonOffset()
    vtkMapper.SetResolveCoincidentTopologyPolygonOffsetParameters(2.0, 8.0)
    rw, ren = _window(W, H)
    try:
        for s in surfaces:
            _add_surface(ren, s, cmap, norm, edge_width)
        r, u, d = camera.frame()
        cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        pts = np.concatenate([s.points for s in surfaces])
        depth = pts @ d
        cd = 0.5 * (depth.min() + depth.max())
        focal = cx * r + cy * u + cd * d
        dist = float(depth.max() - depth.min()) + (x1 - x0) + (y1 - y0) + 1.0
        cam = ren.GetActiveCamera()
        cam.SetFocalPoint(*focal)
        cam.SetPosition(*(focal - dist * d))
        cam.SetViewUp(*u)
        cam.ParallelProjectionOn()
        cam.SetParallelScale(0.5 * (y1 - y0))
        cam.SetClippingRange(1e-3 * dist, 3.0 * dist)
        rw.Render()
        # the back buffer just drawn, read once (vtkWindowToImageFilter renders the scene again)
        w, h = rw.GetSize()
        data = vtkUnsignedCharArray()
        rw.GetPixelData(0, 0, w - 1, h - 1, 0, data, 0)
        rgb = vtk_to_numpy(data).reshape(h, w, 3)[::-1]  # VTK's rows run bottom to top
    except BaseException:
        _drop_window()  # a window in an unknown state is not drawn in again
        raise
    finally:
        ren.RemoveAllViewProps()  # the actors (and the mesh's arrays) are not kept till the next picture
    return np.ascontiguousarray(rgb)


MULTI_SAMPLES = 0
"""The render window's multisampling: none, the picture is supersampled (module docstring)."""

_WINDOW: dict = {}  # {"rw": vtkRenderWindow, "ren": vtkRenderer}: the one this process draws in


def _window(W: int, H: int):
    """The process's one off-screen render window (and its renderer, lit by VTK's light kit),
    resized to W x H px (render_image empties it after each picture): one OpenGL context for all
    its pictures, so the shaders are compiled once (a new window per picture took ~0.4 s of
    compiling with Mesa's software GL)."""
    rw, ren = _WINDOW.get("rw"), _WINDOW.get("ren")
    if rw is None:
        import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 - registers the OpenGL classes
        from vtkmodules.vtkRenderingCore import vtkLightKit, vtkRenderer, vtkRenderWindow

        rw = vtkRenderWindow()
        rw.SetOffScreenRendering(1)
        rw.SetMultiSamples(MULTI_SAMPLES)
        ren = vtkRenderer()
        ren.SetBackground(1.0, 1.0, 1.0)
        vtkLightKit().AddLightsToRenderer(ren)
        ren.LightFollowCameraOn()
        rw.AddRenderer(ren)
        _WINDOW.update(rw=rw, ren=ren)
        import atexit

        atexit.register(_drop_window)
    rw.SetSize(W, H)
    return rw, ren


def _drop_window() -> None:
    rw = _WINDOW.pop("rw", None)
    _WINDOW.pop("ren", None)
    if rw is not None:
        try:
            rw.Finalize()
        except Exception:  # noqa: BLE001, S110 - closing a broken window at exit
            pass
