"""Scene -> problem: the mesh of a scene, its supports, loads, contact bodies and perturbed start,
each checked before any solve, and the Problem a solver runs (:func:`build_problem`).

    mesh, name = build_scene_mesh(scene, "24x8x4")
    problem = build_problem(scene, mesh)

The model, boundary, contact and perturbation modules are imported only when they are needed, so
building and writing a mesh (what ``solidshell mesh`` does) stays fast.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import sizing, solvers
from ..errors import InputError
from . import Scene, check_density, load

MESH_SUFFIXES = (".msh", ".geo", ".vtu", ".vtk", ".xdmf", ".inp", ".med")


# --------------------------------------------------------------------------- checks of a run's inputs
def check_solver_settings(kind: str, merged: dict):
    """The solver's typed settings (solidshell.solvers.validate) before any work: one-line
    InputError naming the key.  Returns the parsed settings model."""
    return solvers.validate(kind, merged)


def check_restart_file(path) -> None:
    """A restart file must be a complete checkpoint archive (.npz, a zip file): a truncated or
    foreign file is refused before any work, naming it (whether it matches this run -- mesh,
    material, settings -- is the solver's check)."""
    import zipfile

    p = Path(path)
    try:
        with zipfile.ZipFile(p) as z:
            bad = z.testzip()  # reads every member and checks its CRC
    except FileNotFoundError:
        raise InputError(f"restart file {p} not found") from None
    except IsADirectoryError:
        raise InputError(f"restart file {p} is a directory") from None
    except (OSError, zipfile.BadZipFile, EOFError, ValueError) as e:
        raise InputError(
            f"restart file {p} is not a readable checkpoint ({e}); truncated or not written by solidshell"
        ) from None
    if bad is not None:
        raise InputError(f"restart file {p} is damaged (member {bad} fails its checksum)")


def run_settings(scene: Scene, kind: str, settings: dict) -> dict | None:
    """The solver settings of a run of ``kind``: the scene's ``[solver.KIND]`` table updated by the
    call's ``settings``, checked against the solver's schema, a restart file checked as an archive;
    None for a mesh-only run (``kind`` "none")."""
    if kind == "static" and ({"checkpoint", "restart"} & set(settings)):
        raise InputError("--checkpoint / --restart apply to the explicit and relax solvers, not static")
    if kind == "none":
        return None
    s = scene.solver_settings(kind)
    s.update(settings)
    check_solver_settings(kind, s)
    if isinstance(s.get("restart"), (str, Path)):  # (another type: the schema refuses it)
        check_restart_file(s["restart"])
    return s


# --------------------------------------------------------------------------- the mesh
def build_scene_mesh(scene: Scene, mesh=None, kind: str = "none", allow_large: bool = False):
    """(ShellMesh, mesh name) for a scene: ``mesh`` None (the scene's density), a density string,
    a mesh/geometry file path or a ShellMesh.

    Size guard (solidshell.sizing): a density is refused *before meshing* when the memory a run of
    ``kind`` needs on it exceeds the machine's available memory; a mesh read from a file is checked
    once read (its size is not known before).  ``allow_large`` skips the guard."""
    from ..mesh import ShellMesh

    if isinstance(mesh, ShellMesh):
        return _guard(mesh, "the given mesh", kind, allow_large), "user ShellMesh"
    from .. import meshing

    def read(p: Path):
        try:
            m = meshing.from_file(p)
        except InputError as e:
            msg = str(e)
            raise InputError(msg if p.name in msg else f"mesh file {p}: {msg}") from None
        return _guard(m, f"mesh file {p}", kind, allow_large), str(p)

    if mesh is not None and (isinstance(mesh, Path) or str(mesh).lower().endswith(MESH_SUFFIXES)):
        return read(Path(mesh))
    if "file" in scene.geometry:
        if mesh is not None:
            raise InputError(
                f"scene {scene.name!r} reads its mesh from {scene.geometry['file']}; "
                f"a density ({mesh!r}) applies to recipe geometries only"
            )
        return read(Path(scene.geometry["file"]))
    where = "--mesh" if mesh is not None else f"{scene.source}: mesh.density"
    density = scene.density if mesh is None else check_density(str(mesh), scene.recipe, "--mesh")
    if density is not None:
        sizing.check(sizing.elements_of_density(density), kind, f"{where} {density}", allow_large)
    params = {k: v for k, v in scene.geometry.items() if k != "recipe"}
    return meshing.build_mesh(scene.recipe, density, **params), density


def _guard(mesh, what, kind, allow_large):
    sizing.check(mesh.n_elements, kind, what, allow_large)
    return mesh


# --------------------------------------------------------------------------- supports, loads, contact
SUPPORT_DOFS = {"clamped": slice(0, 6), "fixed_translations": slice(0, 3), "fixed_x": 0, "fixed_y": 1, "fixed_z": 2}
"""The dofs (of U_o, U_n) each kind of [supports] key fixes."""


def support_mask(scene: Scene, mesh, kind: str = "none") -> np.ndarray:
    """(N,6) bool: the [supports] node sets' dofs (SUPPORT_DOFS), and those of [supports.static]
    when ``kind`` is "static"."""
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    tables = [("supports", scene.supports)]
    if kind == "static" and scene.supports.get("static"):
        tables.append(("supports.static", scene.supports["static"]))
    for where, table in tables:
        for key, dofs in SUPPORT_DOFS.items():
            for name in table.get(key, ()):
                try:
                    idx = mesh.node_set(name)
                except InputError as e:
                    raise InputError(f"{scene.source}: {where}.{key}: {e}") from None
                fixed[idx, dofs] = True
    return fixed


def check_load_sets(scene: Scene, mesh) -> None:
    """Fail early (before any solve) on a load that names a missing or empty node set."""
    for kind in ("point", "line"):
        for ld in scene.loads[kind]:
            if "node_set" in ld:
                mesh.node_set(ld["node_set"])


def scene_loads(scene: Scene, model) -> np.ndarray:
    """(N,6) dead loads of the scene [gf]: self-weight, point, line and surface loads, lumped with
    the model's trapezoidal-rule nodal areas (solidshell.boundary)."""
    from .. import boundary

    mesh = model.mesh
    P = np.zeros((mesh.n_nodes, 6))
    if scene.loads["gravity"]:
        P += boundary.gravity_loads(model, direction=tuple(scene.loads["gravity_direction"]))
    for ld in scene.loads["point"]:
        if "at" in ld:
            idx = np.array([int(np.argmin(np.linalg.norm(mesh.nodes - np.asarray(ld["at"]), axis=1)))])
        else:
            idx = mesh.node_set(ld["node_set"])
        P += boundary.point_load(mesh.n_nodes, idx, np.asarray(ld["force"], float) / len(idx))
    for ld in scene.loads["line"]:
        try:
            P += boundary.line_load(mesh, ld["node_set"], ld["force"])
        except InputError as e:
            raise InputError(f"line load on node set {ld['node_set']!r}: {e}") from None
    for ld in scene.loads["surface"]:
        f = np.asarray(ld["force"], float)
        n = float(np.linalg.norm(f))
        if n > 0.0:
            P += boundary.surface_load(model, n, direction=f / n)
    return P


def contact_bodies(scene: Scene) -> list:
    """solidshell.contact bodies of the scene, one per dict of ``scene.bodies()`` and in its order
    (the pictures draw the same dicts; empty: no contact search)."""
    return [contact_body(b, scene.base_dir) for b in scene.bodies()]


def contact_body(b: dict, base_dir=None):
    """The solidshell.contact body of one resolved body dict (Scene.bodies); a mesh body's file is
    relative to ``base_dir`` (the scene file's folder)."""
    from .. import contact as C

    off, mu = b["offset"], b["friction"]
    if b["type"] == "mesh":
        from ..contact_mesh import mesh_body
        from .schema import MESH_DEFAULTS

        kw = {k: b[k] for k in MESH_DEFAULTS}
        return mesh_body(**kw, offset=off, friction=mu, where=b["origin"], base_dir=base_dir)
    if b["type"] == "sphere":
        return C.Sphere(b["centre"], b["radius"], offset=off, friction=mu)
    if b["type"] == "plane":
        return C.Plane(b["point"], b["normal"], offset=off, friction=mu)
    kw = dict(height=b["height"], edge_radius=b["edge_radius"], offset=off, friction=mu)
    if b["support"] == "cusick":
        return C.CusickSupport(b["centre"], b["diameter"] / 2, b["disc_thickness"], b["stem_diameter"] / 2, **kw)
    if b["shape"] == "disc":
        return C.Pedestal(b["centre"], radius=b["diameter"] / 2, **kw)
    return C.Pedestal(b["centre"], half_widths=(b["size"] / 2, b["size"] / 2), **kw)


def _body_label(scene: Scene, i: int) -> str:
    b = scene.bodies()[i]
    if b["type"] == "mesh":
        src = f"file {b['file']!r}" if b["file"] is not None else f"{len(b['primitives'])} primitive(s)"
        return f"{b['origin']} (mesh from {src})"
    at = list(b["point" if b["type"] == "plane" else "centre"])
    what = f"{b['type']} at {at}"
    if b["origin"] == "geometry.recipe":
        return f"the pedestal of recipe {scene.recipe!r} ({what}; geometry.pedestal_contact = false leaves it out)"
    return f"{b['origin']} ({what})"


def check_initial_contact(scene: Scene, mesh, fixed, bodies=None, U0=None) -> None:
    """InputError when a node or a face point (contact_faces.py) of the sheet starts inside a contact
    body (solidshell.contact.initial_penetration): names the body, the count and the deepest
    penetration [cm].  Nodes with all translations fixed are not checked (they cannot be pushed
    out, and a clamped rim on a pedestal's edge sits exactly on it), nor the face points of
    elements whose nodes are all fixed."""
    bodies = contact_bodies(scene) if bodies is None else bodies
    if not bodies:
        return
    from ..contact import initial_penetration

    x = np.asarray(mesh.nodes, float)
    if U0 is not None:
        u = np.asarray(U0, dtype=float)
        if u.size == 6 * mesh.n_nodes:  # (a wrong shape is the solver's settings' to refuse)
            x = x + u.reshape(-1, 6)[:, :3]
    free = ~np.asarray(fixed, bool)[:, :3].all(axis=1)
    what, hits = "node(s)", initial_penetration(bodies, x, free=free)
    if not hits:  # an element whose nodes lie outside can still start through a body (contact_faces)
        from ..contact_faces import FacePoints, spacing

        faces = FacePoints(mesh, np.ones(mesh.n_nodes), spacing=spacing(bodies, scene.material_object().thickness))
        tol = 1e-9 * float(np.linalg.norm(np.ptp(x, axis=0))) if len(x) > 1 else 0.0
        what, hits = (
            "face point(s)",
            initial_penetration(bodies, faces.positions(x), free=free[faces.nodes].any(1), tol=tol),
        )
    if hits:
        i, body, n, depth = hits[0]
        more = f"; {len(hits) - 1} more bod{'y' if len(hits) == 2 else 'ies'} too" if len(hits) > 1 else ""
        off = f" (its offset {body.offset:g} cm included)" if body.offset else ""
        raise InputError(
            f"{scene.source}: {_body_label(scene, i)}: {n} {what} of the sheet start inside "
            f"the body, deepest {depth:.4g} cm{off}; move the body or the sheet so that "
            f"they start apart or just touching{more}"
        )


def perturbed_start(scene: Scene, mesh, fixed, settings: dict):
    """The starting state U0 of the scene's ``[perturbation]`` (solidshell.perturbation), or None
    when it has none (or amplitude 0).  A perturbation and a solver U0 together are refused."""
    if not scene.perturbation or not scene.perturbation.get("amplitude"):
        return None
    if settings.get("U0") is not None:
        raise InputError(f"{scene.source}: perturbation and solver setting U0 both give the starting state; keep one")
    from ..perturbation import initial_state

    centre = None
    ped = scene.pedestal()
    if ped is not None:
        centre = ped["centre"]
    else:
        centre = next((c["centre"] for c in scene.contact if c["type"] == "sphere"), None)
    try:
        return initial_state(scene.perturbation, mesh, fixed, centre)
    except InputError as e:
        raise InputError(f"{scene.source}: {e}") from None


# --------------------------------------------------------------------------- the run's build step
@dataclass
class SceneSetup:
    """A scene built on its mesh, every part of it checked, before any solve."""

    mesh: Any  # the ShellMesh
    mesh_name: str  # the density, the file read, or "user ShellMesh"
    fixed: np.ndarray  # (N,6) bool support mask
    material: Any  # the scene's section (Fabric or IsotropicShell)
    solver_settings: dict | None  # the run's settings plus a perturbed start U0 (None: mesh only)
    perturbed: bool = False  # the start U0 comes from the scene's [perturbation]


def setup_scene(
    scene: Scene, kind: str, mesh=None, settings: dict | None = None, allow_large: bool = False
) -> SceneSetup:
    """The build step of a run: the mesh (size-guarded), supports, load sets, contact bodies and
    the perturbed start, each checked (InputError) before anything is solved or written.
    ``settings``: the run's checked solver settings (:func:`run_settings`), None for mesh only."""
    m, mesh_name = build_scene_mesh(scene, mesh, kind, allow_large)
    fixed = support_mask(scene, m, kind)  # unknown / empty node sets fail here, before solving
    material = scene.material_object()
    check_load_sets(scene, m)
    bodies = contact_bodies(scene)
    solver_s, U0 = settings, None
    if kind != "none":
        U0 = perturbed_start(scene, m, fixed, settings)
        if U0 is not None:
            solver_s = {**settings, "U0": U0}
        check_initial_contact(scene, m, fixed, bodies, U0=solver_s.get("U0"))
    return SceneSetup(m, mesh_name, fixed, material, solver_s, perturbed=U0 is not None)


# --------------------------------------------------------------------------- the problem
def build_problem(scene: Scene, mesh, fixed=None, membrane=None, constants=None, kind: str = "none"):
    """The solidshell.problem.Problem of a scene on a mesh: the Model (section, thickness-strain
    model), supports, loads (self-weight, point, line, surface) and contact bodies -- everything a
    solver needs.  Unknown or empty node sets raise InputError.  The adaptive driver calls this for
    every new mesh.  ``membrane``: the quads' membrane strains (Model's argument: one choice or one
    per quad) instead of the scene's ``model.membrane``; ``constants``: a model.ElementConstants
    cache shared by the problems of one adaptive run; ``kind``: the solver (support_mask)."""
    from ..model import Model
    from ..problem import Problem

    sc = load(scene)
    if fixed is None:
        fixed = support_mask(sc, mesh, kind)
    check_load_sets(sc, mesh)
    if membrane is None:
        membrane = sc.model.get("membrane", "full")
    model = Model(
        mesh,
        sc.material_object(),
        thickness_strain=sc.model["thickness_strain"],
        mu=sc.model["mu"],
        membrane=membrane,
        constants=constants,
    )
    return Problem(
        model,
        fixed,
        scene_loads(sc, model),
        contact=contact_bodies(sc),
        name=sc.name,
        self_contact=bool(sc.self_contact.get("enabled", False)),
    )
