"""Runs a user can trust (issue 11, parts 3-4): every input checked before a file is written, run
folders that never mix two runs, exit statuses 0/1/2/3/130, warnings, progress, restart after a
real process kill.

In-process tests use a stand-in solver and model (no numba compile); the subprocess tests run the
real explicit solver on a 2- or 4-element strip (a few seconds each)."""

import errno
import io as _stdio
import json
import logging
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from solidshell import InputError
from solidshell import io as sio
from solidshell.errors import IOFailure
from solidshell.problem import SolveResult

ROOT = Path(__file__).resolve().parents[1]


def cli(*args, timeout=300):
    return subprocess.run(
        [sys.executable, "-m", "solidshell", *map(str, args)], capture_output=True, text=True, cwd=ROOT, timeout=timeout
    )


def popen(*args):
    return subprocess.Popen(
        [sys.executable, "-m", "solidshell", *map(str, args)],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def one_error_line(stderr, code, rc, *needles):
    assert rc == code, (rc, stderr)
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("solidshell: ") and "Traceback" not in stderr, stderr
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


def names(d):
    return sorted(p.name for p in Path(d).iterdir())


# ----------------------------------------------------------------------------- stand-ins
class FakeModel:
    """Stands in for solidshell.model.Model: the wiring, not the mechanics, is under test."""

    interpenetrated = 0

    def __init__(self, mesh, material, thickness_strain="green", mu=0.5, membrane="full", constants=None):
        self.mesh, self.material, self.n_nodes = mesh, material, mesh.n_nodes

    def nodal_areas(self):
        return np.full(self.mesh.n_nodes, self.mesh.area() / self.mesh.n_nodes)

    def interpenetrated_nodes(self, U):
        flag = np.zeros(self.n_nodes, bool)
        flag[: self.interpenetrated] = True
        return flag


def fake_solver(status="done", converged=True, warnings=(), raise_=None, t_final=0.4, info=None):
    def solve(problem, settings, progress):
        if raise_ is not None:
            raise raise_
        X = problem.model.mesh.nodes
        U = np.zeros((len(X), 6))
        U[:, 2] = -0.01 * X[:, 0] ** 2
        U[problem.fixed] = 0.0
        progress(0.5, "half way")
        inf = {"status": status, "t_final": t_final, "warnings": list(warnings), **(info or {})}
        return SolveResult(
            U=U,
            converged=converged,
            message=f"fake: {status}",
            info=inf,
            frames=[(0.0, 0 * U), (0.1, 0.25 * U), (t_final, U)],
        )

    return solve


@pytest.fixture
def fake(monkeypatch):
    import solidshell.model
    from solidshell import solvers

    state = {"solver": fake_solver()}
    monkeypatch.setattr(solidshell.model, "Model", FakeModel)
    monkeypatch.setattr(solvers, "get", lambda kind: state["solver"])
    return state


@pytest.fixture
def settings_double(monkeypatch):
    """A small settings schema in place of the real solvers' (a test double, until the merge)."""
    from pydantic import Field

    from solidshell import settings, solvers

    class Double(settings.SettingsModel):
        tol: settings.Finite = Field(1e-8, gt=0)
        max_iter: int = Field(50, ge=1)
        load_factors: list[float] | None = None
        c: float = 1e-3

    monkeypatch.setattr(solvers, "settings_model", lambda kind: Double)
    return Double


# ============================================================================= 1. checked before work
@pytest.mark.parametrize(
    "key, value, needle",
    [
        ("tol", "abc", "tol"),
        ("tol", -1.0, "tol"),
        ("tol", 0.0, "tol"),
        ("max_iter", "abc", "max_iter"),
        ("load_factors", ["a"], "load_factors"),
        ("nonsense", 1, "nonsense"),
    ],
)
def test_bad_setting_refused_before_anything_is_written(tmp_path, settings_double, key, value, needle):
    from solidshell.run import run_scene

    out = tmp_path / "out"
    with pytest.raises(InputError, match=needle) as e:
        run_scene("strip-warp", mesh="4x1", out_dir=out, progress=False, overrides={f"solver.static.{key}": value})
    assert "\n" not in str(e.value) and "solver.static" in str(e.value)
    assert not out.exists()  # not even the folder


@pytest.mark.parametrize(
    "args, needle",
    [
        (["strip-warp", "--set", "solver.static.tol=abc"], "tol"),
        (["strip-warp", "--set", "solver.static.tol=-1"], "tol"),
        (["strip-warp", "--set", "solver.static.tol=0"], "tol"),
        (["strip-warp", "--set", "solver.static.max_iter=abc"], "max_iter"),
        (["strip-warp", "--set", 'solver.static.load_factors=["a"]'], "load_factors"),
        (["strip-warp", "--solver", "relax", "--set", "solver.relax.U0=abc"], "U0"),
        (["strip-warp", "--solver", "relax", "--set", "solver.relax.checkpoint=5"], "checkpoint"),
    ],
)
def test_bad_setting_cli_exit_2_nothing_written(tmp_path, args, needle):
    out = tmp_path / "out"
    r = cli("run", *args, "--mesh", "4x1", "--out", out, timeout=120)  # refused in ~2 s, never a solve
    one_error_line(r.stderr, 2, r.returncode, needle)
    assert not out.exists()


def test_truncated_restart_file_exit_2_nothing_written(tmp_path):
    bad = tmp_path / "ck.npz"
    bad.write_bytes(b"PK\x03\x04 truncated")
    out = tmp_path / "out"
    r = cli("run", "strip-warp", "--mesh", "2x1", "--solver", "relax", "--restart", bad, "--out", out)
    one_error_line(r.stderr, 2, r.returncode, str(bad))
    assert not out.exists()


def test_size_guard_estimate():
    from solidshell import sizing

    assert sizing.elements_of_density("1000000x1000000x4") == 4 * 10**12
    assert sizing.elements_of_density("48x16x4") == 3072 and sizing.elements_of_density("20x1") == 20
    # the estimate is the documented base plus a per-element cost, static costing the most
    assert sizing.estimate_bytes(1000, "static") == sizing.BASE_BYTES + 1000 * 64 * 1024
    assert sizing.estimate_bytes(1000, "explicit") < sizing.estimate_bytes(1000, "static")
    with pytest.raises(InputError, match=r"1e\+04 elements need about .* more than the 512 MiB available"):
        sizing.check(10_000, "static", "--mesh 100x25x4", available=512 * 2**20)
    assert sizing.check(10_000, "static", "x", allow_large=True, available=1) > 0
    assert sizing.check(100, "explicit", "x", available=2**40) > 0
    have = sizing.available_memory()
    assert have is None or have > 0


def test_size_guard_refuses_before_meshing(tmp_path, monkeypatch):
    from solidshell import meshing, sizing
    from solidshell.run import run_scene

    def boom(*a, **k):
        raise AssertionError("meshing must not start")

    monkeypatch.setattr(meshing, "build_mesh", boom)
    t = time.perf_counter()
    with pytest.raises(InputError, match=r"--mesh 1000000x1000000x4: 4e\+12 elements need about") as e:
        run_scene("square-pedestal", mesh="1000000x1000000x4", solver="none", out_dir=tmp_path / "o", progress=False)
    assert time.perf_counter() - t < 2.0 and "--allow-large" in str(e.value)
    assert not (tmp_path / "o").exists()
    # a modest mesh against a machine with 300 MiB free: refused, unless allow_large
    monkeypatch.undo()
    monkeypatch.setattr(sizing, "available_memory", lambda: 300 * 2**20)
    with pytest.raises(InputError, match="mesh.density 48x16x4: 3072 elements"):
        run_scene("square-pedestal", solver="static", progress=False)
    out = run_scene("strip-warp", mesh="4x1", solver="none", progress=False, allow_large=True)
    assert out.summary["counts"]["elements"] == 4


def test_huge_mesh_cli_refused_fast(tmp_path):
    out = tmp_path / "o"
    t = time.perf_counter()
    r = cli("run", "square-pedestal", "--mesh", "1000000x1000000x4", "--out", out)
    wall = time.perf_counter() - t
    one_error_line(r.stderr, 2, r.returncode, "4e+12 elements", "available", "--allow-large")
    assert not out.exists()
    assert wall < 30.0, wall  # an interpreter start-up (~1-2 s; generous for a loaded machine)


def test_initial_penetration_counts_and_depth():
    from solidshell.contact import Plane, Sphere, initial_penetration

    g = np.linspace(-3.0, 3.0, 13)
    x = np.array([(a, b, 0.0) for a in g for b in g])
    # laid exactly on the sphere's top with the offset: touching, not inside (round-off gaps only)
    assert initial_penetration([Sphere((0, 0, -5.02965), 5.0, offset=0.02965)], x) == []
    # centre 1 cm higher: nodes with r^2 < 25 - 16 are inside; the origin by 1 cm exactly
    hits = initial_penetration([Plane((0, 0, -10.0)), Sphere((0, 0, -4.0), 5.0)], x)
    r2 = (x[:, :2] ** 2).sum(1)
    assert len(hits) == 1 and hits[0][0] == 1
    assert hits[0][2] == np.count_nonzero(r2 < 9.0 - 1e-12)
    assert hits[0][3] == pytest.approx(1.0, abs=1e-14)
    # nodes not free (clamped) are not checked
    free = r2 > 0.0
    assert initial_penetration([Sphere((0, 0, -4.0), 5.0)], x, free=free)[0][2] == hits[0][2] - 1


def test_sheet_starting_inside_sphere_exit_2(tmp_path, capsys):
    from solidshell.cli import main

    out = tmp_path / "o"
    rc = main(["run", "sphere", "--mesh", "10x10", "--set", "contact.0.centre=[0.0, 0.0, -4.0]", "--out", str(out)])
    line = one_error_line(capsys.readouterr().err, 2, rc, "contact[0] (sphere", "node(s) of the sheet start inside")
    assert "deepest 1.03 cm" in line  # 1 cm above the centre + the 0.02965 cm offset
    assert not out.exists()


# ============================================================================= 2. run folders
def test_stale_files_replaced_and_run_id_everywhere(tmp_path):
    from solidshell.run import run_scene

    out = tmp_path / "o"
    a = run_scene("strip-warp", mesh="4x1", solver="none", out_dir=out, progress=False)
    assert set(a.summary["files"]) == {"mesh.xdmf", "mesh.vtu", "top.png", "iso.png", "side.png", "summary.json"}
    b = run_scene(
        "strip-warp", mesh="2x1", solver="none", out_dir=out, progress=False, overrides={"output.pictures": ["top"]}
    )
    assert names(out) == sorted(b.summary["files"]) == ["mesh.vtu", "mesh.xdmf", "summary.json", "top.png"]
    assert b.run_id != a.run_id and len(b.run_id) == 32
    assert {sio.read_run_id(out / n) for n in names(out)} == {b.run_id}
    assert b.summary["replaced_files"][0] == "summary.json"  # the old summary goes first
    assert b.summary["warnings"] == []
    _, U = sio.read_state(out / "mesh.vtu")  # the stamp leaves the files readable
    assert U.shape == (6, 6)


def test_foreign_files_refused_or_left_with_force(tmp_path, capsys):
    from solidshell.cli import main

    out = tmp_path / "o"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    rc = main(["mesh", "strip-warp", "--mesh", "2x1", "--out", str(out)])
    one_error_line(capsys.readouterr().err, 2, rc, "notes.txt", "--force")
    assert names(out) == ["notes.txt"]
    rc = main(["mesh", "strip-warp", "--mesh", "2x1", "--out", str(out), "--force", "--set", "output.pictures=[]"])
    err = capsys.readouterr().err
    assert rc == 0 and (out / "notes.txt").read_text() == "mine"
    s = json.loads((out / "summary.json").read_text())
    assert "notes.txt" not in s["files"] and len(s["warnings"]) == 1 and "notes.txt" in s["warnings"][0]
    assert err.strip().splitlines() == [f"solidshell: warning: {s['warnings'][0]}"]


def test_checkpoint_temporary_of_a_killed_run_is_cleared(tmp_path, capsys):
    """A run killed while writing its checkpoint leaves the atomic write's temporary in the
    folder (what made the restart-after-kill test fail once in CI). The next run naming that
    checkpoint takes the temporary for its own and removes it; a run that names no checkpoint
    still refuses it as a file solidshell did not write."""
    from solidshell.cli import main

    out = tmp_path / "o"
    out.mkdir()
    ck = out / "state.ckpt.npz"
    tmp = out / ".state.ckpt.k1ll3d_.npz"
    assert sio.is_temporary_of(tmp.name, ck.name) and not sio.is_temporary_of("state.ckpt.npz.x.npz", ck.name)
    tmp.write_bytes(b"half a zip")
    common = [
        "run",
        "strip-warp",
        "--mesh",
        "2x1",
        "--solver",
        "relax",
        "--set",
        "output.pictures=[]",
        "--no-progress",
        "--out",
        str(out),
    ]
    rc = main(common)
    one_error_line(capsys.readouterr().err, 2, rc, tmp.name, "--force")
    rc = main(common + ["--checkpoint", str(ck), "--set", "solver.relax.checkpoint_every=50"])
    capsys.readouterr()
    assert rc == 0 and not tmp.exists() and ck.exists()  # and written atomically itself
    assert not any(n.startswith(".") for n in names(out))


def test_checkpoint_refused_for_static(tmp_path, capsys):
    from solidshell.cli import main

    rc = main(["run", "strip-warp", "--checkpoint", str(tmp_path / "c.npz"), "--out", str(tmp_path / "o")])
    one_error_line(capsys.readouterr().err, 2, rc, "--checkpoint", "not static")
    assert names(tmp_path) == []


def test_unwritable_output_exit_3_with_path(tmp_path, capsys):
    from solidshell.cli import main

    (tmp_path / "file").write_text("x")
    out = tmp_path / "file" / "sub"  # cannot be created: its parent is a file
    rc = main(["mesh", "strip-warp", "--mesh", "2x1", "--out", str(out)])
    one_error_line(capsys.readouterr().err, 3, rc, "I/O error", str(out))


def test_full_disk_exit_3_names_file_and_keeps_the_earlier_run(tmp_path, capsys, monkeypatch):
    from solidshell import io as sio_mod
    from solidshell.cli import main

    out = tmp_path / "o"
    assert main(["mesh", "strip-warp", "--mesh", "2x1", "--out", str(out), "--set", "output.pictures=[]"]) == 0
    capsys.readouterr()
    before = {n: (out / n).read_bytes() for n in names(out)}
    real = sio_mod.write_mesh_file

    def full(path, *a, **k):
        if Path(path).name == "mesh.vtu":
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(path, *a, **k)

    monkeypatch.setattr(sio_mod, "write_mesh_file", full)
    rc = main(["mesh", "strip-warp", "--mesh", "4x1", "--out", str(out), "--set", "output.pictures=[]"])
    one_error_line(capsys.readouterr().err, 3, rc, str(out / "mesh.vtu"), "No space left on device")
    # the new run's files were written beside the old ones (rundir): the earlier run is left whole,
    # no marker, no staging folder
    assert {n: (out / n).read_bytes() for n in names(out)} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o"]
    with pytest.raises(IOFailure, match="mesh.vtu: No space left on device") as e:
        from solidshell.run import run_scene

        run_scene("strip-warp", mesh="4x1", solver="none", out_dir=out, progress=False)
    assert e.value.path == str(out / "mesh.vtu") and isinstance(e.value, OSError)


# ============================================================================= 3. exit statuses
def test_not_converged_exit_1_state_written(tmp_path):
    out = tmp_path / "o"
    r = cli(
        "run",
        "strip-warp",
        "--mesh",
        "2x1",
        "--solver",
        "relax",
        "--set",
        "solver.relax.max_steps=300",
        "--set",
        "output.pictures=[]",
        "--out",
        out,
        "--no-progress",
    )
    assert r.returncode == 1, r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["converged"] is False and s["interrupted"] is False and s["steps"] == 300
    assert "NOT converged" in r.stdout and "RUNNING" not in names(out)
    assert sio.read_run_id(out / "result.vtu") == s["run_id"]
    _, U = sio.read_state(out / "result.vtu")
    assert np.all(np.isfinite(U)) and np.abs(U).max() > 0  # the last state, not zeros


@pytest.mark.slow
def test_static_max_iter_1_exit_1(tmp_path):
    """Static Newton with one iteration per step cannot converge on the drooping strip (70 s today)."""
    out = tmp_path / "o"
    r = cli(
        "run",
        "strip-warp",
        "--mesh",
        "10x1",
        "--set",
        "solver.static.max_iter=1",
        "--set",
        "output.pictures=[]",
        "--out",
        out,
        "--no-progress",
    )
    assert r.returncode == 1, r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["converged"] is False and (out / "result.vtu").exists()


def test_interrupted_state_written_exit_130(tmp_path, capsys, fake):
    from solidshell.cli import main

    fake["solver"] = fake_solver(status="interrupted", converged=False)
    out = tmp_path / "o"
    rc = main(["run", "strip-warp", "--mesh", "4x1", "--out", str(out), "--set", "output.pictures=[]"])
    captured = capsys.readouterr()
    assert rc == 130 and "INTERRUPTED" in captured.out
    s = json.loads((out / "summary.json").read_text())
    assert s["interrupted"] is True and s["converged"] is False and s["status"] == "interrupted"
    _, U = sio.read_state(out / "result.vtu")
    assert U[:, 2].min() < 0  # the solver's last state
    assert sio.read_run_id(out / "result.vtu") == s["run_id"] and "RUNNING" not in names(out)


def test_ctrl_c_without_state_keeps_earlier_run(tmp_path, capsys, fake):
    from solidshell.cli import main

    out = tmp_path / "o"
    assert main(["run", "strip-warp", "--mesh", "4x1", "--out", str(out), "--set", "output.pictures=[]"]) == 0
    before = {n: (out / n).read_bytes() for n in names(out)}
    fake["solver"] = fake_solver(raise_=KeyboardInterrupt())
    rc = main(["run", "strip-warp", "--mesh", "4x1", "--out", str(out), "--set", "output.pictures=[]"])
    assert rc == 130 and "interrupted" in capsys.readouterr().err
    assert {n: (out / n).read_bytes() for n in names(out)} == before  # untouched, no marker left
    fake["solver"] = fake_solver(raise_=InputError("restart file x.npz does not match this run"))
    new = tmp_path / "new"
    rc = main(["run", "strip-warp", "--mesh", "4x1", "--out", str(new)])
    one_error_line(capsys.readouterr().err, 2, rc, "x.npz")
    assert not new.exists()  # a bad input found by the solver: nothing left


def test_sigint_relax_subprocess_exit_130(tmp_path):
    """Ctrl-C on a real relaxation: the solver returns its last state, the runner writes it."""
    out = tmp_path / "o"
    ck = tmp_path / "ck.npz"
    p = popen(
        "run",
        "strip-warp",
        "--mesh",
        "4x1",
        "--solver",
        "relax",
        "--set",
        "output.pictures=[]",
        "--set",
        "solver.relax.checkpoint_every=50",
        "--checkpoint",
        ck,
        "--out",
        out,
        "--no-progress",
    )
    t0 = time.time()
    # the first checkpoint says the time stepping has begun (a fixed delay is not enough on a loaded
    # machine: a Ctrl-C before the solver runs writes nothing, by design)
    while not ck.exists() and time.time() - t0 < 120:
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=120)
    assert p.returncode == 130, stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["interrupted"] is True and s["converged"] is False and 0 < s["steps"]
    assert sio.read_run_id(out / "result.vtu") == s["run_id"]


# ============================================================================= 4. warnings
def test_warnings_listed_and_logged(tmp_path, capsys, fake, monkeypatch):
    from solidshell.cli import main

    monkeypatch.setattr(FakeModel, "interpenetrated", 2)
    fake["solver"] = fake_solver(
        warnings=["the solver says so"],
        t_final=0.4,
        info={"max_interpenetrated_nodes": 5, "positive_definite": False, "min_tangent_eigenvalue": -2.5e-5},
    )
    out = tmp_path / "o"
    rc = main(["run", "hang-20", "--mesh", "4x4", "--out", str(out), "--set", 'output.pictures=["top"]'])
    err = capsys.readouterr().err.strip().splitlines()
    s = json.loads((out / "summary.json").read_text())
    w = s["warnings"]
    assert rc == 0
    assert w[0] == "the solver says so"
    assert any(x.startswith("2 node(s) interpenetrated at the end") for x in w)
    assert any("not a stable equilibrium" in x and "-2.5e-05" in x for x in w)
    assert any(x == "snapshot t = 2.1 s dropped: after the run's end t = 0.4 s" for x in w)
    assert err == [f"solidshell: warning: {x}" for x in w]
    assert {"iso_t0.000.png", "iso_t0.100.png", "iso_t0.400.png"} <= set(s["files"])
    assert not any("2.100" in f for f in s["files"])
    # a snapshot the solver already reported as dropped is not reported twice
    fake["solver"] = fake_solver(
        warnings=["snapshot time(s) 2.1 s after t_end = 0.4 s dropped"], info={"snapshots_after_t_end_dropped": [2.1]}
    )
    monkeypatch.setattr(FakeModel, "interpenetrated", 0)
    assert main(["run", "hang-20", "--mesh", "4x4", "--out", str(out), "--set", "output.pictures=[]"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["warnings"] == ["snapshot time(s) 2.1 s after t_end = 0.4 s dropped"]


def test_library_user_can_silence_warnings(tmp_path, fake, monkeypatch, capsys):
    from solidshell.run import run_scene

    fake["solver"] = fake_solver(warnings=["quiet please"])
    log = logging.getLogger("solidshell")
    monkeypatch.setattr(log, "disabled", True)
    out = run_scene("strip-warp", mesh="4x1", progress=False)
    assert out.warnings == ["quiet please"] and capsys.readouterr().err == ""


# ============================================================================= 5. progress
class _Tty(_stdio.StringIO):
    def isatty(self):
        return True


def test_progress_bar_appears_within_a_second_and_moves(monkeypatch):
    from solidshell.run.progress import _Bar

    err = _Tty()
    monkeypatch.setattr(sys, "stderr", err)
    bar = _Bar("strip")
    time.sleep(0.9)  # no progress call at all (a solver busy compiling)
    first = err.getvalue()
    bar(0.5, "load factor 0.5")
    time.sleep(0.6)
    second = err.getvalue()
    bar.close()
    assert "strip:   0%" in first
    assert "strip:  50%" in second and "load factor 0.5" in second
    monkeypatch.setattr(sys, "stderr", _stdio.StringIO())  # not a terminal: nothing drawn
    quiet = _Bar("strip")
    quiet(0.5, "x")
    time.sleep(0.6)
    quiet.close()
    assert sys.stderr.getvalue() == ""


# ============================================================================= 6. build_problem
def test_build_problem_public():
    import solidshell
    from solidshell.scenes import load
    from solidshell.scenes.build import build_scene_mesh, support_mask

    sc = load("sphere")
    mesh, _ = build_scene_mesh(sc, "4x4")
    pb = solidshell.build_problem(sc, mesh)
    assert pb.model.mesh is mesh and len(pb.contact) == 1 and pb.contact[0].friction == 0.3
    np.testing.assert_array_equal(pb.fixed, support_mask(sc, mesh))
    # self-weight: wool 0.019 gf/cm^2 on 30x30 cm, lumped by nodal areas (exact to round-off)
    assert pb.loads[:, 2].sum() == pytest.approx(-0.019 * 900.0, rel=1e-12)


# ============================================================================= 7. restart after kill -9
def _kill_and_restart(tmp_path, kind, sets):
    """Uninterrupted run A; run B with a checkpoint, SIGKILLed mid-run in A's folder; run C restarted
    from B's checkpoint in the same folder.  C's final state must equal A's bit for bit."""
    common = [
        "run",
        "strip-warp",
        "--mesh",
        "2x1",
        "--solver",
        kind,
        "--set",
        "output.pictures=[]",
        "--no-progress",
    ] + [x for k in sets for x in ("--set", f"solver.{kind}.{k}")]
    out = tmp_path / "o"
    a = cli(*common, "--out", out)
    assert a.returncode == 0, a.stderr
    sa = json.loads((out / "summary.json").read_text())
    _, UA = sio.read_state(out / "result.vtu")
    files_a = {n: (out / n).read_bytes() for n in names(out)}

    ck = out / "state.ckpt.npz"  # in the output folder: this run's, not foreign
    b = popen(*common, "--out", out, "--checkpoint", ck, "--set", f"solver.{kind}.checkpoint_every=500")
    t0 = time.time()
    while not ck.exists() and b.poll() is None and time.time() - t0 < 120:
        time.sleep(0.01)
    b.send_signal(signal.SIGKILL)
    b.communicate(timeout=60)
    assert b.returncode == -signal.SIGKILL, "run B ended before it could be killed mid-run"
    # the killed run changed nothing of A's files; its RUNNING marker says it never finished
    assert {n: (out / n).read_bytes() for n in names(out) if n in files_a} == files_a
    assert json.loads((out / "RUNNING").read_text())["run_id"] != sa["run_id"]

    c = cli(*common, "--out", out, "--restart", ck)
    assert c.returncode == 0, c.stderr
    sc = json.loads((out / "summary.json").read_text())
    assert sc["restarted_from_step"] > 0 and sc["steps"] == sa["steps"]
    _, UC = sio.read_state(out / "result.vtu")
    assert UC.tobytes() == UA.tobytes()
    assert "RUNNING" not in names(out) and ck.exists() and "state.ckpt.npz" not in sc["files"]
    assert {sio.read_run_id(out / n) for n in sc["files"]} == {sc["run_id"]}


def test_restart_after_kill_explicit_bitwise(tmp_path):
    _kill_and_restart(tmp_path, "explicit", ["t_end=0.2"])


def test_restart_after_kill_relax_bitwise(tmp_path):
    _kill_and_restart(tmp_path, "relax", ['damping="kinetic"'])


def test_run_output_problem_is_the_one_solved():
    """RunOutput.problem is the Problem the solver ran: the static state it returns balances that
    problem's loads.  The solver stops at a relative residual <= tol = 1e-8 (solvers/static.py);
    the bound 1e-6 leaves room for the round-off of re-evaluating the force in another call."""
    from solidshell.run import run_scene

    out = run_scene(
        "strip-warp",
        mesh="4x1",
        out_dir=None,
        progress=False,
        overrides={"output.pictures": [], "output.snapshots": []},
    )
    pb = out.problem
    assert pb.model.n_nodes == out.mesh.n_nodes
    free = ~np.asarray(pb.fixed, bool).reshape(-1)
    r = (pb.model.internal_force(out.U) - pb.loads).reshape(-1)[free]
    assert np.linalg.norm(r) <= 1e-6 * np.linalg.norm(np.asarray(pb.loads).reshape(-1)[free])
