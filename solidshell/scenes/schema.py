"""The scene file's schema: one pydantic model per TOML table, on :class:`solidshell.settings.SettingsModel`.

:func:`parse` validates a scene's table (a parsed TOML file, after ``--set`` overrides) and returns a
:class:`SceneDoc`, or raises one :class:`~solidshell.errors.InputError` line ``FILE: dotted.key: what
is wrong`` (``contact[0].radius``, ``output.snapshots[1]``).  The vocabularies come from where they
are defined: recipes and their geometry keywords and density counts (solidshell.meshing.RECIPES),
fabric and isotropic fields (solidshell.material), membranes (solidshell.elements.quad4), thickness
strains (solidshell.elements), picture views (solidshell.plotting), solver kinds and their tables
(solidshell.solvers.KINDS).  The solver tables are free plain values here: each kind's settings
model checks them before a run (solidshell.solvers.validate).
"""

from __future__ import annotations

import math
import re
from types import UnionType
from typing import Annotated, Optional, Union, get_args, get_origin

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    Discriminator,
    Field,
    PlainValidator,
    Tag,
    ValidationError,
    create_model,
    model_validator,
)

from .. import fabrics, meshing
from ..elements import THICKNESS_STRAINS
from ..elements.quad4 import MEMBRANES
from ..errors import InputError
from ..layers import SELF_CONTACT_DEFAULT
from ..material import FABRIC_FIELDS, ISOTROPIC_FIELDS, ISOTROPIC_REQUIRED, Fabric, IsotropicShell
from ..plotting import VIEWS
from ..settings import SettingsModel
from ..settings import parse as parse_model
from ..solvers import KINDS

__all__ = [
    "SceneDoc",
    "parse",
    "check_density",
    "FABRICS",
    "make_material",
    "PEDESTAL_RECIPES",
    "recipe_pedestal",
    "resolve_bodies",
]

FABRICS = {name: (lambda n: lambda **kw: fabrics.fabric(n, **kw))(name) for name in fabrics.names()}
"""Named fabrics a scene's ``material.fabric`` may start from: the fabric library
(solidshell/fabrics.toml; ``solidshell fabrics`` lists it), each a callable taking field overrides."""
RECIPES = {k: r for k, r in meshing.RECIPES.items() if r.form is not None}  # from_file: geometry.file
PEDESTAL_RECIPES = {
    "square_on_square": ("square", "size", "pedestal"),
    "disc_on_disc": ("disc", "diameter", "pedestal_diameter"),
    "square_on_disc": ("disc", "diameter", "pedestal_diameter"),
}
"""The recipes whose sheet lies on a pedestal: (its shape, the pedestal table's extent key, the
geometry key giving that extent).  Only the hanging part is meshed, its inner edge on the rim."""
PEDESTAL_HEIGHT = 10.0
"""A pedestal's least default height below its top face [cm] (the pictures drew 10 cm before it was
a body); a recipe's pedestal is at least as tall as the sheet's skirt is long (:func:`recipe_pedestal`)."""


def _skirt_length(geometry: dict) -> float:
    """The longest distance of the recipe's sheet from its centre [cm] (the half diagonal of a
    square sheet, the radius of a disc): no skirt reaches further down the pedestal than that."""
    if "sheet" in geometry:
        return float(geometry["sheet"]) / 2.0**0.5
    return 0.5 * float(geometry.get("diameter", 0.0))


SUPPORTS = ("solid", "cusick")
CUSICK_KEYS = ("disc_thickness", "stem_diameter", "clamp_diameter", "clamp_thickness")


# --------------------------------------------------------------------------- one-line errors
class Bad(ValueError):
    """A problem at ``key`` (dotted, relative to where it is raised; "" = right there)."""

    def __init__(self, key: str, msg: str):
        super().__init__(msg)
        self.key, self.msg = key, msg


def _typename(v) -> str:
    return {bool: "boolean", int: "integer", float: "number", str: "string", list: "array", dict: "table"}.get(
        type(v), type(v).__name__
    )


def _got(v) -> str:
    return f"{_typename(v)} {v!r}"


def _join(key: str, sub) -> str:
    """``key`` and a sub-key: a name (``a.b``), an index (``a[0]``) or a key starting with one."""
    if sub is None or sub == "":
        return key
    if isinstance(sub, int):
        return f"{key}[{sub}]"
    return key + sub if sub.startswith("[") or not key else f"{key}.{sub}"


def _strip(t):
    """The type under Annotated[...] and Optional[...] (a tagged union is kept)."""
    while True:
        if get_origin(t) is Annotated:
            t = get_args(t)[0]
        elif get_origin(t) in (Union, UnionType) and type(None) in get_args(t):
            rest = [a for a in get_args(t) if a is not type(None)]
            t = rest[0] if len(rest) == 1 else Union[tuple(rest)]
        else:
            return t


def _tag(member):
    meta = get_args(member)[1:] if get_origin(member) is Annotated else ()
    return next((m.tag for m in meta if isinstance(m, Tag)), None)


def _key(loc, model) -> str:
    """The dotted scene key of a pydantic error location (union tags dropped, indices as [i])."""
    key, t = "", model
    for p in loc:
        t = _strip(t)
        if isinstance(p, int):
            key = _join(key, p)
            t = get_args(t)[0] if get_origin(t) in (list, tuple) and get_args(t) else None
        elif get_origin(t) in (Union, UnionType):  # a tagged union: p is the member's tag
            t = next((m for m in get_args(t) if _tag(m) == p), None)
        else:
            key = _join(key, p)
            f = t.model_fields.get(p) if isinstance(t, type) and issubclass(t, BaseModel) else None
            t = f.annotation if f is not None else None
    return key


def _explain(e: dict, model) -> tuple[str, str]:
    key, kind, v = _key(e.get("loc", ()), model), e.get("type"), e.get("input")
    err = (e.get("ctx") or {}).get("error")
    if isinstance(err, Bad):
        return _join(key, err.key), err.msg
    if isinstance(err, ValueError):
        return key, str(err)
    if kind == "missing":
        return key, "required key is missing"
    if kind == "scene_tag":  # a discriminated union's tag
        c = e["ctx"]
        if not isinstance(v, dict):
            return key, f"must be a table, got {_got(v)}"
        key, tag = _join(key, c["key"]), v.get(c["key"])
        if c["key"] not in v:
            return key, f"required key is missing ({c['missing']})"
        if not isinstance(tag, str):
            return key, f"must be a string, got {_got(tag)}"
        return key, f"unknown {c['what']} {tag!r} (known: {c['known']})"
    if kind in ("model_type", "model_attributes_type", "dict_type"):
        return key, f"must be a table, got {_got(v)}"
    if kind == "list_type":
        return key, f"must be an array, got {_got(v)}"
    return key, e.get("msg", "invalid")


def _one_line(exc: ValidationError, source: str, model) -> str:
    errors = exc.errors()
    unknown = [
        e
        for e in errors
        if isinstance((e.get("ctx") or {}).get("error"), Bad) and e["ctx"]["error"].msg.startswith("unknown key")
    ]
    key, msg = _explain((unknown or errors)[0], model)  # a typo first: it explains the rest
    return f"{source}: {key or '(top level)'}: {msg}"


# --------------------------------------------------------------------------- value types
def _number(v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"must be a number, got {_got(v)}")
    v = float(v)
    if not math.isfinite(v):
        raise ValueError(f"must be finite, got {v!r}")
    return v


def _rule(ok, msg: str) -> AfterValidator:
    """A check after the type's: ``ok(v)`` or ValueError ``msg`` ({v!r}: the value)."""

    def check(v):
        if not ok(v):
            raise ValueError(msg.format(v=v))
        return v

    return AfterValidator(check)


def _string(v) -> str:
    if not isinstance(v, str):
        raise ValueError(f"must be a string, got {_got(v)}")
    return v


def _boolean(v) -> bool:
    if not isinstance(v, bool):
        raise ValueError(f"must be true or false, got {_got(v)}")
    return v


def _vec3(v) -> tuple:
    if not isinstance(v, list) or len(v) != 3:
        raise ValueError(f"must be an array of 3 numbers, got {v!r}")
    out = []
    for i, x in enumerate(v):
        try:
            out.append(_number(x))
        except ValueError as e:
            raise Bad(f"[{i}]", str(e)) from None
    return tuple(out)


def _names(v) -> tuple:
    """A node-set name or a list of names."""
    if isinstance(v, str):
        return (v,)
    if isinstance(v, list) and v and all(isinstance(s, str) for s in v):
        return tuple(v)
    raise ValueError(f"must be a node-set name or a list of names, got {v!r}")


def _plain(v, key=""):
    """A solver setting: a plain TOML value (number, string, boolean, array, table), finite."""
    if isinstance(v, dict):
        return {k: _plain(x, _join(key, k)) for k, x in v.items()}
    if isinstance(v, list):
        return [_plain(x, _join(key, i)) for i, x in enumerate(v)]
    if not isinstance(v, (bool, int, float, str)):
        raise Bad(key, f"must be a number, string, boolean, array or table, got {_typename(v)}")
    if isinstance(v, float) and not math.isfinite(v):
        raise Bad(key, f"must be finite, got {v!r}")
    return v


def _settings_table(v) -> dict:
    if not isinstance(v, dict):
        raise ValueError(f"must be a table, got {_got(v)}")
    return _plain(v)


def choice(choices, what: str | None = None):
    """A string out of ``choices``: "must be 'a' or 'b', got 'x'" or, naming ``what``,
    "unknown what 'x' (known: a, b, c)"."""

    def check(v):
        if _string(v) not in choices:
            if what:
                raise ValueError(f"unknown {what} {v!r} (known: {', '.join(choices)})")
            raise ValueError(f"must be {' or '.join(map(repr, choices))}, got {v!r}")
        return v

    return Annotated[str, PlainValidator(check)]


def array(item, what: str, *, tables: bool = False):
    """An array of ``item``; with ``tables`` a single table counts as an array of one."""

    def check(v):
        if tables and isinstance(v, dict):
            return [v]
        if not isinstance(v, list):
            raise ValueError(f"must be {what}" + ("" if tables else f", got {v!r}"))
        return v

    return Annotated[list[item], BeforeValidator(check)]


Num = Annotated[float, PlainValidator(_number)]
Pos = Annotated[float, PlainValidator(_number), _rule(lambda v: v > 0.0, "must be positive, got {v!r}")]
NonNeg = Annotated[float, PlainValidator(_number), _rule(lambda v: v >= 0.0, "must be >= 0, got {v!r}")]
Str = Annotated[str, PlainValidator(_string)]
Bool = Annotated[bool, PlainValidator(_boolean)]
Vec3 = Annotated[tuple, PlainValidator(_vec3)]
Direction = Annotated[tuple, PlainValidator(_vec3), _rule(lambda v: math.hypot(*v) > 0.0, "must be a non-zero vector")]
Names = Annotated[tuple, PlainValidator(_names)]
SettingsTable = Annotated[dict, PlainValidator(_settings_table)]


def _tagged(members: dict, tag_of, **ctx):
    """A union of models told apart by ``tag_of(table)``; a bad or missing tag is a ``scene_tag``
    error worded by ``ctx`` (key, what, known, missing)."""

    def discriminator(v):
        t = tag_of(v) if isinstance(v, dict) else None
        return t if t is None or isinstance(t, str) else "(not a string)"

    return Annotated[
        Union[tuple(Annotated[m, Tag(t)] for t, m in members.items())],
        Discriminator(
            discriminator, custom_error_type="scene_tag", custom_error_message="bad tag", custom_error_context=ctx
        ),
    ]


# --------------------------------------------------------------------------- the tables
class Table(SettingsModel):
    """A TOML table: unknown keys are named with the keys allowed there."""

    @model_validator(mode="before")
    @classmethod
    def _known(cls, data):
        if isinstance(data, dict):
            for k in data:
                if k not in cls.model_fields:
                    raise Bad(k, f"unknown key (allowed here: {', '.join(sorted(cls.model_fields))})")
        return data

    def given(self) -> dict:
        """The keys the file gave or that have a value (None = absent)."""
        return {k: v for k, v in self.as_dict().items() if v is not None}


class RecipeGeometry(Table):
    """[geometry] of a built-in recipe (solidshell.meshing.RECIPES): its lengths [cm]."""

    recipe: Str

    @model_validator(mode="after")
    def _lengths(self):
        for p in RECIPES[self.recipe].required:
            if getattr(self, p) is None:
                raise Bad(p, f"required by recipe {self.recipe!r} [cm]; missing")
        return self


class FileGeometry(Table):
    """[geometry] from a gmsh .msh/.geo (or any meshio) file, relative to the scene file."""

    file: Str


def _one_geometry(v):
    if isinstance(v, dict) and ("recipe" in v) == ("file" in v):
        raise ValueError("give exactly one of 'recipe' (a built-in mesh recipe) or 'file' (a .msh/.geo file)")
    return v


def _recipe_geometry(name: str, r):
    """[geometry] of recipe ``name``: its lengths [cm]; a pedestal recipe also takes
    ``pedestal_contact`` (false: no pedestal body, the paper's node-free model; Scene.bodies)."""
    fields = {p: (Optional[Pos], None) for p in r.geometry}
    if name in PEDESTAL_RECIPES:
        fields["pedestal_contact"] = (Optional[Bool], None)
    return create_model(f"Geometry_{name}", __base__=RecipeGeometry, **fields)


Geometry = Annotated[
    _tagged(
        {"file": FileGeometry, **{name: _recipe_geometry(name, r) for name, r in RECIPES.items()}},
        lambda d: "file" if "file" in d else d.get("recipe"),
        key="recipe",
        what="recipe",
        known=", ".join(sorted(RECIPES)),
        missing="a recipe name",
    ),
    BeforeValidator(_one_geometry),
]


class MeshTable(Table):
    density: Optional[Str] = None
    paper_meshes: array(Str, "an array of density strings") = []
    adaptive_level0: Optional[Str] = None


def make_material(material: dict):
    """The Fabric or IsotropicShell of a scene's material dict: a library fabric (``fabric``), a
    fabric from KES-FB data (``kes``, solidshell.fabrics.from_kes) or an isotropic shell; the other
    keys override Fabric fields."""
    if "isotropic" in material:
        return IsotropicShell(**material["isotropic"])
    rest = {k: v for k, v in material.items() if k not in ("fabric", "kes")}
    if "kes" in material:
        return Fabric(**{**fabrics.from_kes(material["kes"]), "name": "kes", **rest})
    return FABRICS[material["fabric"]](**rest)


MATERIAL_MAX = 1e12
"""The largest rigidity or weight a [material] value may have, in its units (gf/cm, gf cm^2/cm,
gf/cm^2): a 1 mm steel plate is ~2e8 gf/cm in tension and ~2e5 gf cm in bending, so 1e12 leaves
decades for any sheet, while values near 1e150 overflow the tangent's products (a numpy
RuntimeWarning and a solver that stops, as tensile_warp = 1e300 did)."""
WARP_ANGLE_MAX = 360.0  # [deg]: an angle past a full turn is a typing slip (or radians x 57)


def _bounds(m: dict) -> None:
    """Bad when a fabric value is past MATERIAL_MAX or the warp angle past a full turn."""
    wa = m.get("warp_angle")
    if isinstance(wa, (int, float)) and not abs(wa) <= WARP_ANGLE_MAX:
        raise Bad("warp_angle", f"must lie in [-{WARP_ANGLE_MAX:g}, {WARP_ANGLE_MAX:g}] degrees, got {wa!r}")
    for k, v in m.items():
        if k not in ("warp_angle", "poisson", "thickness") and isinstance(v, (int, float)) and abs(v) > MATERIAL_MAX:
            raise Bad(k, f"{v!r} is past the guard of {MATERIAL_MAX:g} (its units: see solidshell.material)")


class _Section(Table):
    @model_validator(mode="after")
    def _build(self):
        _bounds({k: v for k, v in self.given().items() if not isinstance(v, dict)})
        try:  # built once so that zero/negative rigidities are reported now, with the file
            make_material(self.given())
        except InputError as e:
            key, _, msg = str(e).partition(": ") if str(e).startswith("kes.") else ("", "", str(e))
            raise Bad(key, msg) from None
        return self


FabricMaterial = create_model(
    "FabricMaterial",
    __base__=_Section,
    fabric=(choice(tuple(FABRICS), "fabric"), "wool"),
    name=(Optional[Str], None),
    **{k: (Optional[Num], None) for k in FABRIC_FIELDS},
)
IsotropicTable = create_model(
    "IsotropicTable",
    __base__=Table,
    **{k: (Num, ...) if k in ISOTROPIC_REQUIRED else (Optional[Num], None) for k in ISOTROPIC_FIELDS},
)


def _kes_value(key: str):
    def check(v):
        try:
            return fabrics.check_kes_value(key, v)
        except InputError as e:
            raise ValueError(str(e).removeprefix(f"kes.{key}: ")) from None

    return Annotated[float, PlainValidator(check)]


KesTable = create_model("KesTable", __base__=Table, **{k: (Optional[_kes_value(k)], None) for k in fabrics.KES_KEYS})


class _KesSection(_Section):
    """[material] kes = {...}: a fabric from its KES-FB data (solidshell.fabrics), Fabric fields after."""

    kes: KesTable

    @model_validator(mode="before")
    @classmethod
    def _not_both(cls, data):
        if isinstance(data, dict) and "fabric" in data:
            raise Bad("fabric", "give either fabric (a library name) or kes (measured KES data), not both")
        return data

    def given(self) -> dict:
        return {**{k: v for k, v in super().given().items() if k != "kes"}, "kes": self.kes.given()}


KesMaterial = create_model(
    "KesMaterial", __base__=_KesSection, name=(Optional[Str], None), **{k: (Optional[Num], None) for k in FABRIC_FIELDS}
)


class IsotropicMaterial(_Section):
    isotropic: IsotropicTable

    def given(self) -> dict:
        return {"isotropic": self.isotropic.given()}


Material = _tagged(
    {"fabric": FabricMaterial, "kes": KesMaterial, "isotropic": IsotropicMaterial},
    lambda d: "isotropic" if "isotropic" in d else "kes" if "kes" in d else "fabric",
    key="fabric",
    what="material",
    known="fabric, kes, isotropic",
    missing="",
)


class ModelTable(Table):
    thickness_strain: choice(THICKNESS_STRAINS) = "green"
    mu: Annotated[Num, _rule(lambda v: 0.0 < v < 1.0, "must lie in (0, 1), got {v!r}")] = 0.5  # Eq. (24)
    membrane: choice(MEMBRANES) = "full"


class StaticSupports(Table):
    """Node sets held fixed: all six dofs (clamped), U_o (fixed_translations) or one component of
    U_o (fixed_x / _y / _z; build.SUPPORT_DOFS)."""

    clamped: Optional[Names] = None
    fixed_translations: Optional[Names] = None
    fixed_x: Optional[Names] = None
    fixed_y: Optional[Names] = None
    fixed_z: Optional[Names] = None


class SupportsTable(StaticSupports):
    """[supports]; its [supports.static] holds more only in a static solve: the static solver's
    contact is frictionless, so a drape that friction keeps in place (the sphere) needs its rigid
    in-plane motions held there."""

    static: Optional[StaticSupports] = None

    def given(self) -> dict:
        out = super().given()
        if self.static is not None:
            out["static"] = self.static.given()
        return out


class PointLoad(Table):
    force: Vec3
    node_set: Optional[Str] = None
    at: Optional[Vec3] = None

    @model_validator(mode="after")
    def _where(self):
        if (self.node_set is None) == (self.at is None):
            raise ValueError("give exactly one of 'node_set' or 'at'")
        return self


class LineLoad(Table):
    force: Vec3
    node_set: Str


class SurfaceLoad(Table):
    force: Vec3


class LoadsTable(Table):
    gravity: Bool = True
    gravity_direction: Direction = [0.0, 0.0, -1.0]
    point: array(PointLoad, "a table or an array of tables", tables=True) = []
    line: array(LineLoad, "a table or an array of tables", tables=True) = []
    surface: array(SurfaceLoad, "a table or an array of tables", tables=True) = []

    def given(self) -> dict:
        return {
            "gravity": self.gravity,
            "gravity_direction": self.gravity_direction,
            "point": [x.given() for x in self.point],
            "line": [x.given() for x in self.line],
            "surface": [x.given() for x in self.surface],
        }


class Body(Table):
    """A rigid contact body; ``offset``: the distance kept from the mid-surface, ``friction``: mu."""

    type: Str
    offset: Optional[NonNeg] = None
    friction: Optional[NonNeg] = None


class Sphere(Body):
    centre: Vec3
    radius: Pos


class Plane(Body):
    point: Vec3
    normal: Direction


class Pedestal(Body):
    """A pedestal table as written; the keys it leaves out are filled by :func:`resolve_bodies`
    (from the recipe's pedestal in a pedestal scene, else square, centre at the origin, offset 0)."""

    shape: Optional[choice(("square", "disc"))] = None
    centre: Optional[Vec3] = None  # of its top face
    size: Optional[Pos] = None
    diameter: Optional[Pos] = None
    height: Optional[Pos] = None  # default: the recipe pedestal's (as long as the skirt), else PEDESTAL_HEIGHT
    edge_radius: Optional[NonNeg] = None
    support: Optional[choice(SUPPORTS)] = None  # "solid" (default) | "cusick"
    disc_thickness: Optional[Pos] = None  # cusick: the support disc [cm]
    stem_diameter: Optional[Pos] = None  # cusick: the stem under it [cm]
    clamp_diameter: Optional[Pos] = None  # cusick, optional: the upper clamping disc [cm]
    clamp_thickness: Optional[Pos] = None

    @model_validator(mode="after")
    def _support(self):
        if self.support != "cusick":
            for k in CUSICK_KEYS:
                if getattr(self, k) is not None:
                    raise Bad(k, 'applies to a Cusick-type support only (support = "cusick"), not to a solid pedestal')
            return self
        for k in ("disc_thickness", "stem_diameter"):
            if getattr(self, k) is None:
                raise Bad(k, "required for a cusick support [cm]; missing")
        if (self.clamp_diameter is None) != (self.clamp_thickness is None):
            k = "clamp_thickness" if self.clamp_thickness is None else "clamp_diameter"
            raise Bad(k, "a clamp needs both clamp_diameter and clamp_thickness [cm]; missing")
        return self


def _primitives(v) -> list:
    from ..contact_shapes import check_primitives

    try:
        check_primitives(v, "")
        return v
    except InputError as e:  # "[i].box: ..." -> this key's error
        key, _, msg = str(e).partition(": ")
        raise Bad(key.lstrip("."), msg) from None


class Mesh(Body):
    """A rigid body bounded by a closed triangle surface (solidshell.contact_mesh): read from
    ``file`` (STL/OBJ/PLY/..., relative to the scene file) or built from ``primitives`` with gmsh
    (solidshell.contact_shapes), in ``units`` x ``scale``, turned by ``rotate`` [degrees about x, y,
    z], moved by ``translate`` [cm]; ``spacing``/``band``: its distance grid [cm]."""

    file: Optional[Str] = None
    primitives: Optional[Annotated[list, PlainValidator(_primitives)]] = None
    mesh_size: Optional[Pos] = None  # primitives: the triangles' size [cm]
    units: Optional[Str] = None  # the file's length unit: contact_mesh.UNITS
    scale: Optional[Pos] = None
    rotate: Optional[Vec3] = None
    translate: Optional[Vec3] = None
    spacing: Optional[Pos] = None
    band: Optional[Pos] = None

    @model_validator(mode="after")
    def _source(self):
        from ..contact_mesh import UNITS

        if (self.file is None) == (self.primitives is None):
            raise Bad(
                "file",
                "give a mesh body either file (a surface mesh) or primitives; "
                + ("missing" if self.file is None else "not both"),
            )
        if self.units is not None and self.units not in UNITS:
            raise Bad("units", f"unknown unit {self.units!r} (known: {', '.join(UNITS)})")
        return self


BODIES = {"sphere": Sphere, "plane": Plane, "pedestal": Pedestal, "mesh": Mesh}
Contact = _tagged(
    BODIES,
    lambda d: d.get("type"),
    key="type",
    what="contact body",
    known=", ".join(BODIES),
    missing="sphere, plane, pedestal or mesh",
)

SolverTable = create_model(
    "SolverTable",
    __base__=Table,
    kind=(choice(tuple(KINDS), "solver"), "static"),
    **{k: (SettingsTable, {}) for k in KINDS},
)


class SelfContactTable(Table):
    """``[self_contact]``: whether the sheet's layers push each other apart (solidshell.contact_self_penalty
    in explicit dynamics and relaxation, solidshell.contact_self in the static solver).  A table of its
    own: TOML cannot hold a ``[contact]`` table beside the ``[[contact]]`` array of bodies."""

    enabled: Bool = SELF_CONTACT_DEFAULT


class OutputTable(Table):
    snapshots: Annotated[
        array(NonNeg, "an array of times [s]"), _rule(lambda v: v == sorted(v), "times must be increasing")
    ] = []
    pictures: array(choice(VIEWS, "view"), "an array of views") = ["top", "iso"]


def _own_model(name: str, model, filled: bool):
    """A table its own settings model checks now (``model()`` imports it on demand; its one-line
    message kept): the table as written, or (``filled``) every key with its default ({} = none)."""

    def check(v):
        if not isinstance(v, dict):
            raise ValueError(f"must be a table, got {_got(v)}")
        if not v:
            return {}
        try:
            parsed = parse_model(model(), v, name)
        except InputError as e:
            raise ValueError(str(e).removeprefix(f"{name}: ")) from None
        return parsed.as_dict() if filled else dict(v)

    return Annotated[dict, PlainValidator(check)]


# --------------------------------------------------------------------------- the bodies a scene feels
def recipe_pedestal(geometry: dict, h: float) -> dict | None:
    """The pedestal body a pedestal recipe implies (None for other geometries), every key filled:
    solid, its top face at z = -h/2 under the flat sheet (mid-surface z = 0) with ``offset`` = h/2,
    so the sheet's lower face lies on the top and the clamped mid-surface rim is at gap 0, exactly
    (as the sphere scene's sheet on the sphere top); sharp edge, frictionless, PEDESTAL_HEIGHT high
    or taller, as long as the sheet's skirt can hang (square-on-disc: 35.4 cm; a shorter body
    would let the skirt's corners fold in under its base)."""
    r = PEDESTAL_RECIPES.get(geometry.get("recipe"))
    if r is None:
        return None
    shape, key, gkey = r
    return {
        "type": "pedestal",
        "shape": shape,
        key: float(geometry[gkey]),
        "centre": (0.0, 0.0, -0.5 * h),
        "height": max(PEDESTAL_HEIGHT, round(_skirt_length(geometry), 3)),
        "edge_radius": 0.0,
        "offset": 0.5 * h,
        "friction": 0.0,
        "support": "solid",
        "role": "support",
        "origin": "geometry.recipe",
    }


def _pedestal_bodies(c: dict, implied: dict | None, where: str) -> list[dict]:
    """The resolved body (and, for a Cusick-type support with a clamp, the clamp) of pedestal table
    ``c``: keys it leaves out come from the recipe's pedestal ``implied`` (else square, centre at the
    origin, offset 0).  Bad naming ``where``.key for a table that does not describe a body."""
    d = implied or {"shape": "square", "centre": (0.0, 0.0, 0.0), "offset": 0.0}
    shape = c.get("shape", d["shape"])
    need, other = ("size", "diameter") if shape == "square" else ("diameter", "size")
    if c.get(other) is not None:
        raise Bad(f"{where}.{other}", f"does not apply to a {shape} pedestal")
    extent = c.get(need, d.get(need) if shape == d["shape"] else None)
    if extent is None:
        raise Bad(f"{where}.{need}", f"required for a {shape} pedestal [cm]; missing")
    height = c.get("height")
    height = float(height if height is not None else (implied or {}).get("height", PEDESTAL_HEIGHT))
    er = float(c.get("edge_radius", 0.0))
    support = c.get("support", "solid")
    body = {
        "type": "pedestal",
        "shape": shape,
        need: float(extent),
        "centre": tuple(float(v) for v in c.get("centre", d["centre"])),
        "height": height,
        "edge_radius": er,
        "offset": float(c.get("offset", d["offset"])),
        "friction": float(c.get("friction", 0.0)),
        "support": support,
        "role": "support",
        "origin": where,
    }
    if support == "solid":
        if er >= min(0.5 * extent, 0.5 * height):
            raise Bad(
                f"{where}.edge_radius",
                f"must be smaller than half the pedestal's {need} and half its height, got {er:g}",
            )
        return [body]
    if shape != "disc":
        raise Bad(f"{where}.support", f'a cusick support is a disc (shape = "disc"); this pedestal is {shape}')
    t, sd = float(c["disc_thickness"]), float(c["stem_diameter"])
    if sd > extent:
        raise Bad(
            f"{where}.stem_diameter",
            f"the stem ({sd:g} cm) is wider than the disc (diameter {extent:g} cm); a Cusick-type support's stem must not exceed its disc",
        )
    if t >= height:
        raise Bad(f"{where}.disc_thickness", f"must be smaller than the support's height ({height:g} cm), got {t:g}")
    if er >= min(0.5 * extent, 0.5 * t):
        raise Bad(
            f"{where}.edge_radius", f"must be smaller than half the disc's diameter and half its thickness, got {er:g}"
        )
    cd, ct = c.get("clamp_diameter"), c.get("clamp_thickness")
    body.update(disc_thickness=t, stem_diameter=sd, clamp_diameter=cd, clamp_thickness=ct)
    if cd is None:
        return [body]
    if cd > extent:
        raise Bad(
            f"{where}.clamp_diameter",
            f"the clamp ({cd:g} cm) is wider than the support disc (diameter {extent:g} cm); it would press on the hanging sheet",
        )
    # the clamp lies on the sheet: its lower face as far above the mid-surface as the support's top
    # is below it (offset h/2 each: lower face at z = +h/2 over the recipe's sheet)
    x, y, z = body["centre"]
    off = body["offset"]
    clamp = {
        "type": "pedestal",
        "shape": "disc",
        "diameter": float(cd),
        "centre": (x, y, z + 2.0 * off + float(ct)),
        "height": float(ct),
        "edge_radius": 0.0,
        "offset": off,
        "friction": body["friction"],
        "support": "solid",
        "role": "clamp",
        "origin": f"{where}.clamp",
    }
    return [body, clamp]


MESH_DEFAULTS = {
    "file": None,
    "primitives": None,
    "mesh_size": None,
    "units": "cm",
    "scale": 1.0,
    "rotate": (0.0, 0.0, 0.0),
    "translate": (0.0, 0.0, 0.0),
    "spacing": None,
    "band": None,
}
"""A mesh body's keys left out (None: the body's own default, solidshell.contact_mesh)."""


def resolve_bodies(geometry: dict, material: dict, contact, pedestal_contact: bool = True) -> list[dict]:
    """The contact bodies a scene feels and its pictures show, one dict per body with every key
    filled (Scene.bodies): its [[contact]] tables in order (a Cusick support's clamp right after it),
    then the pedestal its recipe implies (:func:`recipe_pedestal`) unless a table gives a pedestal
    or ``pedestal_contact`` (the file's ``geometry.pedestal_contact``) is false.  ``origin`` names where a body comes from
    ("contact[0]", "contact[0].clamp", "geometry.recipe"); a pedestal's ``role`` is "support" or
    "clamp".  Bad (key, message) for a table that does not describe a body."""
    h = float(make_material(material).thickness)
    implied = recipe_pedestal(geometry, h)
    out: list[dict] = []
    for i, c in enumerate(contact):
        where = f"contact[{i}]"
        base = {"offset": float(c.get("offset", 0.0)), "friction": float(c.get("friction", 0.0)), "origin": where}
        if c["type"] == "sphere":
            out.append({"type": "sphere", "centre": tuple(c["centre"]), "radius": float(c["radius"]), **base})
        elif c["type"] == "plane":
            out.append({"type": "plane", "point": tuple(c["point"]), "normal": tuple(c["normal"]), **base})
        elif c["type"] == "mesh":
            out.append({**MESH_DEFAULTS, **{k: v for k, v in c.items() if k not in ("offset", "friction")}, **base})
        else:
            out += _pedestal_bodies(c, implied, where)
    tables = [i for i, c in enumerate(contact) if c["type"] == "pedestal"]
    if not pedestal_contact:
        if tables:
            raise Bad(
                "geometry.pedestal_contact",
                f"is false (no pedestal body), but contact[{tables[0]}] is a pedestal; remove one of them",
            )
    elif implied is not None and not tables:
        out.append(implied)
    return out


def _adapt_settings():
    from ..adapt.settings import AdaptSettings

    return AdaptSettings


def _perturbation_settings():
    from ..perturbation import PerturbationSettings

    return PerturbationSettings


def _section(v):
    return str(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else v


# --------------------------------------------------------------------------- density strings
_DENSITY_RE = re.compile(r"^\s*\d+(\s*[xX×]\s*\d+)*\s*$")


def _density_problem(density, recipe: str | None) -> str | None:
    if not isinstance(density, str) or not _DENSITY_RE.match(density):
        return f"malformed mesh density {density!r}: expected positive integers joined by 'x', e.g. '48x16x4'"
    parts = [int(p) for p in re.split(r"\s*[xX×]\s*", density.strip())]
    if any(p <= 0 for p in parts):
        return f"malformed mesh density {density!r}: every count must be positive"
    n = RECIPES[recipe].n_fields if recipe in RECIPES else None
    if n is not None and len(parts) != n:
        example = {2: "20x80", 3: "48x16x4"}[n] if n in (2, 3) else "x".join(["10"] * n)
        return f"malformed mesh density {density!r}: recipe {recipe!r} takes {n} counts, e.g. {example!r}"
    return None


def check_density(density: str, recipe: str | None = None, where: str = "mesh density") -> str:
    """Validate a density string like "48x16x4": positive integers joined by 'x', with as many
    factors as the recipe takes.  Returns it normalised ("48x16x4")."""
    problem = _density_problem(density, recipe)
    if problem:
        raise InputError(f"{where}: {problem}")
    return "x".join(str(int(p)) for p in re.split(r"\s*[xX×]\s*", density.strip()))


# --------------------------------------------------------------------------- the scene
class SceneDoc(Table):
    """A scene file, every table validated."""

    name: Annotated[Str, _rule(str.strip, "must not be empty")]
    title: Str
    paper_section: Annotated[str, PlainValidator(_string), BeforeValidator(_section)] = ""
    description: Str = ""
    geometry: Geometry
    mesh: MeshTable = {}
    material: Material = {"fabric": "wool"}
    model: ModelTable = {}
    supports: SupportsTable = {}
    loads: LoadsTable = {}
    contact: array(Contact, "an array of tables ([[contact]])", tables=True) = []
    self_contact: SelfContactTable = {}
    solver: SolverTable = {}
    output: OutputTable = {}
    adapt: _own_model("adapt", _adapt_settings, filled=False) = Field(default_factory=dict)  # §5
    perturbation: _own_model("perturbation", _perturbation_settings, filled=True) = Field(default_factory=dict)

    @model_validator(mode="after")
    def _densities(self):
        """The mesh densities fit the recipe (its number of counts); a mesh file takes none."""
        recipe = self.geometry.recipe if isinstance(self.geometry, RecipeGeometry) else None  # a file: none
        m = self.mesh
        for key, d in (
            ("density", m.density),
            *((f"paper_meshes[{i}]", d) for i, d in enumerate(m.paper_meshes)),
            ("adaptive_level0", m.adaptive_level0),
        ):
            problem = d is not None and _density_problem(d, recipe)
            if problem:
                raise Bad(f"mesh.{key}", problem)
        if recipe is not None and m.density is None:
            raise Bad("mesh.density", f"required for recipe {recipe!r}")
        if recipe is None and m.density is not None:
            raise Bad("mesh.density", "applies to recipe geometries only, not to a mesh file")
        return self

    @model_validator(mode="after")
    def _bodies(self):
        """Every [[contact]] table describes a body once the recipe's pedestal fills its gaps."""
        resolve_bodies(self.geometry.given(), self.material.given(), [c.given() for c in self.contact], self._on())
        return self

    def _on(self) -> bool:
        return getattr(self.geometry, "pedestal_contact", None) is not False

    def tables(self) -> dict:
        """The Scene's fields (every table a plain dict; densities normalised, "48x16x4")."""
        m = self.mesh
        norm = lambda d: None if d is None else check_density(d)  # noqa: E731
        return {
            "name": self.name,
            "title": self.title,
            "paper_section": self.paper_section,
            "description": self.description,
            # the recipe and its mesh parameters; pedestal_contact is a field of its own
            "geometry": {k: v for k, v in self.geometry.given().items() if k != "pedestal_contact"},
            "pedestal_contact": self._on(),
            "mesh": {
                "density": norm(m.density),
                "paper_meshes": [norm(d) for d in m.paper_meshes],
                "adaptive_level0": norm(m.adaptive_level0),
            },
            "material": self.material.given(),
            "model": self.model.as_dict(),
            "supports": self.supports.given(),
            "loads": self.loads.given(),
            "contact": tuple(c.given() for c in self.contact),
            "self_contact": {"enabled": bool(self.self_contact.enabled)},
            "solver": {"kind": self.solver.kind, **{k: dict(getattr(self.solver, k)) for k in KINDS}},
            "output": {"snapshots": list(self.output.snapshots), "pictures": list(self.output.pictures)},
            "adapt": dict(self.adapt),
            "perturbation": dict(self.perturbation),
        }


def parse(data, source: str) -> SceneDoc:
    """The validated scene ``data`` (a TOML table) read from ``source``; one InputError line
    ``source: dotted.key: what is wrong`` if it is not a valid scene."""
    if not isinstance(data, dict):
        raise InputError(f"{source}: (top level): must be a table, got {_got(data)}")
    return parse_model(SceneDoc, data, source, explain=_one_line)
