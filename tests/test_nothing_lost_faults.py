"""Nothing lost (issue 39), fault injection on real CLI runs (slow: ~3-4 min on 2 cores).

Each test starts ``python -m solidshell run ...`` processes and hurts them from outside: kill -9
at random checkpoints (chained: the restarted run is killed again), SIGTERM at a random moment, a
second run into a live run's folder, kill -9 inside the write phase, a full disk (a 1 MB tmpfs,
where this process may mount one), a checkpoint folder taken away mid-run, and a sweep with an
entry that cannot run.  What each must leave behind is in its docstring.  The random points come
from a seeded generator (the seed is printed on failure through the parameters).
"""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow

ENV = {**os.environ, "NUMBA_NUM_THREADS": "1", "SOLIDSHELL_PROGRESS_INTERVAL": "3600"}
# summary keys that measure the computer or name the run (see test_nothing_lost.VARYING)
from test_nothing_lost import VARYING  # noqa: E402

FAST = ["--no-pictures", "-q", "--no-progress"]
CASES = {
    # square-pedestal's adaptive relaxation (§6.1), two levels from its 48-quad level 0: FIRE remeshes
    # 11 times in 6000 steps, Rayleigh (alpha 5 1/s) 38 times
    "adaptive-fire": ["square-pedestal", "--solver", "relax", "--adaptive", "--set", "adapt.levels=2"],
    "adaptive-rayleigh": [
        "square-pedestal", "--solver", "relax", "--adaptive", "--set", "adapt.levels=2",
        "--set", 'solver.relax.damping="rayleigh"', "--set", "solver.relax.alpha=5.0",
    ],
    # the uniform 24x8x4 mesh (steady only after 14300 steps)
    "uniform": ["square-pedestal", "--mesh", "24x8x4", "--solver", "relax"],
}  # fmt: skip
STEPS, CK_EVERY = 6000, 350


def _cmd(args, out, *extra):
    return [sys.executable, "-m", "solidshell", "run", *args, "--out", str(out), *FAST, *extra]


def _run(args, out, *extra, timeout=600):
    return subprocess.run(_cmd(args, out, *extra), env=ENV, capture_output=True, text=True, timeout=timeout)


def _ck_step(p) -> int:
    try:
        with np.load(p) as z:
            return int(z["step"])
    except Exception:  # noqa: BLE001 - absent or being replaced: not yet
        return -1


def _kill_after(args, out, ck, at: int, *extra) -> int:
    """Start the run, kill -9 it once its checkpoint holds step >= at; the checkpoint's step."""
    cmd = _cmd(args, out, "--checkpoint", str(ck), *extra)
    p = subprocess.Popen(cmd, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        while p.poll() is None and _ck_step(ck) < at:
            time.sleep(0.02)
        assert p.poll() is None, "the run ended before the kill"
        p.send_signal(signal.SIGKILL)
        p.wait(60)
    finally:
        if p.poll() is None:
            p.kill()
    return _ck_step(ck)


def _summary(out) -> dict:
    return json.loads((Path(out) / "summary.json").read_text())


def _same(a: dict, b: dict) -> list:
    """Keys that differ, less VARYING and replaced_files (the folder's history, not the run's)."""
    skip = VARYING | {"replaced_files"}
    return sorted(k for k in set(a) | set(b) if k not in skip and a.get(k) != b.get(k))


def _names(d) -> list:
    return sorted(p.name for p in Path(d).iterdir())


@pytest.mark.parametrize("case", list(CASES))
def test_kill_9_at_random_checkpoints_then_restart_bit_for_bit(tmp_path, case):
    """The uninterrupted run, then the same run killed -9 after a random checkpoint, restarted from
    it, killed again after a later random checkpoint and restarted to the end: every key of the
    final summary but the wall-clock and identity ones equals the uninterrupted run's (DC, steps,
    remeshes, active nodes, energies: floats bit for bit), and so does result.vtu's state."""
    from solidshell import io as sio

    args = [
        *CASES[case],
        "--set",
        f"solver.relax.max_steps={STEPS}",
        "--set",
        f"solver.relax.checkpoint_every={CK_EVERY}",
    ]
    ref = _run(args, tmp_path / "ref", "--checkpoint", str(tmp_path / "ref.npz"))
    assert ref.returncode == 1, ref.stderr  # max_steps ends it, not a steady state
    rng = random.Random(f"issue-39-{case}")
    out, ck = tmp_path / "o", tmp_path / "ck.npz"
    k1 = _kill_after(args, out, ck, rng.randrange(CK_EVERY, STEPS // 2))
    shutil.copy(ck, tmp_path / "k1.npz")
    k2 = _kill_after(
        args, out, ck, rng.randrange(k1 + CK_EVERY, STEPS - CK_EVERY), "--restart", str(tmp_path / "k1.npz")
    )
    assert CK_EVERY <= k1 < k2 < STEPS, (k1, k2)
    shutil.copy(ck, tmp_path / "k2.npz")
    last = _run(args, out, "--checkpoint", str(ck), "--restart", str(tmp_path / "k2.npz"))
    assert last.returncode == 1, last.stderr
    a, b = _summary(tmp_path / "ref"), _summary(out)
    assert b["restarted_from_step"] == k2 and _same(a, b) == [], (k1, k2, _same(a, b))
    print(f"{case}: killed at steps {k1}, {k2}; DC {b.get('drape_coefficient')!r}, {b['steps']} steps, "
          f"{b.get('final_active_nodes')} nodes, {b.get('remesh_count')} remeshes: bit-identical")  # fmt: skip
    assert (
        sio.read_state(out / "result.vtu")[1].tobytes() == sio.read_state(tmp_path / "ref" / "result.vtu")[1].tobytes()
    )
    assert "RUNNING" not in _names(out) and _names(tmp_path) == sorted(
        ["ref", "ref.npz", "o", "ck.npz", "k1.npz", "k2.npz"]
    )  # no staging folder left


def test_sigterm_writes_the_state_and_its_checkpoint_continues_the_run(tmp_path):
    """SIGTERM at a random moment of a relaxation: exit 143, the state written with
    "interrupted": true, no marker, no staging folder, the checkpoint at the interrupted step; the
    restart from it ends bit for bit where the uninterrupted run ends."""
    args = [*CASES["uniform"], "--set", f"solver.relax.max_steps={STEPS}", "--set", "solver.relax.checkpoint_every=500"]
    ref = _run(args, tmp_path / "ref")
    out, ck = tmp_path / "o", tmp_path / "ck.npz"
    # before the solver has a state (its marker just written): nothing to write, exit 143 all the same
    p = subprocess.Popen(_cmd(args, out), env=ENV, stderr=subprocess.PIPE, text=True)
    while p.poll() is None and not (out / "RUNNING").exists():
        time.sleep(0.005)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 143 and "terminated (SIGTERM); this run's summary.json was not written" in err, err
    assert not out.exists() and _names(tmp_path) == ["ref"]  # the folder it made goes with it
    # in the stepping: after the first checkpoint, at a random moment of the next ~3 s
    p = subprocess.Popen(_cmd(args, out, "--checkpoint", str(ck)), env=ENV, stdout=subprocess.PIPE, text=True)
    while p.poll() is None and _ck_step(ck) < 500:
        time.sleep(0.01)
    time.sleep(random.Random("issue-39-term").uniform(0.0, 1.0))
    p.send_signal(signal.SIGTERM)
    stdout, _ = p.communicate(timeout=120)
    assert p.returncode == 143 and "INTERRUPTED" in stdout, stdout
    s = _summary(out)
    assert s["interrupted"] is True and 0 < s["steps"] < STEPS and _ck_step(ck) == s["steps"]
    assert "RUNNING" not in _names(out) and "result.vtu" in _names(out) and _names(tmp_path) == ["ck.npz", "o", "ref"]
    shutil.copy(ck, tmp_path / "t.npz")
    again = _run(args, out, "--checkpoint", str(ck), "--restart", str(tmp_path / "t.npz"))
    assert again.returncode == ref.returncode == 1
    assert _same(_summary(tmp_path / "ref"), _summary(out)) == []


def test_a_second_run_into_a_live_runs_folder_is_refused(tmp_path):
    """Run A (the 48x16x4 relaxation, ~20 s) owns its folder; run B into it exits 2 naming the folder
    and A's pid, with --force too, and writes nothing; A then ends (SIGTERM) with its own files."""
    out = tmp_path / "o"
    a = subprocess.Popen(_cmd(["square-pedestal", "--solver", "relax"], out), env=ENV, stdout=subprocess.DEVNULL)
    try:
        t0 = time.time()
        while not (out / "RUNNING").exists() and time.time() - t0 < 120:
            time.sleep(0.02)
        for extra in ([], ["--force"]):
            b = _run(["strip-warp", "--mesh", "2x1"], out, *extra)
            assert b.returncode == 2 and f"output folder {out} is in use" in b.stderr and f"pid {a.pid}" in b.stderr
            assert len(b.stderr.strip().splitlines()) == 1
        assert _names(out) == ["RUNNING"]
    finally:
        a.send_signal(signal.SIGTERM)
        a.wait(120)
    assert a.returncode == 143 and _summary(out)["interrupted"] is True and _summary(out)["scene"] == "square-pedestal"


def test_kill_9_while_writing_leaves_the_earlier_run_whole(tmp_path):
    """Run A complete; run B killed -9 once its first file is in the staging folder (its pictures
    take seconds to draw): the folder holds A's files byte for byte.  Run C then clears B's staging
    folder and marker and replaces A whole."""
    from solidshell import io as sio

    out = tmp_path / "o"
    args = ["square-pedestal", "--mesh", "12x4x4", "--solver", "relax", "--set", "solver.relax.max_steps=300"]
    assert _run(args, out).returncode == 1
    before = {n: (out / n).read_bytes() for n in _names(out)}
    cmd = _cmd(args, out)
    cmd.remove("--no-pictures")  # pictures: a write phase of seconds
    b = subprocess.Popen(cmd, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        staged = None
        while b.poll() is None and staged is None:
            staged = next((d for d in tmp_path.glob(".o.new-*") if (d / "mesh.vtu").exists()), None)
            time.sleep(0.005)
        assert staged is not None, "run B ended before its write phase was seen"
        b.send_signal(signal.SIGKILL)
        b.wait(60)
    finally:
        if b.poll() is None:
            b.kill()
    after = {n: (out / n).read_bytes() for n in _names(out) if n != "RUNNING"}
    assert after == before and "summary.json" not in _names(staged)
    c = _run(args, out)
    assert c.returncode == 1 and _names(tmp_path) == ["o"]
    s = _summary(out)
    assert {sio.read_run_id(out / n) for n in s["files"]} == {s["run_id"]} and "top.png" not in s["files"]


@pytest.fixture
def tiny_disk(tmp_path):
    """A 1 MB tmpfs, where this process may mount one (root on Linux); else the test is skipped."""
    d = tmp_path / "disk"
    d.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(d)], capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.decode().strip()}")
    try:
        yield d
    finally:
        subprocess.run(["umount", str(d)], check=False)


def test_a_full_disk_keeps_the_earlier_run_and_saves_the_state(tiny_disk):
    """On a 1 MB disk the 12x4x4 run fits (~0.5 MB), the 48x16x4 one does not: exit 3, one line
    naming the file that failed and the .npz the solved state went to (the system's temporary
    folder, another disk), the folder still the earlier run, no staging folder."""
    out = tiny_disk / "o"
    args = ["square-pedestal", "--solver", "relax", "--set", "solver.relax.max_steps=100"]
    assert _run([*args, "--mesh", "12x4x4"], out).returncode == 1
    before = {n: (out / n).read_bytes() for n in _names(out)}
    r = _run(args, out)
    line = r.stderr.strip()
    assert r.returncode == 3 and len(line.splitlines()) == 1 and "No space left on device" in line, line
    assert f"{out}/" in line and "holds the earlier run unchanged" in line
    keep = Path(line.rsplit("saved to ", 1)[1].split()[0])
    try:
        with np.load(keep) as z:
            assert z["U"].shape == (3264, 6) and json.loads(str(z["summary"]))["mesh"] == "48x16x4"
    finally:
        keep.unlink()
    assert {n: (out / n).read_bytes() for n in _names(out)} == before and _names(tiny_disk) == ["o"]


def test_a_checkpoint_folder_taken_away_warns_and_the_run_ends(tmp_path):
    """The checkpoint's folder replaced by a file after the first checkpoint: the later ones fail,
    the run goes on to its end (exit 1 at max_steps, results and summary written) with one warning
    naming the checkpoint and the reason."""
    d = tmp_path / "ckdir"
    d.mkdir()
    ck = d / "ck.npz"
    args = [*CASES["uniform"], "--set", "solver.relax.max_steps=4000", "--set", "solver.relax.checkpoint_every=200"]
    p = subprocess.Popen(
        _cmd(args, tmp_path / "o", "--checkpoint", str(ck)), env=ENV, stderr=subprocess.PIPE, text=True
    )
    while p.poll() is None and _ck_step(ck) < 0:
        time.sleep(0.01)
    shutil.rmtree(d)
    d.write_text("in the way")
    _, err = p.communicate(timeout=300)
    assert p.returncode == 1, err
    s = _summary(tmp_path / "o")
    w = [x for x in s["warnings"] if x.startswith(f"checkpoint {ck} not written")]
    assert len(w) == 1 and "the run goes on" in w[0] and s["steps"] == 4000, s["warnings"]


def test_a_sweep_entry_that_cannot_run_ends_the_sweep_with_1_naming_it(tmp_path):
    """A grid of two meshes, one past the size guard: that entry is recorded as failed, the sweep
    exits 1 and names it; the other is recorded."""
    pytest.importorskip("distributed")
    sweep = tmp_path / "s.toml"
    sweep.write_text('name = "g"\nscene = "strip-warp"\nsolver = "static"\n[grid]\nmesh = ["4x1", "3000x3000"]\n')
    r = subprocess.run(
        [sys.executable, "-m", "solidshell", "sweep", str(sweep), "--out", str(tmp_path / "s"), "--workers", "1", "--no-progress"],
        env=ENV, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert r.returncode == 1, r.stderr
    assert "1 run(s) recorded now" in r.stdout and "1 failed now" in r.stdout
    assert "run 1 (mesh=3000x3000)" in r.stderr and "failed" in r.stderr and "--allow-large" in r.stderr
