"""solidshell sweep on a real dask.distributed LocalCluster (tiny strip runs): results recorded,
identical to an in-process run, a second invocation resumes without recomputing."""

import json

import pytest

pytest.importorskip("distributed", reason="dask.distributed not installed (pip install 'solidshell[sweep]')")
pytest.importorskip("pyarrow", reason="pyarrow not installed (pip install 'solidshell[sweep]')")

from solidshell import cli  # noqa: E402
from solidshell.run import run_scene  # noqa: E402
from solidshell.sweep import load_spec  # noqa: E402
from solidshell.sweep.engine import Cluster, run_sweep  # noqa: E402
from solidshell.sweep.ledger import Ledger  # noqa: E402

SWEEP = """
name = "strip-tiny"
scene = "strip-warp"
mesh = "10x1"
[set]
"solver.static.check_stability" = false
[grid]
"material.bending_warp" = [0.06, 0.083]
"""


def test_local_cluster_sweep_and_resume(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text(SWEEP)
    spec = load_spec(f)
    out = tmp_path / "out"
    res = run_sweep(spec, out, Cluster(workers=1), progress=False)
    assert (res.recorded, res.skipped, res.failed, res.workers) == (2, 0, [], 1)
    rows = Ledger(out, spec).read().to_pylist()
    assert [r["material.bending_warp"] for r in rows] == [0.06, 0.083]
    assert all(r["status"] == "done" and r["converged"] and r["worker"].startswith("tcp://127.0.0.1") for r in rows)
    # the worker's run is the in-process run: same single-threaded arithmetic, bit for bit
    ref = run_scene(
        "strip-warp",
        mesh="10x1",
        progress=False,
        overrides={"solver.static.check_stability": False, "material.bending_warp": 0.083},
    )
    s1 = json.loads((out / "runs" / rows[1]["key"] / "summary.json").read_text())
    assert s1["tip_position"] == ref.summary["tip_position"]
    assert rows[1]["residual"] == ref.summary["final_relative_residual"]
    # again: nothing to do, no cluster started, nothing recorded twice; the CLI says so, exit 0
    rc = cli.main(["sweep", str(f), "--out", str(out), "--no-progress"])
    o = capsys.readouterr().out
    assert rc == 0 and "0 run(s) recorded now, 2 before" in o
    assert sorted(p.name for p in (out / "ledger").iterdir()) == sorted(f"{r['key']}.parquet" for r in rows)
    assert (out / "report.md").is_file() and (out / "strip-tiny.png").is_file()
