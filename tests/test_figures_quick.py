"""verification/figures_quick.py: every quick figure made, and its numbers as stored in
reference/figures_quick.json.  The slow test runs the whole quick set (~8 min on one thread of a
shared 2-core machine); the others check the checker on the stored numbers themselves."""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from verification import figures_quick as fq

ROOT = Path(__file__).resolve().parents[1]


def stored():
    return json.loads(fq.REFERENCE.read_text())


def fake_folder(folder: Path, figs: dict) -> Path:
    """figNN.json holding the given key numbers, and a PNG-headed file of 10 kB beside each."""
    folder.mkdir(exist_ok=True)
    for name, numbers in figs.items():
        (folder / f"{name}.json").write_text(json.dumps({"figure": name, "quick": True, **numbers}))
        (folder / f"{name}.png").write_bytes(fq.PNG_MAGIC + bytes(10_000))
    return folder


def test_reference_covers_every_figure_with_a_state():
    """The stored file has every figure of the registry, each run with its identity, and every
    drape run a fold count and a DC (the numbers that say which state it is in)."""
    from paper_figures.registry import FIGURES

    ref = stored()
    assert sorted(ref["figures"]) == sorted(fq.figure_names(FIGURES))
    assert ref["tolerances"] == fq.tolerance_table()  # the file says what the script compares, and why
    for name, fig in ref["figures"].items():
        assert fig["runs"], name
        for r in fig["runs"]:
            assert {"scene", "mesh", "solver", "converged"} <= set(r), (name, r)
            if not r["scene"].startswith(("strip", "hang")):
                assert isinstance(r["fold_count"], int) and 0 < r["drape_coefficient"] < 1, (name, r)


def test_compare_flags_a_change_of_state_and_passes_round_off():
    fig = stored()["figures"]["fig06"]
    rows, diffs = fq.compare(fig, copy.deepcopy(fig), "fig06")
    assert not diffs and rows and all(r[-1] for r in rows)
    now = copy.deepcopy(fig)
    now["runs"][0]["drape_coefficient"] *= 1 + 1e-12  # round-off: far inside 1e-6 relative
    assert not fq.compare(fig, now, "fig06")[1]
    now["runs"][0]["fold_count"] += 4  # another state: 8 folds instead of 4
    now["runs"][2]["drape_coefficient"] *= 1 + 1e-4  # 100 ppm: above the 1e-6 tolerance
    now["runs"][3]["positive_definite"] = False
    diffs = fq.compare(fig, now, "fig06")[1]
    assert [d.split(":")[0] for d in diffs] == [
        "fig06 run 0 fold_count",
        "fig06 run 2 drape_coefficient",
        "fig06 run 3 positive_definite",
    ]
    del now["runs"][3]
    assert "fig06: 3 runs now, 4 stored" in fq.compare(fig, now, "fig06")[1]


def test_check_passes_the_stored_numbers_and_fails_a_missing_or_capped_figure(tmp_path):
    ref = stored()["figures"]
    names = ["fig05", "fig12", "fig19"]
    folder = fake_folder(tmp_path / "ok", {n: ref[n] for n in names})
    lines = []
    assert fq.check(folder, names, fq.REFERENCE, log=lines.append) == 0
    assert "passed: 3 figure(s)" in lines[-1]

    bad = copy.deepcopy({n: ref[n] for n in names})
    bad["fig19"]["runs"][0]["message"] = "stopped at t = 12 s: wall-time limit 120 s reached"
    bad["fig12"]["interpenetrated_node_ids"] = bad["fig12"].get("interpenetrated_node_ids", []) + [0]
    folder = fake_folder(tmp_path / "bad", bad)
    (folder / "fig05.png").unlink()
    lines = []
    assert fq.check(folder, names, fq.REFERENCE, log=lines.append) == 1
    text = "\n".join(lines)
    assert "fig05: fig05.png missing" in text
    assert "fig19 run 0: stopped by its wall-time cap" in text
    assert "fig12 figure interpenetrated_node_ids: stored" in text


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert fq.main(["99"]) == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "figures_quick: unknown figure '99'; valid: 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 19, 20, 21, 22"
    ]
    assert fq.main(["--from", str(tmp_path / "nowhere")]) == 2
    assert "no such folder" in capsys.readouterr().err


@pytest.mark.slow
def test_quick_figures_as_stored(tmp_path):
    """solidshell figures --quick: all 14 PNGs and JSONs, every number as stored (~8 min, 1 thread)."""
    env = {**os.environ, "NUMBA_NUM_THREADS": os.environ.get("NUMBA_NUM_THREADS", "1")}
    r = subprocess.run(
        [sys.executable, "-m", "verification.figures_quick", "--keep", str(tmp_path)],
        cwd=ROOT,
        env=env,
        text=True,
        capture_output=True,
        timeout=3600,
        check=False,
    )
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    assert "passed: 14 figure(s)" in r.stdout
    assert len(list(tmp_path.glob("fig*.png"))) == 14 and len(list(tmp_path.glob("fig*.json"))) == 14
