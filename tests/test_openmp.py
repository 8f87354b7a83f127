"""solidshell/openmp.py: ``import solidshell`` sets libgomp's spin count before any OpenMP runtime
loads, and keeps what the user set."""

import os
import subprocess
import sys

import pytest

PRINT = "import solidshell, os; print(os.environ.get('GOMP_SPINCOUNT'))"


@pytest.mark.parametrize(
    "env, expected", [({}, "10000"), ({"GOMP_SPINCOUNT": "5"}, "5"), ({"OMP_WAIT_POLICY": "active"}, "None")]
)
def test_spincount_default_and_the_users_own_settings_win(env, expected):
    base = {k: v for k, v in os.environ.items() if k not in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY")}
    out = subprocess.run([sys.executable, "-c", PRINT], env={**base, **env}, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == expected


def test_the_runtime_is_not_loaded_before_the_setting():
    """libgomp reads its environment once, when it loads: ``import solidshell`` must not load it."""
    code = "import solidshell, sys; print(any('numba' in m or 'scipy' in m for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
