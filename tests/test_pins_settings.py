"""Behaviours no test pinned before issue 34 (item 5): a deliberate bug in each went through the
whole suite.  ``solidshell verify`` fails (exit 1) when a check raises, returns nothing or returns a
failed verdict; ``adapt.every = 0`` and ``load_steps`` with ``load_factors`` are refused in one line
(exit 2) before anything is written."""

from __future__ import annotations

import json

import pytest

from solidshell import cli
from solidshell.adapt.settings import AdaptSettings
from solidshell.errors import InputError
from solidshell.settings import parse
from solidshell.solvers.static.settings import StaticSettings
from verification.checks import CHECKS, record
from verification.checks.runner import run_checks


# --------------------------------------------------------------------------- solidshell verify
def _register(monkeypatch, name, fn):
    monkeypatch.setitem(CHECKS, name, record.Check(name, "pins", fn, f"test check {name}", False, False))


def _good(ctx):
    return [record.measure("good/x", "x", 1.0, 1.0, 1e-12, reference="r", source="s", why="exact")]


def test_check_that_raises_exits_1_with_an_error_record(tmp_path, monkeypatch, capsys):
    def broken(ctx):
        raise ZeroDivisionError("deliberate\nbug in the check")

    _register(monkeypatch, "good", _good)
    _register(monkeypatch, "broken", broken)
    rc = cli.main(["verify", "good", "broken", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 1
    assert "2 records from 2 checks: 1 passed, 1 failed, 0 skipped" in out
    recs = {r["name"]: r for r in json.loads((tmp_path / "verification.json").read_text())["records"]}
    assert recs["good/x"]["status"] == "passed"  # the run went on after the raise
    err = recs["broken/error"]
    assert err["status"] == "error" and err["passed"] is False and err["check"] == "broken"
    assert err["note"] == "ZeroDivisionError: deliberate bug in the check"  # the exception, one line
    assert err["why"].startswith("ZeroDivisionError raised at test_pins_settings.py:")  # where it raised
    assert err["why"].endswith(" in broken")
    broken_line = next(ln for ln in out.splitlines() if ln.startswith("broken/error"))
    assert broken_line.split()[-1] != "pass" and "ERROR" in broken_line


def test_runner_counts_a_raise_an_empty_check_and_a_false_verdict_as_failed(monkeypatch):
    def raises(ctx):
        raise RuntimeError("no mesh")

    def empty(ctx):
        return []

    def inconsistent(ctx):  # passed=False under the default status "passed": still a failure
        return [
            record.Record(
                name="inc/x",
                reference="r",
                source="s",
                quantity="x",
                value=2.0,
                reference_value=1.0,
                error=1.0,
                tolerance=0.1,
                passed=False,
                wall_time_s=0.0,
            )
        ]

    checks = [
        record.Check(n, "pins", f, n, False, False)
        for n, f in (("good", _good), ("raises", raises), ("empty", empty), ("inc", inconsistent))
    ]
    run = run_checks(checks, log=lambda s: None)
    assert run["failed"] == 3
    assert [c["failed"] for c in run["checks"]] == [0, 1, 1, 1]
    by = {r.name: r for r in run["records"]}
    assert by["raises/error"].note == "RuntimeError: no mesh"
    assert by["empty/error"].status == "error" and "no records" in by["empty/error"].note


def test_verify_exits_1_on_an_empty_check(tmp_path, monkeypatch):
    _register(monkeypatch, "empty", lambda ctx: [])
    assert cli.main(["verify", "empty", "--out", str(tmp_path)]) == 1


# --------------------------------------------------------------------------- adapt.every
def test_adapt_every_zero_is_refused():
    with pytest.raises(InputError, match=r"adapt: setting every = 0: .*greater than or equal to 1"):
        parse(AdaptSettings, {"every": 0}, "adapt")
    assert parse(AdaptSettings, {"every": 1}, "adapt").every == 1  # the smallest legal value


def test_adapt_every_zero_cli_one_line_exit_2(tmp_path, capsys):
    out = tmp_path / "o"
    rc = cli.main(
        [
            "run",
            "square-pedestal",
            "--solver",
            "relax",
            "--adaptive",
            "--set",
            "adapt.every=0",
            "--out",
            str(out),
            "--no-pictures",
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    assert "adapt" in err[0] and "every = 0" in err[0]
    assert not out.exists()  # refused before anything is written


# --------------------------------------------------------------------------- load_steps + load_factors
def test_load_steps_with_load_factors_is_refused():
    with pytest.raises(InputError, match=r"solver\.static: give load_steps or load_factors, not both"):
        parse(StaticSettings, {"load_steps": 2, "load_factors": [0.5, 1.0]}, "solver.static")
    # either one alone is accepted and gives the same factors
    a = parse(StaticSettings, {"load_steps": 2}, "solver.static").factors()
    b = parse(StaticSettings, {"load_factors": [0.5, 1.0]}, "solver.static").factors()
    assert a == b == [0.5, 1.0]


def test_load_steps_with_load_factors_cli_one_line_exit_2(tmp_path, capsys):
    out = tmp_path / "o"
    rc = cli.main(
        [
            "run",
            "strip-warp",
            "--mesh",
            "4x1",
            "--set",
            "solver.static.load_steps=2",
            "--set",
            "solver.static.load_factors=[0.5, 1.0]",
            "--out",
            str(out),
            "--no-pictures",
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    assert "load_steps" in err[0] and "load_factors" in err[0]
    assert not out.exists()
