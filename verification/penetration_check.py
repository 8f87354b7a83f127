"""Independent check of the contact contract on a run's written files.

    .venv/bin/python -m verification.penetration_check RUN_DIR [RUN_DIR ...] [--grid 5]

The contract (DESIGN.md "Contact"): no node and no point of an element's contact face lies inside a
rigid body deeper than 2 % of the sheet's thickness h.  This script reads only what a run wrote:

* ``RUN_DIR/result.vtu`` (meshio): the undeformed nodes, the ``quad`` / ``triangle`` blocks and the
  ``displacement`` point data (x = X + displacement: the deformed mid-surface);
* ``RUN_DIR/summary.json``: the thickness h (``material.thickness``) and the bodies' tables
  (``penetration.bodies``, the resolved tables the run used; runs older than that entry: the
  ``contact`` list of the scene's [[contact]] tables).

and computes the penetration p = offset - g(x) of every node and of every face point with its
own numpy geometry below (it imports nothing of solidshell: not ``contact`` nor
``contact_kernels``, not ``penetration``), where g is the body's signed distance (positive outside):

* sphere   : |x - c| - R
* plane    : (x - p) . n / |n|   (the side opposite to n is solid)
* mesh     : the body's triangles, rebuilt from its table -- ``file`` read by meshio (relative to
  the summary's ``scene_file``), or ``primitives`` fused and meshed by gmsh's OpenCASCADE kernel
  with ``mesh_size`` as the run did --, scaled (``units``, ``scale``), turned (``rotate``, degrees
  about the fixed x, y, z axes) and moved (``translate``) by scipy, oriented outward, and libigl's
  exact signed distance to them (not the grid the solver interpolates);
* pedestal : its top face centred at ``centre``, axis +Z, extending ``height`` down;
  ``shape = "disc"``: a cylinder of ``diameter``; ``shape = "square"``: a box of side ``size``;
  ``edge_radius`` e rounds its edges: the exact distance of the shape shrunk by e, minus e (for
  the box this rounds its vertical edges too, as solidshell.contact's Pedestal does);
  ``support = "cusick"`` (a disc with ``disc_thickness`` t and ``stem_diameter``): the disc (edges
  rounded by e) on a coaxial sharp-edged stem down to the base: min of the two cylinders' distances.

Face points: per quad the bilinear image of the grid x grid lattice of its parameter square, per
triangle the barycentric lattice of order grid - 1 (grid = 5: 25 and 15 points, corners and edges
included).  One line per run and body; exit 0 when every body is clean, 1 when a point lies beyond
the tolerance or the summary's own counts (same grid) disagree with these, 2 for unreadable input.
"""

from __future__ import annotations

import argparse
import json
import sys
import threading
from pathlib import Path

import numpy as np

TOL_FRACTION = 0.02
"""The contract's tolerance as a fraction of h (DESIGN.md "Contact"; solidshell states the same
figure as contact.PENETRATION_TOL, compared below with what the summary says it used)."""

_RESULT_KEYS = {"deepest_node_cm", "nodes_beyond", "deepest_face_point_cm", "face_points_beyond"}
_KEYS = {
    "sphere": {"centre", "radius"},
    "plane": {"point", "normal"},
    "pedestal": {
        "shape", "centre", "size", "diameter", "height", "edge_radius", "support",
        "stem_diameter", "disc_thickness", "clamp_diameter", "clamp_thickness",
    },
    "mesh": {
        "file", "primitives", "mesh_size", "units", "scale", "rotate", "translate", "spacing", "band", "_base",
    },
}  # fmt: skip
_COMMON = {"type", "offset", "friction", "origin", "role"}  # origin, role: where a body comes from
# (a Cusick support's clamp_* keys describe its clamp, which the tables list as a body of its own)


class BadInput(Exception):
    """Unreadable or incomplete run files (exit 2)."""


# ------------------------------------------------------------------ geometry (signed distances)
def _rounded_box(q: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Exact signed distance of the points q (..., k), taken about the box's centre, to the box
    |q_j| <= half_j: Euclidean outside, minus the nearest face's distance inside."""
    d = np.abs(q) - half
    return np.linalg.norm(np.maximum(d, 0.0), axis=-1) + np.minimum(d.max(axis=-1), 0.0)


def _cylinder(x: np.ndarray, top: np.ndarray, radius: float, height: float, edge: float) -> np.ndarray:
    """A vertical cylinder whose top face is centred at ``top``, edges rounded by ``edge``."""
    rho = np.hypot(x[:, 0] - top[0], x[:, 1] - top[1])
    z = x[:, 2] - (top[2] - 0.5 * height)  # about its mid-height
    q = np.column_stack([rho, z])
    return _rounded_box(q, np.array([radius - edge, 0.5 * height - edge])) - edge


_UNITS = {"mm": 0.1, "cm": 1.0, "m": 100.0, "in": 2.54}
_SURFACES: dict = {}


def _gmsh_union(primitives: list, size) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of the union of a mesh body's primitives, meshed by gmsh as the run did."""
    import signal

    import gmsh

    pipe = signal.getsignal(signal.SIGPIPE)
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    if pipe is not None and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGPIPE, pipe)  # gmsh resets it to "die"; Python's is "raise BrokenPipeError"
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("check")
        occ, tags = gmsh.model.occ, []
        for p in primitives:
            ((k, v),) = p.items()
            v = [float(a) for a in v]
            if k == "ellipsoid":
                t = occ.addSphere(v[0], v[1], v[2], 1.0)
                occ.dilate([(3, t)], *v)
            else:
                t = {"sphere": occ.addSphere, "box": occ.addBox, "cylinder": occ.addCylinder}[k](*v)
            tags.append(t)
        if len(tags) > 1:
            occ.fuse([(3, tags[0])], [(3, t) for t in tags[1:]])
        occ.synchronize()
        bb = np.array(gmsh.model.getBoundingBox(-1, -1))
        size = float(size) if size is not None else float(np.linalg.norm(bb[3:] - bb[:3])) / 60.0
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.2 * size)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 12)
        gmsh.model.mesh.generate(2)
        tag, xyz, _ = gmsh.model.mesh.getNodes()
        idx = np.zeros(int(tag.max()) + 1, np.int64)
        idx[np.asarray(tag, np.int64)] = np.arange(len(tag))
        F = idx[np.asarray(gmsh.model.mesh.getElementsByType(2)[1], np.int64).reshape(-1, 3)]
        return np.asarray(xyz, float).reshape(-1, 3), F
    finally:
        gmsh.finalize()


def _mesh_surface(table: dict) -> tuple[np.ndarray, np.ndarray]:
    """(V, F) of a mesh body's table: its triangles where the run had them, oriented outward."""
    import igl
    from scipy.spatial.transform import Rotation

    key = json.dumps(table, sort_keys=True, default=str)
    if key in _SURFACES:
        return _SURFACES[key]
    if table.get("file"):
        import meshio

        p = Path(table["file"])
        p = p if p.is_absolute() else Path(table.get("_base") or ".") / p
        try:
            m = meshio.read(p)
        except Exception as e:
            raise BadInput(f"mesh body file {p}: cannot read ({type(e).__name__}: {e})") from None
        F = np.concatenate(
            [np.asarray(c.data, np.int64) for c in m.cells if c.type == "triangle"]
            + [np.asarray(c.data, np.int64)[:, q] for c in m.cells if c.type == "quad" for q in ([0, 1, 2], [0, 2, 3])]
        )
        V = np.asarray(m.points, float)[:, :3]
    else:
        V, F = _gmsh_union(table["primitives"], table.get("mesh_size"))
    s = _UNITS[table.get("units") or "cm"] * float(table.get("scale") or 1.0)
    R = Rotation.from_euler("xyz", table.get("rotate") or (0, 0, 0), degrees=True).as_matrix()
    V = (s * V) @ R.T + np.asarray(table.get("translate") or (0, 0, 0), float)
    V, _, _, F = igl.remove_duplicate_vertices(V, F, 1e-9 * float(np.ptp(V, axis=0).max()))
    F, comp = igl.bfs_orient(np.asarray(F, np.int64))
    F = np.asarray(F, np.int64).copy()
    a, b, c = (V[F[:, i]] for i in range(3))
    vol = np.einsum("ij,ij->i", a, np.cross(b, c))
    for k in np.unique(comp):  # each connected patch outward (positive enclosed volume)
        if vol[comp == k].sum() < 0.0:
            F[comp == k] = F[comp == k][:, ::-1]
    _SURFACES[key] = (np.ascontiguousarray(V), np.ascontiguousarray(F))
    return _SURFACES[key]


def signed_distance(table: dict, x: np.ndarray) -> np.ndarray:
    """g(x) (M,) of the body a contact table describes, for the points x (M,3)."""
    kind = table.get("type")
    if kind not in _KEYS:
        raise BadInput(f"unknown contact body type {kind!r} (known: {', '.join(_KEYS)})")
    unknown = set(table) - _KEYS[kind] - _COMMON - _RESULT_KEYS
    if unknown:
        raise BadInput(f"{kind} table has keys this check does not know: {', '.join(sorted(unknown))}")
    try:
        if kind == "sphere":
            return np.linalg.norm(x - np.asarray(table["centre"], float), axis=1) - float(table["radius"])
        if kind == "plane":
            n = np.asarray(table["normal"], float)
            return (x - np.asarray(table["point"], float)) @ (n / np.linalg.norm(n))
        if kind == "mesh":
            import igl

            V, F = _mesh_surface(table)
            x = np.ascontiguousarray(x, float).reshape(-1, 3)
            return np.asarray(igl.signed_distance(x, V, F, igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0], float)
        top = np.asarray(table.get("centre", (0.0, 0.0, 0.0)), float)
        e = float(table.get("edge_radius") or 0.0)
        shape = table.get("shape", "square")
        if shape == "disc":
            R = 0.5 * float(table["diameter"])
            H = float(table.get("height") or 10.0 * R)  # solidshell's Pedestal: 10 x its radius
            support = table.get("support", "solid")
            if support not in ("solid", "cusick"):
                raise BadInput(f"pedestal support {support!r} is neither 'solid' nor 'cusick'")
            if support == "cusick":
                t, rs = float(table["disc_thickness"]), 0.5 * float(table["stem_diameter"])
                disc = _cylinder(x, top, R, t, e)
                stem = _cylinder(x, top - np.array([0.0, 0.0, t]), rs, H - t, 0.0)
                return np.minimum(disc, stem)
            return _cylinder(x, top, R, H, e)
        if shape == "square":
            a = 0.5 * float(table["size"])
            H = float(table.get("height") or 10.0 * a)  # solidshell's Pedestal: 10 x its half width
            q = x - (top - np.array([0.0, 0.0, 0.5 * H]))
            return _rounded_box(q, np.array([a - e, a - e, 0.5 * H - e])) - e
        raise BadInput(f"pedestal shape {shape!r} is neither 'square' nor 'disc'")
    except KeyError as k:
        raise BadInput(f"{kind} table lacks {k}") from None


# ------------------------------------------------------------------ face points
def element_points(x: np.ndarray, quads: np.ndarray, tris: np.ndarray, grid: int) -> np.ndarray:
    """Face points of every element: quads as (1-s)(1-t) x0 + s(1-t) x1 + s t x2 + (1-s) t x3 for
    s, t in linspace(0, 1, grid); triangles as x0 + s (x1 - x0) + t (x2 - x0) for s, t in
    {0, 1/m, ..., 1}, s + t <= 1, m = grid - 1."""
    pts = []
    u = np.linspace(0.0, 1.0, grid)
    if len(quads):
        s, t = (a.ravel()[None, :, None] for a in np.meshgrid(u, u))
        x0, x1, x2, x3 = (x[quads[:, k]][:, None, :] for k in range(4))
        pts.append(((1 - s) * (1 - t) * x0 + s * (1 - t) * x1 + s * t * x2 + (1 - s) * t * x3).reshape(-1, 3))
    if len(tris):
        s, t = np.meshgrid(u, u)
        keep = s + t <= 1.0 + 1e-12  # lattice points on the hypotenuse up to round-off
        s, t = s[keep][None, :, None], t[keep][None, :, None]
        x0, x1, x2 = (x[tris[:, k]][:, None, :] for k in range(3))
        pts.append((x0 + s * (x1 - x0) + t * (x2 - x0)).reshape(-1, 3))
    return np.concatenate(pts) if pts else np.zeros((0, 3))


# ------------------------------------------------------------------ a run
def count(table: dict, x_nodes: np.ndarray, x_faces: np.ndarray, tol: float) -> dict:
    """The check of one body: depths p = offset - g and the counts beyond ``tol``."""
    off = float(table.get("offset") or 0.0)
    pn = off - signed_distance(table, x_nodes)
    pf = off - signed_distance(table, x_faces)
    return {
        "deepest_node_cm": float(max(0.0, pn.max(initial=0.0))),
        "nodes_beyond": int(np.count_nonzero(pn > tol)),
        "deepest_face_point_cm": float(max(0.0, pf.max(initial=0.0))),
        "face_points_beyond": int(np.count_nonzero(pf > tol)),
    }


def read_run(run_dir: Path):
    """(summary dict, undeformed nodes, displacement, quads, tris) of a run folder."""
    import meshio

    s_path, r_path = run_dir / "summary.json", run_dir / "result.vtu"
    for p in (s_path, r_path):
        if not p.is_file():
            raise BadInput(f"{p} does not exist (a finished run writes it)")
    try:
        summary = json.loads(s_path.read_text())
        m = meshio.read(r_path)
    except (OSError, ValueError) as e:
        raise BadInput(f"{run_dir}: cannot read ({type(e).__name__}: {e})") from None
    if "displacement" not in m.point_data:
        raise BadInput(f"{r_path} has no 'displacement' point data (fields: {', '.join(m.point_data)})")
    blocks = {c.type: np.asarray(c.data, np.int64) for c in m.cells}
    quads = blocks.get("quad", np.zeros((0, 4), np.int64))
    tris = blocks.get("triangle", np.zeros((0, 3), np.int64))
    if len(quads) + len(tris) == 0:
        raise BadInput(f"{r_path} has no quad or triangle cells")
    return summary, np.asarray(m.points, float), np.asarray(m.point_data["displacement"], float), quads, tris


def thickness(summary: dict, run_dir: Path) -> float:
    try:
        h = float(summary["material"]["thickness"])
    except (KeyError, TypeError, ValueError):
        raise BadInput(f"{run_dir}/summary.json holds no material.thickness (the sheet's h)") from None
    if not np.isfinite(h) or h <= 0.0:
        raise BadInput(f"{run_dir}/summary.json: material.thickness = {h!r} is not a positive length")
    return h


def body_tables(summary: dict) -> tuple[list[dict], dict | None]:
    """(the bodies' tables, the summary's own penetration entry or None)."""
    entry = summary.get("penetration")
    if isinstance(entry, dict) and isinstance(entry.get("bodies"), list):
        return [dict(b) for b in entry["bodies"]], entry
    contact = summary.get("contact")
    if isinstance(contact, list):  # a run from before the penetration entry: the scene's tables
        return [dict(c) for c in contact], None
    raise BadInput("summary.json holds neither penetration.bodies nor a contact list")


def _agrees(said: dict, r: dict) -> bool:
    """The summary's own numbers for a body against these: equal counts, and depths equal to
    1e-9 cm (the same points by other formulas: round-off ~1e-13 cm on coordinates ~10 cm; the
    contract's tolerance is ~1e-3 cm)."""
    if any(said.get(k) != r[k] for k in ("nodes_beyond", "face_points_beyond")):
        return False
    return all(abs(float(said.get(k, np.nan)) - r[k]) <= 1e-9 for k in ("deepest_node_cm", "deepest_face_point_cm"))


def check_run(run_dir: Path, grid: int) -> tuple[list[str], bool]:
    """(lines to print, clean) for one run folder."""
    summary, X, D, quads, tris = read_run(run_dir)
    h = thickness(summary, run_dir)
    tol = TOL_FRACTION * h
    tables, entry = body_tables(summary)
    if not tables:
        return [f"{run_dir}: no contact body"], True
    x = X + D[:, :3]
    xf = element_points(x, quads, tris, grid)
    base = Path(str(summary.get("scene_file", ""))).parent  # a mesh body's file is relative to its scene
    for t in tables:
        if t.get("type") == "mesh":
            t["_base"] = str(base)
    lines, clean = [], True
    if entry is not None and not np.isclose(entry.get("tolerance_cm", tol), tol, rtol=1e-12, atol=0.0):
        lines.append(f"{run_dir}: the summary's tolerance {entry['tolerance_cm']!r} cm is not 2 % of h = {tol!r} cm")
        clean = False
    for i, t in enumerate(tables):
        r = count(t, x, xf, tol)
        bad = r["nodes_beyond"] > 0 or r["face_points_beyond"] > 0
        same = ""
        if entry is not None and entry.get("grid") == grid:
            agree = _agrees(t, r)
            said = f"{t.get('nodes_beyond')} nodes, {t.get('face_points_beyond')} face points"
            same = "  [summary agrees]" if agree else f"  [MISMATCH: summary says {said}]"
            clean = clean and agree
        clean = clean and not bad
        lines.append(
            f"{run_dir} contact[{i}] {t.get('type')}: nodes beyond {r['nodes_beyond']}/{len(x)}, face points beyond "
            f"{r['face_points_beyond']}/{len(xf)}, deepest node {r['deepest_node_cm']:.4g} cm "
            f"({100 * r['deepest_node_cm'] / h:.3g} % of h), deepest face point {r['deepest_face_point_cm']:.4g} cm "
            f"({100 * r['deepest_face_point_cm'] / h:.3g} % of h), tol {tol:.3g} cm{same}  "
            + ("BEYOND" if bad else "clean")
        )
    return lines, clean


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m verification.penetration_check", description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", type=Path, metavar="RUN_DIR")
    ap.add_argument("--grid", type=int, default=5, help="face points per element edge (default 5)")
    a = ap.parse_args(argv)
    if a.grid < 2:
        print(f"penetration_check: --grid must be >= 2 (points per element edge), got {a.grid}", file=sys.stderr)
        return 2
    ok = True
    for run in a.runs:
        try:
            lines, clean = check_run(run, a.grid)
        except BadInput as e:
            print(f"penetration_check: {e}", file=sys.stderr)
            return 2
        print("\n".join(lines))
        ok = ok and clean
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
