"""What ``solidshell run`` prints (issue 40): progress lines when its output goes to a pipe or a log
(every SOLIDSHELL_PROGRESS_INTERVAL seconds, with the fraction done, elapsed time, ETA and the
solver's t and E_kin), ``--quiet`` and ``-v``, and each scene's closing figures."""

import io
import json
import logging
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PROGRESS = re.compile(r"^solidshell: progress: hang-20: +(\d+)% after ([\d.]+ s|\d+ min \d+ s)(, ETA [^-]+)?( -- .*)?$")


def cli(*args, env=None):
    return subprocess.run(
        [sys.executable, "-m", "solidshell", *map(str, args)],
        capture_output=True,  # stdout and stderr are pipes, as in a log file, CI or a Dask worker
        text=True,
        cwd=ROOT,
        timeout=300,
        env={**os.environ, **(env or {})},
    )


# a dynamic run of a few seconds: the hung 20x20 sheet, coarse, to t = 0.6 s
HANG = ["run", "hang-20", "--mesh", "8x8", "--set", "solver.explicit.t_end=0.6", "--no-pictures"]


def test_piped_run_logs_progress_lines(tmp_path):
    r = cli(*HANG, "--out", tmp_path / "o", env={"SOLIDSHELL_PROGRESS_INTERVAL": "0.2"})
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("solidshell: progress: ")]
    assert lines and all(ln.startswith("solidshell: progress: ") for ln in r.stderr.splitlines()), r.stderr
    assert lines[-1].startswith("solidshell: progress: hang-20: done after ")
    steps = [PROGRESS.match(ln) for ln in lines[:-1]]
    assert len(steps) >= 2 and all(steps), lines
    pct = [int(m.group(1)) for m in steps]
    assert pct == sorted(pct) and 0 <= pct[0] and pct[-1] <= 100  # the fraction never goes back
    # the explicit solver's figures: simulated time and kinetic energy, the time within the run's span
    dyn = [re.search(r"t = ([\d.e+-]+) s, E_kin = ([\d.e+-]+)", ln) for ln in lines]
    ts = [float(m.group(1)) for m in dyn if m]
    assert ts and all(0.0 < t <= 0.6 for t in ts) and ts == sorted(ts), lines
    assert any(m.group(3) for m in steps if m.group(4) and "t = " in m.group(4)), "an ETA once the solver runs"
    # the final lines are as before (stdout)
    out = r.stdout.splitlines()
    assert out[0].startswith("hang-20: explicit on mesh 8x8 (81 nodes, 64 elements): converged")
    assert "; wrote " in out[-1]


def test_quiet_prints_one_line_and_no_progress(tmp_path):
    r = cli(*HANG, "--out", tmp_path / "o", "--quiet", env={"SOLIDSHELL_PROGRESS_INTERVAL": "0.2"})
    assert r.returncode == 0 and r.stderr == "", r.stderr
    out = r.stdout.splitlines()
    assert len(out) == 1 and out[0].startswith("hang-20: explicit on mesh 8x8 (81 nodes, 64 elements): converged")
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["converged"] is True


def test_no_progress_and_verbose(tmp_path):
    r = cli(
        "run",
        "strip-warp",
        "--mesh",
        "4x1",
        "--no-pictures",
        "--no-progress",
        "-v",
        "--out",
        tmp_path / "o",
        env={"SOLIDSHELL_PROGRESS_INTERVAL": "0.01"},
    )
    assert r.returncode == 0 and "progress" not in r.stderr, r.stderr
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    solver = next(ln for ln in r.stdout.splitlines() if ln.startswith("  solver: "))
    assert f"iterations = {s['iterations']}," in solver and "method = newton" in solver
    timings = next(ln for ln in r.stdout.splitlines() if ln.startswith("  timings: "))
    assert re.search(r"solve [\d.]+ s", timings) and re.search(r"total [\d.]+ s", timings)


def test_quiet_and_verbose_exclusive(capsys):
    from solidshell.cli import main

    assert main(["run", "strip-warp", "-q", "-v"]) == 2
    assert "not allowed with argument" in capsys.readouterr().err


# ----------------------------------------------------------------------------- the machinery in-process
class _Tty(io.StringIO):
    def isatty(self):
        return True


@pytest.fixture
def plog(caplog):
    """The progress logger's records (its handler attached directly: an in-process CLI test may
    have stopped the "solidshell" logger from propagating to the root)."""
    log = logging.getLogger("solidshell.progress")
    log.addHandler(caplog.handler)
    caplog.set_level(logging.INFO, logger="solidshell.progress")
    yield caplog
    log.removeHandler(caplog.handler)


def test_lines_off_a_terminal_bar_on_one(monkeypatch, plog):
    from solidshell.run import progress

    monkeypatch.setattr(progress, "INTERVAL", 0.1)
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    with progress.reporting(True, "strip") as cb:
        assert isinstance(cb, progress._Lines)
        cb(0.0, "meshing")
        time.sleep(0.25)
        cb(0.25, "t = 0.1 s, E_kin = 0.5, residual 1.0e-02")
        time.sleep(1.2)  # the ETA shows after a second
        cb(0.5, "t = 0.2 s, E_kin = 0.25, residual 1.0e-03")
        time.sleep(0.3)
    msgs = [r.getMessage() for r in plog.records if r.name == "solidshell.progress"]
    assert re.fullmatch(r"strip:   0% after \d\.\d s -- meshing", msgs[0]), msgs
    assert any(
        m.startswith("strip:  25% after") and m.endswith("-- t = 0.1 s, E_kin = 0.5, residual 1.0e-02") for m in msgs
    )
    last = [m for m in msgs if m.startswith("strip:  50%")][-1]
    # ETA from the average rate: 50 % in ~1.8 s leaves ~1.8 s
    eta = float(re.search(r"ETA ([\d.]+) s", last).group(1))
    assert 1.0 <= eta <= 4.0
    assert msgs[-1].startswith("strip: done after ")
    monkeypatch.setattr(sys, "stderr", _Tty())
    with progress.reporting(True, "strip") as cb:
        assert isinstance(cb, progress._Bar)


def test_short_run_logs_nothing(monkeypatch, plog):
    from solidshell.run import progress

    monkeypatch.setattr(progress, "INTERVAL", 5.0)
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    with progress.reporting(True, "strip") as cb:
        cb(0.5, "x")
    assert [r for r in plog.records if r.name == "solidshell.progress"] == []


@pytest.mark.parametrize("seconds, text", [(0.04, "0.0 s"), (4.26, "4.3 s"), (42, "42 s"), (185, "3 min 05 s")])
def test_duration(seconds, text):
    from solidshell.run.progress import duration

    assert duration(seconds) == text
