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

import numpy as np
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
    # the explicit solver's figures: step, simulated time and kinetic energy, the time within the run's span
    dyn = [re.search(r"step (\d+), t = ([\d.e+-]+) s, E_kin = ([\d.e+-]+)", ln) for ln in lines]
    ts = [float(m.group(2)) for m in dyn if m]
    assert ts and all(0.0 < t <= 0.6 for t in ts) and ts == sorted(ts), lines
    n = [int(m.group(1)) for m in dyn if m]
    assert all(k > 0 for k in n) and n == sorted(n), lines  # the step count with the time
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


# ----------------------------------------------------------------------------- each scene's closing figures
def _run(capsys, *argv):
    from solidshell.cli import main

    code = main(["run", *map(str, argv), "--no-pictures", "--no-progress"])
    return code, capsys.readouterr().out.splitlines()


def _elastica(cut):
    return json.loads((ROOT / "reference" / "elastica_strip.json").read_text())["strip"][cut]


def test_strip_prints_tip_against_elastica(tmp_path, capsys):
    out = tmp_path / "o"
    code, lines = _run(capsys, "strip-warp", "--mesh", "10x1", "--out", out)
    assert code == 0 and lines[0].startswith("strip-warp: static on mesh 10x1 (22 nodes, 10 elements): converged")
    s = json.loads((out / "summary.json").read_text())
    m = re.fullmatch(
        r"  tip deflection ([\d.]+) cm \(tip ([\d.]+) cm along x from the clamp, (-[\d.]+) cm in z\); heavy elastica "
        r"\(warp-cut, reference/elastica_strip.json\): ([\d.]+) cm \(([\d.]+) cm along x\): ([+-][\d.]+)%",
        lines[1],
    )
    assert m, lines
    d, x, z, dr, xr, rel = map(float, m.groups())
    ref = _elastica("warp")
    # the clamp is at x = 0, z = 0: the tip's position is its offset from the clamp
    assert d == pytest.approx(-s["tip_position"][2], rel=1e-3) and x == pytest.approx(s["tip_position"][0], rel=1e-3)
    assert z == -d and dr == pytest.approx(-ref["tip_z"], rel=1e-3) and xr == pytest.approx(ref["tip_x"], rel=1e-3)
    exact = 100 * (-s["tip_position"][2] + ref["tip_z"]) / -ref["tip_z"]
    assert rel == pytest.approx(exact, abs=0.006) and 0.0 < rel < 1.0  # 10x1: 0.45 % (docs/verification.md)
    assert lines[2].startswith("  interpenetrated_nodes = 0, max_displacement = ")  # the line parsers read, kept
    code, lines = _run(capsys, "strip-weft", "--mesh", "10x1", "--out", out, "-q")
    m = re.search(r"; tip deflection ([\d.]+) cm \(elastica ([\d.]+), ([+-][\d.]+)%\); ", lines[0])
    assert len(lines) == 1 and m and float(m.group(2)) == pytest.approx(-_elastica("weft")["tip_z"], rel=1e-3)


def test_strip_without_reference_says_so(tmp_path, capsys):
    code, lines = _run(capsys, "strip-warp", "--mesh", "4x1", "--set", "geometry.length=4.0", "--out", tmp_path / "o")
    assert code == 0 and lines[1].startswith("  tip deflection ") and "no stored reference" in lines[1]


def test_pedestal_prints_dc_with_its_definition(tmp_path, capsys):
    out = tmp_path / "o"
    code, lines = _run(capsys, "square-pedestal", "--mesh", "24x8x4", "--out", out)
    s = json.loads((out / "summary.json").read_text())
    m = re.fullmatch(
        r"  drape coefficient DC = ([\d.]+) = \(A_projected - A_pedestal\)/\(A_sheet - A_pedestal\) = "
        r"\(([\d.]+) - ([\d.]+)\)/\(([\d.]+) - ([\d.]+)\) cm\^2, (\d+) folds",
        lines[1],
    )
    assert code == 0 and m, lines
    dc, A, Ap, As, Ap2, folds = map(float, m.groups())
    assert Ap == Ap2 == 100.0 and As == 400.0 and (A - Ap) / (As - Ap) == pytest.approx(dc, abs=1e-3)
    assert dc == pytest.approx(s["drape_coefficient"], abs=1e-4) and folds == s["fold_count"] == 4
    assert lines[2].startswith(f"  drape_coefficient = {s['drape_coefficient']:.4g}, fold_count = 4")


def test_dc_without_pedestal_says_relative_to_what():
    from solidshell.cli import _dc_line

    brief, full = _dc_line({"drape_coefficient": 0.2387, "fold_count": 4, "projected_area": 214.8,
                            "sheet_area": 900.0, "pedestal_area": None})  # fmt: skip
    assert brief == "DC 0.2387, 4 folds"
    assert full == "drape coefficient DC = 0.2387 = A_projected/A_sheet = 214.8/900 cm^2 (no pedestal), 4 folds"


def test_hung_sheet_prints_its_corners(tmp_path, capsys):
    from solidshell import io as sio

    out = tmp_path / "o"
    code, lines = _run(capsys, "hang-20", "--mesh", "8x8", "--set", "solver.explicit.t_end=0.3", "--out", out)
    assert code == 0 and lines[1].startswith("  corners at the end [cm]: "), lines
    corners = {
        name: (np.array([float(v) for v in xyz.split(", ")]), held == " held")
        for name, xyz, held in re.findall(r"(sw|se|ne|nw) \(([^)]*)\)( held)?", lines[1])
    }
    assert set(corners) == {"sw", "se", "ne", "nw"}
    # the hung corners (node set "hung": ne, nw) stay at (+-10, 10, 0); the free ones fell and swung
    assert corners["ne"][1] and corners["nw"][1] and not corners["sw"][1] and not corners["se"][1]
    np.testing.assert_allclose(corners["ne"][0], [10, 10, 0], atol=1e-3)
    np.testing.assert_allclose(corners["nw"][0], [-10, 10, 0], atol=1e-3)
    mesh, U = sio.read_state(out / "result.vtu")
    X = mesh.nodes
    for name in ("sw", "se"):
        i = int(np.argmin(np.linalg.norm(X - [(-10 if name == "sw" else 10), -10, 0], axis=1)))
        np.testing.assert_allclose(corners[name][0], X[i] + U[i, :3], rtol=1e-3, atol=1e-3)
        assert corners[name][0][2] < -10.0
    assert corners["sw"][0][0] == pytest.approx(-corners["se"][0][0], abs=1e-3)  # a symmetric swing
    code, lines = _run(capsys, "hang-20", "--mesh", "8x8", "--set", "solver.explicit.t_end=0.3", "--out", out, "-q")
    assert len(lines) == 1 and f"; lowest free corner z {corners['sw'][0][2]:.4g} cm; " in lines[0]


def test_the_closing_line_counts_a_long_series_instead_of_listing_it():
    """A static run writes one series frame per load step (764 on the sphere's 60x60 static path):
    the closing line names the first and last and counts them; short series and other files are
    listed as they are, in their order."""
    from solidshell.cli import file_list

    frames = [f"series_{i:05d}.vtu" for i in range(764)]
    names = ["deformed.vtu", "iso.png", "series.pvd", "series.xdmf", *frames, "summary.json"]
    assert file_list(names) == (
        "deformed.vtu, iso.png, series.pvd, series.xdmf, series_00000.vtu ... series_00763.vtu (764 files), summary.json"
    )
    short = ["mesh.vtu", "series_00000.vtu", "series_00001.vtu", "top.png"]
    assert file_list(short) == ", ".join(short)
