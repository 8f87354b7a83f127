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

import numpy as np
import scipy.sparse.linalg as spl

from solidshell import IsotropicShell, ShellMesh
from solidshell.boundary import surface_load
from solidshell.model import Model

R, L, PHI, H, E = 25.0, 50.0, np.radians(40.0), 0.25, 4.32e8
REFERENCE = 0.3024
OUT = pathlib.Path(__file__).with_name("out")


def roof(n: int, tri: bool = False) -> ShellMesh:
    x = np.linspace(-L / 2, L / 2, n + 1)
    phi = np.linspace(-PHI, PHI, n + 1)
    Xg, Pg = np.meshgrid(x, phi)
    nodes = np.column_stack([Xg.ravel(), R * np.sin(Pg.ravel()), R * np.cos(Pg.ravel())])
    directors = np.column_stack([np.zeros(Pg.size), np.sin(Pg.ravel()), np.cos(Pg.ravel())])
    a = (np.arange(n)[None, :] + (n + 1) * np.arange(n)[:, None]).ravel()
    q = np.column_stack([a, a + 1, a + n + 2, a + n + 1])      # counter-clockwise about +r
    if tri:
        return ShellMesh(nodes, tris=np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]]), directors=directors)
    return ShellMesh(nodes, quads=q, directors=directors)


def midside_deflection(n: int, tri: bool = False, membrane: str = "full") -> float:
    mesh = roof(n, tri)
    model = Model(mesh, IsotropicShell(E=E, nu=0.0, h=H), membrane=membrane)
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    ends = np.abs(np.abs(mesh.nodes[:, 0]) - L / 2) < 1e-9
    fixed[np.ix_(ends, [1, 2, 4, 5])] = True                   # diaphragm: y, z of U_o and U_n
    P = surface_load(model, 90.0, direction=(0.0, 0.0, -1.0))
    K = model.tangent(np.zeros((mesh.n_nodes, 6)))
    free = np.flatnonzero(~fixed.ravel())
    u = np.zeros(6 * mesh.n_nodes)
    u[free] = spl.spsolve(K[free][:, free].tocsc(), P.ravel()[free])
    edge = np.flatnonzero((np.abs(mesh.nodes[:, 0]) < 1e-9) & (mesh.nodes[:, 1] > R * np.sin(PHI) - 1e-9))
    return float(-u.reshape(-1, 6)[edge[0], 2])


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
