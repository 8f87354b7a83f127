"""Cantilever checks of the static solver against closed forms and a published table.

* End shear: a cantilever (isotropic, nu = 0, L/h = 100, width 1) under a vertical dead tip force
  with P L^2/EI = 1, 4, 10 -- tip deflections against Mattiasson (1981) / Bisshopp & Drucker (1945)
  (reference/elastica.py, which reproduces the table from the elliptic-integral closed form).
* End moment: the end directors rotated by phi (U_n = R(phi) X_n - X_n, displacement control, end
  positions free) roll the strip into a circular arc of radius L/phi; at phi = 2 pi the tip is back
  at the clamp.

Prints the errors for meshes n x 1 (default 8, 16, 32) and writes verification/out/static_cantilevers.json.
Run:  python -m verification.static_cantilevers [--meshes 8 16 32]   (the computations: verification/checks/cantilevers.py)
"""

from __future__ import annotations

import argparse
import json
import os

from verification.checks.cantilevers import large_end_shear as end_shear
from verification.checks.cantilevers import roll_up as end_moment

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=int, nargs="+", default=[8, 16, 32])
    a = ap.parse_args(argv)
    out = {"end_shear": [], "end_moment": []}
    print("end shear (Mattiasson 1981):")
    print(f"{'mesh':>6} {'PL2/EI':>6} {'w/L':>9} {'ref':>8} {'err':>9} {'u/L':>9} {'ref':>8} {'err':>9} {'iters':>6}")
    for n in a.meshes:
        for alpha in (1.0, 4.0, 10.0):
            d = end_shear(n, alpha)
            out["end_shear"].append(d)
            print(
                f"{d['mesh']:>6} {alpha:6g} {d['w_over_L']:9.5f} {d['w_ref']:8.5f} {d['w_rel_error']:9.2e} "
                f"{d['u_over_L']:9.5f} {d['u_ref']:8.5f} {d['u_rel_error']:9.2e} {d['iterations']:6d}",
                flush=True,
            )
    print("end moment (circle of radius L/phi; closure at 2 pi):")
    for n in a.meshes:
        d = end_moment(n)
        out["end_moment"].append(d)
        print(
            f"{d['mesh']:>6}  closure |tip|/L = {d['closure_error_over_L']:.2e}  max tip error along the "
            f"path /L = {d['max_tip_error_over_L_along_path']:.2e}  iterations {d['iterations']}",
            flush=True,
        )
    os.makedirs(os.path.join(HERE, "out"), exist_ok=True)
    with open(os.path.join(HERE, "out", "static_cantilevers.json"), "w") as fh:
        json.dump(out, fh, indent=1)
    return out


if __name__ == "__main__":
    main()
