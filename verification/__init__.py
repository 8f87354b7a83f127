"""Verification studies and table scripts (DESIGN.md, Verification).

The checks against independent references are ``solidshell verify`` (the package
``solidshell/verify/``: records, tolerances and the report).  The scripts here print the longer
tables of the same computations (imported from the package) or run studies too long for it, and
write ``verification/out/<name>.json`` (+ a PNG where useful):

* ``python -m verification.plates``   square plate, uniform pressure, vs the Kirchhoff series (all meshes);
* ``python -m verification.locking``  cantilever strips vs beam theory for L/h = 10..10^4;
* ``python -m verification.patch``    membrane and bending patch tests, with the thickness scan;
* ``python -m verification.report``   the three above into ``verification/out/report.md``;
* ``python -m verification.strip``, ``.static_cantilevers``, ``.zero_modes``, ``.scordelis_lo``,
  ``.dynamic_cantilever``, ``.dynamic_relaxation_strip``: the tables behind the corresponding checks;
* ``static_scenes``, ``static_convergence``, ``dynamic_scenes``, ``dynamic_sphere``, ... : studies.

This file re-exports the shared helpers (from solidshell.verify.common) and writes the JSON tables.
"""

from __future__ import annotations

import json
from pathlib import Path

from solidshell.verify.common import buckling_factors, linear_solve, rate, rect_grid, split_quads  # noqa: F401
from solidshell.verify.plates import plate_reference  # noqa: F401
from solidshell.verify.references import reference_dir

OUT = Path(__file__).resolve().parent / "out"
REFERENCE = reference_dir()


def write_json(name: str, data) -> Path:
    OUT.mkdir(exist_ok=True)
    p = OUT / f"{name}.json"
    p.write_text(json.dumps(data, indent=1, default=float))
    return p
