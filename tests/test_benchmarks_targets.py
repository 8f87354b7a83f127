"""benchmarks/targets.py's adapt rows from fake runs (no subprocess): the ratios, the DC difference,
the met rule and the table line."""

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _load():
    spec = importlib.util.spec_from_file_location("benchmarks_targets", ROOT / "benchmarks" / "targets.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


T = _load()


def _run(variant, wall, process, dc, nodes, max_active=None, load=1.0):
    return {
        "variant": variant,
        "wall_time_s": wall,
        "process_s": process,
        "load": load,
        "steal": 0.0,
        "drape_coefficient": dc,
        "fold_count": 4,
        "steps": 1000,
        "nodes": nodes,
        "max_active_nodes": max_active,
        "background_nodes": 3264 if variant == "adaptive" else None,
    }


def test_adapt_row_met_and_not():
    u = [_run("uniform", 40.0, 45.0, 0.5960, 3264), _run("uniform", 44.0, 49.0, 0.5960, 3264)]
    a = [_run("adaptive", 18.0, 22.0, 0.5990, 1200, 1400), _run("adaptive", 20.0, 24.0, 0.5990, 1300, 1450)]
    row = T.adapt_row("square-pedestal", "48x16x4", u, a)
    assert row["case"] == "adapt:square-pedestal"
    assert row["median"] == pytest.approx(19.0 / 42.0)
    assert row["round_ratios"] == pytest.approx([18.0 / 40.0, 20.0 / 44.0])
    assert row["process_ratio"] == pytest.approx(23.0 / 47.0)
    assert row["node_ratio"] == pytest.approx(1450 / 3264)
    assert row["dc_difference"] == pytest.approx(0.0030 / 0.5960)
    assert row["background_matches"] and row["met"]
    assert [r["variant"] for r in row["runs"]] == ["uniform", "adaptive", "uniform", "adaptive"]
    line = T.table([row]).splitlines()[-1]
    assert line.startswith("| adapt:square-pedestal |") and line.endswith("| yes |")
    assert "0.45 |" in line and "1450 active nodes (0.44)" in line and "(+0.50%)" in line

    # each condition alone fails the row: time, nodes, DC
    slow = [dict(r, wall_time_s=r["wall_time_s"] * 2) for r in a]
    assert not T.adapt_row("square-pedestal", "48x16x4", u, slow)["met"]
    many = [dict(r, max_active_nodes=2000) for r in a]
    assert not T.adapt_row("square-pedestal", "48x16x4", u, many)["met"]
    off = [dict(r, drape_coefficient=0.5960 * 1.011) for r in a]
    row = T.adapt_row("square-pedestal", "48x16x4", u, off)
    assert not row["met"] and T.table([row]).splitlines()[-1].endswith("| no |")


def test_adapt_scenes_option_checked():
    assert set(T.ADAPT_SCENES) <= set(T.ADAPT_UNIFORM)
    assert T.main(["--cases", "adapt", "--adapt-scenes", "no-such-scene"]) == 2


def test_adapt_set_reaches_the_adaptive_command_only(monkeypatch, tmp_path):
    """``--adapt-set KEY=VALUE`` is given to the adaptive runs (``--set``), not to the uniform ones,
    and the row's commands say so."""
    calls = []

    def fake(args, out, pictures=False):
        calls.append(args)
        adaptive = "--adaptive" in args
        return _run("adaptive" if adaptive else "uniform", 1.0, 2.0, 0.596, 3264, 1400 if adaptive else None)

    monkeypatch.setattr(T, "run_once", fake)
    (row,) = T.adaptivity_rows(1, str(tmp_path), ["square-pedestal"], ("adapt.ramp=true", "adapt.freeze_after=0"))
    uniform, adaptive = calls
    assert "--set" not in uniform
    assert adaptive[-4:] == ["--set", "adapt.ramp=true", "--set", "adapt.freeze_after=0"]
    assert row["commands"][1].endswith("--adaptive --set adapt.ramp=true --set adapt.freeze_after=0 --no-pictures")
