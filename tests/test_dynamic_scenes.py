"""Fast checks of the dynamic-scene verification tools (verification/dynamic_scenes.py,
verification/dynamic_stress.py): the report assembles from cached cases, a step above the
critical one is refused, and a forced unstable step is detected rather than returned as good."""

import json

import pytest

from solidshell.errors import InputError
from solidshell.run import run_scene
from verification import dynamic_scenes


def test_report_from_cache(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    cache.mkdir()
    monkeypatch.setattr(dynamic_scenes, "CACHE", cache)
    monkeypatch.setattr(dynamic_scenes, "OUT", tmp_path)
    row = dict(
        case="sp48-kin-dir",
        scene="square-pedestal",
        mesh="48x16x4",
        solver="relax",
        settings_label="kin-dir",
        settings={},
        overrides={},
        run_dir=str(tmp_path / "none"),
        total_wall_s=1.0,
        load_start="1 1 1",
        load_end="1 1 1",
        error=None,
        converged=True,
        steps=10,
        dt=1e-5,
        t_final=1e-4,
        wall_time_s=1.0,
        drape_coefficient=0.5,
        fold_count=4,
        max_interpenetrated_nodes=0,
        energy_balance_error=1e-6,
    )
    (cache / "sp48-kin-dir.json").write_text(json.dumps(row))
    rows = dynamic_scenes.report()
    assert len(rows) == 1
    text = (tmp_path / "dynamic_scenes.md").read_text()
    assert "| sp48-kin-dir | square-pedestal | 48x16x4 | kin-dir | yes | 10 |" in text
    assert "Not run" in text and "sphere60-green" in text


def _crit(**kw):
    o = run_scene("strip-warp", mesh="10x1", solver="explicit", progress=False, t_end=1e-7, **kw)
    return o.summary["critical_time_step"]


def test_step_above_critical_refused():
    dtc = _crit()
    with pytest.raises(InputError, match="critical"):
        run_scene(
            "strip-warp",
            mesh="10x1",
            solver="explicit",
            progress=False,
            t_end=50 * dtc,
            dt=1.1 * dtc,
            critical_time_step=dtc,
        )


def test_forced_unstable_step_detected_and_stable_step_fine():
    dtc = _crit()
    bad = run_scene(
        "strip-warp",
        mesh="10x1",
        solver="explicit",
        progress=False,
        t_end=2000 * 1.2 * dtc,
        dt=1.2 * dtc,
        critical_time_step=dtc,
        allow_unstable=True,
    )
    assert bad.summary["converged"] is False
    assert bad.summary["message"]
    good = run_scene(
        "strip-warp",
        mesh="10x1",
        solver="explicit",
        progress=False,
        t_end=2000 * 0.9 * dtc,
        dt=0.9 * dtc,
        critical_time_step=dtc,
    )
    assert good.summary["converged"] is True
    assert good.summary["energy_balance_error"] < 1e-2


def test_sphere_scene_friction_key():
    """[[contact]] friction: the sphere scene sets mu = 0.3 (frictionless sphere: the cloth slides
    off); a negative or non-finite coefficient is refused with the key named; the runner passes it
    to the body; 0 is the default."""
    from solidshell.scenes import load as load_scene
    from solidshell.scenes.build import contact_bodies

    sc = load_scene("sphere")
    assert sc.contact[0]["friction"] == 0.3
    assert contact_bodies(sc)[0].friction == 0.3
    assert contact_bodies(sc.with_overrides({"contact.0.friction": 0.0}))[0].friction == 0.0
    for bad in (-0.2, float("nan"), float("inf"), "high"):
        with pytest.raises(InputError, match="friction"):
            sc.with_overrides({"contact.0.friction": bad})
    ped = load_scene("square-pedestal")
    assert all(c.get("friction", 0.0) == 0.0 for c in ped.contact)


def test_sphere_study_report_from_cache(tmp_path, monkeypatch):
    from verification import dynamic_sphere

    cache = tmp_path / "cache"
    cache.mkdir()
    monkeypatch.setattr(dynamic_sphere, "CACHE", cache)
    monkeypatch.setattr(dynamic_sphere, "OUT", tmp_path)
    row = dict(
        case="s30-green-uni",
        mesh="30x30",
        label="x",
        settings={},
        overrides={},
        thickness_strain="green",
        run_dir="none",
        load_start="1 1 1",
        load_end="2 2 2",
        error=None,
        steady_state_reached=True,
        status="steady",
        message="steady",
        steps=10,
        dt=1e-5,
        critical_time_step=1.1e-5,
        t_final=1e-4,
        wall_time_s=3.0,
        element_steps_per_second=1e6,
        fold_count=4,
        drape_coefficient=0.2,
        max_interpenetrated_nodes=3,
        max_interpenetration_time=0.5,
        interpenetrated_nodes=0,
        energy_balance_error=1e-5,
        external_work=10.0,
        friction_work=1.0,
        friction=[0.3],
        mass_scaling=100,
        mass_scaling_mode="uniform",
    )
    (cache / "s30-green-uni.json").write_text(json.dumps(row))
    rows = dynamic_sphere.report()
    assert len(rows) == 1
    text = (tmp_path / "dynamic_sphere.md").read_text()
    assert "| s30-green-uni | x | 30x30 | green | uniform x100 | 0.3 | yes |" in text
    assert "0.100" in text and "1 1 1 -> 2 2 2" in text and "Not run" in text


def test_relaxation_with_contact_and_friction_does_not_depend_on_threads():
    """The paper figures' repeatability: a relaxation with penalty contact and friction gives the same
    bits on 1 and 2 numba threads (element pass over fixed chunks, serial sums: solvers/explicit/
    fused.py).  Measured on the figures' settings too: sphere 32x32, 12000 steps, Rayleigh and FIRE,
    bit for bit."""
    import numba
    import numpy as np

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs 2 numba threads")
    out = [
        run_scene(
            "sphere",
            mesh="20x20",
            solver="relax",
            progress=False,
            damping="rayleigh",
            alpha=50.0,
            mass_scaling=100.0,
            mass_scaling_mode="director",
            max_steps=1500,
            threads=th,
        )
        for th in (1, 2)
    ]
    # the sheet has fallen around the sphere with nodes in contact and slipping (5 and 4 when written)
    s = out[0].summary
    assert s["min_z"] < -1.0 and s["max_contact_nodes"] >= 3 and s["max_slipping_nodes"] >= 1
    assert [o.result.info["threads"] for o in out] == [1, 2]
    assert np.array_equal(out[0].U, out[1].U)
