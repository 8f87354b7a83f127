"""solidshell.sweep without a cluster: sweep files, run keys, the ledger, state classification,
and the CLI's one line when dask is missing."""

import builtins

import numpy as np
import pytest

from solidshell import cli
from solidshell.errors import InputError
from solidshell.scenes import load
from solidshell.sweep import load_spec, studies
from solidshell.sweep.spec import from_dict
from solidshell.sweep.states import classify, fingerprint, profile_distance, symmetry_group

TH = np.radians(np.arange(360.0))
BASE = {"name": "t", "scene": "square-pedestal", "mesh": "6x2x4"}


def spec(**kw):
    d = {**BASE, **kw}
    return from_dict({k: v for k, v in d.items() if v is not None}, "t.toml")


# --------------------------------------------------------------------------- sweep files
def test_grid_zip_case_expansion_and_keys():
    s = spec(
        grid={"perturbation.seed": [0, 1, 2]},
        zip={"material.bending_warp": [0.04, 0.08], "material.bending_weft": [0.03, 0.06]},
        case=[{"solver": "static"}, {"solver": "relax", "solver.relax.alpha": 1.0}],
    )
    assert s.n_runs == 2 * 3 * 2
    assert len({r.key for r in s.runs}) == s.n_runs
    # zip keys vary together, never crossed
    assert {(r.overrides["material.bending_warp"], r.overrides["material.bending_weft"]) for r in s.runs} == {
        (0.04, 0.03),
        (0.08, 0.06),
    }
    assert s.axes == (
        "solver",
        "solver.relax.alpha",
        "perturbation.seed",
        "material.bending_warp",
        "material.bending_weft",
    )
    # the key depends on the run's definition only: the same file gives the same keys
    again = spec(
        grid={"perturbation.seed": [0, 1, 2]},
        zip={"material.bending_warp": [0.04, 0.08], "material.bending_weft": [0.03, 0.06]},
        case=[{"solver": "static"}, {"solver": "relax", "solver.relax.alpha": 1.0}],
    )
    assert [r.key for r in again.runs] == [r.key for r in s.runs]
    # adding a seed keeps the keys of the runs that were there (a resumed sweep reuses them)
    more = spec(
        grid={"perturbation.seed": [0, 1, 2, 3]},
        zip={"material.bending_warp": [0.04, 0.08], "material.bending_weft": [0.03, 0.06]},
        case=[{"solver": "static"}, {"solver": "relax", "solver.relax.alpha": 1.0}],
    )
    assert {r.key for r in s.runs} < {r.key for r in more.runs}


def test_random_sample_is_seeded_and_in_range():
    kw = dict(
        sample={
            "n": 20,
            "seed": 5,
            "axes": {
                "material.bending_warp": {"log_uniform": [0.02, 0.3]},
                "perturbation.seed": {"integers": [0, 9]},
                "solver": {"choice": ["static", "relax"]},
            },
        }
    )
    a, b = spec(**kw), spec(**kw)
    assert [r.key for r in a.runs] == [r.key for r in b.runs]
    bw = np.array([r.overrides["material.bending_warp"] for r in a.runs])
    assert bw.min() >= 0.02 and bw.max() <= 0.3
    assert {r.overrides["perturbation.seed"] for r in a.runs} <= set(range(10))
    assert {r.solver for r in a.runs} <= {"static", "relax"}


@pytest.mark.parametrize(
    "kw, words",
    [
        (dict(grid={"material.bending_warp": [0.08, -1.0]}), "run 1 .*material"),
        (dict(grid={"solver.static.c": [0.01, "big"]}), "run 1 .*solver.static.c"),
        (dict(grid={"geometry.colour": ["red"]}), "geometry.colour"),
        (dict(zip={"material.torsion": [0.01, 0.02], "material.shear": [40.0]}), "same length"),
        (dict(grid={"perturbation.amplitude": [0.1]}, sample={"n": 2, "axes": {"x": {"uniform": [0, 1]}}}), "not both"),
        (dict(sample={"n": 2, "axes": {"material.torsion": {"normal": [0, 1]}}}), "sample.axes"),
        (dict(mesh=None, grid={"mesh": ["6x2"]}), "malformed mesh density"),
        (dict(wobble=1), "wobble"),
        (dict(set={"perturbation.seed": 1}, grid={"perturbation.seed": [1, 2]}), "both fixed"),
    ],
)
def test_bad_sweep_one_line(kw, words):
    with pytest.raises(InputError, match=words) as e:
        spec(**kw)
    assert "\n" not in str(e.value) and str(e.value).startswith("t.toml")


def test_packaged_studies_parse():
    names = studies()
    assert {
        "square-on-disc-folds",
        "circle-pedestal-folds",
        "square-pedestal-dc-bending",
        "circle-pedestal-dc-bending",
    } <= set(names)
    for n in names:
        s = load_spec(n)
        assert s.n_runs >= 5 and s.name == n


# --------------------------------------------------------------------------- states
def _profile(n_folds, phase_deg=0.0, amp=0.5, R=10.0):
    th = np.radians(np.arange(360.0))
    return R + amp * np.cos(n_folds * (th - np.radians(phase_deg)))


def test_symmetry_groups():
    # wool: warp and weft rigidities differ, so the square's D4 keeps only what fixes the warp axis
    assert symmetry_group(load("square-pedestal")) == "D2@0"
    iso = load("circle-pedestal").with_overrides(
        {"material": {"isotropic": {"E": 1e4, "nu": 0.3, "h": 0.05, "density": 0.02}}}
    )
    assert symmetry_group(iso) == "O2@0"
    assert symmetry_group(load("circle-pedestal").with_overrides({"material.warp_angle": 30.0})) == "D2@30"
    assert symmetry_group(load("strip-warp")) == "C1@0"


def test_profile_distance_under_groups():
    a = _profile(4, 0.0) + 0.3 * np.cos(np.radians(np.arange(360.0)))  # not symmetric itself
    b = np.roll(a, 90)  # turned by 90 deg
    assert profile_distance(a, b, "D4") == pytest.approx(0.0, abs=1e-12)
    # a quarter turn is not in D2: the cos(theta) lobe stays 90 deg off, max 0.3 sqrt(2) cm of R = 10
    assert profile_distance(a, b, "D2") == pytest.approx(0.3 * np.sqrt(2) / 10.0, rel=1e-9)
    th = np.radians(np.arange(360.0))
    c = _profile(4) + 0.3 * np.sin(2 * th)  # kept by the half turn, not by mirrors
    mirror = np.roll(c[::-1], 1)  # c(-theta)
    assert profile_distance(c, mirror, "D2") == pytest.approx(0.0, abs=1e-12)
    assert profile_distance(c, mirror, "C2") > 0.05
    assert profile_distance(_profile(8), _profile(8, 17.0), "O2") < 0.01  # any turn, to the 1 deg grid


def test_fingerprint_is_invariant_under_the_group():
    ang = [10.0, 100.0, 190.0, 250.0]  # not four-fold symmetric itself
    turned = [(a + 90.0) % 360 for a in ang]
    mirrored = [(-a) % 360 for a in ang]
    assert fingerprint(4, ang, 0.71, "D4") == fingerprint(4, turned, 0.71, "D4") == fingerprint(4, mirrored, 0.71, "D4")
    assert fingerprint(4, ang, 0.71, "C1") != fingerprint(4, turned, 0.71, "C1")
    assert fingerprint(None, [], None) == "unsettled"


def _row(i, n, dc, prof, converged=True):
    return {
        "key": f"k{i}",
        "index": i,
        "status": "done",
        "converged": converged,
        "fold_count": n,
        "drape_coefficient": dc,
        "radius_profile": list(prof),
        "fold_angles_deg": [],
        "stable": True,
        "run_dir": f"/r/{i}",
        "case": 0,
    }


def test_classify_groups_states():
    rows = [
        _row(0, 4, 0.700, _profile(4)),
        _row(1, 4, 0.702, np.roll(_profile(4) + 0.02 * np.cos(TH), 90)),  # same, turned (D4), 0.3 % off
        _row(2, 8, 0.650, _profile(8, amp=0.4)),
        _row(3, 4, 0.760, _profile(4, amp=0.2)),  # 4 folds, other DC: another state
        _row(4, 8, 0.651, _profile(8, 22.5, amp=0.4)),  # 8 folds turned by half a fold: in D4? no
        _row(5, 4, 0.70, _profile(4), converged=False),
    ]
    states, unsettled = classify(rows, dc_tol=0.01, boundary_tol=0.03, group="D4")
    assert [s.fold_count for s in states] == [4, 8, 4, 8]
    assert [s.count for s in states] == [2, 1, 1, 1]
    assert [r["key"] for r in unsettled] == ["k5"]
    # under O2 the half-fold turn is a symmetry: the two 8-fold runs are one state
    states, _ = classify(rows, 0.01, 0.03, "O2")
    assert [s.count for s in states] == [2, 2, 1]


# --------------------------------------------------------------------------- ledger
def test_ledger_once_per_key(tmp_path):
    pytest.importorskip("pyarrow", reason="pyarrow not installed (pip install 'solidshell[sweep]')")
    from solidshell.sweep.ledger import Ledger

    s = spec(grid={"perturbation.seed": [0, 1]})
    led = Ledger(tmp_path, s)
    led.check()
    led.open()
    r0 = s.runs[0]
    row = {
        "key": r0.key,
        "index": 0,
        "case": 0,
        "status": "done",
        "converged": True,
        "drape_coefficient": 0.7,
        "fold_count": 4,
        "fold_angles_deg": [0.0, 90.0],
        "radius_profile": [1.0] * 360,
        "perturbation.seed": 0,
    }
    assert led.append(row) is True
    assert led.append({**row, "drape_coefficient": 0.1}) is False  # never twice
    (led.dir / f".{s.runs[1].key}.tmp").write_bytes(b"half a file")  # a killed write
    assert led.done_keys() == {r0.key}
    t = led.read()
    assert t.num_rows == 1 and t.column("drape_coefficient").to_pylist() == [0.7]
    assert str(t.schema.field("perturbation.seed").type) == "int64"
    # a part written before a column existed reads with that column null
    import pyarrow.parquet as pq

    old = t.drop_columns(["interpenetrated_nodes"]).set_column(0, "key", [[s.runs[1].key]])
    old = old.set_column(old.schema.get_field_index("index"), "index", [[1]])
    pq.write_table(old, led.dir / f"{s.runs[1].key}.parquet")
    t2 = led.read()
    assert t2.num_rows == 2 and t2.column("interpenetrated_nodes").to_pylist() == [None, None]
    other = from_dict({**BASE, "name": "other"}, "o.toml")
    with pytest.raises(InputError, match="ledger of sweep 't'"):
        Ledger(tmp_path, other).check()


# --------------------------------------------------------------------------- CLI without dask
def test_cli_without_dask(monkeypatch, capsys, tmp_path):
    real = builtins.__import__

    def no_dask(name, *a, **kw):
        if name.split(".")[0] in ("distributed", "dask"):
            raise ImportError(f"No module named {name!r}")
        return real(name, *a, **kw)

    monkeypatch.setattr(builtins, "__import__", no_dask)
    rc = cli.main(["sweep", "square-pedestal-dc-bending", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1
    assert "dask.distributed" in err[0] and "pip install" in err[0]
    assert not (tmp_path / "o").exists()


def test_cli_lists_studies(capsys):
    assert cli.main(["sweep", "--list"]) == 0
    out = capsys.readouterr().out
    assert "square-on-disc-folds" in out and "square-pedestal-dc-bending" in out
