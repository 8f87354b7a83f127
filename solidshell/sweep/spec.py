"""A sweep file (TOML): which scene, which settings vary, how runs are grouped and plotted.

::

    name = "square-pedestal-dc-bending"     # required; names the ledger (an --out folder holds one)
    description = "..."                     # optional
    scene = "square-pedestal"               # a packaged scene or a .toml path (relative to this file)
    mesh = "24x8x4"                         # optional: the scene's density otherwise
    solver = "static"                       # optional: the scene's [solver] kind otherwise

    [set]                                   # --set keys given to every run
    "output.pictures" = ["top"]

    [[case]]                                # optional: alternative groups of settings, each one
    solver = "relax"                        #   crossed with the grid (a case may set mesh/solver)
    "solver.relax.alpha" = 1.0

    [grid]                                  # every combination of these values
    "perturbation.seed" = [0, 1, 2, 3]

    [zip]                                   # varied together (equal lengths): one more grid axis
    "material.bending_warp" = [0.02075, 0.083, 0.332]
    "material.bending_weft" = [0.01575, 0.063, 0.252]

    [sample]                                # OR instead of grid/zip: n random draws (seeded)
    n = 32
    seed = 0
    [sample.axes]
    "solver.relax.alpha" = { uniform = [1.0, 5.0] }
    "material.bending_warp" = { log_uniform = [0.02, 0.3] }
    "perturbation.seed" = { integers = [0, 1000] }      # lo <= k <= hi
    "mesh" = { choice = ["10x40", "20x80"] }

    [classify]                              # state grouping (solidshell.sweep.states)
    dc_tol = 0.01                           # same state: |DC1 - DC2| <= dc_tol
    boundary_tol = 0.03                     #   and projected boundaries within this x mean radius
    symmetry = "auto"                       #   up to this group: auto | C1 | C2 | D2 | D4 | O2

    [plot]                                  # solidshell.sweep.plots
    kind = "states"                         # "states" (fold-count histogram + state gallery) or
    x = "material.bending_warp"             # "curve": y against the axis x (x_ref: x is divided
    x_ref = 0.083                           #   by it, e.g. to plot bending rigidity as a factor)
    y = "drape_coefficient"
    by = "case"                             # curve: one line per case (or an axis key)

Every key other than ``mesh`` and ``solver`` is a dotted scene key, exactly as ``solidshell run
--set`` takes it (``solidshell.scenes.Scene.with_overrides``): rigidities, weight and warp angle
(``material.*``), solver settings (``solver.static.c``, the multiplier constant of Eq. 18;
``solver.relax.alpha``, the damping of Eq. 20), the perturbation (``perturbation.seed``,
``perturbation.amplitude``) and so on.  Every run's scene and solver settings are checked before the
first run starts (one InputError line naming the sweep file, the run and the key).

A run's key is a hash of its scene, mesh, solver and settings: the ledger records each key once,
and a resumed sweep skips the keys it holds.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Optional

import numpy as np
from pydantic import Field

from .. import solvers
from ..errors import InputError
from ..settings import Finite, SettingsModel, parse

__all__ = ["SweepSpec", "Run", "load_spec", "STUDY_DIR", "studies", "ClassifySettings", "PlotSettings"]

STUDY_DIR = Path(__file__).with_name("studies")
MAX_RUNS = 10_000
"""The most runs one sweep may expand to, checked before a point is drawn or a grid expanded: a run
is seconds to minutes of a core, so 10^4 are days of a workstation, and the spec, the task list and
the ledger hold a row each (``sample.n = 1e9`` grew to 4 GB before any run).  Split a larger study
into sweeps with their own ``--out``."""
SPECIAL = ("mesh", "solver")  # run keys that are not scene keys
TOP_KEYS = {
    "name",
    "description",
    "scene",
    "mesh",
    "solver",
    "set",
    "case",
    "grid",
    "zip",
    "sample",
    "classify",
    "plot",
}
DISTRIBUTIONS = ("uniform", "log_uniform", "integers", "choice")


class ClassifySettings(SettingsModel):
    """[classify]: two runs are one state when their fold counts agree, |DC1 - DC2| <= dc_tol and
    their projected boundaries r(theta), compared under the symmetry group, differ by at most
    boundary_tol x the mean radius anywhere."""

    dc_tol: Finite = Field(0.01, gt=0.0, lt=1.0)
    boundary_tol: Finite = Field(0.03, gt=0.0, lt=1.0)
    symmetry: Literal["auto", "C1", "C2", "D2", "D4", "O2"] = "auto"


class PlotSettings(SettingsModel):
    """[plot]: what the sweep's figure shows."""

    kind: Literal["states", "curve"] = "states"
    x: Optional[str] = None
    x_ref: Finite = Field(1.0, gt=0.0)
    x_label: Optional[str] = None
    y: str = "drape_coefficient"
    by: Optional[str] = None
    log_x: bool = False


@dataclass(frozen=True)
class Run:
    """One run of a sweep: its index in the expansion, key, case number and settings."""

    index: int
    key: str
    case: int
    mesh: Optional[str]
    solver: Optional[str]
    overrides: dict  # dotted scene key -> value

    def inputs(self) -> dict:
        """Everything that defines the run (JSON-able)."""
        return {"mesh": self.mesh, "solver": self.solver, **self.overrides}


@dataclass(frozen=True)
class SweepSpec:
    name: str
    description: str
    scene: str  # name or absolute path
    source: str
    runs: tuple
    axes: tuple  # the keys that vary (grid, zip, sample, cases)
    classify: ClassifySettings
    plot: PlotSettings
    raw: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def n_runs(self) -> int:
        return len(self.runs)


def studies() -> list[str]:
    """Names of the sweep files shipped with the package (``solidshell sweep NAME`` runs one)."""
    return sorted(p.stem for p in STUDY_DIR.glob("*.toml"))


def _plain(v):
    """TOML value -> a canonical, JSON-able value (ints stay ints, floats stay floats)."""
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in sorted(v.items())}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def run_key(scene: str, mesh, solver, overrides: dict) -> str:
    """A stable 16-hex-digit key of a run's definition (same definition, same key, anywhere)."""
    blob = json.dumps(
        {"scene": scene, "mesh": mesh, "solver": solver, "set": _plain(overrides)},
        sort_keys=True,
        separators=(",", ":"),
    )
    return hashlib.sha1(blob.encode()).hexdigest()[:16]


def _guard(source, key, n: int) -> None:
    """InputError when the sweep would expand to more than MAX_RUNS runs."""
    if n > MAX_RUNS:
        raise _err(
            source, key, f"{n:,} runs exceed the sweep guard of {MAX_RUNS:,}; split the study into smaller sweeps"
        )


def _err(source, key, msg) -> InputError:
    return InputError(f"{source}: {key}: {msg}")


def _values(source, key, v) -> list:
    if not isinstance(v, list) or not v:
        raise _err(source, key, f"must be a non-empty array of values, got {v!r}")
    return v


def _draw(rng, source, key, dist) -> Any:
    if not isinstance(dist, dict) or len(dist) != 1 or next(iter(dist)) not in DISTRIBUTIONS:
        raise _err(
            source,
            f"sample.axes.{key}",
            f"must be one of {{ uniform = [lo, hi] }}, "
            f"{{ log_uniform = [lo, hi] }}, {{ integers = [lo, hi] }}, {{ choice = [...] }}; got {dist!r}",
        )
    kind, arg = next(iter(dist.items()))
    if kind == "choice":
        vals = _values(source, f"sample.axes.{key}.choice", arg)
        return vals[int(rng.integers(len(vals)))]
    if (
        not isinstance(arg, list)
        or len(arg) != 2
        or not all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a) for a in arg)
        or not arg[0] <= arg[1]
    ):
        raise _err(source, f"sample.axes.{key}.{kind}", f"must be [lo, hi] with lo <= hi, got {arg!r}")
    lo, hi = arg
    if kind == "uniform":
        return float(rng.uniform(lo, hi))
    if kind == "integers":
        if not all(isinstance(a, int) for a in arg):
            raise _err(source, f"sample.axes.{key}.integers", f"bounds must be integers, got {arg!r}")
        return int(rng.integers(lo, hi + 1))
    if lo <= 0:
        raise _err(source, f"sample.axes.{key}.log_uniform", f"bounds must be positive, got {arg!r}")
    return float(np.exp(rng.uniform(math.log(lo), math.log(hi))))


def _split(d: dict) -> tuple:
    """(mesh, solver, scene overrides) of a flat settings dict."""
    rest = {k: v for k, v in d.items() if k not in SPECIAL}
    return d.get("mesh"), d.get("solver"), rest


def load_spec(path_or_name) -> SweepSpec:
    """A sweep by path, or a packaged study by name (:func:`studies`)."""
    s = str(path_or_name)
    p = Path(s)
    if "/" not in s and not s.endswith(".toml"):
        p = STUDY_DIR / f"{s}.toml"
        if not p.is_file():
            raise InputError(
                f"unknown sweep {s!r}; packaged studies: {', '.join(studies())} "
                f"(or give the path of a sweep .toml file)"
            )
    from ..scenes import read_toml

    if not p.is_file():
        raise InputError(f"sweep file not found: {p}")
    return from_dict(read_toml(p), str(p), p.resolve().parent)


def from_dict(data: dict, source: str = "<sweep>", base_dir: Path | None = None) -> SweepSpec:
    """Parse and expand a sweep; every run's scene and solver settings are validated here."""
    for k in data:
        if k not in TOP_KEYS:
            raise _err(source, k, f"unknown key (allowed: {', '.join(sorted(TOP_KEYS))})")
    for req in ("name", "scene"):
        if not isinstance(data.get(req), str) or not data[req].strip():
            raise _err(source, req, "required string is missing")
    name = data["name"]
    scene = data["scene"]
    if "/" in scene or scene.endswith(".toml"):
        sp = Path(scene)
        scene = str(sp if sp.is_absolute() else (base_dir or Path.cwd()) / sp)
    base = {}
    for k in SPECIAL:
        if k in data:
            if not isinstance(data[k], str):
                raise _err(source, k, f"must be a string, got {data[k]!r}")
            base[k] = data[k]
    fixed = data.get("set", {})
    if not isinstance(fixed, dict):
        raise _err(source, "set", "must be a table of key = value")
    base.update(fixed)
    cases = data.get("case", [{}])
    if isinstance(cases, dict):
        cases = [cases]
    if not isinstance(cases, list) or not cases or not all(isinstance(c, dict) for c in cases):
        raise _err(source, "case", "must be an array of tables ([[case]])")
    sample = data.get("sample")
    grid = data.get("grid", {})
    zp = data.get("zip", {})
    if not isinstance(grid, dict) or not isinstance(zp, dict):
        raise _err(source, "grid" if not isinstance(grid, dict) else "zip", "must be a table of key = [values]")
    points: list[dict]
    if sample is not None:
        if grid or zp:
            raise _err(source, "sample", "give [grid]/[zip] or [sample], not both")
        if not isinstance(sample, dict):
            raise _err(source, "sample", "must be a table (n, seed, [sample.axes])")
        for k in sample:
            if k not in ("n", "seed", "axes"):
                raise _err(source, f"sample.{k}", "unknown key (allowed: n, seed, axes)")
        n = sample.get("n")
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise _err(source, "sample.n", f"must be a positive integer, got {n!r}")
        _guard(source, "sample.n", n * len(cases))
        seed = sample.get("seed", 0)
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise _err(source, "sample.seed", f"must be an integer >= 0, got {seed!r}")
        axes = sample.get("axes", {})
        if not isinstance(axes, dict) or not axes:
            raise _err(source, "sample.axes", "must be a non-empty table of key = {distribution}")
        rng = np.random.default_rng(seed)
        points = [{k: _draw(rng, source, k, d) for k, d in axes.items()} for _ in range(n)]
        axis_keys = list(axes)
    else:
        gaxes = [[(k, v) for v in _values(source, f"grid.{k}", vals)] for k, vals in grid.items()]
        zlen = {len(_values(source, f"zip.{k}", v)) for k, v in zp.items()}
        if len(zlen) > 1:
            raise _err(source, "zip", f"every array must have the same length, got lengths {sorted(zlen)}")
        if zp:
            m = zlen.pop()
            gaxes.append([tuple((k, zp[k][i]) for k in zp) for i in range(m)])
        _guard(source, "grid", math.prod(len(a) for a in gaxes) * len(cases))
        points = []
        for combo in itertools.product(*gaxes):
            pt = {}
            for item in combo:
                for k, v in item if isinstance(item[0], tuple) else (item,):
                    pt[k] = v
            points.append(pt)
        axis_keys = list(grid) + list(zp)
    case_keys = sorted({k for c in cases for k in c})
    for k in axis_keys:
        if k in base:
            raise _err(source, k, "is both fixed ([set] or top level) and varied; keep one")
    runs, seen = [], {}
    for ci, c in enumerate(cases):
        for pt in points:
            d = {**base, **c, **pt}
            mesh, solver, over = _split(d)
            key = run_key(scene, mesh, solver, over)
            if key in seen:  # a sample may draw the same point twice: one run
                continue
            seen[key] = len(runs)
            runs.append(Run(index=len(runs), key=key, case=ci, mesh=mesh, solver=solver, overrides=over))
    spec = SweepSpec(
        name=name,
        description=str(data.get("description", "")),
        scene=scene,
        source=source,
        runs=tuple(runs),
        axes=tuple(dict.fromkeys(case_keys + axis_keys)),
        classify=parse(ClassifySettings, data.get("classify"), f"{source}: classify"),
        plot=parse(PlotSettings, data.get("plot"), f"{source}: plot"),
        raw=data,
    )
    check_runs(spec)
    return spec


def check_runs(spec: SweepSpec) -> None:
    """Every run's scene, overrides, mesh density and solver settings, before any work (InputError
    naming the sweep, the run and the problem).  The scene is parsed once per distinct setting set."""
    from ..scenes import check_density, load
    from ..scenes.build import check_solver_settings

    base = load(spec.scene)
    for r in spec.runs:
        where = f"{spec.source}: run {r.index} ({_brief(r.inputs())})"
        try:
            sc = base.with_overrides(r.overrides)
            kind = r.solver or sc.solver["kind"]
            solvers.kind(kind)  # the registry's one-line error for an unknown kind
            if r.mesh is not None:
                check_density(r.mesh, sc.recipe, "mesh")
            check_solver_settings(kind, sc.solver_settings(kind))
        except InputError as e:
            raise InputError(f"{where}: {e}") from None


def _brief(d: dict) -> str:
    return ", ".join(f"{k}={v}" for k, v in d.items() if v is not None)[:120]
