"""The peer-code scripts' own logic (benchmarks/peers, reference/pedestal_kratos.py) without Kratos:
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
    code = (f"import sys; sys.path.insert(0, {str(ROOT / 'benchmarks' / 'peers')!r}); import kratos_launch as k; "
            f"k.ROOT = {str(tmp_path)!r}; k.require_kratos()")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env={"SOLIDSHELL_KRATOS_PYTHON": str(tmp_path / "none"), "PATH": "/usr/bin:/bin"})
    assert r.returncode == 3
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "KratosMultiphysics not found" in lines[0]
    assert "pip install KratosMultiphysics KratosStructuralMechanicsApplication" in lines[0]


def _rotate(k, v):
    """Rodrigues: rotate the rows of v by the rotation vectors k."""
    ang = np.linalg.norm(k, axis=1)[:, None]
    axis = np.divide(k, ang, out=np.zeros_like(k), where=ang > 0)
    return (v * np.cos(ang) + np.cross(axis, v) * np.sin(ang)
            + axis * np.sum(axis * v, axis=1)[:, None] * (1 - np.cos(ang)))


def test_rotation_vectors_turn_directors_onto_deformed_directors():
    ped = _load(ROOT / "reference" / "pedestal_kratos.py", "reference_pedestal_kratos")
    rng = np.random.default_rng(3)
    n0 = rng.normal(size=(50, 3))
    n0 /= np.linalg.norm(n0, axis=1)[:, None]
    d = 1.7 * rng.normal(size=(50, 3))           # any length: only the direction is used
    d[0] = 2.0 * n0[0]                           # no rotation
    d[1] = -n0[1] + 1e-9 * np.cross(n0[1], [1.0, 0.0, 0.0])   # nearly half a turn
    k = ped.rotation_vectors(n0, d)
    target = d / np.linalg.norm(d, axis=1)[:, None]
    # exact up to round-off in arctan2/cross products of unit vectors: 1e-7 leaves room for the
    # near-half-turn row whose axis is defined by a 1e-9 component
    assert np.allclose(_rotate(k, n0), target, atol=1e-7)
    assert np.allclose(k[0], 0.0)
    # the smallest rotation has no component along the director (no drilling); 1e-7 because the
    # near-half-turn row's axis is the normalised 1e-9 cross product, accurate to ~1e-16 / 1e-9
    assert np.allclose(np.sum(k * n0, axis=1), 0.0, atol=1e-7)
    assert np.allclose(np.sum(k[2:] * n0[2:], axis=1), 0.0, atol=1e-12)
