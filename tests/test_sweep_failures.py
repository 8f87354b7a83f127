"""solidshell sweep with a run that fails, on a real dask.distributed LocalCluster: the failed run is
counted as failed (not as recorded), named on stderr, the command exits 1 -- also when resumed --
and states.csv / report.md are written with the settled runs' state and the failed run apart."""

import csv

import pytest

pytest.importorskip("distributed", reason="dask.distributed not installed (pip install 'solidshell[sweep]')")
pytest.importorskip("pyarrow", reason="pyarrow not installed (pip install 'solidshell[sweep]')")

from solidshell import cli  # noqa: E402
from solidshell.sweep import load_spec  # noqa: E402
from solidshell.sweep.ledger import Ledger  # noqa: E402

# three runs of the smallest square-pedestal mesh (48 quads, ~2 s each): runs 0 and 1 are the same
# drape (check_stability only adds the tangent's eigenvalue test), run 2 clamps a node set the mesh
# does not have -- accepted by the sweep file's checks (they build no mesh), refused by the run.
SWEEP = """
name = "fail-tiny"
scene = "square-pedestal"
mesh = "6x2x4"
[set]
"output.pictures" = ["top"]
[zip]
"supports.clamped" = ["clamped", "clamped", "no-such-set"]
"solver.static.check_stability" = [false, true, false]
"""


def test_failed_run_is_counted_named_and_exits_1(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text(SWEEP)
    spec = load_spec(f)
    out = tmp_path / "out"
    rc = cli.main(["sweep", str(f), "--out", str(out), "--workers", "1", "--retries", "0", "--no-progress"])
    cap = capsys.readouterr()
    bad = spec.runs[2].key
    assert rc == 1
    assert "2 run(s) recorded now, 0 before, 1 failed now, 0 before, 3 in all" in cap.out
    err = [ln for ln in cap.err.splitlines() if ln.startswith("solidshell:")]  # not the start line
    assert len(err) == 1 and "run 2 (supports.clamped=no-such-set" in err[0] and bad in err[0]
    assert "InputError" in err[0] and "no node set 'no-such-set'" in err[0]

    # the ledger keeps the failed run's row (a resumed sweep does not repeat it), status "error"
    rows = Ledger(out, spec).read().to_pylist()
    assert [r["status"] for r in rows] == ["done", "done", "error"]
    assert rows[2]["key"] == bad and "no-such-set" in rows[2]["error"]
    assert all(r["converged"] and r["fold_count"] == 4 for r in rows[:2])
    # the same scene, mesh and solver: the two settled runs are one drape, bit for bit
    assert rows[0]["drape_coefficient"] == rows[1]["drape_coefficient"]

    # states.csv: one state, the two settled runs; the frequency counts all three recorded runs
    with open(out / "states.csv", newline="") as fh:
        table = list(csv.DictReader(fh))
    assert len(table) == 1
    st = table[0]
    dc = rows[0]["drape_coefficient"]
    assert (st["state"], st["fold_count"], st["runs"], st["frequency"]) == ("1", "4", "2", f"{2 / 3:.4f}")
    assert st["dc_min"] == st["dc_mean"] == st["dc_max"] == f"{dc:.4f}"
    assert st["stable_runs"] == "1"  # only run 1 checked its tangent (positive definite)
    assert st["representative_key"] == spec.runs[0].key
    assert st["picture"].endswith(f"{spec.runs[0].key}/top.png")

    # report.md: the state table's row, the count of failed runs, the failed run among the unsettled
    md = (out / "report.md").read_text()
    assert "3 of 3 runs recorded, 1 of them failed (no result); 1 distinct state(s)" in md
    row = next(ln for ln in md.splitlines() if ln.startswith("| S"))
    assert row.startswith("| S1 | 4 | 2 | 0.67 | ") and "| 1/2 | " in row and row.endswith(f"| {spec.runs[0].key} |")
    assert sum(ln.startswith("| S") for ln in md.splitlines()) == 1
    assert f"Unsettled runs: {bad} (InputError:" in md
    assert "Fold-count frequencies: 4 folds: 2/3" in md

    # resumed: nothing to run (no cluster), still exit 1, the earlier failure named again
    rc = cli.main(["sweep", str(f), "--out", str(out), "--no-progress"])
    cap = capsys.readouterr()
    assert rc == 1
    assert "0 run(s) recorded now, 3 before, 0 failed now, 1 before, 3 in all" in cap.out
    err = [ln for ln in cap.err.splitlines() if ln.startswith("solidshell:")]
    assert len(err) == 1 and "failed in an earlier invocation" in err[0] and bad in err[0]
    assert sorted(p.stem for p in (out / "ledger").glob("*.parquet")) == sorted(r.key for r in spec.runs)
