"""gmsh recipes for the paper's scenes: structured quad meshes with the paper's element counts.

Every recipe returns a :class:`~solidshell.mesh.ShellMesh` in cm, flat in the plane z = 0 (the
pedestal top / initial sheet plane), with every element counter-clockwise seen from +Z and
directors +Z (Section 2).  Sheets are centred at the origin and the warp is global X (Section 3).
Pedestal scenes mesh only the hanging part; its edge on the pedestal is the node set ``clamped``.

Mesh densities use the paper's names (Sections 3-6):

- ``strip`` ``NxM``: N along the strip (X) x M across (3.1: 10x1, 20x1)
- ``square_on_square`` ``AxBx4``: 4 trapezoidal panels, A along the pedestal edge x B outward
  (3.2: 24x8x4, 48x16x4; 3.5: 45x15x4; 6.1/6.2 level 0: 6x2x4)
- ``disc_on_disc`` ``RxC``: R radial x C around, 4 | C (3.3: 10x40, 20x80)
- ``square_on_disc`` ``RxC``: R outward x C around, 8 | C (3.4: 30x240; 6.3 level 0: 4x32)
- ``square`` ``NxM``: whole sheet, N along X x M along Y (4.1: 40x40, 50x50; 4.2: 60x60,
  100x100; 6.4 level 0: 16x16)
- ``from_file``: a user's ``.geo`` (meshed by gmsh) or a mesh file (meshio)

Use :func:`build_mesh` (``build_mesh("square_on_square", "48x16x4")``) or the :data:`RECIPES`
registry.  gmsh is used through its Python API with a private model, silent (``General.Terminal``
= 0) and without reading the user's gmsh configuration files, so the output is deterministic.
"""

from __future__ import annotations

import contextlib
import inspect
import io
import math
import re
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .errors import InputError
from .mesh import ShellMesh

__all__ = [
    "parse_density",
    "build_mesh",
    "from_file",
    "gmsh_initialize",
    "RECIPES",
    "Recipe",
    "strip",
    "square_on_square",
    "disc_on_disc",
    "square_on_disc",
    "square",
]

_GMSH_LOCK = threading.Lock()  # gmsh keeps one global state per process
_FIELD = re.compile(r"\s*[0-9]+\s*")


# --------------------------------------------------------------------------- densities
def parse_density(text: str, n_fields: int, form: str | None = None) -> tuple[int, ...]:
    """Parse a mesh density such as ``"24x8x4"`` (separators ``x``, ``X`` or ``×``).

    Exactly ``n_fields`` positive integers are required; anything else raises InputError naming the
    expected ``form`` (default ``N1xN2x...``).
    """
    form = form or "x".join(f"N{i + 1}" for i in range(n_fields))
    hint = f"expected {form}: {n_fields} positive integer(s) separated by 'x'"
    if not isinstance(text, str):
        raise InputError(f"mesh density must be a string like {form!r}, got {type(text).__name__}; {hint}")
    fields = re.split(r"[xX×]", text.strip())
    if len(fields) != n_fields or not all(_FIELD.fullmatch(f) for f in fields):
        raise InputError(f"mesh density {text!r} is malformed; {hint}")
    counts = tuple(int(f) for f in fields)
    if min(counts) < 1:
        raise InputError(f"mesh density {text!r} has a zero field; {hint}")
    return counts


# --------------------------------------------------------------------------- gmsh plumbing
@contextlib.contextmanager
def _gmsh_model(name: str, options: dict[str, float] | None = None):
    """A fresh, silent gmsh model with the given numeric options.  gmsh is initialised and
    finalised here unless the caller already runs a gmsh session; then only the temporary model
    is removed and the caller's option values are restored."""
    import gmsh

    options = {"General.Terminal": 0, **(options or {})}
    with _GMSH_LOCK:
        owner = not gmsh.isInitialized()
        if owner:
            gmsh_initialize()
        saved = {k: gmsh.option.getNumber(k) for k in options}
        try:
            for k, v in options.items():
                gmsh.option.setNumber(k, v)
            gmsh.model.add(name)
            yield gmsh
        finally:
            if owner:
                gmsh.finalize()
            else:
                gmsh.model.remove()
                for k, v in saved.items():
                    gmsh.option.setNumber(k, v)


def gmsh_initialize() -> None:
    """``gmsh.initialize`` (no config files, no SIGINT handler of its own) with the process's signal
    dispositions kept.  gmsh's C++ side sets SIGTERM, SIGINT and SIGPIPE back to the system default
    when it initialises, under Python's feet: the CLI's SIGTERM handler (state written, exit 143) then
    never runs, and SIGPIPE -- which Python ignores, so that a write to a closed pipe or socket raises
    ``BrokenPipeError`` -- kills the whole process instead (a Dask worker's closed socket, a closed
    ``| head``; the CI run that died with exit 141).  Every gmsh session of the project starts here."""
    import signal

    import gmsh

    names = (signal.SIGINT, signal.SIGTERM, signal.SIGPIPE)
    kept = {s: signal.getsignal(s) for s in names}
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    if threading.current_thread() is threading.main_thread():
        for s, h in kept.items():
            if h is not None:  # None: set outside Python, nothing to put back
                signal.signal(s, h)
    elif kept[signal.SIGPIPE] == signal.SIG_IGN:  # signal.signal is main-thread only; libc's is not
        import ctypes

        ctypes.CDLL(None).signal(int(signal.SIGPIPE), ctypes.c_void_p(1))  # 1 = SIG_IGN


def _extract(gmsh) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """(nodes, quads, tris, node sets) of the current gmsh model's 2-D mesh, 0-based, with only
    the nodes that belong to a surface element.  Node sets come from the physical groups of
    points and curves, by physical name (unnamed groups are called ``point_<tag>``/``curve_<tag>``)."""
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    index = np.full(int(tags.max()) + 1 if len(tags) else 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    cells = {3: [], 2: []}  # gmsh type 3 = 4-node quadrangle, 2 = 3-node triangle
    for etype, _, conn in zip(*gmsh.model.mesh.getElements(dim=2)):
        if etype not in cells:
            name = gmsh.model.mesh.getElementProperties(etype)[0]
            raise InputError(f"unsupported surface element {name!r}: only linear quads and triangles")
        cells[etype].append(index[conn.astype(np.int64)].reshape(-1, 4 if etype == 3 else 3))
    quads = np.concatenate(cells[3]) if cells[3] else np.zeros((0, 4), np.int64)
    tris = np.concatenate(cells[2]) if cells[2] else np.zeros((0, 3), np.int64)
    if not len(quads) and not len(tris):
        raise InputError("the geometry produced no quad or triangle elements (no surface meshed)")
    sets: dict[str, np.ndarray] = {}
    for dim, tag in gmsh.model.getPhysicalGroups():
        if dim > 1:
            continue
        name = gmsh.model.getPhysicalName(dim, tag) or f"{('point', 'curve')[dim]}_{tag}"
        ntags, _ = gmsh.model.mesh.getNodesForPhysicalGroup(dim, tag)
        sets[name] = np.union1d(sets.get(name, []), index[ntags.astype(np.int64)]).astype(np.int64)
    return _compact(xyz.reshape(-1, 3), quads, tris, sets)[:4]


def _compact(X, quads, tris, sets):
    """Drop nodes used by no element (e.g. gmsh geometry points) and renumber 0..N-1; returns
    (nodes, quads, tris, sets, indices of the kept nodes)."""
    used = np.unique(np.concatenate([quads.ravel(), tris.ravel()]))
    remap = np.full(len(X), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    sets = {k: remap[v][remap[v] >= 0] for k, v in sets.items()}
    return X[used], remap[quads], remap[tris], sets, used


def _orient_up(X: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Reverse the node order of every element that is clockwise seen from +Z (shoelace area)."""
    if not len(cells):
        return cells
    P = X[cells, :2]
    Q = np.roll(P, -1, axis=1)
    signed = np.sum(P[..., 0] * Q[..., 1] - Q[..., 0] * P[..., 1], axis=1)
    out = cells.copy()
    out[signed < 0] = out[signed < 0][:, ::-1]
    return out


def _flat_mesh(X, quads, tris, sets) -> ShellMesh:
    """ShellMesh of a flat z = const mesh: elements counter-clockwise from +Z, directors +Z."""
    D = np.tile([0.0, 0.0, 1.0], (len(X), 1))
    return ShellMesh(X, _orient_up(X, quads), _orient_up(X, tris), directors=D, node_sets=sets)


class _Builder:
    """Thin helper over gmsh's OpenCASCADE kernel for transfinite (structured) quad panels.

    OpenCASCADE, not gmsh's built-in kernel: with the built-in kernel gmsh places the nodes of a
    transfinite circle arc up to ~1e-9 rad off uniform (and line nodes ~1e-12 off), which breaks
    the meshes' mirror symmetries at that level; with OpenCASCADE they are uniform to rounding."""

    def __init__(self, gmsh):
        self.gmsh, self.occ = gmsh, gmsh.model.occ
        self.curves: list[tuple[int, int]] = []  # (curve tag, elements)
        self.surfaces: list[int] = []
        self.groups: dict[tuple[int, str], list[int]] = {}

    def point(self, x: float, y: float) -> int:
        return self.occ.addPoint(float(x), float(y), 0.0)

    def line(self, a: int, b: int, n: int, *groups: str, dist: tuple[str, float] = ("Progression", 1.0)) -> int:
        """Straight edge a->b with n elements; ``dist``: gmsh's transfinite distribution
        ("Progression", r: sizes grow by r from a to b; "Bump", c: c < 1 clusters nodes at both ends)."""
        return self._curve(self.occ.addLine(a, b), n, groups, dist)

    def arc(self, a: int, centre: int, b: int, n: int, *groups: str) -> int:
        """Circular arc a->b (< 180 deg) about centre with n elements, uniform in angle."""
        return self._curve(self.occ.addCircleArc(a, centre, b), n, groups)

    def _curve(self, tag, n, groups, dist=("Progression", 1.0)):
        self.curves.append((tag, n, dist))
        for g in groups:
            self.groups.setdefault((1, g), []).append(tag)
        return tag

    def panel(self, *curves: int) -> None:
        """Structured, recombined panel bounded by four curves that form a closed loop."""
        self.surfaces.append(self.occ.addPlaneSurface([self.occ.addCurveLoop(list(curves))]))

    def points_group(self, name: str, pts: list[int]) -> None:
        self.groups[(0, name)] = list(pts)

    def mesh(self) -> ShellMesh:
        self.occ.synchronize()
        m = self.gmsh.model
        for tag, n, (kind, coef) in self.curves:
            m.mesh.setTransfiniteCurve(tag, n + 1, kind, coef)
        for s in self.surfaces:
            m.mesh.setTransfiniteSurface(s)
            m.mesh.setRecombine(2, s)
        for (dim, name), tags in self.groups.items():
            m.addPhysicalGroup(dim, tags, name=name)
        m.mesh.generate(2)
        return _flat_mesh(*_extract(self.gmsh))


def _positive(**values: float) -> list[float]:
    out = []
    for k, v in values.items():
        try:
            f = float(v)
        except (TypeError, ValueError):
            raise InputError(f"{k} must be a length in cm, got {v!r}") from None
        if not (math.isfinite(f) and f > 0.0):
            raise InputError(f"{k} must be a positive finite length in cm, got {v!r}")
        out.append(f)
    return out


# --------------------------------------------------------------------------- recipes
def strip(counts: tuple[int, int], length: float = 5.0, width: float = 1.0) -> ShellMesh:
    """Strip [0, length] x [-width/2, width/2] cm clamped at x = 0 (Section 3.1: 5x1 cm, meshes
    10x1 and 20x1).  counts = (N along X, M across).  Sets ``clamped`` (x = 0), ``tip`` (x = L)."""
    L, W = _positive(length=length, width=width)
    n, m = counts
    with _gmsh_model("strip") as gmsh:
        b = _Builder(gmsh)
        p = [b.point(x, y) for x, y in ((0, -W / 2), (L, -W / 2), (L, W / 2), (0, W / 2))]
        c = [
            b.line(p[0], p[1], n),
            b.line(p[1], p[2], m, "tip"),
            b.line(p[2], p[3], n),
            b.line(p[3], p[0], m, "clamped"),
        ]
        b.panel(*c)
        return b.mesh()


def square_on_square(
    counts: tuple[int, int, int], sheet: float = 20.0, pedestal: float = 10.0, grading: float = 1.0
) -> ShellMesh:
    """Hanging part of a sheet x sheet cm square centred on a pedestal x pedestal cm square
    pedestal (Sections 3.2, 3.5, 6.1, 6.2): four trapezoidal panels between the pedestal edge and
    the sheet edge, meeting on the diagonals.  counts = (A along the pedestal edge, B outward, 4):
    4AB quads, 4A(B+1) nodes.  Sets ``clamped`` (pedestal edge), ``outer`` (sheet boundary).
    ``grading`` >= 1 refines towards the pedestal corners, where the clamped square's re-entrant
    corners make the membrane stresses singular: along the diagonals the element size grows
    geometrically by ``grading`` from the pedestal to the sheet corner, and along the pedestal and
    sheet edges nodes cluster at both ends (gmsh "Bump" 1/grading).  1 (default) is the paper's
    uniform mesh; the DC mesh study (verification/static_convergence.py) uses 8."""
    if not (math.isfinite(float(grading)) and float(grading) >= 1.0):
        raise InputError(f"grading must be a number >= 1, got {grading!r}")
    s, p = _positive(sheet=sheet, pedestal=pedestal)
    if p >= s:
        raise InputError(f"pedestal ({p} cm) must be smaller than the sheet ({s} cm)")
    a, nb, panels = counts
    if panels != 4:
        raise InputError(f"the third density field counts the trapezoidal panels and must be 4, got {panels}")
    corners = ((-1, -1), (1, -1), (1, 1), (-1, 1))
    with _gmsh_model("square_on_square") as gmsh:
        b = _Builder(gmsh)
        inner = [b.point(i * p / 2, j * p / 2) for i, j in corners]
        outer = [b.point(i * s / 2, j * s / 2) for i, j in corners]
        g = float(grading)
        diag = [b.line(inner[k], outer[k], nb, dist=("Progression", g ** (1.0 / max(nb - 1, 1)))) for k in range(4)]
        bump = ("Bump", 1.0 / g) if g != 1.0 else ("Progression", 1.0)
        for k in range(4):
            k1 = (k + 1) % 4
            e_in = b.line(inner[k], inner[k1], a, "clamped", dist=bump)
            e_out = b.line(outer[k], outer[k1], a, "outer", dist=bump)
            b.panel(e_in, diag[k1], e_out, diag[k])
        return b.mesh()


def disc_on_disc(counts: tuple[int, int], diameter: float = 25.4, pedestal_diameter: float = 12.7) -> ShellMesh:
    """Hanging annulus of a disc of ``diameter`` cm centred on a circular pedestal (Section 3.3:
    Ø25.4 on Ø12.7, meshes 10x40 and 20x80).  counts = (R radial, C around), C divisible by 4
    (one panel per quadrant, so the X and Y axes are mesh lines): RC quads, (R+1)C nodes.  Nodes
    on both circles are uniform in angle; elements are straight-sided, so the area converges at
    second order in 1/C.  Sets ``clamped`` (pedestal circle), ``outer`` (sheet circle)."""
    d, dp = _positive(diameter=diameter, pedestal_diameter=pedestal_diameter)
    if dp >= d:
        raise InputError(f"pedestal_diameter ({dp} cm) must be smaller than diameter ({d} cm)")
    nr, nc = counts
    if nc % 4:
        raise InputError(f"disc_on_disc needs C (elements around) divisible by 4, got {nc}")
    with _gmsh_model("disc_on_disc") as gmsh:
        b = _Builder(gmsh)
        o = b.point(0, 0)
        dirs = ((1, 0), (0, 1), (-1, 0), (0, -1))
        inner = [b.point(i * dp / 2, j * dp / 2) for i, j in dirs]
        outer = [b.point(i * d / 2, j * d / 2) for i, j in dirs]
        ray = [b.line(inner[k], outer[k], nr) for k in range(4)]
        for k in range(4):
            k1 = (k + 1) % 4
            a_in = b.arc(inner[k], o, inner[k1], nc // 4, "clamped")
            a_out = b.arc(outer[k], o, outer[k1], nc // 4, "outer")
            b.panel(a_in, ray[k1], a_out, ray[k])
        return b.mesh()  # the arcs' centre point is no mesh node: _extract drops it


def square_on_disc(counts: tuple[int, int], sheet: float = 50.0, pedestal_diameter: float = 20.0) -> ShellMesh:
    """Hanging part of a sheet x sheet cm square centred on a circular pedestal (Sections 3.4,
    4.2, 6.3: 50x50 on Ø20, mesh 30x240, level 0 4x32).  counts = (R outward, C around); four
    panels, one per square side, between the pedestal arc and the side, meeting on the
    diagonals; C divisible by 8 so that the diagonals and the X and Y axes are all mesh lines.
    Pedestal nodes are uniform in angle, side nodes uniform in length.  RC quads, (R+1)C nodes.
    Sets ``clamped`` (pedestal circle), ``outer`` (sheet boundary)."""
    s, dp = _positive(sheet=sheet, pedestal_diameter=pedestal_diameter)
    if dp >= s:
        raise InputError(f"pedestal_diameter ({dp} cm) must be smaller than the sheet ({s} cm)")
    nr, nc = counts
    if nc % 8:
        raise InputError(f"square_on_disc needs C (elements around) divisible by 8, got {nc}")
    r = dp / 2 / math.sqrt(2.0)  # pedestal points on the diagonals
    corners = ((1, -1), (1, 1), (-1, 1), (-1, -1))
    with _gmsh_model("square_on_disc") as gmsh:
        b = _Builder(gmsh)
        o = b.point(0, 0)
        inner = [b.point(i * r, j * r) for i, j in corners]
        outer = [b.point(i * s / 2, j * s / 2) for i, j in corners]
        diag = [b.line(inner[k], outer[k], nr) for k in range(4)]
        for k in range(4):
            k1 = (k + 1) % 4
            a_in = b.arc(inner[k], o, inner[k1], nc // 4, "clamped")
            e_out = b.line(outer[k], outer[k1], nc // 4, "outer")
            b.panel(a_in, diag[k1], e_out, diag[k])
        return b.mesh()  # the arcs' centre point is no mesh node: _extract drops it


def square(counts: tuple[int, int], size: float = 20.0) -> ShellMesh:
    """Whole size x size cm sheet centred at the origin (Section 4.1: 20x20 as 40x40, 100x100 as
    50x50; Section 4.2/6.4: 30x30 cloth as 60x60, 100x100, level 0 16x16).  counts = (N along X,
    M along Y).  Sets ``outer``, ``corners`` (4), ``corner_sw``/``corner_se``/``corner_ne``/
    ``corner_nw`` (s/n = -/+Y, w/e = -/+X), ``hung`` = the two corners at y = +size/2 that the
    hang scenes fix (Section 4.1), ``centre`` = the node nearest the centre and ``centre_east`` = the
    next node from it along +X (the static sphere holds them: scenes/paper/sphere.toml)."""
    (a,) = _positive(size=size)
    n, m = counts
    names = ("corner_sw", "corner_se", "corner_ne", "corner_nw")
    with _gmsh_model("square") as gmsh:
        b = _Builder(gmsh)
        p = [b.point(i * a / 2, j * a / 2) for i, j in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        c = [
            b.line(p[0], p[1], n, "outer"),
            b.line(p[1], p[2], m, "outer"),
            b.line(p[2], p[3], n, "outer"),
            b.line(p[3], p[0], m, "outer"),
        ]
        b.panel(*c)
        for name, q in zip(names, p):
            b.points_group(name, [q])
        b.points_group("corners", p)
        b.points_group("hung", [p[2], p[3]])
        mesh = b.mesh()
    xy = mesh.nodes[:, :2]
    c = int(np.argmin(np.hypot(xy[:, 0], xy[:, 1])))
    row = np.flatnonzero((np.abs(xy[:, 1] - xy[c, 1]) <= 1e-9 * a) & (xy[:, 0] > xy[c, 0] + 1e-9 * a))
    mesh.add_node_set("centre", [c])
    mesh.add_node_set("centre_east", row[np.argmin(xy[row, 0])])
    return mesh


def from_file(path) -> ShellMesh:
    """Mesh from a file: a gmsh ``.geo`` (meshed in 2-D by gmsh, recombined into quads where it
    can) or any mesh file meshio reads (``.msh``, ``.vtu``, ``.xdmf``, ...).  Node sets come from
    physical groups of points and curves, by physical name, or from ``set:<name>`` point data
    written by :meth:`ShellMesh.to_meshio`.  Directors stored in the file (``director`` point
    data) are kept with the file's element order; otherwise a flat (z = const) mesh is turned
    counter-clockwise seen from +Z with directors +Z, and a curved one keeps its element order and
    gets averaged-normal directors.  Lengths are taken as cm."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"mesh file {str(path)!r} does not exist")
    if p.stat().st_size == 0:
        raise InputError(f"mesh file {str(path)!r} is empty")
    if p.suffix.lower() == ".geo":
        X, quads, tris, sets = _mesh_geo(p)
        D = None
    else:
        X, quads, tris, sets, D = _read_meshio(p)
    if D is None and np.ptp(X[:, 2]) <= 1e-12 * max(float(np.ptp(X, axis=0).max()), 1.0):
        return _flat_mesh(X, quads, tris, sets)
    return ShellMesh(X, quads, tris, directors=D, node_sets=sets)


def _mesh_geo(p: Path):
    """Open a .geo with gmsh and mesh it in 2-D, recombined (gmsh's error line -> InputError)."""
    # RecombineAll is set before opening, so that the user's file can still turn it off
    with _gmsh_model("from_file", {"Mesh.RecombineAll": 1}) as gmsh:
        gmsh.logger.start()
        try:
            gmsh.open(str(p))
            gmsh.model.mesh.generate(2)
            errors = [m for m in gmsh.logger.get() if m.startswith("Error")]
        except Exception as e:  # gmsh raises a plain Exception with its log line
            errors = [str(e) or "error"]
            _reset_geo_parser(gmsh)
        finally:
            gmsh.logger.stop()
        if errors:
            raise InputError(f"gmsh cannot mesh {p.name}: {errors[0].splitlines()[0]}")
        if gmsh.model.getDimension() < 2:
            raise InputError(f"{p.name} defines no surface to mesh")
        return _extract(gmsh)


def _reset_geo_parser(gmsh) -> None:
    """gmsh 4.15 keeps a stale token after a .geo syntax error, so the next .geo parsed in this
    process fails with "line 0: syntax error (;)"; parsing a throwaway file consumes it."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        f = Path(d) / "reset.geo"
        f.write_text("solidshell_reset = 0;\n")
        try:
            gmsh.merge(str(f))
        except Exception:
            pass


def _read_meshio(p: Path):
    import meshio

    out = io.StringIO()
    try:  # meshio prints its errors and may even sys.exit(1) on an unreadable file
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            m = meshio.read(str(p))
    except (Exception, SystemExit) as e:  # ReadError, KeyError, ValueError, SystemExit, ...
        msg = next(
            (line for line in [str(e)] + out.getvalue().splitlines() if line.strip() and not line.strip().isdigit()),
            type(e).__name__,
        )
        raise InputError(f"cannot read mesh file {p.name}: {msg.strip()}") from None
    X = np.asarray(m.points, dtype=float)
    if X.ndim != 2 or len(X) == 0:
        raise InputError(f"mesh file {p.name} holds no nodes")
    if X.shape[1] == 2:
        X = np.column_stack([X, np.zeros(len(X))])
    blocks = {"quad": [], "triangle": []}
    for c in m.cells:
        if c.type in blocks:
            blocks[c.type].append(np.asarray(c.data, dtype=np.int64))
    if not blocks["quad"] and not blocks["triangle"]:
        raise InputError(f"mesh file {p.name} holds no quad or triangle cells")
    quads = np.concatenate(blocks["quad"]) if blocks["quad"] else np.zeros((0, 4), np.int64)
    tris = np.concatenate(blocks["triangle"]) if blocks["triangle"] else np.zeros((0, 3), np.int64)
    pd = m.point_data or {}
    sets = {k[4:]: np.flatnonzero(np.asarray(v) > 0) for k, v in pd.items() if k.startswith("set:")}
    sets.update(_physical_sets(m))
    D = pd.get("director")
    D = None if D is None else np.asarray(D, dtype=float)
    X, quads, tris, sets, used = _compact(X, quads, tris, sets)
    return X, quads, tris, sets, None if D is None else D[used]


def _physical_sets(m) -> dict[str, np.ndarray]:
    """Node sets from a gmsh file's physical groups of points (vertex cells) and curves (line
    cells), named as in :func:`_extract`."""
    phys = (m.cell_data or {}).get("gmsh:physical")
    if phys is None:
        return {}
    names = {(int(t), int(d)): k for k, (t, d) in ((k, v[:2]) for k, v in (m.field_data or {}).items())}
    sets: dict[str, np.ndarray] = {}
    for c, tags in zip(m.cells, phys):
        dim = {"vertex": 0, "line": 1}.get(c.type)
        if dim is None:
            continue
        for t in np.unique(tags):
            name = names.get((int(t), dim), f"{('point', 'curve')[dim]}_{int(t)}")
            nodes = np.asarray(c.data)[np.asarray(tags) == t].ravel()
            sets[name] = np.union1d(sets.get(name, np.zeros(0, np.int64)), nodes).astype(np.int64)
    return sets


# --------------------------------------------------------------------------- registry
@dataclass(frozen=True)
class Recipe:
    """A mesh recipe: ``build(counts, **geometry)``, its default density and density form;
    ``optional``: the geometry keywords a scene file may leave out (it states every length)."""

    build: Callable[..., ShellMesh]
    density: str | None
    form: str | None
    doc: str
    optional: tuple[str, ...] = ()

    @property
    def n_fields(self) -> int:
        return 0 if self.form is None else self.form.count("x") + 1

    @property
    def geometry(self) -> tuple[str, ...]:
        """The geometry keywords (cm) the recipe accepts."""
        params = list(inspect.signature(self.build).parameters)
        return tuple(params[1:]) if self.form is not None else tuple(params)

    @property
    def required(self) -> tuple[str, ...]:
        """The geometry keywords a scene file must give (solidshell.scenes)."""
        return tuple(p for p in self.geometry if p not in self.optional)


RECIPES: dict[str, Recipe] = {
    "strip": Recipe(strip, "10x1", "NxM", "5x1 cm strip clamped at x = 0; N along x M across (§3.1)"),
    "square_on_square": Recipe(
        square_on_square,
        "24x8x4",
        "AxBx4",
        "hanging part of a square sheet on a square pedestal; 4 trapezoidal panels (§3.2, §3.5)",
        optional=("grading",),
    ),
    "disc_on_disc": Recipe(
        disc_on_disc, "10x40", "RxC", "hanging annulus of a Ø25.4 disc on a Ø12.7 pedestal; R radial x C around (§3.3)"
    ),
    "square_on_disc": Recipe(
        square_on_disc,
        "30x240",
        "RxC",
        "hanging part of a 50x50 sheet on a Ø20 pedestal; R outward x C around, 8 | C (§3.4)",
    ),
    "square": Recipe(square, "40x40", "NxM", "whole square sheet centred at the origin; N along x M along y (§4)"),
    "from_file": Recipe(from_file, None, None, "a user's .geo (meshed by gmsh) or a mesh file read by meshio"),
}


def build_mesh(recipe: str, density: str | None = None, **geometry) -> ShellMesh:
    """Build the named recipe's mesh (cm, z = 0).  ``density`` uses the paper's names (e.g.
    ``"48x16x4"``), default the recipe's paper mesh; ``geometry`` overrides its lengths in cm
    (e.g. ``sheet=40.0, pedestal=20.0``) or gives ``path`` for ``from_file``."""
    key = str(recipe).strip().replace("-", "_")
    if key not in RECIPES:
        raise InputError(f"unknown mesh recipe {recipe!r}; known: {', '.join(RECIPES)}")
    r = RECIPES[key]
    unknown = sorted(set(geometry) - set(r.geometry))
    if unknown:
        raise InputError(
            f"mesh recipe {key!r} has no geometry keyword {', '.join(map(repr, unknown))}; "
            f"it accepts: {', '.join(r.geometry) or 'none'}"
        )
    if r.form is None:
        if density is not None:
            raise InputError(f"mesh recipe {key!r} takes no density (got {density!r})")
        if "path" not in geometry:
            raise InputError(f"mesh recipe {key!r} needs path=<mesh or .geo file>")
        return r.build(**geometry)
    counts = parse_density(r.density if density is None else density, r.n_fields, r.form)
    return r.build(counts, **geometry)
