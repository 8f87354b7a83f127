"""A sweep's runs log their progress on the worker (issue 40, "progress everywhere"): the lines of
solidshell.run.progress (fraction, elapsed, ETA, the solver's step, t and E_kin) labelled with the
run's index, varied setting and key -- in a Dask worker's own log, and on stderr in a process where
nobody configured logging.  The runs are a coarse hung sheet for 0.15-0.2 s of simulated time
(~1-3 s each) with the line interval at 0.1 s, so every run logs several lines."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("distributed", reason="dask.distributed not installed (pip install 'solidshell[sweep]')")
pytest.importorskip("pyarrow", reason="pyarrow not installed (pip install 'solidshell[sweep]')")

from solidshell.run import progress  # noqa: E402
from solidshell.sweep import load_spec  # noqa: E402
from solidshell.sweep.engine import Cluster, run_sweep  # noqa: E402
from solidshell.sweep.task import make_task  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SWEEP = """
name = "hang-tiny"
scene = "hang-20"
mesh = "4x4"
solver = "explicit"
[grid]
"solver.explicit.t_end" = [0.15, 0.2]
"""
# "<label>: NN% after X s[, ETA Y] -- step N, t = T s, E_kin = E ..." (solidshell.run.progress._Lines);
# X as progress.duration writes it: "4.2 s", "17 s", "1 min 05 s" (a fresh clone compiles numba's
# kernels in the first run: ~65 s here), "1 h 02 min"
DURATION = r"(?:[\d.]+ s|\d+ min \d\d s|\d+ h \d\d min)"
LINE = rf"sweep hang-tiny run (\d) \(solver\.explicit\.t_end=(0\.15|0\.2)\) \[key (\w+)\]: +(\d+)% after {DURATION}(.*)"


def _spec(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text(SWEEP)
    return load_spec(f)


def _check(lines, spec):
    """Each run: progress lines in order with the explicit solver's figures, then its done line."""
    keys = {r.index: r.key for r in spec.runs}
    for i, t_end in ((0, 0.15), (1, 0.2)):
        mine = [m for m in (re.search(LINE, ln) for ln in lines) if m and int(m.group(1)) == i]
        assert len(mine) >= 2, lines  # a run of >= 1 s at 0.1 s intervals
        assert all(m.group(3) == keys[i] for m in mine)
        pct = [int(m.group(4)) for m in mine]
        assert pct == sorted(pct)  # the fraction never goes back
        ts = [float(x) for m in mine for x in re.findall(r"t = ([\d.e+-]+) s, E_kin = [\d.e+-]+", m.group(5))]
        assert ts and all(0.0 < t <= t_end for t in ts) and ts == sorted(ts), lines
        done = [ln for ln in lines if re.search(rf"run {i} .*\[key {keys[i]}\]: done after ", ln)]
        assert len(done) == 1, lines


def test_sweep_runs_log_progress_in_the_worker_log(tmp_path, monkeypatch):
    """An in-process LocalCluster's worker (threads, so the interval can be patched here): the runs'
    lines are in its log as Client.get_worker_logs() returns it; nothing is left configured after."""
    from distributed import Client, LocalCluster

    monkeypatch.setattr(progress, "INTERVAL", 0.1)
    spec = _spec(tmp_path)
    level, handlers = progress.plog.level, list(progress.plog.handlers)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        res = run_sweep(spec, tmp_path / "out", Cluster(scheduler=cluster.scheduler_address), pictures=())
        assert (res.recorded, res.failed) == (2, [])
        with Client(cluster) as client:
            logs = client.get_worker_logs()
    (entries,) = logs.values()
    lines = [msg for lvl, msg in reversed(entries) if "solidshell.progress" in msg]
    assert all(" - solidshell.progress - INFO - " in ln for ln in lines)
    _check(lines, spec)
    assert (progress.plog.level, progress.plog.handlers) == (level, handlers)


def test_no_progress_sweep_logs_nothing(tmp_path, monkeypatch):
    """--no-progress (run_sweep progress=False): the tasks ask for no lines."""
    spec = _spec(tmp_path)
    assert not any(make_task(spec, r, tmp_path, progress=False)["progress"] for r in spec.runs)
    assert all(make_task(spec, r, tmp_path)["progress"] for r in spec.runs)


def test_task_logs_on_stderr_where_logging_is_not_configured(tmp_path):
    """The task in a fresh process (a worker nobody configured logging in; before, its INFO lines
    were dropped): the lines on stderr in Dask's log format."""
    spec = _spec(tmp_path)
    tasks = [make_task(spec, r, tmp_path / "out", pictures=()) for r in spec.runs]
    code = "import sys, json; from solidshell.sweep.task import run_task\nfor t in json.loads(sys.argv[1]): run_task(t)"
    import json

    r = subprocess.run(
        [sys.executable, "-c", code, json.dumps(tasks)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
        env={**os.environ, "SOLIDSHELL_PROGRESS_INTERVAL": "0.1", "NUMBA_NUM_THREADS": "1"},
    )
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if " - solidshell.progress - INFO - " in ln]
    assert lines and re.match(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d+ - solidshell.progress - INFO - sweep", lines[0])
    _check(lines, spec)
