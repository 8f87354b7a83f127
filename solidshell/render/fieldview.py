"""A run's fields drawn from its files alone: ``python -m solidshell.render.fieldview RUN_DIR
--field M_xx --field contact_pressure:sphere --out fields.png``.

PyVista reads ``deformed.vtu`` (the draped sheet with every field of solidshell/fields.py, the
pedestal patch included; docs/output.md) and renders each field in a panel of its own, off-screen:
a field with both signs on a diverging map centred on 0, others on viridis; cell fields as the
elements' values, point fields interpolated.  Nothing here knows the solver: what is drawn is what
ParaView would read.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

UNITS = {"M": "gf cm/cm", "N": "gf/cm", "Q": "gf/cm", "curvature": "1/cm", "gap": "cm", "contact_pressure": "gf/cm^2"}
SIDE_ELEVATION_DEG = 20.0
"""How far the side view looks down on the sheet [deg]: from exactly -y a strip shows edge-on, as nothing."""


def _unit(field: str) -> str:
    head = field.split(":")[0]
    for k, u in UNITS.items():
        if head == k or head.startswith(k + "_"):
            return u
    return "-"


def field_picture(run_dir, fields, out, view: str = "iso", file: str = "deformed.vtu", size=(720, 720)) -> Path:
    """Render ``fields`` (names of point or cell data of ``run_dir/file``) side by side into the
    PNG ``out``; returns its path.  ``view``: "iso", "top" or "side" (from -y, raised by
    SIDE_ELEVATION_DEG)."""
    from .vtk_backend import _windows

    win = _windows()[0]
    if win and "VTK_DEFAULT_OPENGL_WINDOW" not in os.environ:
        os.environ["VTK_DEFAULT_OPENGL_WINDOW"] = win  # headless: EGL where the system has it
    import pyvista as pv

    path = Path(run_dir) / file
    grid = pv.read(str(path))
    fields = [fields] if isinstance(fields, str) else list(fields)
    p = pv.Plotter(off_screen=True, shape=(1, len(fields)), window_size=(size[0] * len(fields), size[1]), border=False)
    p.set_background("white")
    for i, f in enumerate(fields):
        p.subplot(0, i)
        on_cells = f in grid.cell_data
        if not on_cells and f not in grid.point_data:
            known = sorted(set(grid.point_data) | set(grid.cell_data))
            raise KeyError(f"{path} has no field {f!r} (fields: {', '.join(known)})")
        v = np.asarray(grid.cell_data[f] if on_cells else grid.point_data[f], float)
        lo, hi = float(np.nanmin(v)), float(np.nanmax(v))
        if lo < 0.0 < hi:  # both signs: centred diverging map
            m = max(-lo, hi)
            cmap, clim = "coolwarm", (-m, m)
        else:
            # a constant field (no contact: pressure 0 everywhere) gets a readable bar, not 0 .. 1e-30
            cmap, clim = "viridis", (lo, hi if hi > lo else lo + max(1.0, abs(lo)))
        sheet = grid
        if "clamped_part" in grid.cell_data and np.any(grid.cell_data["clamped_part"]):
            # the pedestal patch: one polygon, drawn without the edges of VTK's triangulation of it
            patch = grid.extract_cells(np.flatnonzero(grid.cell_data["clamped_part"]))
            sheet = grid.extract_cells(np.flatnonzero(grid.cell_data["clamped_part"] == 0))
            p.add_mesh(
                patch,
                scalars=f,
                preference="cell" if on_cells else "point",
                cmap=cmap,
                clim=clim,
                show_scalar_bar=False,
            )
        p.add_mesh(
            sheet,
            scalars=f,
            preference="cell" if on_cells else "point",
            cmap=cmap,
            clim=clim,
            show_edges=True,
            edge_color="#303030",
            line_width=0.3,
            smooth_shading=not on_cells,
            scalar_bar_args=dict(
                title=f"{f} [{_unit(f)}] ({'cells' if on_cells else 'points'})",
                color="black",
                vertical=False,
                position_x=0.2,
                position_y=0.04,
                width=0.6,
                title_font_size=14,
                label_font_size=12,
                fmt="%.3g",
            ),
        )
        const = f" (constant {lo:.3g})" if hi == lo else ""
        p.add_text(f"{path.parent.name}: {f}{const}", font_size=10, color="black")
        p.enable_parallel_projection()  # orthographic, as the run's own pictures: fits predictably
        {"top": p.view_xy, "side": p.view_xz}.get(view, p.view_isometric)()
        if view == "side":
            p.camera.elevation = SIDE_ELEVATION_DEG  # a strip seen exactly edge-on has no area to draw
        p.reset_camera(bounds=grid.bounds)
        p.camera.zoom(0.85)  # room for the colour bar below
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    p.screenshot(str(out))
    p.close()
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m solidshell.render.fieldview", description=__doc__.split("\n\n")[0])
    ap.add_argument("run_dir")
    ap.add_argument("--field", action="append", required=True, help="a point or cell field (repeatable)")
    ap.add_argument("--out", required=True, help="the PNG to write")
    ap.add_argument("--view", choices=("iso", "top", "side"), default="iso")
    ap.add_argument("--file", default="deformed.vtu", help="the run's VTU to read (default deformed.vtu)")
    a = ap.parse_args(argv)
    path = Path(a.run_dir) / a.file
    if not path.is_file():
        print(f"fieldview: error: {path} is not a file (a run folder holds {a.file})", file=sys.stderr)
        return 2
    try:
        print(field_picture(a.run_dir, a.field, a.out, a.view, a.file))
    except KeyError as e:
        print(f"fieldview: error: {e.args[0]}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"fieldview: error: {e.filename or a.out}: {e.strerror or e}", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
