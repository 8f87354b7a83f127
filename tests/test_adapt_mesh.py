"""Adaptive mesh (paper Sections 5.1-5.3): background mesh and labels, 2:1 balanced split/merge,
hybrid macro-transition patterns, and the element consistency on adapted meshes."""

import numba
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from solidshell import Fabric, IsotropicShell, ShellMesh
from solidshell.adapt import (
    AdaptiveMesh,
    BackgroundMesh,
    boundary_area_report,
    circle_projector,
    estimate_background_bytes,
)
from solidshell.adapt.transition import CENTRE, TABLE, TRANSITION_POLICIES, choose_variant, pattern_quality
from solidshell.errors import InputError
from solidshell.meshing import build_mesh
from solidshell.model import Model

ISO = IsotropicShell(E=1.0e4, nu=0.3, h=0.05)
WOOL = Fabric.wool()


def grid(nx, ny, jitter=0.0, seed=0, affine=None, z=None):
    """Structured nx x ny quad grid of the unit square, interior nodes jittered by up to
    ``jitter`` of the spacing, then mapped by the 2x2 ``affine`` matrix; ``z(x, y)`` lifts it."""
    x, y = np.meshgrid(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1))
    P = np.column_stack([x.ravel(), y.ravel()])
    inner = (P[:, 0] > 0) & (P[:, 0] < 1) & (P[:, 1] > 0) & (P[:, 1] < 1)
    h = np.array([1.0 / nx, 1.0 / ny])
    P[inner] += jitter * h * np.random.default_rng(seed).uniform(-1, 1, (inner.sum(), 2))
    if affine is not None:
        P = P @ np.asarray(affine).T
    Z = np.zeros(len(P)) if z is None else z(P[:, 0], P[:, 1])
    a = (np.arange(nx)[None, :] + (nx + 1) * np.arange(ny)[:, None]).ravel()
    q = np.column_stack([a, a + 1, a + nx + 2, a + nx + 1])
    sets = {"left": np.flatnonzero(np.isclose(x.ravel(), 0.0)), "corner": [0]}
    D = None if z is not None else np.tile([0.0, 0.0, 1.0], (len(P), 1))
    return ShellMesh(np.column_stack([P, Z]), quads=q, directors=D, node_sets=sets)


PEDESTAL = build_mesh("square_on_square", "2x1x4", sheet=20, pedestal=10)  # 8 trapezoids


# ----------------------------------------------------------------------------- geometry checks
def cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _cells(mesh):
    return [c for c in (mesh.quads, mesh.tris) if len(c)]


def conformity_report(am: AdaptiveMesh, level0: ShellMesh) -> dict:
    """Geometric checks of the computational mesh of a flat state (z = 0, directors +Z)."""
    a = am.active_mesh()
    X = a.mesh.nodes[:, :2]
    h_fine = np.sqrt(level0.area() / level0.n_quads) / 2**am.bg.levels
    # signed corner areas (counter-clockwise about +Z): no inverted or degenerate element
    min_corner = min(cross2(np.roll(X[c], -1, 1) - X[c], np.roll(X[c], 1, 1) - X[c]).min() for c in _cells(a.mesh))
    # element edges, each with the leaf level of the element(s) owning it
    sides = np.concatenate([np.stack([c, np.roll(c, -1, 1)], 2).reshape(-1, 2) for c in _cells(a.mesh)])
    nq = len(a.mesh.quads)
    lev = np.concatenate([np.repeat(a.elem_leaf[:nq, 0], 4), np.repeat(a.elem_leaf[nq:, 0], 3)])
    key = np.sort(sides, 1)
    edges, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    lo = np.full(len(edges), 99)
    hi = np.full(len(edges), -1)
    np.minimum.at(lo, inv, lev)
    np.maximum.at(hi, inv, lev)
    # a node strictly inside an edge (not an end, within 1e-9 h of the segment) is a hanging node
    P, Q = X[edges[:, 0]], X[edges[:, 1]]
    d = Q - P
    t = np.einsum("enk,ek->en", X[None] - P[:, None], d) / np.sum(d * d, 1)[:, None]
    dist = np.abs(cross2(d[:, None, :], X[None] - P[:, None])) / np.linalg.norm(d, axis=1)[:, None]
    hanging = (t > 1e-9) & (t < 1 - 1e-9) & (dist < 1e-9 * h_fine)
    qa, ta = a.mesh.element_areas()
    bl = np.linalg.norm(np.diff(X[edges[cnt == 1]], axis=1)[:, 0], axis=1).sum()
    b0 = level0.boundary_edges()
    bl0 = np.linalg.norm(level0.nodes[b0[:, 1], :2] - level0.nodes[b0[:, 0], :2], axis=1).sum()
    return dict(
        min_corner=min_corner / h_fine**2,
        hanging=int(hanging.sum()),
        shared_max=int(cnt.max()),
        level_jump=int((hi - lo).max()),
        area_error=abs(qa.sum() + ta.sum() - level0.area()) / level0.area(),
        boundary_error=abs(bl - bl0) / bl0,
        balance=am.balance_violations(),
    )


def assert_conforming(am, level0):
    r = conformity_report(am, level0)
    assert r["hanging"] == 0, r
    assert r["shared_max"] <= 2, r
    assert r["level_jump"] <= 1 and r["balance"] == 0, r
    # the jittered grids (jitter <= 0.3) and their affine maps keep every corner angle of every leaf
    # well above 15 deg; the worst transition pattern halves a fine edge: corner area >~ 0.02 h^2
    assert r["min_corner"] > 1e-3, r
    # the patches tile the level-0 quads exactly (straight-sided flat parents): area and boundary
    # length agree to round-off, so no gap or overlap and no edge left unmatched inside
    assert r["area_error"] < 1e-12 and r["boundary_error"] < 1e-12, r


# ----------------------------------------------------------------------------- background mesh
def test_background_nodes_labels_and_sets():
    m = grid(2, 1, jitter=0.0)
    bg = BackgroundMesh.from_level0(m, 3)
    assert [len(c) for c in bg.conn] == [2, 8, 32, 128]
    assert bg.n_nodes == (2 * 8 + 1) * (8 + 1)  # a 16 x 8 grid of finest elements
    np.testing.assert_array_equal(bg.Xo[: m.n_nodes], m.nodes)
    # Fig. 15: child k of (l, e) is 4e + k, its first node is the parent's node k; the mid-edge node
    # of edge k is child k's node 1, the centre child k's node 2
    for l in range(3):
        P, C = bg.conn[l], bg.conn[l + 1].reshape(-1, 4, 4)
        np.testing.assert_array_equal(C[:, :, 0], P)
        mids = C[:, :, 1]
        np.testing.assert_array_equal(bg.mid_parent[mids, :2], np.sort(np.stack([P, np.roll(P, -1, 1)], 2), 2))
        np.testing.assert_allclose(bg.Xo[mids], 0.5 * (bg.Xo[P] + bg.Xo[np.roll(P, -1, 1)]), atol=1e-15)
        assert np.all(C[:, :, 2] == C[:, :1, 2])
        np.testing.assert_array_equal(bg.centre_parent[C[:, 0, 2]], np.column_stack([P, mids]))
        np.testing.assert_array_equal(bg.node_level[C[:, 0, 2]], l + 1)
    # labels: i0-c1-c2 with c = k + 1 (the paper's i0-3-1 is child 0 of child 2 of i0)
    assert bg.label(2, 4 * (4 * 1 + 2) + 0) == "1-3-1"
    assert bg.from_label("1-3-1") == (2, 4 * (4 * 1 + 2) + 0)
    for l, e in [(0, 1), (3, 127), (3, 77), (1, 5)]:
        assert bg.from_label(bg.label(l, e)) == (l, e)
    with pytest.raises(InputError, match="bad element label '0-5' for 2 level-0 elements and 3 levels"):
        bg.from_label("0-5")
    # node sets: the left edge x = 0 keeps all its 9 finest nodes, the single corner node stays alone
    assert np.allclose(bg.Xo[bg.node_sets["left"], 0], 0.0) and len(bg.node_sets["left"]) == 9
    np.testing.assert_array_equal(bg.node_sets["corner"], [0])


def test_serendipity_centre_on_a_curved_surface():
    # on z = x^2 the edge mids are chord midpoints (z off the surface by h^2/4); the serendipity
    # centre -1/4 sum corners + 1/2 sum mids is what Section 5.1 prescribes: check it literally
    m = grid(1, 1, z=lambda x, y: x**2)
    bg = BackgroundMesh.from_level0(m, 1)
    c = bg.conn[1][0, 2]
    expect = -0.25 * m.nodes.sum(0) + 0.5 * bg.Xo[bg.centre_parent[c, 4:]].sum(0)
    np.testing.assert_allclose(bg.Xo[c], expect, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(bg.Xn, axis=1), 1.0, atol=1e-15)


def test_curved_boundary_nodes_on_the_circle_and_area():
    m = build_mesh("square_on_disc", "4x32")
    r = boundary_area_report(m, 2, circle_projector((0, 0), 10.0), exact=50.0**2 - np.pi * 10.0**2)
    # averaged mids keep the 32-gon's chords, so the hole is too small and the area too large by
    # ~ pi R^2 (pi/32)^2 / 3... the projected one converges to the exact area at O((1/128)^2)
    assert r["error_averaged"] > 0 and abs(r["error_projected"]) < 0.1 * r["error_averaged"]
    bg = BackgroundMesh.from_level0(m, 2, circle_projector((0, 0), 10.0))
    cl = bg.node_sets["clamped"]
    assert len(cl) == 32 * 4
    np.testing.assert_allclose(np.linalg.norm(bg.Xo[cl, :2], axis=1), 10.0, rtol=1e-13)
    # the straight outer sides stay straight (|x| or |y| = 25)
    out = bg.node_sets["outer"]
    assert np.all(np.isclose(np.abs(bg.Xo[out, :2]).max(1), 25.0, rtol=1e-13))
    # circle-pedestal: both rims are circles, each boundary node goes to its own
    disc = build_mesh("disc_on_disc", "2x8")
    bg = BackgroundMesh.from_level0(disc, 2, circle_projector((0, 0), (6.35, 12.7)))
    for name, r in (("clamped", 6.35), ("outer", 12.7)):
        np.testing.assert_allclose(np.linalg.norm(bg.Xo[bg.node_sets[name], :2], axis=1), r, rtol=1e-13)


def test_bad_input():
    tri = ShellMesh([[0, 0], [1, 0], [0, 1], [1, 1]], quads=None, tris=[[0, 1, 2], [1, 3, 2]])
    with pytest.raises(InputError, match="only quadrilateral level-0 meshes"):
        BackgroundMesh.from_level0(tri)
    with pytest.raises(InputError, match="levels"):
        BackgroundMesh.from_level0(grid(1, 1), -1)
    with pytest.raises(InputError, match="GiB"):
        BackgroundMesh.from_level0(PEDESTAL, 13)  # 5.4e8 elements: beyond any machine here


def test_background_that_does_not_fit_is_refused_before_any_work(monkeypatch):
    from solidshell.adapt import background

    # pretend 10 MiB are free: 8 quads x 4^6 ~ 8.3 MiB estimated, more than half of it
    monkeypatch.setattr(background, "_available_bytes", lambda: 10 * 2**20)
    with pytest.raises(InputError, match=r"levels = 6 on 8 level-0 quads .* GiB"):
        BackgroundMesh.from_level0(PEDESTAL, 6)
    BackgroundMesh.from_level0(PEDESTAL, 2)
    assert estimate_background_bytes(48, 3) == 48 * 64 * estimate_background_bytes(1, 0)
    am = AdaptiveMesh(BackgroundMesh.from_level0(grid(2, 1), 2))
    with pytest.raises(InputError, match=r"no element \(1, 8\)"):
        am.split([[1, 8]])
    with pytest.raises(InputError, match="levels must lie in 0..2"):
        am.merge([[3, 0]])
    # zero levels: a valid (if static) adaptive mesh
    am0 = AdaptiveMesh(BackgroundMesh.from_level0(grid(2, 1), 0))
    assert am0.split([[0, 0]]) == 0 and am0.active_mesh().mesh.n_quads == 2


# ----------------------------------------------------------------------------- patterns
def test_patterns_cover_every_mask_and_tile_the_square():
    sq = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5], [0.5, 0.5]])
    for mask in range(16):
        for q, t in TABLE[mask][1]:
            # as few triangles as the parity of the boundary segments allows
            assert len(t) == bin(mask).count("1") % 2
            # counter-clockwise (positive signed areas) and tiling the square exactly
            signed = [
                0.5 * cross2(pts[c] - pts[c[0]], np.roll(pts[c], -1, 0) - pts[c[0]]).sum() for c in list(q) + list(t)
            ]
            assert min(signed) > 0 and sum(signed) == pytest.approx(1.0, abs=1e-15)
            used = set(np.concatenate([np.ravel(q), np.ravel(t)]).tolist())
            assert all(4 + k in used for k in range(4) if mask >> k & 1)
            assert not any(4 + k in used for k in range(4) if not mask >> k & 1)
    quality = pattern_quality(sq, "quality")
    assert min(a for a, _ in quality.values()) >= 45.0 - 1e-9
    assert max(r for _, r in quality.values()) <= 2.0 + 1e-9


def test_fewest_nodes_policy_leaves_the_centre_out_of_patterns_one_and_four():
    """adapt.transitions = "fewest_nodes": patterns 1 and 4 take a variant without the centre node
    (the best of those on the leaf's geometry), every other pattern what "quality" takes."""
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5], [0.5, 0.5]])[None]
    for mask in range(16):
        pid, variants = TABLE[mask]
        q, t = variants[choose_variant(mask, pts, "fewest_nodes")[0]]
        uses_centre = CENTRE in np.ravel(q) or CENTRE in np.ravel(t)
        assert uses_centre == (pid in (2, 5)), mask
        if pid not in (1, 4):
            assert choose_variant(mask, pts, "fewest_nodes")[0] == choose_variant(mask, pts, "quality")[0]
    # on the unit square: one side -> a trapezoid and a right triangle with legs 1/2 and 1 (smallest
    # angle atan(1/2) = 26.57 deg, longest / shortest edge sqrt(5)); three sides -> two quads and a
    # corner triangle at 45 deg, as "quality"'s worst; exact geometry, so 1e-9 is round-off
    sq = pts[0, :4]
    lean, best = pattern_quality(sq, "fewest_nodes"), pattern_quality(sq, "quality")
    assert lean[1] == pytest.approx((np.degrees(np.arctan(0.5)), np.sqrt(5.0)), abs=1e-9)
    assert lean[4] == pytest.approx((45.0, 2.0), abs=1e-9)
    assert {k: v for k, v in lean.items() if k not in (1, 4)} == {k: v for k, v in best.items() if k not in (1, 4)}
    with pytest.raises(InputError, match="transitions"):
        BackgroundMesh.from_level0(grid(1, 1), 1, transitions="fewest")


def test_fewest_nodes_policy_saves_one_node_per_one_and_three_sided_patch():
    """The same leaves under both policies: one active node fewer per patch of pattern 1 or 4 (its
    centre), the same nodes otherwise; on a straight grid every lean variant is valid."""
    meshes = {}
    for policy in TRANSITION_POLICIES:
        am, a = every_pattern_state(grid(8, 8), policy=policy)
        meshes[policy] = a
    a, b = meshes["quality"], meshes["fewest_nodes"]
    patches = {(l, e) for (l, e), k in zip(a.elem_leaf.tolist(), a.elem_kind) if k in (1, 4)}
    assert len(patches) >= 2
    assert a.mesh.n_nodes - b.mesh.n_nodes == len(patches)
    assert set(np.flatnonzero(b.active)) < set(np.flatnonzero(a.active))
    assert a.mesh.area() == pytest.approx(b.mesh.area(), rel=1e-14)


@pytest.mark.parametrize("chunk", [None, 7])
def test_memoised_transition_variants_are_each_elements_own_choice(chunk, monkeypatch):
    """BackgroundMesh.transition_variants chooses every element of a level at the first use of a
    mask there (vectorised calls of _VARIANT_CHUNK elements; 7 puts chunk boundaries inside every
    level); each answer must be what choose_variant gives that element alone, exactly (integer
    variants), on a jittered grid where the variants differ by element."""
    import solidshell.adapt.background as background
    from solidshell.adapt.transition import choose_variant

    if chunk:
        monkeypatch.setattr(background, "_VARIANT_CHUNK", chunk)

    bg = BackgroundMesh.from_level0(grid(3, 2, jitter=0.3, seed=5), 2)
    rng = np.random.default_rng(4)
    picked = set()
    for l in range(bg.levels):
        e = rng.integers(0, bg.n_elements(l), 40)
        mask = rng.integers(1, 16, 40)
        got = bg.transition_variants(l, e, mask)
        for ei, m, g in zip(e, mask, got):
            ch = bg.conn[l + 1][4 * ei + np.arange(4)]
            loc = np.concatenate([bg.conn[l][ei], ch[:, 1], ch[:1, 2]])
            assert g == choose_variant(int(m), bg.Xo[loc][None])[0]
            picked.add(int(g))
    assert len(picked) > 1  # elements do get different variants


# ----------------------------------------------------------------------------- property-based
@st.composite
def level0_meshes(draw):
    kind = draw(st.sampled_from(["grid", "grid", "pedestal"]))
    if kind == "pedestal":
        return PEDESTAL
    nx, ny = draw(st.integers(1, 3)), draw(st.integers(1, 3))
    seed = draw(st.integers(0, 10**6))
    A = None
    if draw(st.booleans()):
        rng = np.random.default_rng(seed + 1)
        th = rng.uniform(0, 2 * np.pi)
        R = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
        A = R @ np.array([[rng.uniform(0.5, 2.0), rng.uniform(-0.5, 0.5)], [0.0, rng.uniform(0.5, 2.0)]])
    return grid(nx, ny, jitter=draw(st.floats(0.0, 0.3)), seed=seed, affine=A)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    m=level0_meshes(),
    levels=st.integers(1, 3),
    ops=st.lists(
        st.tuples(st.sampled_from(["split", "merge"]), st.floats(0.05, 1.0), st.integers(0, 2**31)),
        min_size=1,
        max_size=8,
    ),
    policy=st.sampled_from(TRANSITION_POLICIES),
)
def test_random_split_merge_sequences_stay_conforming(m, levels, ops, policy):
    bg = BackgroundMesh.from_level0(m, levels, transitions=policy)
    am = AdaptiveMesh(bg)
    s0 = am.state_arrays()
    a0 = am.active_mesh()
    for op, frac, seed in ops:
        rng = np.random.default_rng(seed)
        if op == "split":
            items = am.leaves()
        else:  # any parent whose children are all leaves, also those whose merge is vetoed
            items = np.concatenate(
                [
                    np.column_stack([np.full(k.size, l), k])
                    for l in range(levels)
                    for k in [np.flatnonzero(am.leaf[l + 1].reshape(-1, 4).all(1))]
                ]
            )
        pick = items[rng.random(len(items)) < frac]
        (am.split if op == "split" else am.merge)(pick)
        assert_conforming(am, m)
    # checkpoint round trip reproduces the computational mesh exactly
    b = AdaptiveMesh.from_state_arrays(bg, am.state_arrays()).active_mesh()
    a = am.active_mesh()
    np.testing.assert_array_equal(a.mesh.quads, b.mesh.quads)
    np.testing.assert_array_equal(a.elem_leaf, b.elem_leaf)
    # split everything, then merge everything: the exact level-0 mesh and state
    am.refine_all()
    assert all(not f.any() for f in am.leaf[:-1]) and am.leaf[-1].all()
    am.coarsen_all()
    for k, v in s0.items():
        np.testing.assert_array_equal(am.state_arrays()[k], v)
    a = am.active_mesh()
    np.testing.assert_array_equal(a.nodes, np.arange(m.n_nodes))
    np.testing.assert_array_equal(np.flatnonzero(a.active), a.nodes)
    np.testing.assert_array_equal(a.mesh.quads, m.quads)
    np.testing.assert_array_equal(a.mesh.nodes, m.nodes)
    np.testing.assert_array_equal(a.mesh.directors, m.directors)
    assert a.mesh.n_tris == 0 and not a.elem_kind.any()
    for k in m.node_sets:
        np.testing.assert_array_equal(a.mesh.node_sets[k], m.node_sets[k])
    np.testing.assert_array_equal(a0.mesh.quads, a.mesh.quads)


def test_balance_propagates_splits_and_vetoes_merges():
    m = grid(4, 1)
    am = AdaptiveMesh(BackgroundMesh.from_level0(m, 3))
    am.split([[0, 3]])
    # the finest child of element 3 touching element 2 forces element 2 to split, not more
    e1 = 4 * 3 + 0  # child 0 of element 3: its left edge is on element 2
    am.split([[1, e1]])
    am.split([[2, 4 * e1 + 3]])  # child 3 (left-top) of it
    assert not am.leaf[0][2] and am.leaf[0][1] and am.balance_violations() == 0
    # merging element 2 back would leave level-3 leaves next to a level-0 leaf: vetoed
    assert am.merge([[0, 2]]) == 0
    assert_conforming(am, m)


# ----------------------------------------------------------------------------- consistency
def every_pattern_state(mesh_level0, nx=8, policy="quality"):
    """A state of an nx x nx level-0 grid whose computational mesh holds every transition pattern
    at level 0 and transitions at level 1 as well (variants chosen under ``policy``)."""
    am = AdaptiveMesh(BackgroundMesh.from_level0(mesh_level0, 2, transitions=policy))
    cell = [
        (1, 1),
        (3, 1),
        (5, 1),
        (5, 3),
        (4, 2),
        (0, 5),
        (1, 6),
        (3, 5),
        (5, 5),
        (4, 4),
        (4, 6),
        (6, 6),
        (7, 6),
        (6, 7),
        (7, 7),
    ]
    am.split([[0, j * nx + i] for i, j in cell])
    am.split([[1, 4 * (6 * nx + 6) + 2], [1, 4 * (7 * nx + 7) + 0]])
    a = am.active_mesh(check=True)
    assert set(a.elem_kind[a.elem_leaf[:, 0] == 0]) == {0, 1, 2, 3, 4, 5}
    assert set(a.elem_kind[a.elem_leaf[:, 0] == 1]) >= {1, 2}
    return am, a


FLAT8 = grid(8, 8, jitter=0.25, seed=7)
CURVED8 = grid(8, 8, jitter=0.2, seed=3, z=lambda x, y: 0.3 * x**2 - 0.2 * y**2 + 0.1 * x * y)


def _interior(mesh):
    b = np.unique(mesh.boundary_edges())
    return np.setdiff1d(np.arange(mesh.n_nodes), b)


@pytest.mark.parametrize("policy", TRANSITION_POLICIES)
@pytest.mark.parametrize("level0", [FLAT8, CURVED8], ids=["flat", "curved"])
def test_rigid_motion_has_no_energy_on_an_adapted_mesh(level0, policy):
    am, a = every_pattern_state(level0, policy=policy)
    mesh = a.mesh
    model = Model(mesh, WOOL)
    R = Rotation.from_rotvec([0.9, -1.7, 0.4]).as_matrix()
    c = np.array([3.0, -2.0, 1.0])

    def rigid(U):
        xo = (mesh.nodes + U[:, :3]) @ R.T + c
        xn = (mesh.directors + U[:, 3:]) @ R.T
        return np.column_stack([xo - mesh.nodes, xn - mesh.directors])

    # reference: a 1% random strain of the same mesh
    rng = np.random.default_rng(0)
    Uref = np.column_stack(
        [0.01 * rng.standard_normal((mesh.n_nodes, 3)) / 8, 0.01 * rng.standard_normal((mesh.n_nodes, 3))]
    )
    Wref, Fref = model.energy_and_force(Uref)
    W, F = model.energy_and_force(rigid(np.zeros((mesh.n_nodes, 6))))
    # strains of a rigid motion are differences of squared lengths of O(3) vectors: ~1e-15, so the
    # energy is ~1e-30 of a unit-strain energy, ~1e-26 of the 1e-2-strain reference (measured
    # 1.4e-26) and the force ~1e-13 of the reference force (measured 1.1e-13): the bounds allow
    # round-off strains up to 1e-14, a non-objective term would give O(1)
    assert abs(W) <= 1e-24 * Wref
    assert np.abs(F).max() <= 1e-12 * np.abs(Fref).max()
    # a rigid motion of a deformed state changes its energy only by round-off (measured 3e-15)
    assert abs(model.energy(rigid(Uref)) - Wref) <= 1e-11 * Wref


@pytest.mark.parametrize("policy", TRANSITION_POLICIES)
@pytest.mark.parametrize("membrane", ["full", "ans"])
def test_membrane_patch_test_on_an_adapted_mesh(membrane, policy):
    am, a = every_pattern_state(FLAT8, policy=policy)
    mesh = a.mesh
    model = Model(mesh, ISO, membrane=membrane)
    G = np.array([[2e-3, 1e-3], [-0.5e-3, 3e-3]])  # linear in-plane field, constant strain
    U = np.zeros((mesh.n_nodes, 6))
    U[:, :2] = mesh.nodes[:, :2] @ G.T
    F = model.internal_force(U)
    inner = _interior(mesh)
    # constant stress: the nodal forces of each interior node cancel between its elements; the
    # boundary forces are the O(|sigma| h) tractions.  The Green strains are differences of squared
    # lengths, exact to ~1e-16 absolute, so the residual is ~1e-16 / 1e-3 ~ 1e-13 relative (measured
    # 7e-13 here and on the level-0 grid alike); a pattern failing the patch test would give ~1e-2
    assert np.abs(F[inner]).max() <= 1e-10 * np.abs(F).max()


@pytest.mark.parametrize("policy", TRANSITION_POLICIES)
def test_bending_patch_test_on_an_adapted_mesh(policy):
    am, a = every_pattern_state(FLAT8, policy=policy)
    mesh = a.mesh
    model = Model(mesh, ISO)
    kappa, n = 0.02, np.array([np.cos(0.6), np.sin(0.6)])
    s = mesh.nodes[:, :2] @ n
    # constant curvature kappa about the axis normal to n, linearised: w = kappa s^2 / 2 and
    # directors rotated by -kappa s (no transverse shear at the mid-edge tying points)
    U = np.zeros((mesh.n_nodes, 6))
    U[:, 2] = 0.5 * kappa * s**2
    U[:, 3:5] = -kappa * s[:, None] * n
    K = model.tangent(np.zeros((mesh.n_nodes, 6)))
    F = (K @ U.ravel()).reshape(-1, 6)
    inner = _interior(mesh)
    D = ISO.E * ISO.h**3 / (12 * (1 - ISO.nu**2))
    W = 0.5 * U.ravel() @ (K @ U.ravel())
    # the linear energy of constant curvature is 1/2 D kappa^2 A exactly (measured 4e-13 relative)
    assert W == pytest.approx(0.5 * D * kappa**2 * mesh.area(), rel=1e-10)
    # constant moment: interior nodes in balance.  K U cancels terms ~2e5 times the boundary forces
    # (shear and membrane stiffness against bending), so round-off leaves ~1e-11 (measured 1.6e-11
    # here, 0.9e-11 on the uniform level-0 grid); a failing pattern would leave ~1e-2
    assert np.abs(F[inner]).max() <= 1e-10 * np.abs(F).max()


@pytest.mark.parametrize("policy", TRANSITION_POLICIES)
def test_internal_force_is_the_energy_gradient_on_an_adapted_mesh(policy):
    am, a = every_pattern_state(CURVED8, policy=policy)
    mesh = a.mesh
    model = Model(mesh, WOOL)
    rng = np.random.default_rng(5)
    U = np.column_stack([0.02 * rng.standard_normal((mesh.n_nodes, 3)), 0.1 * rng.standard_normal((mesh.n_nodes, 3))])
    F = model.internal_force(U).ravel()
    u = U.ravel()
    eps = 1e-6
    fd = np.empty_like(u)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)  # ~1200 small evaluations: thread start-up would dominate
    try:
        for k in range(u.size):
            up, um = u.copy(), u.copy()
            up[k] += eps
            um[k] -= eps
            fd[k] = (model.energy(up.reshape(U.shape)) - model.energy(um.reshape(U.shape))) / (2 * eps)
    finally:
        numba.set_num_threads(threads)
    # energy polynomial in U of size O(0.1): truncation O(eps^2) ~ 1e-12, round-off ~ 1e-16 W / eps;
    # measured 8e-11 of the largest force; 1e-6 (as tests/test_elements.py) catches any wrong term
    assert np.abs(F - fd).max() <= 1e-6 * np.abs(F).max()


def test_active_mesh_node_sets_follow_the_background():
    am, a = every_pattern_state(FLAT8)
    left = a.mesh.node_sets["left"]
    assert np.allclose(a.mesh.nodes[left, 0], 0.0)
    # every active node on x = 0 is in the set (inserted nodes on the set's edge inherit it)
    np.testing.assert_array_equal(left, np.flatnonzero(np.isclose(a.mesh.nodes[:, 0], 0.0)))
    np.testing.assert_allclose(np.linalg.norm(a.mesh.directors, axis=1), 1.0, atol=1e-15)
