"""Mesh sequencing of the static solver (solidshell/solvers/sequence.py), the static ``sequence``
setting, serial kernels on small meshes and ``solidshell run --no-pictures``."""

import numpy as np
import pytest

from solidshell.errors import InputError
from solidshell.meshing import build_mesh
from solidshell.scenes import load
from solidshell.solvers import sequence


def test_plan_halves_the_letter_fields_of_the_recipe_form():
    sp = load("square-pedestal")  # form AxBx4: the 4 panels stay
    assert sequence.plan(sp, "48x16x4", 3072, "auto") == ["12x4x4", "24x8x4"]
    assert sequence.plan(sp, "48x16x4", 3072, 1) == ["24x8x4"]
    assert sequence.plan(sp, "48x16x4", 3072, 0) == []
    # below AUTO_MIN_ELEMENTS "auto" does nothing; an explicit count still stops at MIN_ELEMENTS
    assert sequence.plan(sp, "24x8x4", 768, "auto") == []
    assert sequence.plan(sp, "24x8x4", 768, 5) == ["12x4x4"]
    # an odd field cannot be halved: no coarse level (large-square-pedestal 45x15x4, strip 20x1)
    assert sequence.plan(load("large-square-pedestal"), "45x15x4", 2700, "auto") == []
    assert sequence.plan(load("strip-warp"), "20x1", 20, 3) == []
    assert sequence.plan(load("square-on-disc"), "30x240", 7200, "auto") == ["15x120"]


def test_prolong_reproduces_linear_fields_exactly():
    # the coarse shape functions reproduce a field linear in (X, Y), so its translations are carried
    # over to every fine node exactly (round-off only: 1e-12 of its size), including the nodes on
    # the edges and at the centres of the coarse quads (the directors take the interpolated length
    # of the coarse ones: next test)
    coarse = build_mesh("square_on_square", "6x2x4")
    fine = build_mesh("square_on_square", "12x4x4")

    def field(X):
        x, y = X[:, 0], X[:, 1]
        return np.column_stack(
            [0.1 * x - 0.3 * y + 1.0, 0.2 * y, -0.05 * x, 0.01 * x * 0 + 0.3, 0.02 * y, 0.5 - 0.01 * x]
        )

    U = sequence.prolong(coarse, field(coarse.nodes), fine)
    assert np.abs(U - field(fine.nodes))[:, :3].max() <= 1e-12 * np.abs(field(fine.nodes)).max()


def test_prolong_is_the_coarse_bilinear_field_on_a_nested_mesh():
    # 12x4x4 is 6x2x4 with every quad split in four: a coarse node keeps its value, a node at a
    # coarse edge's midpoint takes the mean of the edge's two ends and a node at a coarse quad's
    # centre the mean of its four corners (bilinear shape functions at (0, 0)), for any nodal
    # values (translations; the directors keep the interpolated length, tested below).  Round-off
    # only: 1e-12 of the values' size
    coarse = build_mesh("square_on_square", "6x2x4")
    fine = build_mesh("square_on_square", "12x4x4")
    rng = np.random.default_rng(3)
    Uc = np.zeros((coarse.n_nodes, 6))
    Uc[:, :3] = rng.standard_normal((coarse.n_nodes, 3))
    U = sequence.prolong(coarse, Uc, fine)
    X, x = coarse.nodes, fine.nodes

    def at(points):
        d = np.linalg.norm(x[None, :, :] - points[:, None, :], axis=2)
        assert d.min(axis=1).max() <= 1e-9
        return U[np.argmin(d, axis=1)]

    q = coarse.quads
    tol = 1e-12 * np.abs(Uc).max()
    assert np.abs(at(X) - Uc).max() <= tol
    assert np.abs(at(X[q].mean(axis=1)) - Uc[q].mean(axis=1)).max() <= tol
    assert np.abs(at(0.5 * (X[q[:, 0]] + X[q[:, 1]])) - 0.5 * (Uc[q[:, 0]] + Uc[q[:, 1]])).max() <= tol
    # rotated directors: the prolonged ones have the interpolated length (1 here), not the
    # shortened length of the interpolated vectors
    phi = rng.uniform(-1.0, 1.0, coarse.n_nodes)
    Uc[:, 3:] = np.column_stack([np.sin(phi), np.zeros_like(phi), np.cos(phi)]) - coarse.directors
    U = sequence.prolong(coarse, Uc, fine)
    assert np.abs(np.linalg.norm(fine.directors + U[:, 3:], axis=1) - 1.0).max() <= 1e-12


def test_static_settings_sequence_and_start_state_are_checked():
    from solidshell.settings import parse
    from solidshell.solvers.static import StaticSettings, solve_static

    assert parse(StaticSettings, {}, "s").sequence == 0  # off unless a scene asks
    assert load("square-pedestal").solver_settings("static")["sequence"] == "auto"
    assert parse(StaticSettings, {"sequence": 2}, "s").sequence == 2
    # a run's setting (the mesh sequence is built from the scene): one solve refuses it by name
    with pytest.raises(InputError, match=r"^solve_static: 'sequence' is a setting of a scene run"):
        solve_static(None, None, None, sequence=2)
    for bad in (-1, "coarse", True, 1.5):
        with pytest.raises(InputError, match="sequence"):
            parse(StaticSettings, {"sequence": bad}, "s")
    with pytest.raises(InputError, match="U0"):
        parse(StaticSettings, {"U0": [[0.0, 1.0, float("nan"), 0.0, 0.0, 0.0]]}, "s")


def test_sequenced_solve_reaches_the_direct_equilibrium(monkeypatch):
    """square-pedestal 12x4x4 from its 6x2x4 coarse mesh (MIN_ELEMENTS lowered to allow 48
    quads): the same stable equilibrium as the direct solve from the flat sheet."""
    from solidshell.run import run_scene

    monkeypatch.setattr(sequence, "MIN_ELEMENTS", 40)
    direct = run_scene("square-pedestal", mesh="12x4x4", solver="static", out_dir=None, progress=False, sequence=0)
    seq = run_scene("square-pedestal", mesh="12x4x4", solver="static", out_dir=None, progress=False, sequence=1)
    rec = seq.summary["sequence"]
    assert [r["mesh"] for r in rec] == ["6x2x4", "12x4x4"] and rec[-1]["from_coarse"]
    assert "sequence" not in direct.summary
    assert seq.converged and direct.converged
    assert seq.summary["positive_definite"] and direct.summary["positive_definite"]
    # both end at the tolerance of the Newton iteration (relative residual 1e-8, Newton
    # correction 1e-10 of |U|) on the same minimum; 1e-6 of max|U| separates "the same state"
    # from a different fold pattern (those differ by ~10 % of max|U|)
    du = np.abs(seq.U - direct.U).max() / np.abs(direct.U).max()
    assert du <= 1e-6
    assert seq.summary["fold_count"] == direct.summary["fold_count"]


def test_the_sequenced_fine_mesh_takes_cg_steps_to_the_same_equilibrium(monkeypatch):
    """The fine mesh of a sequence takes inexact Newton steps (CG preconditioned by the last
    factorisation; thresholds lowered so that square-pedestal 12x4x4 from 6x2x4 qualifies) and ends
    on the equilibrium of the exact-step solve."""
    from solidshell.run import run_scene
    from solidshell.solvers.static import newton

    monkeypatch.setattr(sequence, "MIN_ELEMENTS", 40)
    monkeypatch.setattr(newton, "PCG_MIN_DOFS", 0)
    cg = run_scene("square-pedestal", mesh="12x4x4", solver="static", out_dir=None, progress=False, sequence=1)
    exact = run_scene(
        "square-pedestal", mesh="12x4x4", solver="static", out_dir=None, progress=False, sequence=1, pcg_iterations=0
    )
    assert cg.converged and exact.converged and cg.summary["positive_definite"]
    assert cg.summary["cg_steps"] > 0 and exact.summary["cg_steps"] == 0
    assert cg.summary["cg_iterations"] >= cg.summary["cg_steps"]
    # a CG step replaces an iteration's factorisation (every other iteration factorises at least
    # once); measured 40 factorisations and 22 CG steps in 53 iterations against 61 in 52
    s = cg.summary
    assert s["factorizations"] >= s["iterations"] - s["cg_steps"]
    assert s["factorizations"] < exact.summary["factorizations"]
    # both stop at the Newton tolerance (relative residual 1e-8) on the same minimum: 1e-6 of max|U|
    # separates that from another fold pattern (~10 % of max|U| apart)
    assert np.abs(cg.U - exact.U).max() <= 1e-6 * np.abs(exact.U).max()
    assert cg.summary["fold_count"] == exact.summary["fold_count"]


def test_small_meshes_run_the_kernels_on_one_thread():
    import numba

    from solidshell.solvers.blas import SERIAL_KERNEL_ELEMENTS, kernel_threads

    before = numba.get_num_threads()
    with kernel_threads(20):
        assert numba.get_num_threads() == 1
    assert numba.get_num_threads() == before
    with kernel_threads(SERIAL_KERNEL_ELEMENTS):
        assert numba.get_num_threads() == before


def test_run_without_pictures_writes_no_png(tmp_path):
    from solidshell.cli import main

    out = tmp_path / "strip"
    assert main(["run", "strip-warp", "--mesh", "10x1", "--out", str(out), "--no-progress", "--no-pictures"]) == 0
    names = {p.name for p in out.iterdir()}
    assert "summary.json" in names and "result.vtu" in names
    assert not [n for n in names if n.endswith(".png")]


def test_an_interpenetrated_coarse_state_is_not_a_start():
    """square-pedestal with the assumed membrane and grading 8: the 12x4x4 state passes through
    itself (n_p . d_p < 0, Section 4.3), so the 24x8x4 solve must start from the flat sheet and end
    where the direct solve ends (from that coarse state 48x16x4 had landed in another state,
    DC 0.5307 with 19 interpenetrated nodes against 0.5515)."""
    from solidshell.run import run_scene

    over = {"model.membrane": "ans", "geometry.grading": 8.0}
    seq = run_scene(
        "square-pedestal",
        mesh="24x8x4",
        solver="static",
        out_dir=None,
        progress=False,
        overrides={**over, "solver.static.sequence": 1},
    )
    direct = run_scene(
        "square-pedestal",
        mesh="24x8x4",
        solver="static",
        out_dir=None,
        progress=False,
        overrides={**over, "solver.static.sequence": 0},
    )
    rec = seq.summary["sequence"]
    assert [r["mesh"] for r in rec] == ["12x4x4", "24x8x4"]
    assert rec[0]["interpenetrated"] and not rec[-1]["from_coarse"]
    # the same solve from flat: the same Newton path, so the same state to round-off
    assert np.abs(seq.U - direct.U).max() <= 1e-12 * np.abs(direct.U).max()
