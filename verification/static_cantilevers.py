"""Cantilever checks of the static solver against closed forms and a published table.

* End shear: a cantilever (isotropic, nu = 0, L/h = 100, width 1) under a vertical dead tip force
  with P L^2/EI = 1, 4, 10 -- tip deflections against Mattiasson (1981) / Bisshopp & Drucker (1945)
  (reference/elastica.py, which reproduces the table from the elliptic-integral closed form).
* End moment: the end directors rotated by phi (U_n = R(phi) X_n - X_n, displacement control, end
  positions free) roll the strip into a circular arc of radius L/phi; at phi = 2 pi the tip is back
  at the clamp.

Prints the errors for meshes n x 1 (default 8, 16, 32) and writes verification/out/static_cantilevers.json.
Run:  python verification/static_cantilevers.py [--meshes 8 16 32]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
_spec = importlib.util.spec_from_file_location("elastica", os.path.join(ROOT, "reference", "elastica.py"))
elastica = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(elastica)

L = 10.0


def _setup(n):
    from solidshell.material import IsotropicShell
    from solidshell.meshing import build_mesh
    from solidshell.model import Model

    mesh = build_mesh("strip", f"{n}x1", length=L, width=1.0)
    mat = IsotropicShell(E=1.2e6, nu=0.0, h=0.1)
    return mesh, mat, Model(mesh, mat)


def end_shear(n, alpha, method="newton"):
    from solidshell.boundary import clamp
    from solidshell.solvers.static import solve_static

    mesh, mat, model = _setup(n)
    tip = mesh.node_set("tip")
    P = np.zeros((mesh.n_nodes, 6))
    P[tip, 2] = -alpha * mat.C_b[0, 0] / L**2 / len(tip)
    r = solve_static(model, clamp(mesh, "clamped"), P, method=method)
    u = r.U[tip].mean(axis=0)
    u_ref, w_ref, _ = elastica.MATTIASSON_1981[alpha]
    return dict(mesh=f"{n}x1", PL2_over_EI=alpha, converged=r.converged,
                w_over_L=-u[2] / L, w_ref=w_ref, w_rel_error=(-u[2] / L - w_ref) / w_ref,
                u_over_L=-u[0] / L, u_ref=u_ref, u_rel_error=(-u[0] / L - u_ref) / u_ref,
                iterations=r.info["iterations"], wall_time_s=r.info["wall_time_s"])


def end_moment(n, steps=32):
    from solidshell.boundary import clamp, director_rotation
    from solidshell.solvers.static import solve_static

    mesh, mat, model = _setup(n)
    tip = mesh.node_set("tip")
    fixed = clamp(mesh, "clamped")
    fixed[tip, 3:] = True

    def prescribed(lam):   # end directors turned by 2 pi lam about -y
        return director_rotation(mesh, tip, (0.0, -1.0, 0.0), 2.0 * np.pi * lam)

    r = solve_static(model, fixed, np.zeros((mesh.n_nodes, 6)),
                     load_factors=np.arange(1, steps + 1) / steps, prescribed=prescribed)
    worst_tip = 0.0
    for lam, U in r.path:
        phi = 2 * np.pi * lam
        Rr = L / phi
        xt = (mesh.nodes + U[:, :3])[tip].mean(axis=0)
        worst_tip = max(worst_tip, np.hypot(xt[0] - Rr * np.sin(phi), xt[2] - Rr * (1 - np.cos(phi))) / L)
    xt = (mesh.nodes + r.U[:, :3])[tip].mean(axis=0)
    return dict(mesh=f"{n}x1", converged=r.converged, closure_error_over_L=float(np.hypot(xt[0], xt[2]) / L),
                max_tip_error_over_L_along_path=float(worst_tip), iterations=r.info["iterations"],
                wall_time_s=r.info["wall_time_s"])


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
            print(f"{d['mesh']:>6} {alpha:6g} {d['w_over_L']:9.5f} {d['w_ref']:8.5f} {d['w_rel_error']:9.2e} "
                  f"{d['u_over_L']:9.5f} {d['u_ref']:8.5f} {d['u_rel_error']:9.2e} {d['iterations']:6d}", flush=True)
    print("end moment (circle of radius L/phi; closure at 2 pi):")
    for n in a.meshes:
        d = end_moment(n)
        out["end_moment"].append(d)
        print(f"{d['mesh']:>6}  closure |tip|/L = {d['closure_error_over_L']:.2e}  max tip error along the "
              f"path /L = {d['max_tip_error_over_L_along_path']:.2e}  iterations {d['iterations']}", flush=True)
    os.makedirs(os.path.join(HERE, "out"), exist_ok=True)
    with open(os.path.join(HERE, "out", "static_cantilevers.json"), "w") as fh:
        json.dump(out, fh, indent=1)
    return out


if __name__ == "__main__":
    main()
