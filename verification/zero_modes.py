"""Zero-energy modes of undeformed flat elements and patches (issue 3).

Prints the smallest eigenvalues of the tangent K(U=0) for one quad, one triangle, distorted 2x2 and
4x4 patches of quads, of triangles, and mixed, relative to the largest eigenvalue.  A correct
element has exactly six zero eigenvalues (rigid-body modes) and no spurious mechanism.

    python verification/zero_modes.py
"""

from __future__ import annotations

import json
import pathlib

import numpy as np

from solidshell import IsotropicShell, ShellMesh
from solidshell.model import Model

OUT = pathlib.Path(__file__).with_name("out")


def patch(n: int, kind: str, distort: float = 0.3) -> ShellMesh:
    x = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(x, x)
    P = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    inner = (P[:, 0] > 0) & (P[:, 0] < 1) & (P[:, 1] > 0) & (P[:, 1] < 1)
    P[inner, :2] += distort / n * np.random.default_rng(1).uniform(-1, 1, (inner.sum(), 2))
    a = (np.arange(n)[None, :] + (n + 1) * np.arange(n)[:, None]).ravel()
    q = np.column_stack([a, a + 1, a + n + 2, a + n + 1])
    if kind == "quad":
        return ShellMesh(P, quads=q)
    t = np.vstack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    if kind == "tri":
        return ShellMesh(P, tris=t)
    half = len(q) // 2 if len(q) > 1 else 0          # mixed: first half quads, rest split
    rest = q[half:]
    return ShellMesh(P, quads=q[:half], tris=np.vstack([rest[:, [0, 1, 2]], rest[:, [0, 2, 3]]]))


def main():
    mat = IsotropicShell(E=1.0e4, nu=0.3, h=0.01)
    rows = []
    print(f"{'mesh':<14}{'zero modes':>11}   eigenvalues 1..8 / max eigenvalue")
    for n, kind in [(1, "quad"), (1, "tri"), (2, "quad"), (2, "tri"), (2, "mixed"), (4, "quad"),
                    (4, "tri"), (4, "mixed")]:
        mesh = patch(n, kind)
        K = Model(mesh, mat).tangent(np.zeros((mesh.n_nodes, 6))).toarray()
        ev = np.linalg.eigvalsh(K)
        rel = ev / ev.max()
        nzero = int(np.sum(np.abs(rel) < 1e-10))
        name = f"{n}x{n} {kind}"
        print(f"{name:<14}{nzero:>11}   " + " ".join(f"{v:9.2e}" for v in rel[:8]))
        rows.append({"mesh": name, "zero_modes": nzero, "smallest_relative_eigenvalues": rel[:8].tolist()})
    OUT.mkdir(exist_ok=True)
    (OUT / "zero_modes.json").write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
