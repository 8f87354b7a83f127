"""``solidshell bench``: the work-precision machinery on the quick strip study (seconds)."""

import json
import math

import pytest

from solidshell.bench import STUDIES
from solidshell.bench.workprec import cheapest, run_study, write
from solidshell.cli import main


@pytest.fixture(scope="module")
def strip_result():
    return run_study(STUDIES["strip"], quick=True, say=lambda m: None)


def test_strip_errors_converge_at_second_order(strip_result):
    """The quad strip's tip error against the elastica on 5x1, 10x1, 20x1 falls at the bilinear
    element's O(h^2) (measured 1.87 and 1.92; [1.5, 2.5] leaves room for the pre-asymptotic
    coarsest mesh but fails a first-order or a non-converging element), and every error is a
    real number below 2 % (the coarsest: 1.7 %)."""
    quads = [r for r in strip_result["rows"] if r["family"] == "static Newton, quads"]
    e = [r["errors"]["tip"] for r in quads]
    assert [r["label"] for r in quads] == ["5x1", "10x1", "20x1"]
    assert all(0.0 < x < 0.02 for x in e)
    for a, b in zip(e, e[1:]):
        assert 1.5 < math.log2(a / b) < 2.5
    # triangles and quads share the nodes and converge alike (to 10 % of each other)
    tris = [r["errors"]["tip"] for r in strip_result["rows"] if r["family"] == "static Newton, triangles"]
    assert all(abs(t / q - 1.0) < 0.1 for t, q in zip(tris, e))


def test_cheapest_and_outputs(strip_result, tmp_path):
    c = cheapest(strip_result, "tip")
    assert c is not None and c["errors"]["tip"] <= 0.01
    assert all(r["wall_s"] >= c["wall_s"] for r in strip_result["rows"] if r["errors"]["tip"] <= 0.01)
    paths = write(strip_result, tmp_path, "test")
    assert [p.name for p in paths] == ["strip.json", "strip.md", "strip.png"]
    back = json.loads(paths[0].read_text())
    assert len(back["rows"]) == len(strip_result["rows"]) and back["machine"]["cores"] >= 1
    md = paths[1].read_text()
    assert "Cheapest configuration within 1%" in md and "\\|tip deflection" in md


def test_unknown_study_is_bad_input(capsys, tmp_path):
    assert main(["bench", "nope", "--out", str(tmp_path / "b")]) == 2
    assert "unknown bench study 'nope'" in capsys.readouterr().err
    assert not (tmp_path / "b").exists()
