"""The peer-code scripts' own logic (benchmarks/peers: kratos_launch.py, pedestal_kratos.py) without Kratos:
the one-line refusal when Kratos is missing, and the director-to-rotation-vector seed."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def _load(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_missing_kratos_says_so_in_one_line_and_exits_3(tmp_path):
    # No interpreter has Kratos: the environment variable points nowhere, the repository root is
    # an empty folder (no .venv-kratos), and the test's Python lacks Kratos (checked first).
    assert subprocess.run([sys.executable, "-c", "import KratosMultiphysics"], capture_output=True).returncode != 0
    code = (
        f"import sys; sys.path.insert(0, {str(ROOT / 'benchmarks' / 'peers')!r}); import kratos_launch as k; "
        f"k.ROOT = {str(tmp_path)!r}; k.require_kratos()"
    )
    r = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={"SOLIDSHELL_KRATOS_PYTHON": str(tmp_path / "none"), "PATH": "/usr/bin:/bin"},
    )
    assert r.returncode == 3
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "KratosMultiphysics not found" in lines[0]
    assert "pip install KratosMultiphysics KratosStructuralMechanicsApplication" in lines[0]


def test_nodal_rotation_vectors_recover_a_rigid_rotation(monkeypatch):
    # A rigid rotation of the whole pedestal mesh (translations and directors rotated alike) must
    # come back as the same rotation vector at every node, drilling part included.
    from scipy.spatial.transform import Rotation

    from solidshell.meshing import build_mesh

    monkeypatch.syspath_prepend(str(ROOT / "benchmarks" / "peers"))  # its kratos_launch, as when run as a script
    ped = _load(ROOT / "benchmarks" / "peers" / "pedestal_kratos.py", "peers_pedestal_kratos")
    mesh = build_mesh("square_on_square", "6x2x4")
    rv = np.array([0.4, -1.1, 0.7])
    R = Rotation.from_rotvec(rv).as_matrix()
    X = mesh.nodes
    U = np.zeros((mesh.n_nodes, 6))
    U[:, :3] = X @ R.T - X
    U[:, 3:] = mesh.directors @ R.T - mesh.directors
    k = ped.nodal_rotation_vectors(mesh, U)
    # exact up to the SVD's round-off on O(1) matrices
    assert np.allclose(k, rv, atol=1e-10)
    # and no rotation for no deformation
    assert np.allclose(ped.nodal_rotation_vectors(mesh, np.zeros_like(U)), 0.0, atol=1e-12)
