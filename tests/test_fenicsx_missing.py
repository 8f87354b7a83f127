"""The DOLFINx cross-check without DOLFINx: one line on stderr, exit status 3, no traceback.

The cross-check itself (verification/fenicsx/crosscheck.py) is heavy and not part of the test run;
this only checks the behaviour promised in docs/fenicsx.md when the system python has no DOLFINx,
by pointing SOLIDSHELL_FENICSX_PYTHON at a python that cannot import it (or does not exist).
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("python", ["/nonexistent/python3", sys.executable])
def test_crosscheck_without_dolfinx_says_so_in_one_line(tmp_path, python):
    if python == sys.executable:
        try:
            import dolfinx  # noqa: F401

            pytest.skip("the venv python has DOLFINx")
        except ImportError:
            pass
    env = dict(os.environ, SOLIDSHELL_FENICSX_PYTHON=python)
    p = subprocess.run(
        [sys.executable, "-m", "verification.fenicsx.crosscheck", "--out", str(tmp_path)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 3
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "DOLFINx" in lines[0] and "Traceback" not in p.stderr
    assert not any(tmp_path.iterdir())  # nothing written
