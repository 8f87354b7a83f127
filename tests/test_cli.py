"""The command line, run as a user runs it: ``python -m solidshell ...`` in a subprocess."""

import json
import os
import subprocess
import sys

import meshio
import numpy as np
import pytest

PAPER_SCENES = [
    "circle-pedestal",
    "hang-100",
    "hang-20",
    "large-square-pedestal",
    "sphere",
    "square-on-disc",
    "square-pedestal",
    "strip-warp",
    "strip-weft",
]


def cli(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "solidshell", *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=300
    )


def test_scenes_lists_the_paper_scenes_and_the_examples():
    r = cli("scenes")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.strip().splitlines()
    names = [ln.split()[0] for ln in lines]
    assert names == sorted(names) and set(PAPER_SCENES) | {"drape-tester"} <= set(names)
    dt = next(ln for ln in lines if ln.startswith("drape-tester "))
    assert dt.split()[1:3] == ["-", "24x192"]  # no paper section
    sp = next(ln for ln in lines if ln.startswith("square-pedestal "))
    assert sp.split()[1:3] == ["§3.2", "48x16x4"] and "10x10 cm square pedestal" in sp


def test_mesh_square_pedestal(tmp_path):
    out = tmp_path / "runs" / "sp"
    r = cli("mesh", "square-pedestal", "--mesh", "48x16x4", "--out", out)
    assert r.returncode == 0, r.stderr
    assert "3264 nodes" in r.stdout and "3072 quads" in r.stdout and str(out) in r.stdout
    assert "Traceback" not in r.stderr
    names = sorted(p.name for p in out.iterdir())
    assert names == ["iso.png", "mesh.vtu", "mesh.xdmf", "summary.json", "top.png"]
    s = json.loads((out / "summary.json").read_text())
    assert s["scene"] == "square-pedestal" and s["mesh"] == "48x16x4" and s["solver"] == "none"
    assert s["counts"]["nodes"] == 3264 and s["counts"]["quads"] == 3072 and s["counts"]["triangles"] == 0
    assert s["counts"]["node_sets"]["clamped"] == 192 and s["counts"]["fixed_dofs"] == 6 * 192
    assert s["area"] == pytest.approx(300.0) and s["units"]["force"] == "gf"
    for v in ("numpy", "scipy", "numba", "gmsh", "meshio"):
        assert s["versions"][v]
    m = meshio.read(out / "mesh.vtu")
    assert len(m.points) == 3264 and sum(len(c.data) for c in m.cells) == 3072
    assert "director" in m.point_data and "set:clamped" in m.point_data
    for png in ("top.png", "iso.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _write(path, pts, quads, point_data=None):
    meshio.Mesh(np.asarray(pts, float), [("quad", np.asarray(quads))], point_data=point_data or {}).write(path)
    return path


@pytest.fixture(scope="module")
def bad_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("bad")
    f = {}
    f["degenerate"] = _write(d / "degenerate.vtu", [[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0]], [[0, 1, 2, 3]])
    f["duplicate"] = _write(
        d / "duplicate.vtu",
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0]],
        [[0, 1, 2, 3], [4, 5, 6, 7]],
    )
    f["inverted"] = _write(
        d / "inverted.vtu",
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0]],
        [[0, 1, 2, 3], [1, 4, 2, 5]],
    )  # second quad is a bow-tie
    f["emptyset"] = _write(
        d / "emptyset.vtu",
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
        [[0, 1, 2, 3]],
        {"set:clamped": np.zeros(4, np.int32)},
    )
    (d / "garbage.msh").write_text("this is not a mesh\n")
    f["garbage"] = d / "garbage.msh"
    base = 'name = "mine"\ntitle = "t"\n[geometry]\nrecipe = "square"\nsize = 10.0\n[mesh]\ndensity = "4x4"\n'
    (d / "typo.toml").write_text(base.replace('density = "4x4"', 'density = "4x4"\ndenisty = "4x4"'))
    f["typo"] = d / "typo.toml"
    (d / "wrongtype.toml").write_text(base.replace("size = 10.0", 'size = "ten"'))
    f["wrongtype"] = d / "wrongtype.toml"
    (d / "zero_bending.toml").write_text(base + '[material]\nfabric = "wool"\nbending_weft = 0.0\n')
    f["zero_bending"] = d / "zero_bending.toml"
    (d / "no_clamp.toml").write_text(base + '[supports]\nclamped = "pedestal_edge"\n')
    f["no_clamp"] = d / "no_clamp.toml"
    (d / "broken.toml").write_text('name = "x"\ntitle = [\n')
    f["broken"] = d / "broken.toml"
    (d / "missing_mesh.toml").write_text('name = "m"\ntitle = "t"\n[geometry]\nfile = "nowhere.msh"\n')
    f["missing_mesh"] = d / "missing_mesh.toml"
    f["dir"] = d
    return f


# Every kind of bad input the brief names, each through a real interpreter (exit status, stderr) ...
BAD = [
    (["mesh", "no-such-scene"], "unknown scene"),
    (["mesh", "square-pedestal", "--mesh", "24x8"], "24x8"),
    (["mesh", "hang-20", "--mesh", "0x5"], "0x5"),
    (["mesh", "hang-20", "--mesh", "-3x4"], "-3x4"),
    (["mesh", "{dir}/absent.toml"], "not found"),
    (["mesh", "square-pedestal", "--mesh", "{dir}/nowhere.msh"], "nowhere.msh"),
    (["mesh", "{typo}"], "mesh.denisty"),
    (["mesh", "{zero_bending}"], "bending_weft"),
    (["run", "square-pedestal", "--set", "material.thickness=0"], "thickness"),
    (["mesh", "square-pedestal", "--mesh", "{inverted}"], "inverted"),
    (["mesh", "square-pedestal", "--mesh", "{degenerate}"], "degenerate"),
    (["mesh", "square-pedestal", "--mesh", "{duplicate}"], "duplicate"),
    (["mesh", "square-pedestal", "--mesh", "{emptyset}"], "selects no node"),
]
# ... and more variants in-process through solidshell.cli.main (same code path, no interpreter start-up).
BAD_IN_PROCESS = [
    (["run", "no-such-scene"], "unknown scene"),
    (["run", "square-pedestal", "--mesh", "-3x4x4"], "-3x4x4"),
    (["mesh", "{dir}"], "scene"),
    (["mesh", "{broken}"], "TOML"),
    (["mesh", "{wrongtype}"], "geometry.size"),
    (["run", "{zero_bending}"], "bending_weft"),
    (["run", "square-pedestal", "--set", "material.weight=-0.019"], "weight"),
    (["run", "square-pedestal", "--set", "material.tensile_warp=-1"], "tensile_warp"),
    (["run", "square-pedestal", "--set", "solver.statik.c=1"], "solver.statik"),
    (["run", "square-pedestal", "--set", "nonsense"], "key=value"),
    (["mesh", "{no_clamp}"], "pedestal_edge"),
    (["mesh", "square-pedestal", "--mesh", "{garbage}"], "garbage.msh"),
    (["mesh", "{missing_mesh}"], "nowhere.msh"),
    (["run", "square-pedestal", "--solver", "implicit"], "implicit"),
    (["frobnicate"], "frobnicate"),
]


@pytest.fixture(scope="module")
def bad_results(bad_files, tmp_path_factory):
    """Run the bad-input commands two at a time (each is a fresh interpreter)."""
    from concurrent.futures import ThreadPoolExecutor

    out = tmp_path_factory.mktemp("out")
    jobs = {i: [a.format(**bad_files) for a in args] + ["--out", out / f"o{i}"] for i, (args, _) in enumerate(BAD)}
    with ThreadPoolExecutor(max_workers=max(2, min(8, os.cpu_count() or 2))) as ex:
        futs = {i: ex.submit(cli, *a) for i, a in jobs.items()}
        return {i: (f.result(), out / f"o{i}") for i, f in futs.items()}


def _check_one_line(code, stderr, needle, out):
    assert code == 2, (code, stderr)
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert "Traceback" not in stderr and lines[0].startswith("solidshell: ")
    assert needle in lines[0]
    assert not out.exists()  # nothing written, not even the folder (issue 11 part 4)


@pytest.mark.parametrize("i", range(len(BAD)), ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_exit_2_one_line(bad_results, bad_files, i):
    r, out = bad_results[i]
    _check_one_line(r.returncode, r.stderr, BAD[i][1].format(**bad_files), out)


@pytest.mark.parametrize("args, needle", BAD_IN_PROCESS, ids=[" ".join(a) for a, _ in BAD_IN_PROCESS])
def test_bad_input_in_process(tmp_path, capsys, bad_files, args, needle):
    from solidshell.cli import main

    code = main([a.format(**bad_files) for a in args] + ["--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    _check_one_line(code, err, needle.format(**bad_files), tmp_path / "out")


@pytest.mark.parametrize(
    "argv, line",
    [
        (["frobnicate"], "solidshell: error: argument COMMAND: invalid choice: 'frobnicate' (choose from"),
        (
            ["run", "sp", "--solver", "implicit"],
            "solidshell: error: run: argument --solver: invalid choice: 'implicit'",
        ),
        (["run"], "solidshell: error: run: the following arguments are required: scene"),
        (["sweep"], "solidshell: error: sweep: give a sweep file or a packaged study name"),
    ],
)
def test_usage_error_one_prefix(capsys, argv, line):
    """A usage error says ``solidshell: error:`` once (was ``solidshell: error: solidshell: argument ...``)
    and names the subcommand it belongs to."""
    from solidshell.cli import main

    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(line), err
    assert err[0].count("solidshell") == 1


def test_version_and_help(capsys):
    from solidshell.cli import main

    for argv, needles in ((["--version"], ["solidshell 0."]), (["run", "--help"], ["--set", "--solver", "--mesh"])):
        with pytest.raises(SystemExit, match="^0$") as e:  # argparse exits 0 after printing
            main(argv)
        assert e.value.code == 0
        out = capsys.readouterr().out
        assert all(n in out for n in needles), out


@pytest.mark.slow
def test_run_strip_end_to_end(tmp_path):
    """The real static solver through the CLI (slow: numba compilation on a fresh install)."""
    r = cli("run", "strip-warp", "--mesh", "10x1", "--out", tmp_path, "--no-progress")
    assert r.returncode == 0, r.stderr
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["converged"] is True and s["solver"] == "static"
    assert {"result.xdmf", "result.vtu", "deformed.vtu", "top.png", "iso.png", "side.png"} <= set(s["files"])
    assert -5.0 < s["min_z"] < -3.0  # a 5 cm wool strip droops by several cm (Fig. 4)


def test_readme_commands_and_ci():
    """The README opens with the two commands; .ci/run ends with the test command."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    readme = (root / "README.md").read_text()
    blocks = [b.split("```", 1)[0].strip() for b in readme.split("```bash\n")[1:3]]
    assert blocks[0].startswith("python3.11 -m venv .venv && .venv/bin/pip install -e . && .venv/bin/solidshell ")
    assert "square-pedestal" in blocks[0]
    # static checks, the suite, then the whole default verify (not --quick): a failed record fails CI
    assert blocks[1] == (
        "python3.11 -m venv .venv && .venv/bin/pip install -e '.[test,sweep]' && .venv/bin/ruff check . && "
        ".venv/bin/ruff format --check . && .venv/bin/mypy && .venv/bin/python -m pytest -q && .venv/bin/solidshell verify"
    )
    ci = (root / ".ci" / "run").read_text().strip().splitlines()
    assert ci[0] == "#!/usr/bin/env bash" and "set -euo pipefail" in ci and ci[-1] == blocks[1]
    assert os.access(root / ".ci" / "run", os.X_OK)
