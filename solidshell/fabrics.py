"""The fabric library (fabrics by name, from their published measurements) and the KES-FB conversion.

The library is data, not code: ``solidshell/fabrics.toml`` (package data) holds each fabric's
source and its measured quantities as published, either as the resultant rigidities the material
model takes (:class:`~solidshell.material.Fabric`, the paper's Table 1 form) or as Kawabata KES-FB
quantities, which :func:`from_kes` converts.  A scene names a fabric with ``[material] fabric =
"NAME"`` or gives its own KES data with ``[material] kes = {...}``; ``solidshell fabrics`` lists
the library.

KES-FB quantities and their conversion (docs/fabrics.md)
--------------------------------------------------------
The material model (Eq. 7, Table 1) takes resultants per unit width: tensile and shear rigidities
[gf/cm], bending and torsional rigidities [gf*cm^2/cm], weight per area [gf/cm^2], thickness [cm].

``B_warp``, ``B_weft`` [gf*cm^2/cm]
    KES-FB2 bending rigidity: bending moment per unit width per unit curvature, the resultant C_b
    acts with.  Taken as it is (factor 1): ``bending_warp = B_warp`` for curvature along the warp.
    In SI, 1 gf*cm^2/cm = 9.80665e-5 N*m (:data:`GF_CM2_PER_CM_IN_SI`).
``G`` [gf/(cm*deg)]
    KES-FB1 shear rigidity: shear force per unit width per *degree* of shear angle.  The model's
    shear rigidity acts on the engineering shear strain gamma (radians; tan(phi) ~ phi at the
    small angles KES fits G over), so ``shear = G * 180/pi`` = 57.2958 G [gf/cm]
    (:data:`SHEAR_PER_DEG`).
``W`` [mg/cm^2]
    KES-FB weight per area (1 mg/cm^2 = 10 g/m^2).  A mass of 1 mg weighs 1e-3 gf under standard
    gravity, so ``weight = W * 1e-3`` [gf/cm^2] (:data:`WEIGHT_PER_MG_CM2`).
``T`` [mm]
    KES-FB3 thickness (at 0.5 gf/cm^2): ``thickness = T / 10`` [cm].
tensile rigidity [gf/cm], per direction (``_warp``, ``_weft``): one of
    ``tensile_warp`` -- an initial (small-strain) modulus per unit width, as the paper's Table 1
    gives it; or KES-FB1's tensile test to the maximum load ``Fm`` (default 500 gf/cm, the
    standard setting for woven fabrics): ``EMT_warp`` [%] the strain at Fm with ``WT_warp``
    [gf*cm/cm^2] the tensile energy to EMT, giving the linear rigidity that stores the same energy
    over the same strain, 2 WT / EMT^2 (EMT as a fraction); or with ``LT_warp`` [-] the linearity
    WT / (Fm EMT / 2), giving the same quantity as LT Fm / EMT.  Fabrics stiffen in tension, so
    this exceeds the initial modulus; a drape barely feels it (membrane strains stay ~1e-4 while
    bending and shear shape the folds), but a stiffer membrane shortens the explicit time step.
``torsion`` [gf*cm^2/cm], optional
    KES measures no torsional rigidity.  Default ``TORSION_FACTOR * sqrt(B_warp B_weft)`` with
    TORSION_FACTOR = 0.5: the M_xy = D (1 - nu)/2 gamma_xy of a plate with nu = 0 (the model's
    default coupling), with Huber's geometric mean standing for D of an orthotropic plate.

Every KES value must be positive and inside a range no fabric measurement leaves
(:data:`KES_KEYS`: e.g. B in [1e-4, 100] gf*cm^2/cm, W in [0.5, 1000] mg/cm^2); a value outside is
a one-line :class:`~solidshell.errors.InputError` naming the key (most often the value was given
in other units).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from functools import cache
from importlib import resources
from typing import Any, Mapping

from .errors import InputError
from .material import FABRIC_FIELDS, Fabric
from .units import CM_IN_M, GF_IN_N

__all__ = [
    "KES_KEYS",
    "SHEAR_PER_DEG",
    "WEIGHT_PER_MG_CM2",
    "THICKNESS_PER_MM",
    "FM_DEFAULT",
    "TORSION_FACTOR",
    "GF_CM2_PER_CM_IN_SI",
    "LibraryFabric",
    "check_kes_value",
    "from_kes",
    "to_kes",
    "library",
    "names",
    "fabric",
]

SHEAR_PER_DEG = 180.0 / math.pi
"""KES G [gf/(cm*deg)] -> shear rigidity [gf/cm] per unit (radian) shear strain: x 57.2958."""
WEIGHT_PER_MG_CM2 = 1.0e-3
"""KES W [mg/cm^2] -> weight per area [gf/cm^2] (1 mg weighs 1e-3 gf at standard gravity)."""
THICKNESS_PER_MM = 0.1
"""KES T [mm] -> thickness [cm]."""
FM_DEFAULT = 500.0
"""KES-FB1's maximum tensile load Fm [gf/cm] for woven fabrics, the EMT/LT/WT reference (kes.Fm)."""
TORSION_FACTOR = 0.5
"""torsion = TORSION_FACTOR * sqrt(B_warp * B_weft) when the KES data give none (nu = 0 plate)."""
GF_CM2_PER_CM_IN_SI = GF_IN_N * CM_IN_M
"""1 gf*cm^2/cm in N*m (9.80665e-5): the SI value of a bending rigidity per unit width."""


@dataclass(frozen=True)
class KesKey:
    """One KES quantity a ``kes`` table may give: its unit, meaning and plausible range."""

    unit: str
    what: str
    lo: float
    hi: float


KES_KEYS: dict[str, KesKey] = {
    "B_warp": KesKey("gf*cm^2/cm", "bending rigidity, curvature along the warp (KES-FB2)", 1e-4, 100.0),
    "B_weft": KesKey("gf*cm^2/cm", "bending rigidity, curvature along the weft (KES-FB2)", 1e-4, 100.0),
    "G": KesKey("gf/(cm*deg)", "shear rigidity (KES-FB1)", 1e-3, 100.0),
    "W": KesKey("mg/cm^2", "weight per area (10 g/m^2 = 1 mg/cm^2)", 0.5, 1000.0),
    "T": KesKey("mm", "thickness (KES-FB3, at 0.5 gf/cm^2)", 0.01, 50.0),
    "tensile_warp": KesKey("gf/cm", "initial tensile rigidity, warp", 1.0, 1.0e6),
    "tensile_weft": KesKey("gf/cm", "initial tensile rigidity, weft", 1.0, 1.0e6),
    "EMT_warp": KesKey("%", "tensile strain at Fm, warp (KES-FB1)", 0.05, 100.0),
    "EMT_weft": KesKey("%", "tensile strain at Fm, weft (KES-FB1)", 0.05, 100.0),
    "WT_warp": KesKey("gf*cm/cm^2", "tensile energy to EMT, warp (KES-FB1)", 0.01, 1000.0),
    "WT_weft": KesKey("gf*cm/cm^2", "tensile energy to EMT, weft (KES-FB1)", 0.01, 1000.0),
    "LT_warp": KesKey("-", "tensile linearity, warp (KES-FB1)", 0.05, 2.0),
    "LT_weft": KesKey("-", "tensile linearity, weft (KES-FB1)", 0.05, 2.0),
    "Fm": KesKey("gf/cm", "maximum tensile load of the KES-FB1 test", 1.0, 5000.0),
    "torsion": KesKey(
        "gf*cm^2/cm", "torsional rigidity (not a KES quantity; default 0.5 sqrt(B_warp B_weft))", 1e-5, 100.0
    ),
}
"""The keys of a ``[material] kes`` table (docs/fabrics.md).  Ranges: generous bounds round what
apparel and technical fabrics measure; a value outside them is refused as a likely unit slip."""
_REQUIRED = ("B_warp", "B_weft", "G", "W", "T")


def check_kes_value(key: str, value: Any) -> float:
    """``value`` of KES key ``key`` as a float, or a one-line InputError naming ``kes.key``."""
    spec = KES_KEYS.get(key)
    if spec is None:
        raise InputError(f"kes.{key}: unknown KES key (known: {', '.join(KES_KEYS)})")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"kes.{key}: must be a number [{spec.unit}], got {value!r}")
    v = float(value)
    if not math.isfinite(v) or v <= 0.0:
        raise InputError(f"kes.{key}: must be positive and finite [{spec.unit}], got {value!r}")
    if not spec.lo <= v <= spec.hi:
        raise InputError(
            f"kes.{key}: {v:g} {spec.unit} is outside [{spec.lo:g}, {spec.hi:g}] {spec.unit}, the range of a "
            f"{spec.what} (other units?)"
        )
    return v


def _tensile(k: dict, d: str) -> float:
    """The tensile rigidity [gf/cm] along direction ``d`` ("warp"/"weft") of checked KES values."""
    direct, emt, wt, lt = (k.get(f"{q}_{d}") for q in ("tensile", "EMT", "WT", "LT"))
    if direct is not None:
        extra = [f"{q}_{d}" for q in ("EMT", "WT", "LT") if k.get(f"{q}_{d}") is not None]
        if extra:
            raise InputError(f"kes.{extra[0]}: give either tensile_{d} or the KES tensile test (EMT_{d} ...), not both")
        return direct
    if emt is None:
        bad = next((f"{q}_{d}" for q in ("WT", "LT") if k.get(f"{q}_{d}") is not None), None)
        if bad:
            raise InputError(f"kes.EMT_{d}: required with {bad} (the strain at Fm [%]); missing")
        raise InputError(
            f"kes.tensile_{d}: missing: give tensile_{d} [gf/cm] or EMT_{d} [%] with WT_{d} [gf*cm/cm^2] or LT_{d}"
        )
    eps = emt / 100.0
    if wt is not None:
        if lt is not None:
            raise InputError(f"kes.LT_{d}: give WT_{d} or LT_{d}, not both (each fixes the rigidity with EMT_{d})")
        return 2.0 * wt / eps**2
    if lt is None:
        raise InputError(f"kes.WT_{d}: required with EMT_{d} (or LT_{d}); missing")
    return lt * k.get("Fm", FM_DEFAULT) / eps


def from_kes(kes: Mapping[str, Any]) -> dict:
    """The :class:`~solidshell.material.Fabric` fields (gf-cm-s) of KES-FB data ``kes`` (keys of
    :data:`KES_KEYS`, in KES units).  One-line InputError naming ``kes.KEY`` for a missing,
    unknown, non-positive or implausible value."""
    if not isinstance(kes, Mapping):
        raise InputError(f"kes: must be a table of KES quantities, got {kes!r}")
    k = {key: check_kes_value(key, v) for key, v in kes.items()}
    for key in _REQUIRED:
        if key not in k:
            raise InputError(f"kes.{key}: required ({KES_KEYS[key].what} [{KES_KEYS[key].unit}]); missing")
    bw, bf = k["B_warp"], k["B_weft"]
    return {
        "tensile_warp": _tensile(k, "warp"),
        "tensile_weft": _tensile(k, "weft"),
        "shear": k["G"] * SHEAR_PER_DEG,
        "bending_warp": bw,
        "bending_weft": bf,
        "torsion": k.get("torsion", TORSION_FACTOR * math.sqrt(bw * bf)),
        "weight": k["W"] * WEIGHT_PER_MG_CM2,
        "thickness": k["T"] * THICKNESS_PER_MM,
    }


def to_kes(fab: Fabric) -> dict:
    """A Fabric's rigidities in KES units (B, G, W, T, initial tensile rigidity, torsion): the
    inverse of :func:`from_kes` for data given by initial tensile rigidities."""
    return {
        "B_warp": fab.bending_warp,
        "B_weft": fab.bending_weft,
        "G": fab.shear / SHEAR_PER_DEG,
        "W": fab.weight / WEIGHT_PER_MG_CM2,
        "T": fab.thickness / THICKNESS_PER_MM,
        "tensile_warp": fab.tensile_warp,
        "tensile_weft": fab.tensile_weft,
        "torsion": fab.torsion,
    }


# --------------------------------------------------------------------------- the library
@dataclass(frozen=True)
class LibraryFabric:
    """One fabric of the library: its source and its quantities as published (``kind``:
    "rigidities" or "kes"), the Fabric fields they give, and a measured drape if the source has one."""

    name: str
    title: str
    source: str
    table: str
    kind: str
    published: dict
    fields: dict
    note: str = ""
    drape: dict = field(default_factory=dict)

    def fabric(self, **overrides) -> Fabric:
        """The Fabric (gf-cm-s); keywords override fields (e.g. warp_angle=90)."""
        return Fabric(**{**self.fields, "name": self.name, **overrides})


_ENTRY_KEYS = {"title", "source", "table", "note", "rigidities", "kes", "drape"}
_DRAPE_KEYS = {"dc", "specimen_diameter", "disc_diameter", "source"}


def _entry(name: str, e: Any, where: str) -> LibraryFabric:
    if not isinstance(e, dict):
        raise InputError(f"{where}: [{name}] must be a table")
    unknown = sorted(set(e) - _ENTRY_KEYS)
    if unknown:
        raise InputError(f"{where}: {name}.{unknown[0]}: unknown key (allowed: {', '.join(sorted(_ENTRY_KEYS))})")
    for key in ("title", "source", "table"):
        if not isinstance(e.get(key), str) or not e[key].strip():
            raise InputError(f"{where}: {name}.{key}: required text; missing")
    if ("rigidities" in e) == ("kes" in e):
        raise InputError(f"{where}: {name}: give exactly one of [{name}.rigidities] or [{name}.kes]")
    kind = "kes" if "kes" in e else "rigidities"
    published = dict(e[kind])
    try:
        if kind == "kes":
            fields = from_kes(published)
        else:
            bad = sorted(set(published) - set(FABRIC_FIELDS))
            if bad:
                raise InputError(f"rigidities.{bad[0]}: unknown field (known: {', '.join(FABRIC_FIELDS)})")
            fields = published
        Fabric(**fields)  # checked now: every entry of the file builds
    except InputError as exc:
        raise InputError(f"{where}: {name}: {exc}") from None
    drape = dict(e.get("drape", {}))
    if drape:
        _check_drape(drape, f"{where}: {name}.drape")
    return LibraryFabric(
        name, e["title"], e["source"], e["table"], kind, published, dict(fields), e.get("note", ""), drape
    )


def _check_drape(d: dict, where: str) -> None:
    """A measured drape: its DC in (0, 1], specimen and disc diameters [cm] with disc < specimen, a source."""
    odd = sorted(set(d) ^ _DRAPE_KEYS)  # keys given but unknown, or known but missing
    if odd:
        raise InputError(f"{where}.{odd[0]}: " + ("unknown key" if odd[0] in d else "required; missing"))
    for key in ("dc", "specimen_diameter", "disc_diameter"):
        v = d[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0.0:
            raise InputError(f"{where}.{key}: must be a positive number, got {v!r}")
    if d["dc"] > 1.0:
        raise InputError(f"{where}.dc: a drape coefficient is at most 1, got {d['dc']!r}")
    if d["disc_diameter"] >= d["specimen_diameter"]:
        raise InputError(f"{where}.disc_diameter: must be smaller than specimen_diameter, got {d['disc_diameter']!r}")
    if not isinstance(d["source"], str) or not d["source"].strip():
        raise InputError(f"{where}.source: required text; missing")


def load_library(text: str, where: str = "fabrics.toml") -> dict[str, LibraryFabric]:
    """The library of a TOML text (the format of solidshell/fabrics.toml), checked entry by entry."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{where}: not valid TOML: {exc}") from None
    return {name: _entry(name, e, where) for name, e in data.items()}


@cache
def library() -> dict[str, LibraryFabric]:
    """The packaged library (solidshell/fabrics.toml), by name, in file order."""
    text = resources.files("solidshell").joinpath("fabrics.toml").read_text(encoding="utf-8")
    return load_library(text, "solidshell/fabrics.toml")


def names() -> tuple[str, ...]:
    """The library's fabric names, in file order."""
    return tuple(library())


def fabric(name: str, **overrides) -> Fabric:
    """The library fabric ``name`` as a Fabric; keywords override fields."""
    lib = library()
    if name not in lib:
        raise InputError(f"unknown fabric {name!r} (known: {', '.join(lib)})")
    return lib[name].fabric(**overrides)


# --------------------------------------------------------------------------- listings (solidshell fabrics)
def listing() -> list[str]:
    """The lines ``solidshell fabrics`` prints: one row per fabric in KES units, then the sources."""
    head = ("name", "B warp/weft", "G", "shear", "W", "T", "tensile warp/weft", "torsion", "DC measured")
    units = ("", "gf*cm^2/cm", "gf/(cm*deg)", "gf/cm", "mg/cm^2", "mm", "gf/cm", "gf*cm^2/cm", "")
    rows = [head, units]
    for f in library().values():
        k = to_kes(f.fabric())
        dc = f"{f.drape['dc']:.3g}" if "dc" in f.drape else "-"
        rows.append(
            (
                f.name,
                f"{k['B_warp']:.4g} / {k['B_weft']:.4g}",
                f"{k['G']:.4g}",
                f"{f.fields['shear']:.4g}",
                f"{k['W']:.4g}",
                f"{k['T']:.4g}",
                f"{k['tensile_warp']:.5g} / {k['tensile_weft']:.5g}",
                f"{k['torsion']:.4g}",
                dc,
            )
        )
    w = [max(len(r[i]) for r in rows) for i in range(len(head))]
    lines = ["  ".join(f"{c:<{w[i]}}" for i, c in enumerate(r)).rstrip() for r in rows]
    lines.append("")
    for f in library().values():
        lines.append(
            f"{f.name}: {f.title}; as published ({f.kind}): "
            + ", ".join(f"{k} = {v:g}" for k, v in f.published.items())
        )
        lines.append(f"  source: {f.source}")
        lines.append(f"  where: {f.table}")
        if f.note:
            lines.append(f"  note: {f.note}")
    return lines
