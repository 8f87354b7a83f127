"""Scenes: a drape problem described as data, in a TOML file a user can write.

The paper's scenes ship as package data (``solidshell/scenes/paper/*.toml``), with scenes beyond the
paper (``solidshell/scenes/examples/*.toml``: the drape tester), and load by name (:func:`load`,
:func:`available`); a user's own scene loads by path.  Every unknown key, every
value of the wrong type and every missing required key is an :class:`~solidshell.errors.InputError`
that names the key and the file (:mod:`solidshell.scenes.schema`: one pydantic model per table;
:mod:`solidshell.scenes.overrides`: the dotted ``--set`` keys).  All quantities are in the paper's
units: cm, gf, s (degrees for angles).

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
    # pedestal_contact = false            # pedestal recipes only: no pedestal body (see [[contact]])
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
    # kes = { B_warp = 0.083, B_weft = 0.063, G = 0.73, W = 19.0,   # OR a fabric's KES-FB data
    #         T = 0.593, tensile_warp = 1118.2, tensile_weft = 759.5 }  (solidshell.fabrics: units,
    #                                       factors; Fabric fields may follow; fabric names the
    #                                       library's (solidshell fabrics), --set material.kes.*
    #                                       replaces it)

    [model]                               # optional
    thickness_strain = "green"            # "green" | "quasi" (Eq. 24)
    mu = 0.5                              # the mu of Eq. (24), 0 < mu < 1
    membrane = "full"                     # quads: "full" (2x2 Gauss, the paper) | "ans" (quad4.py)

    [supports]                            # node sets of the mesh (a name or a list of names)
    clamped = "clamped"                   # all six dofs fixed (U_o = U_n = 0)
    # fixed_translations = "hung"         # U_o = 0 only (corners a sheet hangs from)
    # fixed_x = "centre"                  # one component of U_o (also fixed_y, fixed_z)
    # [supports.static]                   # the same keys, held only by the static solver (its
    # fixed_y = ["centre", "centre_east"] #   contact is frictionless: paper/sphere.toml)

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
    support = "cusick"                    # plane:    point = [x,y,z], normal = [nx,ny,nz] (the
    disc_thickness = 0.3                  #           side opposite the normal is solid)
    stem_diameter = 5.0                   # pedestal: shape = "square" (size = side) or "disc"
                                          #           (diameter); centre = centre of its top face;
                                          #           height (default: as long as the skirt, >= 10), edge_radius (default 0);
                                          #           support = "solid" (default: a column down to
                                          #           its base) or "cusick" (a disc of
                                          #           disc_thickness on a coaxial stem of
                                          #           stem_diameter <= diameter; optional upper
                                          #           clamping disc clamp_diameter <= diameter,
                                          #           clamp_thickness, lying on the sheet)
                                          # all:      offset = distance kept between the body and
                                          #           the mid-surface (h/2 for the lower face);
                                          #           friction = Coulomb coefficient mu >= 0
                                          #           (default 0: frictionless; explicit/relax
                                          #           solvers only, stick spring + return map)
    # A pedestal recipe (square_on_square, disc_on_disc, square_on_disc) meshes only the hanging
    # part and clamps its inner edge on the rim; the sheet lies on a pedestal, and the scene has
    # that pedestal as a contact body without a [[contact]] table: solid, the recipe's shape and
    # size, its top face at z = -h/2 with offset = h/2 (h: the material's thickness; the sheet's
    # lower face on the top, the clamped rim at gap 0, like the sphere scene's sheet), sharp edge,
    # frictionless, 10 cm high.  It keeps the hanging skirt out of the pedestal (without it, the
    # static skirt of square-on-disc 30x240 passes up to 2 cm into it, issue 36).  A pedestal table in such a
    # scene replaces it and takes every key it leaves out from it (so the table above, in
    # square-on-disc, is a Cusick-type support of the recipe's 20 cm disc).  The paper's own
    # node-free model (no pedestal body, only the clamped rim) stays one key away:
    # [geometry] pedestal_contact = false.  Scene.bodies() lists the bodies with every key filled:
    # the solvers feel exactly these and the pictures draw exactly these (planes are not drawn).

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
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError
from . import overrides as _overrides
from . import schema
from .overrides import parse_overrides, parse_value
from .schema import FABRICS, check_density, make_material

__all__ = [
    "Scene",
    "load",
    "available",
    "read_toml",
    "check_density",
    "parse_overrides",
    "parse_value",
    "SCENE_DIR",
    "EXAMPLE_DIR",
    "FABRICS",
]

SCENE_DIR = Path(__file__).with_name("paper")
"""The paper's scenes (Sections 3, 4 and 6), each loadable by its file name."""
EXAMPLE_DIR = Path(__file__).with_name("examples")
"""Scenes beyond the paper (e.g. the drape tester), loadable by name like the paper's; a name is
unique across both folders."""
_SCENE_DIRS = (SCENE_DIR, EXAMPLE_DIR)


@dataclass(frozen=True)
class Scene:
    """A validated scene.  ``raw`` is the TOML table it came from (after overrides)."""

    name: str
    title: str
    paper_section: str
    description: str
    geometry: dict  # {"recipe": str, **params} or {"file": Path}
    mesh: dict  # {"density": str|None, "paper_meshes": [...], "adaptive_level0": str|None}
    material: dict  # {"fabric": "wool", **overrides} or {"isotropic": {...}}
    model: dict  # {"thickness_strain": ..., "mu": ..., "membrane": ...}
    supports: dict  # {"clamped": (names...), "fixed_translations": (names...)}
    loads: dict  # {"gravity": bool, "gravity_direction": (3,), "point": [...], "line": [...], "surface": [...]}
    contact: tuple  # ({"type": ..., ...}, ...)
    solver: dict  # {"kind": str, "static": {...}, "explicit": {...}, "relax": {...}}
    output: dict  # {"snapshots": [...], "pictures": [...]}
    adapt: dict = field(default_factory=dict)  # the [adapt] table (solidshell.adapt.settings.AdaptSettings)
    self_contact: dict = field(default_factory=dict)  # [self_contact]: {"enabled": bool}
    perturbation: dict = field(default_factory=dict)  # [perturbation] (solidshell.perturbation), {} = none
    pedestal_contact: bool = True  # [geometry] pedestal_contact of a pedestal recipe (False: no pedestal body)
    source: str = "<dict>"
    raw: dict = field(default_factory=dict, repr=False, compare=False)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_dict(cls, data: dict, source: str = "<dict>", base_dir: Path | None = None) -> "Scene":
        """The scene of a TOML table (solidshell.scenes.schema validates it; one-line InputError
        naming ``source`` and the key otherwise); a mesh file's path becomes absolute."""
        tables = schema.parse(data, source).tables()
        raw = copy.deepcopy(data)
        if "file" in tables["geometry"]:
            f = Path(tables["geometry"]["file"])
            f = f if f.is_absolute() else (base_dir or Path.cwd()) / f
            tables["geometry"] = {"file": f}
            raw["geometry"]["file"] = str(f)  # absolute from now on (overrides re-parse raw)
        return cls(**tables, source=source, raw=raw)

    def with_overrides(self, overrides: dict | None) -> "Scene":
        """A new, validated scene with dotted keys set: ``{"mesh.density": "24x8x4",
        "solver.static.c": 2e-3, "contact.0.radius": 6.0}``.  Unknown keys are errors, as in a file."""
        if not overrides:
            return self
        src = f"{self.source} (with overrides)" if "(with overrides)" not in self.source else self.source
        return Scene.from_dict(_overrides.apply(self.raw, overrides), source=src, base_dir=self.base_dir)

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
        return make_material(self.material)

    def solver_settings(self, kind: str | None = None) -> dict:
        """The free settings table of a solver kind (default: the scene's kind), with the output
        snapshot times added as ``snapshots`` for the explicit solver unless the table sets them
        (dynamic relaxation has no meaningful times and keeps its own frames)."""
        kind = kind or self.solver["kind"]
        s = dict(self.solver.get(kind, {}))
        if kind == "explicit" and self.output["snapshots"] and "snapshots" not in s:
            s["snapshots"] = list(self.output["snapshots"])
        return s

    def bodies(self) -> list[dict]:
        """The rigid bodies of this scene, one dict per body with every key filled: the
        ``[[contact]]`` tables resolved (a Cusick support's clamp as a second body right after it),
        then the pedestal the recipe implies unless a table gives one or ``geometry.pedestal_contact``
        is false (schema.resolve_bodies).  The one source of truth: the solvers feel exactly these
        (build.contact_bodies) and the pictures draw exactly these (render.bodies_of; planes not
        drawn).  Fresh dicts on every call."""
        return schema.resolve_bodies(self.geometry, self.material, self.contact, self.pedestal_contact)

    def pedestal(self) -> dict | None:
        """The pedestal the sheet lies on (its outline, centre and area: pictures, the perturbation's
        centre, the DC): the supporting pedestal among :meth:`bodies`, else, when the scene opts out
        of the pedestal body (``geometry.pedestal_contact = false``), the recipe's pedestal all the
        same (the sheet still lies on it, nothing keeps the skirt out); None without a pedestal."""
        for b in self.bodies():
            if b["type"] == "pedestal" and b["role"] == "support":
                return b
        return schema.recipe_pedestal(self.geometry, float(self.material_object().thickness))

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

        return {
            "name": self.name,
            "title": self.title,
            "paper_section": self.paper_section,
            "source": self.source,
            "geometry": plain(self.geometry),
            "mesh": plain(self.mesh),
            "material": plain(self.material),
            "model": plain(self.model),
            "supports": plain(self.supports),
            "loads": plain(self.loads),
            "contact": plain(list(self.contact)),
            "pedestal_contact": self.pedestal_contact,
            "bodies": plain(self.bodies()),
            "solver": plain(self.solver),
            "output": plain(self.output),
            "adapt": plain(self.adapt),
            "perturbation": plain(self.perturbation),
        }


# --------------------------------------------------------------------------- loading
def available() -> list[str]:
    """Names of the scenes shipped with the package (the paper's and the examples), sorted."""
    return sorted({p.stem for d in _SCENE_DIRS for p in d.glob("*.toml")})


def _builtin(name: str) -> Path | None:
    """The packaged scene file of ``name`` (paper folder first), or None."""
    return next((d / f"{name}.toml" for d in _SCENE_DIRS if (d / f"{name}.toml").is_file()), None)


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
    builtin = _builtin(s)
    if "/" not in s and "\\" not in s and not s.endswith(".toml"):
        if builtin is None:
            raise InputError(
                f"unknown scene {s!r}; available: {', '.join(available())} (or give the path of a .toml scene file)"
            )
        p = builtin
    elif not p.exists():
        raise InputError(f"scene file not found: {p}")
    data = read_toml(p)
    scene = Scene.from_dict(data, source=str(p), base_dir=p.resolve().parent)
    if any(p.parent.resolve() == d.resolve() for d in _SCENE_DIRS) and scene.name != p.stem:
        raise InputError(f"{p}: name {scene.name!r} differs from the file name {p.stem!r}")
    return scene
