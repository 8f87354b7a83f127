"""The sheet against itself, measured (solidshell/layers.py): intersecting triangle pairs against a
brute-force count written here (every pair of triangles, every edge against every triangle), the
gap between two layers against its closed form, and invariance under rigid motions.  Random
states come from hypothesis; their perturbations keep the triangles in general position (no
coplanar or edge-on touching), where the two counts must agree exactly."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from solidshell import layers
from solidshell.mesh import ShellMesh
from solidshell.meshing import build_mesh
from verification import self_check

H = 0.06


def _crossings(x, F) -> int:
    """Brute force: the triangle pairs sharing no node of which an edge of one crosses the other
    (self_check's segment-triangle test on every pair and edge at once, no broad phase), counted
    once per pair."""
    i, j = np.triu_indices(len(F), 1)
    keep = ~(F[i][:, :, None] == F[j][:, None, :]).any(axis=(1, 2))
    i, j = i[keep], j[keep]
    hit = np.zeros(len(i), dtype=bool)
    for a, b in ((i, j), (j, i)):
        for k in range(3):
            p, q = x[F[a, k]], x[F[a, (k + 1) % 3]]
            hit |= self_check.segment_hits(p, q, x[F[b, 0]], x[F[b, 1]], x[F[b, 2]])
    return int(np.count_nonzero(hit))


def _fold(mesh, lift, seed):
    """The half x > 0 of a flat sheet folded over the half x < 0 at heights ``lift`` (a function of
    the reference x), plus a small random wobble (general position)."""
    X = mesh.nodes
    U = np.zeros((mesh.n_nodes, 6))
    right = X[:, 0] > 1e-9
    U[right, 0] = -2.0 * X[right, 0]
    U[right, 2] = lift(X[right, 0])
    U[:, :3] += 1e-4 * np.random.default_rng(seed).standard_normal((mesh.n_nodes, 3))
    return U


@settings(max_examples=40, deadline=None)
@given(st.floats(-0.05, 0.05), st.floats(1.0, 3.5), st.integers(0, 2**31 - 1))
def test_intersections_match_a_brute_force_count(dz, x_cross, seed):
    """A folded 6x6 sheet whose upper layer dips below the lower one beyond x_cross (by dz < 0) or
    stays above it (dz > 0): layers.self_intersections finds exactly the pairs the brute force does."""
    mesh = build_mesh("square", "6x6", size=8.0)
    U = _fold(mesh, lambda x: np.where(x > x_cross, dz, 0.03 * np.minimum(x, 1.0)), seed)
    x = mesh.nodes + U[:, :3]
    F = layers.triangles(mesh)
    found = layers.self_intersections(mesh, U)
    assert len(found) == _crossings(x, F)
    assert np.array_equal(found, self_check.intersecting_pairs(x, F.astype(np.int64)))  # the runs' checker
    assert all(not set(F[i]) & set(F[j]) for i, j in found)


def test_a_flat_sheet_is_clear_in_any_rigid_position():
    """No intersection and no second layer, before and after a rigid rotation and translation
    (distances are invariant; a layer needs sheet brought together)."""
    mesh = build_mesh("square", "12x12", size=10.0)
    assert layers.report(mesh, None, H) == layers.report(mesh, np.zeros((mesh.n_nodes, 6)), H)
    R = np.linalg.qr(np.random.default_rng(1).standard_normal((3, 3)))[0]
    U = np.zeros((mesh.n_nodes, 6))
    U[:, :3] = mesh.nodes @ R.T + (3.0, -2.0, 7.0) - mesh.nodes
    r = layers.report(mesh, U, H)
    assert r["self_intersections"] == 0 and r["min_layer_gap"] is None and r["layer_pairs_close"] == 0


def _two_sheets(n=6, size=4.0, apart=10.0):
    m = build_mesh("square", f"{n}x{n}", size=size)
    X = np.vstack([m.nodes, m.nodes + (0.0, 0.0, apart)])
    return ShellMesh(X, quads=np.vstack([m.quads, m.quads + m.n_nodes])), m.n_nodes


def test_the_gap_between_two_sheets_is_their_distance():
    """Two parallel sheets, the upper one lowered to d above the lower and shifted sideways by a
    fraction of an element (so its nodes lie over the lower one's faces): min_layer_gap = d to
    round-off (1e-12 relative); pairs are reported closer than 0.9 h only when d is; none beyond 2 h."""
    mesh, n = _two_sheets()
    for d in (0.3 * H, 0.95 * H, 1.5 * H, 2.5 * H):
        U = np.zeros((mesh.n_nodes, 6))
        U[n:, 2] = d - 10.0
        U[n:, :2] = (0.13, 0.07)
        r = layers.report(mesh, U, H)
        assert r["self_intersections"] == 0
        if d < layers.SEARCH * H:
            assert abs(r["min_layer_gap"] - d) < 1e-12 * d
        else:
            assert r["min_layer_gap"] is None
        assert (r["layer_pairs_close"] > 0) == (d < (1.0 - layers.LAYER_TOL) * H)
        assert not layers.warnings(r) if d >= (1.0 - layers.LAYER_TOL) * H else len(layers.warnings(r)) == 1


def test_two_sheets_through_each_other_are_counted():
    """The upper sheet lowered through the lower one and tilted: its triangles cross the lower
    sheet's along a line; the count equals the brute force's, and report warns."""
    mesh, n = _two_sheets(n=5)
    U = np.zeros((mesh.n_nodes, 6))
    X = mesh.nodes
    U[n:, 2] = -10.0 + 0.3 * X[n:, 0] + 0.011
    x = X + U[:, :3]
    r = layers.report(mesh, U, H)
    assert r["self_intersections"] == _crossings(x, layers.triangles(mesh)) > 0
    assert any("passes through itself" in w for w in layers.warnings(r))


def test_a_run_reports_the_sheet_against_itself(tmp_path):
    """summary.json holds the measures of layers.report for the final state (a short sphere
    relaxation: one layer, nothing through itself), and the same numbers from the written state."""
    import json

    from solidshell import run_scene

    out = run_scene(
        "sphere", mesh="4x4", solver="relax", out_dir=tmp_path / "r", progress=False,
        overrides={"solver.relax.t_max": 0.05, "output.pictures": [], "output.snapshots": []},
    )  # fmt: skip
    s = json.loads((tmp_path / "r" / "summary.json").read_text())
    h = s["material"]["thickness"]
    assert {k: s[k] for k in layers.report(out.mesh, out.U, h)} == layers.report(out.mesh, out.U, h)
    assert s["self_intersections"] == 0 and s["layer_pairs_close"] == 0
    assert not any("itself" in w or "layers closer" in w for w in s["warnings"])
