"""Run output: meshes and fields for ParaView (XDMF + VTU via meshio), time series, summary.json.

A run directory holds (only the files that apply)::

    mesh.xdmf, mesh.vtu        the undeformed mesh: point data ``director`` (X_n) and one 0/1
                               field ``set:<name>`` per node set
    result.xdmf, result.vtu    the undeformed mesh with the final state: ``displacement`` (U_o),
                               ``director_displacement`` (U_n), ``director`` (X_n),
                               ``deformed_director`` (X_n + U_n), ``position`` (X_o + U_o) and the
                               node sets; in ParaView use "Warp By Vector" with ``displacement``
    deformed.vtu               the deformed mid-surface itself (points X_o + U_o), same fields
    series.xdmf                dynamic runs: one frame per kept time (the time in the XDMF
                               ``Time`` value), fields ``displacement`` and ``director_displacement``
    summary.json               inputs, counts, units, versions, timings, the solver's info,
                               ``run_id``, ``warnings``, ``interrupted``, ``files``; written last
    top.png, iso.png, ...      pictures (solidshell.plotting)
    projected_boundary.csv     draped sheets: the projected boundary on the X-Y plane
    RUNNING                    present while a run is under way (solidshell.rundir)

Every file carries the run's id (:func:`stamp_xml`, :func:`stamp_png`, :func:`read_run_id`).

XDMF files are written with inline XML data (no HDF5 needed), so each is self-contained.  Every
file is written atomically: to a temporary file in the same directory, flushed and fsync'ed, then
renamed over the final name with ``os.replace`` -- a crash or an exception mid-write leaves no
file (and no temporary) under the final name.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import tempfile
from pathlib import Path

import numpy as np

UNITS = {
    "length": "cm",
    "force": "gf",
    "time": "s",
    "mass": "gf*s^2/cm",
    "angle": "deg",
    "displacement": "cm",
    "energy": "gf*cm",
    "rigidity_tensile": "gf/cm",
    "rigidity_bending": "gf*cm^2/cm",
    "weight": "gf/cm^2",
}


# --------------------------------------------------------------------------- atomic writes
def _fsync_dir(d: Path) -> None:
    try:
        fd = os.open(str(d), os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _umask() -> int:
    old = os.umask(0o022)
    os.umask(old)
    return old


_FILE_MODE = 0o666 & ~_umask()  # what open() would give a new file (mkstemp gives 0600)


def _fsync_file(p: Path) -> None:
    with open(p, "rb+") as f:
        os.fsync(f.fileno())


def _temporary_affixes(path: Path, suffix: str | None = None) -> tuple[str, str]:
    """(prefix, suffix) of :func:`atomic_path`'s temporaries of ``path``, tempfile's random part
    between them: the one naming rule the writer and :func:`is_temporary_of` share."""
    return f".{path.stem}.", suffix if suffix is not None else path.suffix


@contextlib.contextmanager
def atomic_path(path, suffix: str | None = None):
    """Yield a temporary path in the same directory as ``path``; on normal exit the file written
    there is fsync'ed and renamed to ``path``; on an exception it is removed.  For writers that
    take a file name (meshio, matplotlib).  ``suffix`` (default: path's suffix) lets writers that
    pick the format from the extension see the right one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    prefix, suffix = _temporary_affixes(path, suffix)
    fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        yield tmp
        _fsync_file(tmp)
        os.chmod(tmp, _FILE_MODE)
        os.replace(tmp, path)
        _fsync_dir(path.parent)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def is_temporary_of(name: str, target: str) -> bool:
    """True when ``name`` is an :func:`atomic_path` temporary of a file named ``target`` (in the
    same folder): what a writer killed mid-write leaves behind."""
    prefix, suffix = _temporary_affixes(Path(target))
    return re.fullmatch(rf"{re.escape(prefix)}[A-Za-z0-9_]+{re.escape(suffix)}", name) is not None


@contextlib.contextmanager
def atomic_write(path, mode: str = "w", encoding: str | None = "utf-8"):
    """``with atomic_write(p) as f: f.write(...)`` -- the file appears under ``p`` complete or not
    at all."""
    binary = "b" in mode
    with atomic_path(path) as tmp:
        with open(tmp, mode, encoding=None if binary else encoding) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())


def write_json(path, data) -> Path:
    """Write ``data`` as indented JSON, atomically (numpy scalars/arrays become plain numbers/lists;
    non-finite floats become null)."""
    text = json.dumps(to_jsonable(data), indent=2, allow_nan=False) + "\n"
    with atomic_write(path) as f:
        f.write(text)
    return Path(path)


def to_jsonable(v):
    """Plain JSON types from numpy values, paths, tuples; NaN/inf -> None.  Other objects raise
    TypeError (so a bad summary fails loudly instead of writing half a file)."""
    if isinstance(v, dict):
        return {str(k): to_jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [to_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return to_jsonable(v.tolist())
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return f if math.isfinite(f) else None
    if v is None or isinstance(v, str):
        return v
    if isinstance(v, Path):
        return str(v)
    raise TypeError(f"summary value of type {type(v).__name__} is not JSON-serialisable: {v!r}")


# --------------------------------------------------------------------------- meshio files
@contextlib.contextmanager
def _no_h5py_needed():
    """meshio 5.3's XdmfWriter imports h5py unconditionally, even for data_format="XML" where it
    never touches it.  Unless h5py is already loaded, lend the writer an empty stand-in module for
    the duration of the call: its import (with HDF5) cost ~0.05 s of a 20-element run's start-up
    for nothing (issue 13)."""
    import sys
    import types

    if "h5py" in sys.modules:
        yield
        return
    sys.modules["h5py"] = types.ModuleType("h5py")
    try:
        yield
    finally:
        sys.modules.pop("h5py", None)


def _fields(mesh, U=None) -> dict:
    """Point data of a state U (N,6) on the mesh (nothing extra when U is None)."""
    if U is None:
        return {}
    U = np.asarray(U, dtype=float).reshape(mesh.n_nodes, 6)
    return {
        "displacement": U[:, :3].copy(),
        "director_displacement": U[:, 3:].copy(),
        "deformed_director": mesh.directors + U[:, 3:],
        "position": mesh.nodes + U[:, :3],
    }


def _with_fields(m, mesh, fields, patches):
    """The meshio mesh ``m`` with the state's fields: point and cell data (solidshell.fields), and
    the clamped patches (fields.clamped_patches) as one polygon cell each, where every cell field
    is 0 and ``clamped_part`` 1 (the solver's elements 0)."""
    import meshio

    point, cell = fields if fields is not None else ({}, {})
    for k, v in point.items():
        m.point_data[k] = _plain(v)
    blocks = [len(mesh.quads)] * bool(len(mesh.quads)) + [len(mesh.tris)] * bool(len(mesh.tris))
    cell = dict(cell)
    if patches:
        cell["clamped_part"] = np.zeros(mesh.n_elements, dtype=np.int32)
    for k, v in cell.items():
        v = _plain(v)
        parts = np.split(v, np.cumsum(blocks)[:-1]) if len(blocks) > 1 else [v]
        m.cell_data[k] = parts + [
            np.full((1,) + v.shape[1:], 1 if k == "clamped_part" else 0, dtype=v.dtype) for _ in patches
        ]
    for lp in patches:
        m.cells.append(meshio.CellBlock("polygon", np.asarray(lp, dtype=np.int64)[None, :]))
    return m


def _plain(v) -> np.ndarray:
    """A field as meshio's writers take it: float64, or int32 for integer and boolean flags."""
    v = np.asarray(v)
    return np.ascontiguousarray(v, dtype=np.int32 if v.dtype.kind in "biu" else np.float64)


def write_mesh_file(
    path, mesh, U=None, deformed: bool = False, run_id: str | None = None, fields=None, patches=()
) -> Path:
    """Write the mesh (and the state U, if given) with meshio; the format comes from the suffix
    (.xdmf -> XDMF with inline XML data, .vtu -> VTU).  ``deformed`` puts the points at X_o + U_o;
    ``run_id`` is stamped into the file (:func:`stamp_xml`).  ``fields``: (point data, cell data)
    of the state (solidshell.fields.state_fields); ``patches``: node loops of the sheet's clamped,
    unmeshed parts (fields.clamped_patches), written as polygon cells in VTU files only (meshio's
    XDMF has no polygon cell)."""
    import meshio

    path = Path(path)
    m = mesh.to_meshio(point_data=_fields(mesh, U))
    vtu = path.suffix.lower() == ".vtu"
    if fields is not None or (patches and vtu):
        m = _with_fields(m, mesh, fields, list(patches) if vtu else [])
    if deformed and U is not None:
        m.points = m.points + np.asarray(U, float).reshape(-1, 6)[:, :3]
    # meshio's XDMF writer wants float/int data only; sets are int32 already
    with atomic_path(path) as tmp:
        if path.suffix.lower() == ".xdmf":
            _write_xdmf(tmp, m)
        elif path.suffix.lower() == ".vtu":
            meshio.vtu.write(str(tmp), m, binary=True, compression="zlib")
        else:
            meshio.write(str(tmp), m)
        if run_id is not None and path.suffix.lower() in (".xdmf", ".vtu"):
            stamp_xml(tmp, run_id)
    return path


def _savetxt_text(data, fmt: str) -> str:
    """The text ``np.savetxt(f, data, fmt)`` writes, byte for byte, formatted in one join instead
    of savetxt's loop over rows: a 1-D array one value per line, a 2-D array one row per line with
    its values separated by one space, each line ending in a newline."""
    a = np.asarray(data)
    if a.ndim == 1:
        lines = map(fmt.__mod__, a.tolist())
    elif a.ndim == 2:
        lines = map(" ".join([fmt] * a.shape[1]).__mod__, map(tuple, a.tolist()))
    else:
        raise ValueError(f"inline XDMF data must be 1-D or 2-D, got shape {a.shape}")
    text = "\n".join(lines)
    return text + "\n" if len(a) else ""


def _write_xdmf(path, m) -> None:
    """meshio's XDMF writer with inline XML data (``meshio.xdmf.write(path, m, data_format="XML")``,
    the same file byte for byte, tests/test_io.py), its numbers formatted by :func:`_savetxt_text`:
    np.savetxt's loop took ~0.2 s of each square-pedestal 48x16x4 state file (issue 41)."""
    from meshio.xdmf.main import XdmfWriter

    with _no_h5py_needed():
        _fast_xml(XdmfWriter, flat=False)(str(path), m, data_format="XML")


def _fast_xml(base, flat: bool):
    """The meshio XDMF writer class ``base`` whose inline XML numbers are formatted by
    :func:`_savetxt_text` in one join instead of np.savetxt's Python loop, the text byte for byte
    meshio's (tests/test_io.py): ``flat`` as meshio's TimeSeriesWriter (the values one per line),
    else as its XdmfWriter (one row per line, after a newline).  savetxt took ~6 s of the sphere
    100x100 relaxation's 23-frame, 34 MB series."""
    from meshio.xdmf.common import dtype_to_format_string

    class _Writer(base):
        def numpy_to_xml_string(self, data):
            if self.data_format != "XML":
                return super().numpy_to_xml_string(data)
            fmt = dtype_to_format_string[data.dtype.name]
            return _savetxt_text(np.ravel(data), fmt) if flat else "\n" + _savetxt_text(data, fmt)

    return _Writer


def write_time_series(path, mesh, frames, run_id: str | None = None) -> Path:
    """XDMF time series (meshio TimeSeriesWriter, inline XML data) of ``frames`` = [(t, U (N,6)), ...]
    on the undeformed mesh: fields ``displacement`` and ``director_displacement`` per frame."""
    path = Path(path)
    cells = []
    if mesh.n_quads:
        cells.append(("quad", mesh.quads))
    if mesh.n_tris:
        cells.append(("triangle", mesh.tris))
    from meshio.xdmf.time_series import TimeSeriesWriter

    with atomic_path(path) as tmp:
        with _fast_xml(TimeSeriesWriter, flat=True)(str(tmp), data_format="XML") as w:
            w.write_points_cells(mesh.nodes, cells)
            for t, U in frames:
                U = np.asarray(U, dtype=float).reshape(mesh.n_nodes, 6)
                w.write_data(
                    float(t), point_data={"displacement": U[:, :3].copy(), "director_displacement": U[:, 3:].copy()}
                )
        if run_id is not None:
            stamp_xml(tmp, run_id)
    return path


def read_state(path):
    """(mesh, U) back from a result .vtu/.xdmf written here (U from ``displacement`` and
    ``director_displacement``; zeros where absent)."""
    import meshio

    from .mesh import ShellMesh

    with _no_h5py_needed():
        m = meshio.read(str(path))
    mesh = ShellMesh.from_meshio(m)
    U = np.zeros((mesh.n_nodes, 6))
    pd = m.point_data or {}
    if "displacement" in pd:
        U[:, :3] = np.asarray(pd["displacement"], float)[: mesh.n_nodes]
    if "director_displacement" in pd:
        U[:, 3:] = np.asarray(pd["director_displacement"], float)[: mesh.n_nodes]
    return mesh, U


# --------------------------------------------------------------------------- run ids
# Every file of a run carries the run's id (uuid4 hex, also in summary.json "run_id"), so files of
# two runs can never be mistaken for one: XML files (VTU, XDMF) as a comment before the root
# element's content, PNG pictures as a tEXt chunk (keyword "solidshell:run_id"), CSV files as a
# "# run_id" line.  :func:`read_run_id` reads it back from any of them.
_RUN_ID_RE = re.compile(rb"solidshell run_id=([0-9a-f]{32})")
_PNG_SIG = b"\x89PNG\r\n\x1a\n"
PNG_RUN_ID_KEY = b"solidshell:run_id"


def _check_run_id(run_id: str) -> bytes:
    b = str(run_id).encode("ascii")
    if not re.fullmatch(rb"[0-9a-f]{32}", b):
        raise ValueError(f"run_id must be 32 lowercase hex digits (uuid4().hex), got {run_id!r}")
    return b


def stamp_xml(path, run_id: str) -> None:
    """Put ``<!-- solidshell run_id=... -->`` into an XML file in place: after the XML
    declaration if there is one, else first (a comment before the root element is valid XML, and
    ParaView and meshio ignore it).  Used on the temporary file before its atomic rename."""
    tag = b"<!-- solidshell run_id=" + _check_run_id(run_id) + b" -->\n"
    path = Path(path)
    data = path.read_bytes()
    at = data.index(b"?>") + 2 if data.startswith(b"<?xml") else 0
    if at and data[at : at + 1] == b"\n":
        at += 1
    path.write_bytes(data[:at] + tag + data[at:])


def _png_chunk(kind: bytes, body: bytes) -> bytes:
    import struct
    import zlib

    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def stamp_png(path, run_id: str) -> Path:
    """Add a tEXt chunk ``solidshell:run_id`` = ``run_id`` to a PNG (before its IEND chunk),
    rewriting the file atomically."""
    path = Path(path)
    data = path.read_bytes()
    if not data.startswith(_PNG_SIG) or data[-8:-4] != b"IEND":
        raise ValueError(f"{path} is not a complete PNG file")
    chunk = _png_chunk(b"tEXt", PNG_RUN_ID_KEY + b"\0" + _check_run_id(run_id))
    with atomic_write(path, "wb") as f:
        f.write(data[:-12] + chunk + data[-12:])
    return path


def _png_text(data: bytes) -> dict:
    import struct

    out, i = {}, 8
    while i + 8 <= len(data):
        (n,) = struct.unpack(">I", data[i : i + 4])
        kind = data[i + 4 : i + 8]
        if kind == b"tEXt":
            k, _, v = data[i + 8 : i + 8 + n].partition(b"\0")
            out[k] = v
        i += 12 + n
    return out


def read_run_id(path) -> str | None:
    """The run id stamped into an output file (VTU, XDMF, CSV, JSON summary, PNG), or None."""
    path = Path(path)
    data = path.read_bytes()
    if data.startswith(_PNG_SIG):
        v = _png_text(data).get(PNG_RUN_ID_KEY)
        return v.decode("ascii") if v else None
    if path.suffix.lower() == ".json":
        v = json.loads(data.decode("utf-8")).get("run_id")
        return str(v) if v else None
    m = _RUN_ID_RE.search(data[:4096])
    return m.group(1).decode("ascii") if m else None


# --------------------------------------------------------------------------- summaries
def package_versions() -> dict:
    """Versions of Python and of the packages a run depends on (without importing them)."""
    import platform
    from importlib import metadata

    out = {"python": platform.python_version()}
    for name in ("solidshell", "numpy", "scipy", "numba", "gmsh", "meshio", "matplotlib", "scikit-fem"):
        try:
            out[name.replace("-", "_")] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name.replace("-", "_")] = None
    return out


def mesh_counts(mesh, fixed=None) -> dict:
    c = {
        "nodes": int(mesh.n_nodes),
        "quads": int(mesh.n_quads),
        "triangles": int(mesh.n_tris),
        "elements": int(mesh.n_elements),
        "dofs": 6 * int(mesh.n_nodes),
        "node_sets": {k: int(len(v)) for k, v in sorted(mesh.node_sets.items())},
    }
    if fixed is not None:
        nf = int(np.count_nonzero(fixed))
        c["fixed_dofs"] = nf
        c["free_dofs"] = c["dofs"] - nf
    return c


def series_frame_paths(path, n: int) -> list[Path]:
    """The VTU files of an n-frame :func:`write_mesh_series` collection ``path`` (beside it)."""
    path = Path(path)
    return [path.with_name(f"{path.stem}_{i:05d}.vtu") for i in range(n)]


def write_mesh_series(path, frames, run_id: str | None = None, fields_of=None) -> Path:
    """ParaView collection (``.pvd``) of ``frames`` = [(t, ShellMesh, U (N,6)), ...] whose meshes may
    differ from frame to frame (an adaptive run): one VTU per frame beside the .pvd
    (:func:`series_frame_paths`), each with its undeformed mesh and the ``displacement`` /
    ``director_displacement`` fields (in ParaView, Warp By Vector on ``displacement`` shows the
    drape); the .pvd is written last, atomically.  ``fields_of(t, mesh, U) -> (fields, patches)``
    adds each frame's fields and clamped patches (:func:`write_mesh_file`)."""
    from xml.sax.saxutils import quoteattr

    path = Path(path)
    rows = []
    for p, (t, mesh, U) in zip(series_frame_paths(path, len(frames)), frames):
        fields, patches = fields_of(t, mesh, U) if fields_of is not None else (None, ())
        write_mesh_file(p, mesh, U, run_id=run_id, fields=fields, patches=patches)
        rows.append(f'    <DataSet timestep="{float(t)!r}" part="0" file={quoteattr(p.name)}/>\n')
    with atomic_path(path) as tmp:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n')
            f.writelines(rows)
            f.write("  </Collection>\n</VTKFile>\n")
        if run_id is not None:
            stamp_xml(tmp, run_id)
    return path
