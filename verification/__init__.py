"""Verification studies and table scripts (DESIGN.md, Verification).

The checks against independent references are ``solidshell verify``: the subpackage
``verification.checks`` (records, tolerances, the checks by topic, the runner and the report), with
the stored reference data in the package ``reference``.  The scripts here print the longer tables
of the same computations (imported from ``verification.checks``) or run studies too long for it,
and write ``verification/out/<name>.json`` (+ a PNG where useful; out/ is not part of the wheel):

* ``python -m verification.plates``   square plate, uniform pressure, vs the Kirchhoff series (all meshes);
* ``python -m verification.locking``  cantilever strips vs beam theory for L/h = 10..10^4;
* ``python -m verification.patch``    membrane and bending patch tests, with the thickness scan;
* ``python -m verification.report``   the three above into ``verification/out/report.md``;
* ``python -m verification.strip``, ``.static_cantilevers``, ``.zero_modes``, ``.scordelis_lo``,
  ``.dynamic_cantilever``, ``.dynamic_relaxation_strip``: the tables behind the corresponding checks;
* ``static_scenes``, ``static_convergence``, ``dynamic_scenes``, ``dynamic_sphere``, ... : studies.

This file writes the JSON tables and re-exports the shared helpers (``verification.checks.common``,
``plate_reference``, ``REFERENCE``: the reference folder) on first use, so that importing
``verification.checks`` (``solidshell verify``) does not load the element kernels through it.
"""

from __future__ import annotations

import json
from pathlib import Path

OUT = Path(__file__).resolve().parent / "out"

_LAZY = {
    "buckling_factors": "common",
    "linear_solve": "common",
    "rate": "common",
    "rect_grid": "common",
    "split_quads": "common",
    "plate_reference": "plates",
}


def write_json(name: str, data) -> Path:
    OUT.mkdir(exist_ok=True)
    p = OUT / f"{name}.json"
    p.write_text(json.dumps(data, indent=1, default=float))
    return p


def __getattr__(name):
    # PEP 562: the helpers the table scripts import from here, loaded when first asked for
    import importlib

    if name in _LAZY:
        return getattr(importlib.import_module(f"{__name__}.checks.{_LAZY[name]}"), name)
    if name == "REFERENCE":
        from .checks.references import reference_dir

        return reference_dir()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
