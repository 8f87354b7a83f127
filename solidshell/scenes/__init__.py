"""Scenes: a drape problem described as data, in a TOML file a user can write.

The paper's scenes ship as package data (``solidshell/scenes/paper/*.toml``) and load by name
(:func:`load`, :func:`available`); a user's own scene loads by path.  Every unknown key, every
value of the wrong type and every missing required key is an :class:`~solidshell.errors.InputError`
that names the key and the file.  All quantities are in the paper's units: cm, gf, s (degrees for
angles).

Scene file format
-----------------
::

    name = "square-pedestal"              # required; a package scene's name is its file name
    title = "20x20 cm wool sheet on a 10x10 cm square pedestal"   # required
    paper_section = "3.2"                 # optional ("" for a user's own scene)
    description = "..."                   # optional free text

    [geometry]                            # required: EITHER a built-in recipe and its parameters
    recipe = "square_on_square"           #   strip(length, width), square_on_square(sheet, pedestal),
    sheet = 20.0                          #   disc_on_disc(diameter, pedestal_diameter),
    pedestal = 10.0                       #   square_on_disc(sheet, pedestal_diameter), square(size)
    # file = "my_sheet.msh"               # OR a gmsh .msh/.geo file (or any mesh meshio reads:
                                          #   .vtu, .xdmf, ...), relative to this scene file

    [mesh]
    density = "48x16x4"                   # recipe density (see solidshell.meshing); default mesh
    paper_meshes = ["24x8x4", "48x16x4", "6x2x4"]   # the meshes the paper uses (informative)
    adaptive_level0 = "6x2x4"             # the level-0 mesh of the paper's adaptive run (Sec. 6)

    [material]                            # EITHER a named fabric plus overrides of its fields
    fabric = "wool"                       #   (Table 1); any Fabric field may follow, e.g.
    warp_angle = 90.0                     #   tensile_warp, tensile_weft, shear, bending_warp,
                                          #   bending_weft, torsion, weight, thickness, warp_angle,
                                          #   poisson, transverse_shear, thickness_modulus
    # isotropic = { E = 1e5, nu = 0.3, h = 0.1, density = 0.0 }   # OR an isotropic shell

    [model]                               # optional
    thickness_strain = "green"            # "green" | "quasi" (Eq. 24)
    mu = 0.5                              # the mu of Eq. (24), 0 < mu < 1
    membrane = "full"                     # quads: "full" (2x2 Gauss, the paper) | "ans" (quad4.py)

    [supports]                            # node sets of the mesh (a name or a list of names)
    clamped = "clamped"                   # all six dofs fixed (U_o = U_n = 0)
    # fixed_translations = "hung"         # U_o = 0 only (corners a sheet hangs from)

    [loads]
    gravity = true                        # self-weight, Fabric.weight [gf/cm^2]
    gravity_direction = [0.0, 0.0, -1.0]  # optional
    # [[loads.point]]   node_set = "tip"  OR  at = [x, y, z] (nearest node);  force = [fx, fy, fz] gf,
    #                   the total force, shared equally by the nodes of the set
    # [[loads.line]]    node_set = "outer";  force = [fx, fy, fz] gf/cm on the boundary edges whose
    #                   both ends are in the set (lumped by the trapezoidal rule)
    # [[loads.surface]] force = [fx, fy, fz] gf/cm^2 on the whole sheet (dead load per initial area)

    [[contact]]                           # zero or more rigid bodies (solidshell.contact, penalty)
    type = "pedestal"                     # sphere:   centre = [x,y,z], radius
    shape = "square"                      # plane:    point = [x,y,z], normal = [nx,ny,nz] (the
    size = 10.0                           #           side opposite the normal is solid)
    centre = [0.0, 0.0, 0.0]              # pedestal: shape = "square" (size = side) or "disc"
                                          #           (diameter); centre = centre of its top face;
                                          #           height (default 10), edge_radius (default 0)
                                          # all:      offset = distance kept between the body and
                                          #           the mid-surface (h/2 for the lower face);
                                          #           friction = Coulomb coefficient mu >= 0
                                          #           (default 0: frictionless; explicit/relax
                                          #           solvers only, stick spring + return map)
    # The paper's pedestal scenes clamp the sheet on the pedestal edge and need no pedestal body
    # (a picture still shows the pedestal); add one to keep folds out of the pedestal.

    [solver]
    kind = "static"                       # static | explicit | relax
    [solver.static]                       # free settings of each kind, passed to the solver
    method = "newton"
    [solver.explicit]
    t_end = 2.1
    alpha = 5.0                           # Rayleigh mass damping [1/s] (Eq. 20)
    [solver.relax]
    alpha = 5.0
    mass_scaling = 100

    [adapt]                               # optional: reversible adaptive subdivision (Sec. 5),
    enabled = false                       #   dynamic runs only (or --adaptive); the level-0 mesh is
    levels = 3                            #   mesh.adaptive_level0 (or --mesh); every key of
    const = 0.5                           #   solidshell.adapt.settings.AdaptSettings: levels, const,
    eps = 0.2                             #   eps (Eqs. 25-26), every (steps between passes),
    every = 200                           #   transfer ("dk" | "linear"), project_boundary

    [output]
    snapshots = [0.0, 0.1, 0.4, 2.1]      # times [s] kept in the time series and pictured
    pictures = ["top", "iso"]             # any of top, iso, side (x-z), side_yz (y-z)

    [perturbation]                        # optional: a seeded starting state (solidshell.perturbation)
    shape = "random"                      #   "random" (smooth field: seed, wavelength [cm]) or
    amplitude = 0.5                       #   "folds" (folds = n, phase [deg]); amplitude [cm],
    seed = 0                              #   0 = none; --set perturbation.seed=3 in a sweep

Scenes are immutable; :meth:`Scene.with_overrides` returns a validated copy with dotted keys set,
e.g. ``{"mesh.density": "24x8x4", "solver.static.c": 2e-3, "material.warp_angle": 90}``.
"""

from __future__ import annotations

import copy
import inspect
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..solvers import KINDS

SCENE_DIR = Path(__file__).with_name("paper")

# Parameters of the built-in meshing recipes (the contract of solidshell.meshing), and how many
# factors their density strings have.  Used when meshing.RECIPES cannot tell us.
RECIPE_PARAMS = {
    "strip": ("length", "width"),
    "square_on_square": ("sheet", "pedestal"),
    "disc_on_disc": ("diameter", "pedestal_diameter"),
    "square_on_disc": ("sheet", "pedestal_diameter"),
    "square": ("size",),
}
DENSITY_FACTORS = {"strip": 2, "square_on_square": 3, "disc_on_disc": 2, "square_on_disc": 2, "square": 2}

PICTURES = ("top", "iso", "side", "side_yz")
FABRIC_FIELDS = ("tensile_warp", "tensile_weft", "shear", "bending_warp", "bending_weft", "torsion",
                 "weight", "thickness", "warp_angle", "poisson", "transverse_shear", "thickness_modulus")
ISOTROPIC_FIELDS = ("E", "nu", "h", "density", "shear_factor")
CONTACT_KEYS = {
    "sphere": {"centre": "vec3", "radius": "pos"},
    "plane": {"point": "vec3", "normal": "vec3"},
    "pedestal": {"shape": "str", "centre": "vec3", "size": "pos", "diameter": "pos", "height": "pos",
                 "edge_radius": "nonneg"},
}
CONTACT_COMMON = {"type": "str", "offset": "nonneg", "friction": "nonneg"}

_DENSITY_RE = re.compile(r"^\s*\d+(\s*[xX×]\s*\d+)*\s*$")


# --------------------------------------------------------------------------- validation helpers
class _Ctx:
    """Where we are: the file and the dotted key, for error messages."""

    def __init__(self, source: str):
        self.source = source

    def err(self, key: str, msg: str) -> InputError:
        return InputError(f"{self.source}: {key}: {msg}")


def _typename(v) -> str:
    return {bool: "boolean", int: "integer", float: "number", str: "string", list: "array",
            dict: "table"}.get(type(v), type(v).__name__)


def _num(ctx, key, v, *, positive=False, nonneg=False) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ctx.err(key, f"must be a number, got {_typename(v)} {v!r}")
    v = float(v)
    if not math.isfinite(v):
        raise ctx.err(key, f"must be finite, got {v!r}")
    if positive and v <= 0.0:
        raise ctx.err(key, f"must be positive, got {v!r}")
    if nonneg and v < 0.0:
        raise ctx.err(key, f"must be >= 0, got {v!r}")
    return v


def _str(ctx, key, v) -> str:
    if not isinstance(v, str):
        raise ctx.err(key, f"must be a string, got {_typename(v)} {v!r}")
    return v


def _bool(ctx, key, v) -> bool:
    if not isinstance(v, bool):
        raise ctx.err(key, f"must be true or false, got {_typename(v)} {v!r}")
    return v


def _vec3(ctx, key, v) -> tuple:
    if not isinstance(v, list) or len(v) != 3:
        raise ctx.err(key, f"must be an array of 3 numbers, got {v!r}")
    return tuple(_num(ctx, f"{key}[{i}]", x) for i, x in enumerate(v))


def _table(ctx, key, v) -> dict:
    if not isinstance(v, dict):
        raise ctx.err(key, f"must be a table, got {_typename(v)} {v!r}")
    return v


def _unknown(ctx, prefix, table: dict, allowed) -> None:
    for k in table:
        if k not in allowed:
            full = f"{prefix}.{k}" if prefix else k
            raise ctx.err(full, f"unknown key (allowed here: {', '.join(sorted(allowed))})")


def _names(ctx, key, v) -> tuple:
    """A node-set name or a list of names."""
    if isinstance(v, str):
        return (v,)
    if isinstance(v, list) and v and all(isinstance(s, str) for s in v):
        return tuple(v)
    raise ctx.err(key, f"must be a node-set name or a list of names, got {v!r}")


def check_density(density: str, recipe: str | None = None, where: str = "mesh density") -> str:
    """Validate a density string like "48x16x4": positive integers joined by 'x', with as many
    factors as the recipe takes.  Returns it normalised ("48x16x4")."""
    if not isinstance(density, str) or not _DENSITY_RE.match(density):
        raise InputError(f"{where}: malformed mesh density {density!r}: expected positive integers "
                         f"joined by 'x', e.g. '48x16x4'")
    parts = [int(p) for p in re.split(r"\s*[xX×]\s*", density.strip())]
    if any(p <= 0 for p in parts):
        raise InputError(f"{where}: malformed mesh density {density!r}: every count must be positive")
    n = _density_fields(recipe)
    if n is not None and len(parts) != n:
        example = {2: "20x80", 3: "48x16x4"}[n] if n in (2, 3) else "x".join(["10"] * n)
        raise InputError(f"{where}: malformed mesh density {density!r}: recipe {recipe!r} takes {n} "
                         f"counts, e.g. {example!r}")
    return "x".join(str(p) for p in parts)


def _recipe_params(recipe: str):
    """(parameter names, required names) of a recipe, or False when the recipe is unknown.
    The names come from solidshell.meshing.RECIPES when it is importable, else from the contract
    table; a scene file must give every parameter of the contract table (self-documenting)."""
    try:
        from .. import meshing  # lazy: meshing imports gmsh only when it meshes
        recipes = getattr(meshing, "RECIPES", {})
    except ImportError:
        recipes = {}
    r = recipes.get(recipe) if recipe != "from_file" else None
    names = tuple(getattr(r, "geometry", ()) or ()) if r is not None else ()
    required = RECIPE_PARAMS.get(recipe, ())
    if not names:
        if recipe not in RECIPE_PARAMS:
            return False
        names = RECIPE_PARAMS[recipe]
    return names, tuple(p for p in required if p in names)


def _density_fields(recipe: str | None) -> int | None:
    if recipe is None:
        return None
    try:
        from .. import meshing
        r = meshing.RECIPES.get(recipe)
        if r is not None and getattr(r, "n_fields", 0):
            return int(r.n_fields)
    except (ImportError, AttributeError):
        pass
    return DENSITY_FACTORS.get(recipe)


# --------------------------------------------------------------------------- the Scene
@dataclass(frozen=True)
class Scene:
    """A validated scene.  ``raw`` is the TOML table it came from (after overrides)."""

    name: str
    title: str
    paper_section: str
    description: str
    geometry: dict            # {"recipe": str, **params} or {"file": Path}
    mesh: dict                # {"density": str|None, "paper_meshes": [...], "adaptive_level0": str|None}
    material: dict            # {"fabric": "wool", **overrides} or {"isotropic": {...}}
    model: dict               # {"thickness_strain": ..., "mu": ...}
    supports: dict            # {"clamped": (names...), "fixed_translations": (names...)}
    loads: dict               # {"gravity": bool, "gravity_direction": (3,), "point": [...], "line": [...], "surface": [...]}
    contact: tuple            # ({"type": ..., ...}, ...)
    solver: dict              # {"kind": str, "static": {...}, "explicit": {...}, "relax": {...}}
    output: dict              # {"snapshots": [...], "pictures": [...]}
    adapt: dict = field(default_factory=dict)   # the [adapt] table (solidshell.adapt.settings.AdaptSettings)
    perturbation: dict = field(default_factory=dict)   # [perturbation] (solidshell.perturbation), {} = none
    source: str = "<dict>"
    raw: dict = field(default_factory=dict, repr=False, compare=False)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dict(cls, data: dict, source: str = "<dict>", base_dir: Path | None = None) -> "Scene":
        ctx = _Ctx(source)
        raw = copy.deepcopy(data)
        _table(ctx, "(top level)", data)
        top = {"name", "title", "paper_section", "description", "geometry", "mesh", "material", "model",
               "supports", "loads", "contact", "solver", "output", "adapt", "perturbation"}
        _unknown(ctx, "", data, top)
        for req in ("name", "title", "geometry"):
            if req not in data:
                raise ctx.err(req, "required key is missing")
        name = _str(ctx, "name", data["name"])
        if not name.strip():
            raise ctx.err("name", "must not be empty")
        title = _str(ctx, "title", data["title"])
        section = data.get("paper_section", "")
        if isinstance(section, (int, float)) and not isinstance(section, bool):
            section = str(section)
        section = _str(ctx, "paper_section", section)
        description = _str(ctx, "description", data.get("description", ""))

        # geometry ------------------------------------------------------------------
        g = _table(ctx, "geometry", data["geometry"])
        if ("recipe" in g) == ("file" in g):
            raise ctx.err("geometry", "give exactly one of 'recipe' (a built-in mesh recipe) or 'file' "
                                      "(a .msh/.geo file)")
        if "file" in g:
            _unknown(ctx, "geometry", g, {"file"})
            f = Path(_str(ctx, "geometry.file", g["file"]))
            if not f.is_absolute():
                f = (base_dir or Path.cwd()) / f
            raw["geometry"]["file"] = str(f)      # absolute from now on (overrides re-parse raw)
            geometry = {"file": f}
            recipe = None
        else:
            recipe = _str(ctx, "geometry.recipe", g["recipe"])
            params = _recipe_params(recipe)
            if params is False:
                raise ctx.err("geometry.recipe", f"unknown recipe {recipe!r} (known: "
                                                 f"{', '.join(sorted(RECIPE_PARAMS))})")
            if params is not None:
                names, required = params
                _unknown(ctx, "geometry", g, {"recipe", *names})
                for p in required:
                    if p not in g:
                        raise ctx.err(f"geometry.{p}", f"required by recipe {recipe!r} [cm]; missing")
            geometry = {"recipe": recipe}
            for k, v in g.items():
                if k != "recipe":
                    geometry[k] = _num(ctx, f"geometry.{k}", v, positive=True)

        # mesh ----------------------------------------------------------------------
        m = _table(ctx, "mesh", data.get("mesh", {}))
        _unknown(ctx, "mesh", m, {"density", "paper_meshes", "adaptive_level0"})
        density = m.get("density")
        if density is not None:
            density = check_density(_str(ctx, "mesh.density", density), recipe, f"{source}: mesh.density")
        pm = m.get("paper_meshes", [])
        if not isinstance(pm, list):
            raise ctx.err("mesh.paper_meshes", f"must be an array of density strings, got {pm!r}")
        pm = [check_density(_str(ctx, f"mesh.paper_meshes[{i}]", d), recipe, f"{source}: mesh.paper_meshes[{i}]")
              for i, d in enumerate(pm)]
        lvl0 = m.get("adaptive_level0")
        if lvl0 is not None:
            lvl0 = check_density(_str(ctx, "mesh.adaptive_level0", lvl0), recipe, f"{source}: mesh.adaptive_level0")
        if recipe is not None and density is None:
            raise ctx.err("mesh.density", f"required for recipe {recipe!r}")
        if recipe is None and density is not None:
            raise ctx.err("mesh.density", "applies to recipe geometries only, not to a mesh file")
        mesh = {"density": density, "paper_meshes": pm, "adaptive_level0": lvl0}

        # material ------------------------------------------------------------------
        mt = _table(ctx, "material", data.get("material", {"fabric": "wool"}))
        if "isotropic" in mt:
            _unknown(ctx, "material", mt, {"isotropic"})
            iso = _table(ctx, "material.isotropic", mt["isotropic"])
            _unknown(ctx, "material.isotropic", iso, set(ISOTROPIC_FIELDS))
            for req in ("E", "nu", "h"):
                if req not in iso:
                    raise ctx.err(f"material.isotropic.{req}", "required key is missing")
            material = {"isotropic": {k: _num(ctx, f"material.isotropic.{k}", v) for k, v in iso.items()}}
        else:
            _unknown(ctx, "material", mt, {"fabric", "name", *FABRIC_FIELDS})
            fab = _str(ctx, "material.fabric", mt.get("fabric", "wool"))
            if fab not in FABRICS:
                raise ctx.err("material.fabric", f"unknown fabric {fab!r} (known: {', '.join(FABRICS)})")
            material = {"fabric": fab}
            for k, v in mt.items():
                if k == "name":
                    material[k] = _str(ctx, "material.name", v)
                elif k != "fabric":
                    material[k] = _num(ctx, f"material.{k}", v)
        # build it once so that zero/negative rigidities are reported now, with the file name
        try:
            _make_material(material)
        except InputError as e:
            raise InputError(f"{source}: material: {e}") from None

        # model ---------------------------------------------------------------------
        md = _table(ctx, "model", data.get("model", {}))
        _unknown(ctx, "model", md, {"thickness_strain", "mu", "membrane"})
        model = {"thickness_strain": _str(ctx, "model.thickness_strain", md.get("thickness_strain", "green")),
                 "mu": _num(ctx, "model.mu", md.get("mu", 0.5)),
                 "membrane": _str(ctx, "model.membrane", md.get("membrane", "full"))}
        if model["membrane"] not in ("full", "ans"):
            raise ctx.err("model.membrane", f"must be 'full' or 'ans', got {model['membrane']!r}")
        if model["thickness_strain"] not in ("green", "quasi"):
            raise ctx.err("model.thickness_strain", f"must be 'green' or 'quasi', got {model['thickness_strain']!r}")
        if not 0.0 < model["mu"] < 1.0:
            raise ctx.err("model.mu", f"must lie in (0, 1), got {model['mu']!r}")

        # supports ------------------------------------------------------------------
        s = _table(ctx, "supports", data.get("supports", {}))
        _unknown(ctx, "supports", s, {"clamped", "fixed_translations"})
        supports = {k: _names(ctx, f"supports.{k}", v) for k, v in s.items()}

        # loads ---------------------------------------------------------------------
        ld = _table(ctx, "loads", data.get("loads", {}))
        _unknown(ctx, "loads", ld, {"gravity", "gravity_direction", "point", "line", "surface"})
        loads = {"gravity": _bool(ctx, "loads.gravity", ld.get("gravity", True)),
                 "gravity_direction": _vec3(ctx, "loads.gravity_direction", ld.get("gravity_direction", [0.0, 0.0, -1.0])),
                 "point": [], "line": [], "surface": []}
        if math.hypot(*loads["gravity_direction"]) == 0.0:
            raise ctx.err("loads.gravity_direction", "must be a non-zero vector")
        for kind, allowed in (("point", {"node_set", "at", "force"}), ("line", {"node_set", "force"}),
                              ("surface", {"force"})):
            items = ld.get(kind, [])
            if isinstance(items, dict):
                items = [items]
            if not isinstance(items, list):
                raise ctx.err(f"loads.{kind}", "must be a table or an array of tables")
            for i, it in enumerate(items):
                key = f"loads.{kind}[{i}]"
                _table(ctx, key, it)
                _unknown(ctx, key, it, allowed)
                if "force" not in it:
                    raise ctx.err(f"{key}.force", "required key is missing")
                ent = {"force": _vec3(ctx, f"{key}.force", it["force"])}
                if kind == "point":
                    if ("node_set" in it) == ("at" in it):
                        raise ctx.err(key, "give exactly one of 'node_set' or 'at'")
                    if "at" in it:
                        ent["at"] = _vec3(ctx, f"{key}.at", it["at"])
                    else:
                        ent["node_set"] = _str(ctx, f"{key}.node_set", it["node_set"])
                elif kind == "line":
                    if "node_set" not in it:
                        raise ctx.err(f"{key}.node_set", "required key is missing")
                    ent["node_set"] = _str(ctx, f"{key}.node_set", it["node_set"])
                loads[kind].append(ent)

        # contact -------------------------------------------------------------------
        cl = data.get("contact", [])
        if isinstance(cl, dict):
            cl = [cl]
        if not isinstance(cl, list):
            raise ctx.err("contact", "must be an array of tables ([[contact]])")
        contact = []
        for i, c in enumerate(cl):
            key = f"contact[{i}]"
            _table(ctx, key, c)
            if "type" not in c:
                raise ctx.err(f"{key}.type", "required key is missing (sphere, plane or pedestal)")
            t = _str(ctx, f"{key}.type", c["type"])
            if t not in CONTACT_KEYS:
                raise ctx.err(f"{key}.type", f"unknown contact body {t!r} (known: {', '.join(CONTACT_KEYS)})")
            spec = {**CONTACT_COMMON, **CONTACT_KEYS[t]}
            _unknown(ctx, key, c, set(spec))
            ent = {"type": t}
            for k, v in c.items():
                kind = spec[k]
                if k == "type":
                    continue
                if kind == "vec3":
                    ent[k] = _vec3(ctx, f"{key}.{k}", v)
                elif kind == "pos":
                    ent[k] = _num(ctx, f"{key}.{k}", v, positive=True)
                elif kind == "nonneg":
                    ent[k] = _num(ctx, f"{key}.{k}", v, nonneg=True)
                else:
                    ent[k] = _str(ctx, f"{key}.{k}", v)
            if t == "sphere":
                for req in ("centre", "radius"):
                    if req not in ent:
                        raise ctx.err(f"{key}.{req}", "required key is missing")
            elif t == "plane":
                for req in ("point", "normal"):
                    if req not in ent:
                        raise ctx.err(f"{key}.{req}", "required key is missing")
                if math.hypot(*ent["normal"]) == 0.0:
                    raise ctx.err(f"{key}.normal", "must be a non-zero vector")
            else:
                shape = ent.setdefault("shape", "square")
                if shape not in ("square", "disc"):
                    raise ctx.err(f"{key}.shape", f"must be 'square' or 'disc', got {shape!r}")
                need = "size" if shape == "square" else "diameter"
                other = "diameter" if shape == "square" else "size"
                if need not in ent:
                    raise ctx.err(f"{key}.{need}", f"required for a {shape} pedestal [cm]; missing")
                if other in ent:
                    raise ctx.err(f"{key}.{other}", f"does not apply to a {shape} pedestal")
                ent.setdefault("centre", (0.0, 0.0, 0.0))
                ent.setdefault("height", 10.0)
            contact.append(ent)

        # solver --------------------------------------------------------------------
        sv = _table(ctx, "solver", data.get("solver", {}))
        _unknown(ctx, "solver", sv, {"kind", *KINDS})
        kind = _str(ctx, "solver.kind", sv.get("kind", "static"))
        if kind not in KINDS:
            raise ctx.err("solver.kind", f"unknown solver {kind!r} (known: {', '.join(KINDS)})")
        solver = {"kind": kind}
        for k in KINDS:
            t = _table(ctx, f"solver.{k}", sv.get(k, {}))
            for kk, vv in t.items():
                _setting(ctx, f"solver.{k}.{kk}", vv)
            solver[k] = dict(t)

        # output --------------------------------------------------------------------
        o = _table(ctx, "output", data.get("output", {}))
        _unknown(ctx, "output", o, {"snapshots", "pictures"})
        snaps = o.get("snapshots", [])
        if not isinstance(snaps, list):
            raise ctx.err("output.snapshots", f"must be an array of times [s], got {snaps!r}")
        snaps = [_num(ctx, f"output.snapshots[{i}]", t, nonneg=True) for i, t in enumerate(snaps)]
        if snaps != sorted(snaps):
            raise ctx.err("output.snapshots", "times must be increasing")
        pics = o.get("pictures", ["top", "iso"])
        if not isinstance(pics, list):
            raise ctx.err("output.pictures", f"must be an array of views, got {pics!r}")
        for i, p in enumerate(pics):
            if _str(ctx, f"output.pictures[{i}]", p) not in PICTURES:
                raise ctx.err(f"output.pictures[{i}]", f"unknown view {p!r} (known: {', '.join(PICTURES)})")
        output = {"snapshots": snaps, "pictures": list(pics)}

        # adaptivity (§5): the table is checked here, so a bad value fails before any work ----------
        adapt = dict(_table(ctx, "adapt", data.get("adapt", {})))
        if adapt:
            from ..adapt.settings import parse_adapt
            parse_adapt(adapt, f"{source}: adapt")

        # perturbation of the starting state (solidshell.perturbation), checked here too ------------
        perturbation = dict(_table(ctx, "perturbation", data.get("perturbation", {})))
        if perturbation:
            from ..perturbation import parse_perturbation
            perturbation = parse_perturbation(perturbation, f"{source}: perturbation").as_dict()

        return cls(name=name, title=title, paper_section=section, description=description,
                   geometry=geometry, mesh=mesh, material=material, model=model, supports=supports,
                   loads=loads, contact=tuple(contact), solver=solver, output=output, adapt=adapt,
                   perturbation=perturbation, source=source, raw=raw)

    # ------------------------------------------------------------------ derived
    @property
    def base_dir(self) -> Path:
        p = Path(self.source)
        return p.parent if p.suffix == ".toml" else Path.cwd()

    @property
    def recipe(self) -> str | None:
        return self.geometry.get("recipe")

    @property
    def density(self) -> str | None:
        return self.mesh["density"]

    def material_object(self):
        """The Fabric or IsotropicShell this scene describes."""
        return _make_material(self.material)

    def solver_settings(self, kind: str | None = None) -> dict:
        """The free settings table of a solver kind (default: the scene's kind), with the output
        snapshot times added as ``snapshots`` for the explicit solver unless the table sets them
        (dynamic relaxation has no meaningful times and keeps its own frames)."""
        kind = kind or self.solver["kind"]
        s = dict(self.solver.get(kind, {}))
        if kind == "explicit" and self.output["snapshots"] and "snapshots" not in s:
            s["snapshots"] = list(self.output["snapshots"])
        return s

    def pedestal(self) -> dict | None:
        """The pedestal (for pictures): from a pedestal contact body, else from the recipe."""
        for c in self.contact:
            if c["type"] == "pedestal":
                return dict(c)
        r, g = self.recipe, self.geometry
        if r == "square_on_square":
            return {"type": "pedestal", "shape": "square", "size": g["pedestal"], "centre": (0.0, 0.0, 0.0), "height": 10.0}
        if r in ("disc_on_disc", "square_on_disc"):
            return {"type": "pedestal", "shape": "disc", "diameter": g["pedestal_diameter"],
                    "centre": (0.0, 0.0, 0.0), "height": 10.0}
        return None

    def with_overrides(self, overrides: dict | None) -> "Scene":
        """A new, validated scene with dotted keys set: ``{"mesh.density": "24x8x4",
        "solver.static.c": 2e-3, "contact.0.radius": 6.0}``.  Unknown keys are errors, as in a file."""
        if not overrides:
            return self
        raw = copy.deepcopy(self.raw)
        for key, value in overrides.items():
            if not isinstance(key, str) or not key or any(not p for p in key.split(".")):
                raise InputError(f"override {key!r}: expected a dotted key like 'mesh.density'")
            parts = key.split(".")
            node = raw
            for i, p in enumerate(parts[:-1]):
                here = ".".join(parts[: i + 1])
                if isinstance(node, list):
                    try:
                        node = node[int(p)]
                    except (ValueError, IndexError):
                        raise InputError(f"override {key!r}: {here} is not an index of the array") from None
                    continue
                if not isinstance(node, dict):
                    raise InputError(f"override {key!r}: {here} is not a table")
                if p not in node:
                    node[p] = {}
                node = node[p]
            last = parts[-1]
            if isinstance(node, list):
                try:
                    node[int(last)] = value
                except (ValueError, IndexError):
                    raise InputError(f"override {key!r}: {last!r} is not an index of the array") from None
            elif isinstance(node, dict):
                if parts[0] == "geometry" and len(parts) == 2:
                    if last == "file":
                        node.pop("recipe", None)
                        for k in list(node):
                            if k != "file":
                                node.pop(k)
                node[last] = value
            else:
                raise InputError(f"override {key!r}: the parent is not a table")
        if "geometry.file" in overrides:
            for k in ("density", "paper_meshes", "adaptive_level0"):
                if f"mesh.{k}" not in overrides:
                    raw.get("mesh", {}).pop(k, None)
        src = f"{self.source} (with overrides)" if "(with overrides)" not in self.source else self.source
        return Scene.from_dict(raw, source=src, base_dir=self.base_dir)

    def summary(self) -> dict:
        """JSON-able description (for summary.json)."""
        def plain(v):
            if isinstance(v, Path):
                return str(v)
            if isinstance(v, tuple):
                return [plain(x) for x in v]
            if isinstance(v, dict):
                return {k: plain(x) for k, x in v.items()}
            if isinstance(v, list):
                return [plain(x) for x in v]
            return v
        return {"name": self.name, "title": self.title, "paper_section": self.paper_section,
                "source": self.source, "geometry": plain(self.geometry), "mesh": plain(self.mesh),
                "material": plain(self.material), "model": plain(self.model),
                "supports": plain(self.supports), "loads": plain(self.loads),
                "contact": plain(list(self.contact)), "solver": plain(self.solver),
                "output": plain(self.output), "adapt": plain(self.adapt),
                "perturbation": plain(self.perturbation)}


def _setting(ctx, key, v):
    """Solver settings are free, but must be plain TOML values."""
    if isinstance(v, dict):
        for k, x in v.items():
            _setting(ctx, f"{key}.{k}", x)
    elif isinstance(v, list):
        for i, x in enumerate(v):
            _setting(ctx, f"{key}[{i}]", x)
    elif not isinstance(v, (bool, int, float, str)):
        raise ctx.err(key, f"must be a number, string, boolean, array or table, got {_typename(v)}")
    elif isinstance(v, float) and not math.isfinite(v):
        raise ctx.err(key, f"must be finite, got {v!r}")


def _make_material(material: dict):
    from ..material import Fabric, IsotropicShell

    if "isotropic" in material:
        return IsotropicShell(**material["isotropic"])
    over = {k: v for k, v in material.items() if k != "fabric"}
    return FABRICS[material["fabric"]](**over)


def _wool(**kw):
    from ..material import Fabric
    return Fabric.wool(**kw)


FABRICS = {"wool": _wool}


# --------------------------------------------------------------------------- loading
def available() -> list[str]:
    """Names of the scenes shipped with the package, sorted."""
    return sorted(p.stem for p in SCENE_DIR.glob("*.toml"))


def read_toml(path: Path) -> dict:
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{path}: not valid TOML: {e}") from None
    except UnicodeDecodeError as e:
        raise InputError(f"{path}: not a UTF-8 text file ({e.reason} at byte {e.start})") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, not a scene file") from None
    except OSError as e:
        raise InputError(f"cannot read scene file {path}: {e.strerror or e}") from None


def load(name_or_path) -> Scene:
    """A scene by package name (``"square-pedestal"``) or by path to a .toml file."""
    if isinstance(name_or_path, Scene):
        return name_or_path
    s = str(name_or_path)
    p = Path(s)
    builtin = SCENE_DIR / f"{s}.toml"
    if "/" not in s and "\\" not in s and not s.endswith(".toml"):
        if not builtin.is_file():
            raise InputError(f"unknown scene {s!r}; available: {', '.join(available())} "
                             f"(or give the path of a .toml scene file)")
        p = builtin
    elif not p.exists():
        raise InputError(f"scene file not found: {p}")
    data = read_toml(p)
    scene = Scene.from_dict(data, source=str(p), base_dir=p.resolve().parent)
    if p.parent.resolve() == SCENE_DIR.resolve() and scene.name != p.stem:
        raise InputError(f"{p}: name {scene.name!r} differs from the file name {p.stem!r}")
    return scene


def parse_value(text: str):
    """A --set value: a TOML value if it parses as one (2e-3, true, [1, 2], "x"), else the string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_overrides(items) -> dict:
    """['key=value', ...] -> {key: parsed value}."""
    out = {}
    for it in items or []:
        if "=" not in it:
            raise InputError(f"--set {it!r}: expected key=value, e.g. solver.static.c=2e-3")
        k, v = it.split("=", 1)
        k = k.strip()
        if not k:
            raise InputError(f"--set {it!r}: empty key")
        out[k] = parse_value(v.strip())
    return out
