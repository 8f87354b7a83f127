"""``solidshell verify``: the quick set passes (an accuracy regression fails the test run), the
command's exit statuses, the record format, and the regenerate-and-compare of the reference data."""

from __future__ import annotations

import copy
import json

import pytest

from solidshell import cli
from verification.checks import CHECKS, references
from verification.checks.pedestal import check_pedestal_kratos
from verification.checks.record import Context

FIELDS = {
    "name",
    "reference",
    "source",
    "quantity",
    "value",
    "reference_value",
    "error",
    "tolerance",
    "passed",
    "wall_time_s",
    "why",
    "status",
}


def test_quick_verification_passes(tmp_path, capsys):
    # the whole --quick set through the command line (about 30 CPU-seconds): every record within
    # its stated tolerance, each with its why, and the report with its plots written
    rc = cli.main(["verify", "--quick", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    data = json.loads((tmp_path / "verification.json").read_text())
    failed = [r["name"] for r in data["records"] if r["status"] != "passed"]
    assert rc == 0 and not failed, (failed, out[-3000:])
    assert len(data["records"]) >= 60
    for r in data["records"]:
        assert FIELDS <= set(r) and r["why"] and r["passed"] is True and r["error"] <= r["tolerance"]
    assert {c["name"] for c in data["checks"]} == {c.name for c in CHECKS.values() if c.quick}
    report = (tmp_path / "report.md").read_text()
    for f in data["figures"].values():
        for png in f:
            assert (tmp_path / png).stat().st_size > 10_000 and png in report


def test_unknown_check_is_one_line_exit_2(tmp_path, capsys):
    rc = cli.main(["verify", "strip", "no-such-check", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1
    assert "no-such-check" in err and all(name in err for name in CHECKS)
    assert not (tmp_path / "o").exists()  # nothing ran, nothing written


def test_unwritable_output_is_exit_3(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    rc = cli.main(["verify", "zero-modes", "--out", str(blocker / "sub")])
    assert rc == 3 and str(blocker) in capsys.readouterr().err


def test_list_names_every_check(capsys):
    assert cli.main(["verify", "--list"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in CHECKS)


def test_fenicsx_without_dolfinx_is_one_line_exit_2(capsys, monkeypatch, tmp_path):
    # DOLFINx lives under the system python (verification/fenicsx/jobs.py): point that at nothing
    import verification.fenicsx.jobs as jobs

    monkeypatch.setattr(jobs, "SYSTEM_PYTHON", str(tmp_path / "no-python"))
    monkeypatch.setattr(jobs.check_dolfinx, "__defaults__", (jobs.SYSTEM_PYTHON,))
    out = tmp_path / "never-written"
    rc = cli.main(["verify", "--fenicsx", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and "dolfinx" in err.lower()
    assert not out.exists()  # bad input: nothing written


def test_failed_record_gives_exit_1(tmp_path, monkeypatch):
    # a check whose measurement misses its tolerance must fail the command
    from verification.checks import record

    def bad(ctx):
        return [record.measure("fake/x", "x", 1.1, 1.0, 1e-3, reference="r", source="s", why="test")]

    monkeypatch.setitem(CHECKS, "fake", record.Check("fake", "t", bad, "a failing check", False, False))
    assert cli.main(["verify", "fake", "--out", str(tmp_path)]) == 1
    rec = json.loads((tmp_path / "verification.json").read_text())["records"][0]
    assert rec["passed"] is False and rec["status"] == "failed" and rec["error"] == pytest.approx(0.1)


def test_missing_kratos_reference_is_skipped_not_passed():
    if (references.reference_dir() / "pedestal_kratos.json").exists():
        pytest.skip("the Kratos reference exists: the check compares (default set)")
    (r,) = check_pedestal_kratos(Context(quick=True))
    assert r.status == "skipped" and r.passed is None and "not present" in r.note


def test_compare_json_finds_a_changed_value():
    old = {"a": [1.0, 2.0], "t": {"x": 1.0, "seconds": 3.0}, "rows": [{"v": 1.0}, {"v": 2.0}]}
    new = copy.deepcopy(old)
    new["t"]["seconds"] = 99.0  # bookkeeping: ignored
    new["rows"] = new["rows"][:1]  # a quick regeneration has fewer rows: compared
    assert references.compare_json(old, new, 1e-9, 0.0) == []
    new["a"][1] = 2.0 + 1e-6
    (d,) = references.compare_json(old, new, 1e-9, 0.0)
    assert d.startswith("/a[1]")


def test_stored_elastica_regenerates_unchanged():
    # reference/elastica.py rerun into a temporary file reproduces elastica_strip.json (1e-9)
    (row,) = references.check_references(names={"elastica_strip.json"}, log=lambda s: None)
    assert row["passed"] is True and row["differences"] == []
