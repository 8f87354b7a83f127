"""The README's Python API, run as a user copies it: every ```python block of README.md is executed
(in a fresh namespace, from an empty working folder) and what it computed is checked -- the drape
coefficient and folds of the main job, the strip's tip against the heavy elastica, the posed problem's
sizes and load; the one-line reprs the README shows in its comments are what the objects print.
Also the public face: ``solidshell.__all__`` and ``dir(solidshell)``."""

import contextlib
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

import solidshell

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
BLOCKS = re.findall(r"^```python\n(.*?)^```", README, flags=re.S | re.M)


def elastica_tip_z(cut="warp"):
    return json.loads((ROOT / "reference" / "elastica_strip.json").read_text())["strip"][cut]["tip_z"]


def check_run_scene(ns):
    out, s = ns["out"], ns["s"]
    assert out.converged is True and s["converged"] is True and s["scene"] == "square-pedestal"
    assert {"drape_coefficient", "fold_count", "run_id", "warnings", "timings", "counts"} <= set(s)
    # the paper element on 24x8x4 (docs: DC 0.679, 4 folds; the converged drape is 0.548)
    assert 0.60 < s["drape_coefficient"] < 0.75 and s["fold_count"] == 4
    A = (s["projected_area"] - s["pedestal_area"]) / (s["sheet_area"] - s["pedestal_area"])
    assert s["pedestal_area"] == pytest.approx(100.0) and s["drape_coefficient"] == pytest.approx(A)
    summary, U, mesh, run_id = ns["summary"], ns["U"], ns["mesh"], ns["run_id"]
    assert summary is s and U is out.U and mesh is out.mesh and run_id == s["run_id"] == out.run_id
    assert U.shape == (mesh.n_nodes, 6) == (864, 6) and re.fullmatch("[0-9a-f]{32}", run_id)
    assert np.all(U[mesh.node_sets["clamped"]] == 0.0) and U[:, 2].min() < -3.0  # clamped edge held, skirt hangs
    assert out.out_dir is None and out.files == []  # out_dir=None: nothing written
    r = repr(out)
    assert "\n" not in r and len(r) < 300 and "converged" in r and "DC 0.6" in r


def check_own_model(ns):
    res, nodes, tip = ns["res"], ns["nodes"], ns["tip"]
    assert res.converged and res.U.shape == (22, 6)
    assert np.all(res.U[ns["fixed"]] == 0.0)
    z = float((nodes[tip] + res.U[tip, :3]).mean(0)[2])
    assert z == pytest.approx(elastica_tip_z(), rel=0.01)  # 10x1: 0.45 % from the elastica
    assert "\n" not in repr(res) and len(repr(res)) < 300


def check_build_problem(ns):
    problem, mesh = ns["problem"], ns["mesh"]
    assert problem.model.n_nodes == mesh.n_nodes == 864
    assert problem.fixed.sum() == 6 * len(mesh.node_sets["clamped"]) == 576
    assert len(problem.contact) == 1  # the pedestal as a contact body
    # self-weight: 0.019 gf/cm^2 on the 300 cm^2 skirt, all downwards
    assert problem.loads[:, 2].sum() == pytest.approx(-0.019 * 300.0) and np.all(problem.loads[:, :2] == 0.0)
    assert problem.model.material.warp_angle_rad == pytest.approx(np.pi / 4)


# each README block, told apart by what it calls (the first key found), with its check
CHECKS = {"build_problem(": check_build_problem, "ShellMesh(": check_own_model, "run_scene(": check_run_scene}


def _check_of(block):
    found = [f for key, f in CHECKS.items() if key in block]
    assert found, f"a README python block without a check in tests/test_readme.py:\n{block}"
    return found[0]


def test_readme_has_the_python_blocks():
    assert len(BLOCKS) == 3
    assert sorted(_check_of(b).__name__ for b in BLOCKS) == sorted(f.__name__ for f in CHECKS.values())


@pytest.mark.parametrize("i", range(len(BLOCKS)))
def test_readme_python_block(i, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    block = BLOCKS[i]
    check = _check_of(block)
    ns: dict = {"__name__": "__readme__"}
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        exec(compile(block, f"README.md python block {i}", "exec"), ns)
    printed = buf.getvalue().splitlines()
    check(ns)
    # what a comment says a print shows is what it shows: "# <Cls text, ...>" begins a printed line
    for shown in re.findall(r"#[^<\n]*<([^>\n]*?)(?:, \.\.\.)?>", block):
        assert any(line.startswith("<" + shown) for line in printed), (shown, printed)
    assert list(tmp_path.iterdir()) == []  # none of the blocks writes a file


def test_public_face():
    names = set(solidshell.__all__)
    assert {
        "ShellMesh",
        "Fabric",
        "IsotropicShell",
        "Model",
        "solve_static",
        "run_scene",
        "RunOutput",
        "build_problem",
        "Problem",
        "SolveResult",
        "load_scene",
        "Scene",
        "InputError",
        "SolverError",
        "IOFailure",
    } <= names
    assert names <= set(dir(solidshell))  # the lazily imported ones too
    for n in solidshell.__all__:
        assert getattr(solidshell, n) is not None
    from solidshell.run.driver import run_scene
    from solidshell.scenes import load

    assert solidshell.run_scene is run_scene and solidshell.load_scene is load
    with pytest.raises(AttributeError):
        _ = solidshell.no_such_name
