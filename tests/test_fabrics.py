"""The fabric library and the KES-FB conversion (solidshell.fabrics), and the drape-tester scene.

Tolerances: conversions are closed-form products of exact factors, so they are checked to a few
ulps (rel 1e-12); the drape runs are checked against the physics they must obey (the DC formula
from the printed areas, monotone response, bodies respected), not against stored numbers.
"""

import math
import subprocess
import sys

import pytest

from solidshell import Fabric, InputError, fabrics, run_scene, scenes, units

TABLE_1 = dict(  # the paper's Table 1 (Xie, Sze & Zhou 2015), the wool of Kang & Yu [10]
    tensile_warp=1118.2,
    tensile_weft=759.5,
    shear=41.8,
    bending_warp=0.083,
    bending_weft=0.063,
    torsion=0.027,
    weight=0.019,
    thickness=0.0593,
)


def cli(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "solidshell", *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=300
    )


# --------------------------------------------------------------------------- units and factors
def test_bending_rigidity_unit_in_si():
    # 1 gf*cm^2/cm = 1 gf * 1 cm = 9.80665e-3 N * 1e-2 m, exactly (g0 is exact by definition)
    assert fabrics.GF_CM2_PER_CM_IN_SI == pytest.approx(9.80665e-5, rel=1e-15)
    assert units.to_si(1.0, "bending_rigidity") == pytest.approx(9.80665e-5, rel=1e-15)


def test_kes_factors_by_hand():
    f = fabrics.from_kes(dict(B_warp=0.2, B_weft=0.05, G=1.0, W=10.0, T=0.5, tensile_warp=900.0, tensile_weft=400.0))
    assert f["shear"] == pytest.approx(180.0 / math.pi, rel=1e-12)  # 1 gf/(cm deg) per degree -> per radian
    assert f["weight"] == pytest.approx(0.01, rel=1e-12)  # 10 mg/cm^2 = 100 g/m^2 weighs 0.01 gf/cm^2
    assert f["thickness"] == pytest.approx(0.05, rel=1e-12)  # 0.5 mm
    assert (f["bending_warp"], f["bending_weft"]) == (0.2, 0.05)  # B is already a resultant rigidity
    assert f["torsion"] == pytest.approx(0.5 * math.sqrt(0.2 * 0.05), rel=1e-12)  # nu = 0 plate, Huber's mean
    assert (f["tensile_warp"], f["tensile_weft"]) == (900.0, 400.0)


def test_kes_tensile_test_routes():
    base = dict(B_warp=0.1, B_weft=0.1, G=0.5, W=20.0, T=0.6)
    # EMT 5 %, WT 10 gf cm/cm^2: the linear rigidity storing 10 over 0.05 is 2*10/0.05^2 = 8000 gf/cm
    f = fabrics.from_kes({**base, "EMT_warp": 5.0, "WT_warp": 10.0, "EMT_weft": 6.0, "LT_weft": 0.7})
    assert f["tensile_warp"] == pytest.approx(8000.0, rel=1e-12)
    assert f["tensile_weft"] == pytest.approx(0.7 * 500.0 / 0.06, rel=1e-12)  # LT Fm / EMT, Fm = 500 gf/cm
    g = fabrics.from_kes({**base, "EMT_warp": 6.0, "LT_warp": 0.7, "EMT_weft": 6.0, "LT_weft": 0.7, "Fm": 50.0})
    assert g["tensile_warp"] == pytest.approx(0.7 * 50.0 / 0.06, rel=1e-12)
    # a linear curve (LT = 1) stores WT = Fm EMT / 2: both routes give the secant Fm / EMT
    emt, fm = 4.0, 500.0
    a = fabrics.from_kes({**base, "EMT_warp": emt, "WT_warp": fm * emt / 100 / 2, "EMT_weft": emt, "LT_weft": 1.0})
    assert a["tensile_warp"] == pytest.approx(a["tensile_weft"], rel=1e-12)
    assert a["tensile_warp"] == pytest.approx(fm / (emt / 100), rel=1e-12)


def test_wool_from_table_1_and_through_kes():
    wool = Fabric.wool()
    assert {k: getattr(wool, k) for k in TABLE_1} == TABLE_1 and wool.name == "wool"
    lib = fabrics.library()["wool"]
    assert lib.kind == "rigidities" and lib.published == TABLE_1 and "Kang" in lib.source and "Table 1" in lib.table
    # the same wool given as a KES data set (G per degree, W in mg/cm^2, T in mm) converts back to Table 1
    kes = dict(B_warp=0.083, B_weft=0.063, G=41.8 * math.pi / 180.0, W=19.0, T=0.593)
    f = fabrics.from_kes({**kes, "tensile_warp": 1118.2, "tensile_weft": 759.5, "torsion": 0.027})
    for k, v in TABLE_1.items():
        assert f[k] == pytest.approx(v, rel=1e-12), k
    assert fabrics.to_kes(wool) == pytest.approx(
        {**kes, "tensile_warp": 1118.2, "tensile_weft": 759.5, "torsion": 0.027}
    )


def test_library_entries_are_sourced_and_build():
    lib = fabrics.library()
    assert "wool" in lib and fabrics.names() == tuple(lib)
    for name, f in lib.items():
        assert f.source.strip() and f.table.strip() and f.title.strip(), name
        assert f.kind in ("rigidities", "kes") and f.published, name
        fab = f.fabric(warp_angle=90.0)
        assert fab.name == name and fab.warp_angle == 90.0
    assert set(scenes.FABRICS) == set(lib)
    with pytest.raises(InputError, match=r"unknown fabric 'silk' \(known: .*wool"):
        fabrics.fabric("silk")


def test_library_file_errors_name_the_entry():
    ok = '[a]\ntitle = "t"\nsource = "s"\ntable = "x"\n[a.kes]\nB_warp = 0.1\nB_weft = 0.1\nG = 1\nW = 10\nT = 0.5\ntensile_warp = 100\ntensile_weft = 100\n'
    assert fabrics.load_library(ok)["a"].fields["shear"] == pytest.approx(180 / math.pi)
    with pytest.raises(InputError, match=r"x.toml: a: kes.G: must be positive"):
        fabrics.load_library(ok.replace("G = 1", "G = -1"), "x.toml")
    with pytest.raises(InputError, match=r"a.source: required text"):
        fabrics.load_library(ok.replace('source = "s"\n', ""))
    with pytest.raises(InputError, match=r"exactly one of \[a.rigidities\] or \[a.kes\]"):
        fabrics.load_library(ok.split("[a.kes]")[0])
    with pytest.raises(InputError, match=r"a.other: unknown key"):
        fabrics.load_library(ok.replace("[a.kes]", "[a.other]"))
    drape = '[a.drape]\ndc = 0.45\nspecimen_diameter = 30.0\ndisc_diameter = 18.0\nsource = "s, Table 2"\n'
    assert fabrics.load_library(ok + drape)["a"].drape["dc"] == 0.45
    with pytest.raises(InputError, match=r"a.drape.dc: a drape coefficient is at most 1"):
        fabrics.load_library(ok + drape.replace("0.45", "45"))
    with pytest.raises(InputError, match=r"a.drape.disc_diameter: must be smaller"):
        fabrics.load_library(ok + drape.replace("18.0", "30.0"))
    with pytest.raises(InputError, match=r"a.drape.source: required; missing"):
        fabrics.load_library(ok + drape.replace('source = "s, Table 2"\n', ""))


GOOD_KES = dict(B_warp=0.083, B_weft=0.063, G=0.73, W=19.0, T=0.593, tensile_warp=1118.2, tensile_weft=759.5)


@pytest.mark.parametrize(
    "changes, drop, key, words",
    [
        ({"B_warp": -0.1}, (), "B_warp", "must be positive"),
        ({"B_warp": 0.0}, (), "B_warp", "must be positive"),
        ({"G": float("nan")}, (), "G", "must be positive and finite"),
        ({"B_warp": 83.0e3}, (), "B_warp", "outside"),  # a bending rigidity in the wrong units
        ({"W": 190.0e3}, (), "W", "outside"),  # not mg/cm^2
        ({"T": 593.0}, (), "T", "outside"),  # micrometres for mm
        ({"W": "heavy"}, (), "W", "must be a number"),
        ({"W": True}, (), "W", "must be a number"),
        ({"G": None}, (), "G", "must be a number"),
        ({"B_wrap": 0.1}, (), "B_wrap", "unknown KES key"),
        ({"EMT_warp": 5.0}, ("tensile_warp",), "WT_warp", "required with EMT_warp"),
        ({"WT_warp": 3.0}, ("tensile_warp",), "EMT_warp", "required with WT_warp"),
        ({"EMT_warp": 5.0, "WT_warp": 10.0, "LT_warp": 0.6}, ("tensile_warp",), "LT_warp", "not both"),
        ({"EMT_warp": 5.0}, (), "EMT_warp", "either tensile_warp"),
        ({}, ("tensile_weft",), "tensile_weft", "missing"),
        ({}, ("T",), "T", "required"),
    ],
)
def test_bad_kes_input_one_line_naming_the_key(changes, drop, key, words):
    data = {k: v for k, v in {**GOOD_KES, **changes}.items() if k not in drop}
    with pytest.raises(InputError) as e:
        fabrics.from_kes(data)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith(f"kes.{key}:") and words in msg, msg


# --------------------------------------------------------------------------- scenes and the CLI
KES_SCENE = """
name = "my-kes"
title = "a KES fabric on the drape tester"
[geometry]
recipe = "disc_on_disc"
diameter = 30.0
pedestal_diameter = 18.0
[mesh]
density = "8x64"
[material]
kes = {{ B_warp = 0.083, B_weft = 0.063, G = {G}, W = 19.0, T = 0.593, tensile_warp = 1118.2, tensile_weft = 759.5 }}
warp_angle = 90.0
[supports]
clamped = "clamped"
"""


def test_scene_with_kes_data(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(KES_SCENE.format(G=0.73))
    fab = scenes.load(p).material_object()
    assert fab.shear == pytest.approx(0.73 * 180 / math.pi, rel=1e-12) and fab.warp_angle == 90.0
    assert fab.weight == pytest.approx(0.019, rel=1e-12) and fab.thickness == pytest.approx(0.0593, rel=1e-12)
    # --set material.kes.* on a scene naming a library fabric replaces the fabric by the KES data
    s = scenes.load("drape-tester").with_overrides(
        {
            f"material.kes.{k}": v
            for k, v in dict(
                B_warp=0.2, B_weft=0.1, G=1.0, W=20.0, T=0.5, tensile_warp=2000.0, tensile_weft=1000.0
            ).items()
        }
    )
    assert "fabric" not in s.material and s.material_object().bending_warp == 0.2
    with pytest.raises(InputError, match=r"material\.fabric: give either fabric .* or kes"):
        scenes.Scene.from_dict({**scenes.load(p).raw, "material": {"fabric": "wool", "kes": {"B_warp": 0.1}}})


def test_cli_bad_kes_exit_2_nothing_written(tmp_path):
    p = tmp_path / "s.toml"
    p.write_text(KES_SCENE.format(G=-0.73))
    out = tmp_path / "out"
    r = cli("run", p, "--out", out)
    assert r.returncode == 2 and not out.exists()
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and str(p) in lines[0] and "material.kes.G" in lines[0] and "positive" in lines[0], r.stderr
    r = cli("run", "drape-tester", "--set", "material.fabric=silk", "--out", out)
    assert r.returncode == 2 and not out.exists() and "unknown fabric 'silk'" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_cli_fabrics_lists_the_library():
    r = cli("fabrics")
    assert r.returncode == 0, r.stderr
    rows = {ln.split()[0]: ln for ln in r.stdout.splitlines() if ln and not ln.startswith(" ")}
    for name, f in fabrics.library().items():
        k = fabrics.to_kes(f.fabric())
        assert f"{k['B_warp']:.4g} / {k['B_weft']:.4g}" in rows[name] and f"{k['G']:.4g}" in rows[name]
        assert f"  source: {f.source}" in r.stdout
    assert "0.7295" in rows["wool"]  # 41.8 gf/cm per radian = 0.7295 gf/(cm deg)


# --------------------------------------------------------------------------- the drape tester
def test_drape_tester_scene_is_the_standard_geometry():
    s = scenes.load("drape-tester")
    assert s.recipe == "disc_on_disc" and s.geometry["diameter"] == 30.0 and s.geometry["pedestal_diameter"] == 18.0
    support, clamp = s.bodies()
    assert support["support"] == "cusick" and support["diameter"] == 18.0 and support["role"] == "support"
    assert clamp["role"] == "clamp" and clamp["diameter"] == 18.0
    h = s.material_object().thickness  # the specimen lies between them: lower face on the disc, clamp on top
    assert support["centre"][2] + support["offset"] == pytest.approx(0.0, abs=1e-15)
    assert clamp["centre"][2] - clamp["height"] - clamp["offset"] == pytest.approx(0.0, abs=1e-15)
    assert support["offset"] == pytest.approx(h / 2)
    for d in (24.0, 36.0):
        assert scenes.load("drape-tester").with_overrides({"geometry.diameter": d}).geometry["diameter"] == d


def _dc(**material):
    out = run_scene(
        "drape-tester", mesh="8x64", progress=False, overrides={f"material.{k}": v for k, v in material.items()}
    )
    return out.summary


def test_drape_tester_dc_is_the_shadow_ratio_and_follows_bending_and_weight():
    s = _dc()
    assert s["converged"]
    a_disc, a_spec = math.pi * 9.0**2, math.pi * 15.0**2
    # the mesh is a polygon: its areas fall short of the circles' by O(1/C^2) (C = 64 around: 0.16 %)
    assert s["pedestal_area"] == pytest.approx(a_disc, rel=2e-3) and s["sheet_area"] == pytest.approx(a_spec, rel=2e-3)
    dc = (s["projected_area"] - s["pedestal_area"]) / (s["sheet_area"] - s["pedestal_area"])
    assert s["drape_coefficient"] == pytest.approx(dc, rel=1e-12) and 0.0 < dc < 1.0
    # the shadow: the outline encloses the star-shaped envelope (no lobe folded back over another)
    assert s["envelope_area"] == pytest.approx(s["projected_area"], rel=1e-3)
    # the specimen respects the support, its stem and the clamp (the contract: 2 % of h)
    assert all(b["nodes_beyond"] == 0 and b["face_points_beyond"] == 0 for b in s["penetration"]["bodies"])
    stiffer = _dc(bending_warp=4 * 0.083, bending_weft=4 * 0.063)["drape_coefficient"]
    heavier = _dc(weight=4 * 0.019)["drape_coefficient"]
    # a drape is set by bending length (B/W)^(1/3): 4x B raises the DC, 4x W lowers it, by far more
    # than the mesh's own scatter between neighbouring densities (0.06 at 8x64 vs 12x96)
    assert stiffer > dc + 0.05 and heavier < dc - 0.05, (dc, stiffer, heavier)
