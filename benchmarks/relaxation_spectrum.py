"""omega_max, omega_min and sqrt(kappa) of M^-1 K at a drape for several mass scalings (issue 13).

A relaxation costs ~sqrt(kappa) = omega_max / omega_min steps whatever its damper (docs/explicit.md,
"Relaxation: dampers, mass scaling and presets"); this prints that number for uniform and director
mass scalings and for Underwood's fictitious Gerschgorin masses (row sums of |K|), with K = the
model tangent at a state (default: the scene's static equilibrium on the mesh, solved first).

    python benchmarks/relaxation_spectrum.py [--scene square-pedestal] [--mesh 24x8x4]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from solidshell.run import run_scene  # noqa: E402
from solidshell.scenes import load  # noqa: E402
from solidshell.scenes.build import build_problem, build_scene_mesh  # noqa: E402
from solidshell.solvers.explicit import scaled_mass  # noqa: E402


def extremes(K, m):
    """(omega_max, omega_min) of K x = omega^2 diag(m) x (ARPACK; shift-invert for the bottom)."""
    d = sp.diags(1.0 / np.sqrt(m))
    A = (d @ K @ d).tocsc()
    lmax = float(eigsh(A, k=1, which="LA", return_eigenvectors=False)[0])
    lmin = float(np.min(eigsh(A, k=3, sigma=-1e-12 * lmax, which="LM", return_eigenvectors=False)))
    return np.sqrt(lmax), np.sqrt(max(lmin, 0.0))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="square-pedestal")
    ap.add_argument("--mesh", default="24x8x4")
    a = ap.parse_args(argv)
    sc = load(a.scene)
    mesh, _ = build_scene_mesh(sc, a.mesh)
    prob = build_problem(sc, mesh)
    U = np.asarray(run_scene(a.scene, mesh=a.mesh, solver="static", out_dir=None, progress=False).U)
    N = mesh.n_nodes
    free = np.flatnonzero(~prob.fixed.ravel())
    Kfull = prob.model.tangent(U).tocsr()
    K = Kfull[free][:, free]
    rows = []
    for mode, s in (("uniform", 1.0), ("director", 1e2), ("director", 1e3), ("director", 1e4), ("director", 1e5)):
        rows.append((f"{mode} x{s:g}", *extremes(K, scaled_mass(prob.model, s, mode).ravel()[free])))
    r = np.abs(Kfull).sum(axis=1).A1
    rows.append(("Gerschgorin row sums per dof", *extremes(K, r[free])))
    print(f"{a.scene} {a.mesh} ({N} nodes), K at the static equilibrium")
    print("| masses | omega_max | omega_min | sqrt(kappa) |\n|---|---|---|---|")
    for name, wmax, wmin in rows:
        print(f"| {name} | {wmax:.4g} | {wmin:.4g} | {wmax / wmin:.0f} |")


if __name__ == "__main__":
    main()
