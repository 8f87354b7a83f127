"""Quasi-static directors after a transfer (solidshell/adapt/settle.py).

A 4x2 wool sheet is bent onto a cylinder of radius 8 cm (positions and directors of the exact
bending), refined once, and its new nodes filled by the DK transfer (Eq. 32): the directors are then
off equilibrium.  Settling must put them at equilibrium (director residual down by at least 1e3, the
target of the settler's rtol), lower the total potential, leave every translational dof bit for bit,
and change nothing where there is nothing to settle (a rigid motion of the flat sheet; an already
settled state).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from solidshell import Fabric, ShellMesh
from solidshell.adapt.settle import DirectorSettler, director_dofs, settle_directors
from solidshell.adapt.transfer import fill_new_nodes
from solidshell.model import Model
from verification.adapt_transfer import refine

R_BEND = 8.0  # cm


def _bent(X, Xn):
    """(N,6) state of the exact bending of the flat sheet z = 0 onto a cylinder of radius R_BEND
    about the y axis (arc length along x kept, directors along the cylinder's normal)."""
    phi = X[:, 0] / R_BEND
    x = np.stack([R_BEND * np.sin(phi), X[:, 1], R_BEND * (1.0 - np.cos(phi))], axis=1)
    n = np.stack([-np.sin(phi), np.zeros_like(phi), np.cos(phi)], axis=1)
    return np.concatenate([x - X, n - Xn], axis=1)


def _case():
    x, y = np.meshgrid(np.linspace(0.0, 4.0, 5), np.linspace(0.0, 2.0, 3))
    X = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    q = np.array([[j * 5 + i, j * 5 + i + 1, (j + 1) * 5 + i + 1, (j + 1) * 5 + i] for j in range(2) for i in range(4)])
    coarse = ShellMesh(X, quads=q)
    bg, fine = refine(coarse, 1)
    model = Model(fine, Fabric.wool())
    Nc = len(X)
    Ubg = np.zeros((len(bg.Xo), 6))
    Ubg[:Nc] = _bent(X, coarse.directors)
    U = fill_new_nodes(bg, Ubg, np.arange(Nc, len(bg.Xo)), "dk")
    fixed = np.zeros((fine.n_nodes, 6), dtype=bool)
    fixed[np.isclose(fine.nodes[:, 0], 0.0)] = True  # clamped edge x = 0
    loads = np.zeros((fine.n_nodes, 6))
    return model, fixed, loads, U


def _pi(model, loads, U):
    return float(model.energy(U.reshape(loads.shape))) - float(loads.ravel() @ U.ravel())


def test_settling_puts_dk_directors_at_equilibrium_and_keeps_positions():
    model, fixed, loads, U = _case()
    idx = director_dofs(fixed)
    r_before = np.linalg.norm((loads.ravel() - model.internal_force(U).ravel())[idx])
    S, rep = settle_directors(model, loads, fixed, U)
    S = S.reshape(U.shape)
    r_after = np.linalg.norm((loads.ravel() - model.internal_force(S).ravel())[idx])
    assert rep.converged and rep.iterations >= 1
    # Newton on a smooth block: the residual falls by the settler's rtol (1e-3) at least
    assert r_after <= 1e-3 * r_before, (r_before, r_after)
    assert np.isclose(rep.residual_before, r_before) and np.isclose(rep.residual_after, r_after)
    assert np.array_equal(S[:, :3], U[:, :3])  # translations untouched, bit for bit
    assert np.array_equal(S[fixed], U[fixed])  # and every prescribed dof
    assert _pi(model, loads, S) < _pi(model, loads, U)  # a minimisation: the potential falls
    # the change is a correction of the DK directors, not a different shape: well below their length
    assert 0.0 < np.abs(S[:, 3:] - U[:, 3:]).max() < 0.1


def test_settling_a_settled_state_or_a_rigid_motion_changes_nothing():
    model, fixed, loads, U = _case()
    S, _ = settle_directors(model, loads, fixed, U)
    S2, rep = settle_directors(model, loads, fixed, S)
    # a settled state moves by at most the correction of its residual (<= 1e-3 of the first, whose
    # correction was < 0.1): far below the first settling's change
    d1 = np.abs(S - U.ravel()).max()
    assert np.abs(S2 - S).max() < 1e-3 * d1, (np.abs(S2 - S).max(), d1)
    # a rigid motion of the flat sheet is stress free: nothing to settle, no iteration taken
    X, Xn = model.mesh.nodes, model.mesh.directors
    Q = Rotation.from_rotvec([0.3, -0.5, 0.2]).as_matrix()
    R = np.concatenate([X @ Q.T + np.array([1.0, 2.0, 3.0]) - X, Xn @ Q.T - Xn], axis=1)
    free = np.zeros_like(fixed)
    S3, rep3 = settle_directors(model, loads, free, R)
    assert np.abs(S3.reshape(R.shape) - R).max() < 1e-12
    assert rep3.residual_before < 1e-9


def test_quasi_static_step_keeps_the_settled_dofs_at_equilibrium_one_step_behind():
    """The driver's D_n-1: held dofs one transferred step v behind, settled dofs one quasi-static
    step w = -K_SS^-1 K_SH v behind.  The settled dofs' residual at D_s - (v + w) is second order in
    the step (a tenth of the step: a hundredth of the residual), while the plain step's (w = v's own
    entries) is first order (a tenth); the held entries are v's, bit for bit."""
    model, fixed, loads, U = _case()
    settler = DirectorSettler(model, loads, fixed)
    S, rep = settler(U, rtol=1e-6, max_iter=20)  # residual ~1e-9: below every one below
    assert rep.converged
    idx = settler.idx
    held = np.setdiff1d(np.arange(U.size), idx)

    def res(D):
        return np.linalg.norm((loads.ravel() - model.internal_force(D.reshape(U.shape)).ravel())[idx])

    v = np.random.default_rng(3).standard_normal(U.shape)  # a rough motion of every free dof
    v[fixed] = 0.0
    r_plain, r_quasi = [], []
    for size in (1e-4, 1e-5):  # a time step's motion [cm]
        step = settler.quasi_static_step(S, size * v.ravel())
        assert np.array_equal(step[held], size * v.ravel()[held])
        r_plain.append(res(S - size * v.ravel()))
        r_quasi.append(res(S - step))
    # orders 1 and 2 within 20 %: ratios 10 and 100 for a tenth of the step
    assert 8.0 < r_plain[0] / r_plain[1] < 12.0, r_plain
    assert r_quasi[0] / r_quasi[1] > 80.0, r_quasi
    assert r_quasi[0] < 0.05 * r_plain[0]


def test_settling_new_nodes_moves_only_their_positions_and_lowers_the_potential_further():
    """With the inserted nodes given, their positions settle too (adapt.settle_new_nodes): the DK
    mid-edge node on the cubic stretches its half-edges, and freeing it releases that membrane
    energy.  Old nodes' positions stay bit for bit; the residual over the settled dofs falls by the
    settler's rtol (1e-3); the potential ends below the directors-only settling's, which is the
    same minimisation over fewer dofs."""
    model, fixed, loads, U = _case()
    Nc = 15  # the 5x3 coarse nodes come first (refine)
    new = np.arange(Nc, model.n_nodes)
    S_dir, _ = settle_directors(model, loads, fixed, U)
    S, rep = DirectorSettler(model, loads, fixed, new)(U)
    S = S.reshape(U.shape)
    idx = director_dofs(fixed, new)
    r = np.linalg.norm((loads.ravel() - model.internal_force(S).ravel())[idx])
    assert rep.converged and r <= 1e-3 * rep.residual_before
    assert np.array_equal(S[:Nc, :3], U[:Nc, :3])
    assert np.array_equal(S[fixed], U[fixed])
    moved = np.abs(S[Nc:, :3] - U[Nc:, :3]).max(axis=1)
    assert moved[~fixed[Nc:, 0]].max() > 0.0
    assert _pi(model, loads, S) < _pi(model, loads, S_dir.reshape(U.shape))


def test_model_around_nodes_has_the_whole_force_and_tangent_on_their_dofs():
    """Model.around(nodes) keeps only the elements touching ``nodes``: its force on their dofs is
    the whole model's (the other elements do not depend on them), to round-off (1e-12 relative:
    the same element terms summed in another grouping), and its tangent block on them too."""
    model, fixed, loads, U = _case()
    nodes = np.array([3, 17, 30])
    sub = model.around(nodes)
    assert sum(len(b.conn) for b in sub.blocks) < sum(len(b.conn) for b in model.blocks)
    dofs = (6 * nodes[:, None] + np.arange(6)).ravel()
    F, Fs = model.internal_force(U).ravel(), sub.internal_force(U).ravel()
    assert np.allclose(Fs[dofs], F[dofs], rtol=0, atol=1e-12 * np.abs(F).max())
    K, Ks = model.tangent(U).toarray(), sub.tangent(U).toarray()
    assert np.allclose(Ks[np.ix_(dofs, dofs)], K[np.ix_(dofs, dofs)], rtol=0, atol=1e-12 * np.abs(K).max())


def test_settling_a_region_moves_only_its_directors_and_equals_the_held_minimisation():
    """DirectorSettler(region=...) settles the directors of the region's nodes with every other dof
    held, evaluating only the elements around them: every dof outside the region's directors stays
    bit for bit, the region's director residual (whole model) falls by the settler's rtol (1e-3),
    and the potential falls."""
    model, fixed, loads, U = _case()
    region = np.flatnonzero(model.mesh.nodes[:, 0] > 2.4)
    S, rep = DirectorSettler(model, loads, fixed, region=region)(U)
    S = S.reshape(U.shape)
    keep = np.ones(U.shape, dtype=bool)
    keep[region, 3:] = False
    assert np.array_equal(S[keep], U[keep])
    idx = director_dofs(fixed, region=region)
    r = np.linalg.norm((loads.ravel() - model.internal_force(S).ravel())[idx])
    assert rep.converged and r <= 1e-3 * rep.residual_before
    assert _pi(model, loads, S) < _pi(model, loads, U)


@pytest.mark.parametrize("weak_hash", [False, True])
def test_element_constants_cache_gives_the_same_model_bit_for_bit(weak_hash, monkeypatch):
    """The adaptive runs share one model.ElementConstants over their meshes: each element's folded
    constants are computed once and gathered afterwards.  Models of a sequence of adapted meshes
    (transition triangles, "ans" coarse quads, "full" finest ones; splits, then merges that bring
    back elements stored several meshes earlier) built with the cache equal the models built from
    scratch bit for bit -- the precompute functions treat every element apart, which a restart of
    an adaptive run (a fresh cache) relies on -- and a model of another section is refused.  With
    ``weak_hash`` the row hash is cut to 2 bits, so nearly every lookup meets a colliding element:
    the rows themselves decide a hit, and the result stays bit for bit."""
    import solidshell.model as model_mod
    from solidshell.adapt import AdaptiveMesh, BackgroundMesh
    from solidshell.meshing import build_mesh
    from solidshell.model import ElementConstants

    if weak_hash:
        strong = model_mod._row_hash
        monkeypatch.setattr(model_mod, "_row_hash", lambda rows: strong(rows) & np.uint64(3))
    bg = BackgroundMesh.from_level0(build_mesh("square", "3x3", size=6.0), 2)
    forest = AdaptiveMesh(bg)
    cache = ElementConstants()
    wool = Fabric.wool()
    rng = np.random.default_rng(2)
    for it in range(7):
        if it < 4:
            leaves = forest.leaves()
            pick = leaves[(leaves[:, 0] < bg.levels) & (rng.random(len(leaves)) < 0.4)]
            if len(pick):
                forest.split(pick)
        else:
            for l in range(bg.levels):
                m = forest.mergeable(l)
                m = m[rng.random(m.size) < 0.5]
                forest.merge(np.column_stack([np.full(m.size, l), m]))
        act = forest.active_mesh()
        nq = len(act.mesh.quads)
        membrane = np.where(act.elem_leaf[:nq, 0] < bg.levels, "ans", "full").tolist()
        a = Model(act.mesh, wool, membrane=membrane, constants=cache)
        b = Model(act.mesh, wool, membrane=membrane)
        assert len(a.blocks) == len(b.blocks)
        for ba, bb in zip(a.blocks, b.blocks):
            assert ba.c.keys() == bb.c.keys()
            assert all(np.array_equal(ba.c[k], bb.c[k]) for k in bb.c)
        if it == 3:
            assert len(act.mesh.tris) > 0
    with pytest.raises(ValueError, match="one section"):
        Model(act.mesh, Fabric.wool(warp_angle=30.0), constants=cache)
