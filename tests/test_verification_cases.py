"""The case studies' shared cache, report and command line (verification/cases.py), and the committed
reports: each is what its script regenerates from the committed per-case cache, so no row lives only
in a report (dynamic_sphere's report once held rows whose cached json was not in the checkout)."""

import json
import shutil
from pathlib import Path

import pytest

from verification import cases, dynamic_scenes, dynamic_sphere, fold_pursuit

STORED = Path(dynamic_sphere.__file__).resolve().parent / "out"


def test_cell_formats():
    assert cases.cell(None) == "–"
    assert cases.cell(True) == "yes" and cases.cell(False) == "NO" and cases.cell(False, no="no") == "no"
    assert cases.cell(0.123456, ".3f") == "0.123"
    assert cases.cell(7, ".3f") == "7"  # a count stays a count: the spec is for floats
    assert cases.cell("8x64") == "8x64"


def test_store_and_cached_round_trip(tmp_path):
    row = {"case": "a", "x": 1.5, "path": tmp_path}  # a Path is stored by str
    cases.store(tmp_path, "a", row)
    rows, missing = cases.cached(tmp_path, ["b", "a", "c"])
    assert rows == [{"case": "a", "x": 1.5, "path": str(tmp_path)}]
    assert missing == ["b", "c"]


def test_run_recorded_keeps_a_failure_as_a_row():
    def boom():
        raise ValueError("bad mesh")

    row = {}
    assert cases.run_recorded(boom, row) is None
    assert row["error"] == "ValueError: bad mesh"
    assert row["total_wall_s"] >= 0.0 and row["load_start"] and row["load_end"] and row["started"].endswith("UTC")


def test_main_list_case_and_report(capsys):
    ran, reported = [], []
    demo = {"one": ("x",), "two": ("y",)}

    def run(n):
        ran.append(n)
        return {"case": n, "ok": True, "other": 1}

    cases.main(["--list"], "doc", demo, run, lambda: reported.append(1), lambda n, c: f"{n}:{c[0]}")
    assert capsys.readouterr().out.split() == ["one:x", "two:y"] and not ran and not reported
    cases.main(["--case", "two"], "doc", demo, run, lambda: reported.append(1), str, echo_keys=("case", "ok"))
    assert ran == ["two"] and not reported
    assert json.loads(capsys.readouterr().out) == {"case": "two", "ok": True}
    cases.main([], "doc", demo, run, lambda: reported.append(1), str)  # no option: the report
    assert reported == [1]
    with pytest.raises(SystemExit, match="^2$") as e:  # an unknown case is a usage error (argparse, exit 2)
        cases.main(["--case", "three"], "doc", demo, run, lambda: None, str)
    assert e.value.code == 2


@pytest.mark.parametrize(
    "module, stem",
    [(fold_pursuit, "fold_pursuit"), (dynamic_sphere, "dynamic_sphere"), (dynamic_scenes, "dynamic_scenes")],
)
def test_committed_report_is_regenerated_from_the_committed_cache(module, stem, tmp_path, monkeypatch, capsys):
    shutil.copy(STORED / "static_scenes.json", tmp_path)  # dynamic_scenes' static reference column
    monkeypatch.setattr(module, "OUT", tmp_path)
    module.report()
    capsys.readouterr()
    assert (tmp_path / f"{stem}.md").read_text() == (STORED / f"{stem}.md").read_text()
    assert json.loads((tmp_path / f"{stem}.json").read_text()) == json.loads((STORED / f"{stem}.json").read_text())
