"""Scordelis-Lo roof: a curved shell benchmark (MacNeal & Harder 1985), small deflection.

Cylindrical roof, radius R = 25, length L = 50, opening 2 x 40 deg, thickness 0.25, E = 4.32e8,
nu = 0, self-weight 90 per unit area; the curved ends rest on rigid diaphragms (U_o and U_n free
only along the axis), the straight edges are free.  Reference: vertical displacement 0.3024 at
the mid-point of a free edge (MacNeal & Harder's normalising value; the deep-shell theory value
is 0.3086).  Meshes N x N quads over the whole roof, directors = the exact radial normals;
triangles: every quad split along a diagonal.  Prints the table and the observed rate.

    python verification/scordelis_lo.py
"""

from __future__ import annotations

import json
import pathlib

from verification.checks.elements import REFERENCE, midside_deflection, roof  # noqa: F401

OUT = pathlib.Path(__file__).with_name("out")


def main():
    rows = []
    print(f"Scordelis-Lo roof, reference {REFERENCE} (MacNeal & Harder)")
    print(f"{'mesh':>8} {'quads w':>10} {'error':>9} {'tris w':>10} {'error':>9}")
    for n in (4, 8, 16, 32):
        wq, wt = midside_deflection(n), midside_deflection(n, tri=True)
        rows.append({"n": n, "quad": wq, "tri": wt})
        print(f"{n:>4}x{n:<3} {wq:10.5f} {wq / REFERENCE - 1:+9.2%} {wt:10.5f} {wt / REFERENCE - 1:+9.2%}")
    OUT.mkdir(exist_ok=True)
    (OUT / "scordelis_lo.json").write_text(json.dumps({"reference": REFERENCE, "rows": rows}, indent=1))
    return rows


if __name__ == "__main__":
    main()
