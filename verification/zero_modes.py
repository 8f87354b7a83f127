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

from solidshell import IsotropicShell
from solidshell.model import Model
from verification.checks.elements import distorted_patch as patch

OUT = pathlib.Path(__file__).with_name("out")


def main():
    mat = IsotropicShell(E=1.0e4, nu=0.3, h=0.01)
    rows = []
    print(f"{'mesh':<14}{'zero modes':>11}   eigenvalues 1..8 / max eigenvalue")
    for n, kind in [
        (1, "quad"),
        (1, "tri"),
        (2, "quad"),
        (2, "tri"),
        (2, "mixed"),
        (4, "quad"),
        (4, "tri"),
        (4, "mixed"),
    ]:
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
