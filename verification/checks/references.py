"""Where the stored reference data live, how to load them, and the regenerate-and-compare command.

The data and the scripts that make them are the package ``reference`` (the repository's
``reference/`` folder; the wheel ships its JSON and Markdown files with it), found through
``importlib.resources`` -- the same in a checkout's editable install and in an installed wheel.
``SOLIDSHELL_REFERENCE_DIR`` points at another folder laid out alike (its scripts are then loaded
by file path).  None of the generating scripts imports solidshell.

``solidshell verify --references [--quick]`` regenerates every stored reference file into a
temporary folder and compares it with the stored one, number by number (tolerances in
:data:`REGENERATED`): it fails when a stored value no longer follows from its script.
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import math
import os
import sys
import tempfile
import time
from functools import lru_cache
from importlib import resources
from pathlib import Path

from solidshell.errors import InputError

ENV = "SOLIDSHELL_REFERENCE_DIR"


def reference_dir() -> Path:
    """The folder of the reference data: ``$SOLIDSHELL_REFERENCE_DIR``, else the installed package
    ``reference`` (a real folder: wheels and editable installs are not zipped)."""
    env = os.environ.get(ENV)
    p = Path(env) if env else Path(resources.files("reference"))
    if not p.is_dir():
        raise InputError(
            f"reference data folder {p} not found ({ENV} must name a folder laid out like the package reference/)"
        )
    return p


@lru_cache(maxsize=None)
def module(name: str):
    """The reference script ``reference/<name>.py`` as a module (elastica, beams, kirchhoff_plate):
    ``reference.<name>``, or the file in ``$SOLIDSHELL_REFERENCE_DIR`` when that is set."""
    if not os.environ.get(ENV):
        return importlib.import_module(f"reference.{name}")
    path = reference_dir() / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"solidshell_reference_{name}", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


@lru_cache(maxsize=None)
def _json(name: str):
    return json.loads((reference_dir() / name).read_text())


def load(name: str):
    """A stored JSON reference file by name (``elastica_strip.json``, ``plates.json``, ...)."""
    return _json(name)


def elastica_strip() -> dict:
    """The heavy elastica of the wool strips (reference/elastica.py -> elastica_strip.json)."""
    return load("elastica_strip.json")


def plates() -> dict:
    """The square Kirchhoff plate (reference/kirchhoff_plate.py -> plates.json)."""
    return load("plates.json")


# --------------------------------------------------------------------------- regenerate + compare
# Ignored keys are bookkeeping (timings, interpreter version, command line).  Tolerances: the
# elastica is an ODE solved to 1e-10 (solve_bvp) and agrees with shooting to 2e-12, so a rerun
# reproduces it to ~1e-12; 1e-9 admits another BLAS/scipy, a changed equation moves it >1e-4.  The
# plate series are sums of fixed terms (1e-12); the scikit-fem tables are direct solves whose
# round-off is ~1e-8 relative on the finest Argyris mesh (plates.md), hence 1e-6 on them.
IGNORE = {"seconds", "python", "generated_by"}
REGENERATED = {
    "elastica_strip.json": {"script": "elastica.py", "rtol": 1e-9, "atol": 1e-9},
    "plates.json": {
        "script": "kirchhoff_plate.py",
        "rtol": 1e-6,
        "atol": 1e-12,
        # extrapolated from the two finest meshes, which a quick regeneration leaves out
        "quick_ignore": {"morley_richardson"},
    },
}


def compare_json(old, new, rtol: float, atol: float, path: str = "", ignore=frozenset()) -> list[str]:
    """Differences between two JSON trees beyond |a - b| <= atol + rtol |a| (numbers); keys and
    lengths must match, except that ``new`` may hold fewer rows of a list of tables (a quick
    regeneration computes the coarser meshes only: those are compared); keys in ``ignore`` are
    skipped at any depth."""
    out = []
    if isinstance(old, dict) and isinstance(new, dict):
        for k in sorted(set(old) | set(new)):
            if k in IGNORE or k in ignore:
                continue
            if k not in old or k not in new:
                out.append(f"{path}/{k}: {'missing in the regenerated file' if k in old else 'new key'}")
                continue
            out += compare_json(old[k], new[k], rtol, atol, f"{path}/{k}", ignore)
    elif isinstance(old, list) and isinstance(new, list):
        rows = all(isinstance(x, dict) for x in old + new)
        if len(old) != len(new) and not (rows and len(new) < len(old)):
            return [f"{path}: {len(old)} items stored, {len(new)} regenerated"]
        for i, (a, b) in enumerate(zip(old, new)):
            out += compare_json(a, b, rtol, atol, f"{path}[{i}]", ignore)
    elif isinstance(old, bool) or isinstance(new, bool) or old is None or new is None:
        if old != new:
            out.append(f"{path}: stored {old!r}, regenerated {new!r}")
    elif isinstance(old, (int, float)) and isinstance(new, (int, float)):
        if not (abs(old - new) <= atol + rtol * abs(old) or (math.isnan(old) and math.isnan(new))):
            out.append(f"{path}: stored {old!r}, regenerated {new!r}")
    elif old != new:
        out.append(f"{path}: stored {old!r}, regenerated {new!r}")
    return out


def _regenerate(name: str, out: Path, quick: bool) -> None:
    if name == "elastica_strip.json":
        module("elastica").generate(str(out))
    elif name == "plates.json":
        import contextlib
        import io

        with contextlib.redirect_stdout(io.StringIO()):  # its own convergence table
            module("kirchhoff_plate").main(["--out", str(out)] + (["--quick"] if quick else []))
    else:  # pragma: no cover - table above
        raise KeyError(name)


def check_references(quick: bool = False, log=print, names=None) -> list[dict]:
    """Regenerate every stored reference file (or those in ``names``) and compare; one dict per
    file: {file, script, passed, differences, wall_time_s} (passed None: could not be regenerated).
    ``quick`` skips the finest scikit-fem meshes of plates.json (the coarser rows are compared)."""
    ref = reference_dir()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, spec in REGENERATED.items():
            if names is not None and name not in names:
                continue
            t0 = time.perf_counter()
            out = Path(tmp) / name
            try:
                _regenerate(name, out, quick)
                diffs = compare_json(
                    json.loads((ref / name).read_text()),
                    json.loads(out.read_text()),
                    spec["rtol"],
                    spec["atol"],
                    ignore=spec.get("quick_ignore", frozenset()) if quick else frozenset(),
                )
            except Exception as exc:  # noqa: BLE001 - a script that fails is a changed reference
                diffs = [f"regeneration failed: {type(exc).__name__}: {exc}"]
            row = {
                "file": f"reference/{name}",
                "script": f"reference/{spec['script']}",
                "rtol": spec["rtol"],
                "atol": spec["atol"],
                "passed": not diffs,
                "differences": diffs,
                "wall_time_s": time.perf_counter() - t0,
            }
            rows.append(row)
            log(
                f"{row['file']:<32} from {row['script']:<28} {'unchanged' if not diffs else 'CHANGED'}"
                f" (rtol {spec['rtol']:g}, atol {spec['atol']:g}; {row['wall_time_s']:.1f} s)"
            )
            for d in diffs[:10]:
                log(f"    {d}")
    kratos = ref / "pedestal_kratos.json"
    if kratos.exists() and (names is None or kratos.name in names):
        # made by KratosMultiphysics (an optional, heavy dependency): regenerated only where it is
        # installed, by the script the file names
        try:
            import KratosMultiphysics  # noqa: F401

            have = True
        except ImportError:
            have = False
        log(
            f"reference/pedestal_kratos.json{'':<3} not regenerated: "
            + (
                "run its generating script (KratosMultiphysics is installed)"
                if have
                else "KratosMultiphysics is not installed"
            )
        )
        rows.append(
            {
                "file": "reference/pedestal_kratos.json",
                "script": None,
                "passed": None,
                "differences": [],
                "wall_time_s": 0.0,
            }
        )
    return rows
