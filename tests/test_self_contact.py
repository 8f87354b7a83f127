"""Self-contact of the sheet in the static solver (solidshell/contact_self.py, issue 37): the
barrier's energy, gradient and consistent tangent, the layers it keeps apart, the steps continuous
collision detection cuts, and a deep static drape that passed through itself and no longer does --
counted by verification/self_check.py's own geometry, not the code under test."""

import numpy as np
import pytest
import scipy.sparse as sp

from solidshell import contact_self, layers, run_scene
from solidshell.contact_self import CCD_SAFETY, SelfContact
from solidshell.errors import InputError
from solidshell.mesh import ShellMesh
from solidshell.meshing import build_mesh
from verification import self_check

H = 0.06


def _two_sheets(n=8, size=4.0):
    m = build_mesh("square", f"{n}x{n}", size=size)
    X = np.vstack([m.nodes, m.nodes + (0.0, 0.0, 10.0)])
    return ShellMesh(X, quads=np.vstack([m.quads, m.quads + m.n_nodes])), m.n_nodes


def _lowered(mesh, n, d):
    """The upper sheet lowered to about d above the lower one, shifted sideways and waved a little."""
    U = np.zeros((mesh.n_nodes, 6))
    X = mesh.nodes
    U[n:, 2] = -10.0 + d + 0.001 * np.sin(3.0 * X[n:, 0])
    U[n:, :2] = (0.13, 0.07)
    return U.ravel()


def test_the_barrier_acts_inside_the_band_only_and_its_tangent_is_consistent():
    """Zero energy beyond h, infinite at d_min = 0.9 h, positive between; gradient = central
    differences of the energy (1e-6 relative: FD error of a smooth function at eps 1e-7); tangent =
    differences of the gradient (1e-5 relative) and symmetric to round-off; the force at the middle
    of the band is the load scale w given (the kappa rule, 1e-9 relative)."""
    mesh, n = _two_sheets()
    w = 2.5e-3
    s = SelfContact(mesh, H, w)
    assert s.energy_gradient(_lowered(mesh, n, 1.05 * H))[0] == 0.0
    assert s.energy_gradient(_lowered(mesh, n, 0.85 * H))[0] == np.inf
    D = _lowered(mesh, n, 0.95 * H)
    e, g, ent = s.energy_gradient(D, want_tangent=True)
    assert 0.0 < e < np.inf
    rng = np.random.default_rng(1)
    v = np.zeros_like(D)
    v.reshape(-1, 6)[:, :3] = rng.standard_normal((mesh.n_nodes, 3))
    eps = 1e-7
    fd = (s.energy_gradient(D + eps * v)[0] - s.energy_gradient(D - eps * v)[0]) / (2 * eps)
    assert fd == pytest.approx(g @ v, rel=1e-6)
    r, c, vals = (np.concatenate(a) for a in ent)
    K = sp.coo_matrix((vals, (r, c)), shape=(D.size, D.size)).tocsr()
    dg = (s.energy_gradient(D + eps * v)[1] - s.energy_gradient(D - eps * v)[1]) / (2 * eps)
    assert np.abs(dg - K @ v).max() < 1e-5 * np.abs(K @ v).max()
    assert abs(K - K.T).max() <= 1e-14 * abs(K).max()
    # a small triangle parallel to a large one, over its middle: each corner feels the force w
    one = ShellMesh(
        np.array([[0, 0, 0], [9, 0, 0], [0, 9, 0], [2, 2, 5.0], [2.5, 2, 5.0], [2, 2.5, 5.0]]),
        tris=np.array([[0, 1, 2], [3, 4, 5]]),
    )  # fmt: skip
    s1 = SelfContact(one, H, w)
    U = np.zeros((6, 6))
    U[3:, 2] = -5.0 + s1.d_min + 0.5 * s1.s_hat
    g1 = s1.energy_gradient(U.ravel())[1].reshape(6, 6)
    np.testing.assert_allclose(-g1[3:, 2], w, rtol=1e-9)


def test_a_step_through_another_layer_is_cut_short_of_the_minimum_distance():
    """The upper sheet moved from 0.95 h above the lower to 1.55 h below it: both ends lie outside
    the band (zero barrier energy: a barrier alone would let the step through), CCD allows a
    fraction of it, and the cut step (CCD_SAFETY of it) ends above d_min with no intersection; a
    step away is free (1.0)."""
    mesh, n = _two_sheets()
    s = SelfContact(mesh, H, 1e-3)
    D0 = _lowered(mesh, n, 0.95 * H)
    D1 = D0.copy()
    D1.reshape(-1, 6)[n:, 2] -= 2.5 * H
    assert s.energy_gradient(D1)[0] == 0.0
    t = s.free_fraction(D0, D1)
    assert 0.0 < t < (0.95 - 0.9) / 2.5 + 1e-9  # it stops before d_min (additive CCD: conservative)
    c = s.cut(D0, D1)
    assert c == pytest.approx(CCD_SAFETY * t)
    Dc = D0 + c * (D1 - D0)
    assert np.isfinite(s.energy_gradient(Dc)[0])
    assert layers.report(mesh, Dc.reshape(-1, 6), H)["self_intersections"] == 0
    D2 = D0.copy()
    D2.reshape(-1, 6)[n:, 2] += H
    assert s.cut(D0, D2) == 1.0


def test_a_mesh_finer_than_the_thickness_is_refused():
    """Elements much smaller than h put non-adjacent triangles of the flat sheet inside the band:
    one line, InputError."""
    with pytest.raises(InputError, match="closer than the thickness"):
        SelfContact(build_mesh("square", "40x40", size=1.0), H, 1e-3)


def test_the_deep_static_drape_no_longer_passes_through_itself(tmp_path):
    """square-on-disc 10x80 static (issue 37's example): without self-contact 24 triangle pairs
    intersect (counted by verification/self_check.py); with solver.static.self_contact none does,
    every pair of layers stays at least 0.9 h apart (the barrier's minimum distance), the state is
    a stable minimum, and the drape keeps its 4 folds (DC within 1 % of the crossing drape's)."""
    runs = {}
    for on in (False, True):
        out = run_scene(
            "square-on-disc", mesh="10x80", out_dir=tmp_path / str(on), progress=False,
            overrides={"self_contact.enabled": on, "output.pictures": [], "output.snapshots": []},
        )  # fmt: skip
        runs[on] = out.summary, self_check.check_run(tmp_path / str(on))
    (off, (_, off_clean)), (s, (line, clean)) = runs[False], runs[True]
    assert off["self_intersections"] > 0 and not off_clean
    assert clean and s["self_intersections"] == 0, line
    h = s["material"]["thickness"]
    assert s["min_layer_gap"] is None or s["min_layer_gap"] >= (1.0 - layers.LAYER_TOL) * h * (1 - 1e-9)
    assert s["converged"] and s["positive_definite"]
    assert s["fold_count"] == off["fold_count"] == 4
    assert s["drape_coefficient"] == pytest.approx(off["drape_coefficient"], rel=0.01)


def _solve(scene, mesh, skip, tmp_path, monkeypatch, **overrides):
    monkeypatch.setattr(contact_self, "SKIP", skip)
    ov = {"self_contact.enabled": True, "output.pictures": [], "output.snapshots": [], **overrides}
    out = run_scene(
        scene, mesh=mesh, solver="static", out_dir=tmp_path / f"{scene}-{skip}", progress=False, overrides=ov
    )
    return out.summary, out.U


_COUNTS = ("iterations", "factorizations", "energy_evaluations", "self_contact_evaluations", "self_contact_ccd_cuts")


@pytest.mark.parametrize(
    ("scene", "mesh", "close"), [("square-on-disc", "10x80", True), ("square-pedestal", "12x4x4", False)]
)
def test_skipping_the_broad_phase_and_ccd_changes_no_iterate(scene, mesh, close, tmp_path, monkeypatch):
    """The skip tests of contact_self.py (issue 41) answer exactly what the library would (each
    skipped call returns the library's own exact zero or 1.0): the whole static solve takes the
    same path with and without them -- every count equal (iterations, factorisations, energy and
    barrier evaluations, CCD cuts) and the final U equal bit for bit (the barrier's set and sums
    are taken on one ipctk thread, contact_self._serial: on its pool their order varied, and two
    runs of the same code without the skips took 267 and 265 iterations on 10x80) -- on square-on-disc 10x80,
    whose layers come within the barrier's reach (CCD cuts steps), and on square-pedestal 12x4x4,
    whose layers never come near; on both the skips spare CCDs, and broad phases where no layers meet."""
    ref, U_ref = _solve(scene, mesh, False, tmp_path, monkeypatch)
    new, U_new = _solve(scene, mesh, True, tmp_path, monkeypatch)
    for k in _COUNTS:
        assert new[k] == ref[k], k
    assert np.array_equal(U_new, U_ref)
    assert new["self_contact_ccd_runs"] < ref["self_contact_ccd_runs"]
    if not close:  # where layers come near, a reference search precedes the barrier's own build:
        # broad phases may then rise a little (10x80 on a clean clone: 321 against 317)
        assert new["self_contact_builds"] < ref["self_contact_builds"]
    if close:
        assert ref["self_contact_ccd_cuts"] > 0  # the layers did come near
    else:
        assert ref["self_contact_ccd_cuts"] == 0 and ref["min_layer_gap"] is None
