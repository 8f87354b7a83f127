"""The wheel carries the checks and their reference data: built from this checkout's files, installed
into a fresh virtualenv, ``solidshell verify --quick`` runs outside the checkout and passes.

Slow (``-m slow``): the build, and the quick set's ~2 minutes of checks.  The wheel's third-party
dependencies are not downloaded: the fresh venv reaches the project venv's site-packages through a
``.pth`` line, which puts that folder on sys.path *after* the venv's own (so solidshell, verification
and reference come from the wheel; the editable install's finder, a ``.pth`` of that folder, is not
run).  The build itself needs pip's build isolation (setuptools >= 68 from PyPI or pip's cache).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

pytestmark = pytest.mark.slow


def _checkout_copy(dst: Path) -> Path:
    """The files a commit of this checkout would hold (tracked and new, not ignored), as they are now."""
    out = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        check=True,
    ).stdout.decode()
    for rel in filter(None, out.split("\0")):
        src = ROOT / rel
        if src.is_file():  # a tracked file deleted in the working tree is gone
            (dst / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dst / rel)
    return dst


def _run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    assert r.returncode == 0, f"{' '.join(map(str, cmd))} -> {r.returncode}\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    return r


def test_installed_wheel_runs_the_quick_verification_outside_the_checkout(tmp_path):
    src = _checkout_copy(tmp_path / "src")
    dist = tmp_path / "dist"
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", str(src), "-w", str(dist)])
    (whl,) = dist.glob("solidshell-*.whl")

    names = set(zipfile.ZipFile(whl).namelist())
    # the checks, the CLI and the reference data ship; the studies' results and the old folder do not
    for f in (
        "verification/checks/runner.py",
        "verification/checks/strips.py",
        "verification/locking.py",
        "solidshell/verify_cli.py",
        "reference/__init__.py",
        "reference/elastica.py",
        "reference/elastica_strip.json",
        "reference/plates.json",
        "reference/README.md",
    ):
        assert f in names, f
    assert not [n for n in names if n.startswith(("verification/out/", "solidshell/verify/"))]

    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)])
    py = venv / "bin" / "python"
    _run([sys.executable, "-m", "pip", "--python", str(py), "install", "--no-deps", "--no-index", "-q", str(whl)])
    purelib = Path(_run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"]).stdout.strip())
    deps = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}  # the project venv's
    (purelib / "zz_project_deps.pth").write_text("".join(f"{d}\n" for d in sorted(deps)))

    work = tmp_path / "elsewhere"  # cwd outside the checkout, nothing of it on sys.path
    work.mkdir()
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("PYTHONPATH", "SOLIDSHELL_REFERENCE_DIR", "VIRTUAL_ENV", "PYTHONHOME")
    }
    env["PYTHONSAFEPATH"] = "1"
    where = json.loads(
        _run(
            [
                py,
                "-c",
                "import json, solidshell, verification.checks.references as r, reference; "
                "print(json.dumps([solidshell.__file__, r.__file__, str(r.reference_dir())]))",
            ],
            cwd=work,
            env=env,
        ).stdout
    )
    for p in where:  # all three from the wheel, none from the checkout
        assert Path(p).resolve().is_relative_to(purelib.resolve()), where

    out = tmp_path / "vout"
    r = subprocess.run(
        [venv / "bin" / "solidshell", "verify", "--quick", "--out", str(out)],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        timeout=1500,
    )
    summary = [ln for ln in r.stdout.splitlines() if " records from " in ln]
    print("\n".join(summary))
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    recs = json.loads((out / "verification.json").read_text())["records"]
    # the quick set measures every quantity it names (none is skipped without an optional code)
    assert len(recs) > 0 and all(x["status"] == "passed" and x["passed"] is True for x in recs), [
        x["name"] for x in recs if x["status"] != "passed"
    ]
