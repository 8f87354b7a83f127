"""The static solvers' factorisations (solidshell/solvers/linear.py): the Cholesky of CHOLMOD and of
MKL PARDISO (solvers/pardiso.py; its tests skip, with the reason, where MKL is not installed) with
a reused symbolic analysis, and SuperLU's LDL^T-type inertia."""

import numpy as np
import pytest
import scipy.sparse as sp

from solidshell.errors import InputError
from solidshell.solvers import linear, pardiso
from solidshell.solvers.linear import Cholesky, ldl_inertia, positive_definite_factor

KINDS = [
    pytest.param("cholmod"),
    pytest.param(
        "pardiso", marks=pytest.mark.skipif(not pardiso.available(), reason=str(pardiso.unavailable_reason()))
    ),
]


def laplacian(n, shift=0.0):
    """1-D Dirichlet Laplacian (eigenvalues 2 - 2 cos(k pi / (n + 1)), all in (0, 4)) + shift I."""
    main = np.full(n, 2.0 + shift)
    off = -np.ones(n - 1)
    return sp.diags([off, main, off], [-1, 0, 1], format="csc")


@pytest.mark.parametrize("kind", KINDS)
def test_cholesky_solves_positive_definite_systems_and_reuses_the_analysis(kind):
    A = laplacian(200)
    b = np.random.default_rng(0).standard_normal(200)
    ch = positive_definite_factor(kind)
    assert ch.factor(A)
    # cond(A) ~ 4 (n+1)^2 / pi^2 ~ 1.6e4: a backward-stable solve leaves a residual ~1e-16 * cond
    assert np.linalg.norm(A @ ch.solve(b) - b) <= 1e-11 * np.linalg.norm(b)
    # same pattern, new values: no new symbolic analysis, new solution
    A2 = laplacian(200, shift=1.0)
    assert ch.factor(A2)
    assert ch.n_symbolic == 1
    assert np.linalg.norm(A2 @ ch.solve(b) - b) <= 1e-12 * np.linalg.norm(b)
    # a diagonal shift is applied to the factorised matrix, not to A
    assert ch.factor(A, np.full(200, 1.0))
    assert np.linalg.norm(A2 @ ch.solve(b) - b) <= 1e-12 * np.linalg.norm(b)
    assert np.linalg.norm(A @ ch.solve(b) - b) > 0.1 * np.linalg.norm(b)
    # a new pattern is analysed again
    assert ch.factor(laplacian(150))
    assert ch.n_symbolic == 2


@pytest.mark.parametrize("kind", KINDS)
def test_cholesky_reports_indefinite_and_singular_matrices(kind):
    n = 50
    ch = positive_definite_factor(kind)
    # smallest eigenvalue of the Laplacian is 2 - 2 cos(pi/51) = 3.8e-3: a shift of -0.01 makes
    # one eigenvalue negative, which the factorisation must refuse (no solve afterwards)
    assert not ch.factor(laplacian(n, shift=-0.01))
    with pytest.raises(RuntimeError, match="no positive-definite factorisation to solve with"):
        ch.solve(np.ones(n))
    # ... and a diagonal shift back to positive definite is accepted
    assert ch.factor(laplacian(n, shift=-0.01), np.full(n, 0.02))
    # singular: the Neumann Laplacian (constant null vector) fails or is caught by the pivot test
    N = laplacian(n).tolil()
    N[0, 0] = N[n - 1, n - 1] = 1.0
    assert not ch.factor(N.tocsc())


@pytest.mark.skipif(not pardiso.available(), reason=str(pardiso.unavailable_reason()))
def test_pardiso_and_cholmod_agree_on_a_drape_tangent_and_repeat_bit_for_bit():
    """The square-pedestal 12x4x4 tangent at a sagged state, indefinite (the sag compresses the
    membrane), and shifted by 0.1 of its diagonal as the energy Newton's first Levenberg steps
    factorise it: both factorisations agree on definiteness, their solutions agree to cond * 1e-16,
    and PARDISO, sequential, gives the same bits on a repeated factorisation."""
    from solidshell.scenes import load
    from solidshell.scenes.build import build_problem, build_scene_mesh
    from solidshell.solvers.static.system import System

    sc = load("square-pedestal")
    mesh = build_scene_mesh(sc, "12x4x4")[0]
    pb = build_problem(sc, mesh)
    sys_ = System(pb.model, pb.fixed, pb.loads, pb.prescribed, pb.contact, None, "pardiso")
    U = np.zeros((mesh.n_nodes, 6))
    U[:, 2] = -0.05 * np.hypot(mesh.nodes[:, 0], mesh.nodes[:, 1])  # a sag, 0.7 cm at the corners
    _, A = sys_.free_tangent(U.ravel())
    P, C = positive_definite_factor("pardiso"), Cholesky()
    assert not P.factor(A) and not C.factor(A)
    shift = 0.1 * np.abs(A.diagonal())
    b = np.random.default_rng(3).standard_normal(A.shape[0])
    assert P.factor(A, shift) and C.factor(A, shift)
    x = P.solve(b)
    dense = A.toarray() + np.diag(shift)
    cond = np.linalg.cond(dense)
    # both backward stable: their difference is bounded by ~cond * eps relative to |x|
    assert np.abs(x - C.solve(b)).max() <= 100 * cond * 2.2e-16 * np.abs(x).max()
    assert np.linalg.norm(dense @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert P.factor(A, shift) and np.array_equal(P.solve(b), x)


_THREADED_CHILD = """
import numpy as np, numba
from solidshell.scenes.build import build_problem, build_scene_mesh
from solidshell.scenes import load
from solidshell.solvers import pardiso
from solidshell.solvers.static.system import System

sc = load("square-pedestal")
mesh = build_scene_mesh(sc, "12x4x4")[0]
pb = build_problem(sc, mesh)
sys_ = System(pb.model, pb.fixed, pb.loads, pb.prescribed, pb.contact, None, "pardiso")
U = np.zeros((mesh.n_nodes, 6))
U[:, 2] = -0.05 * np.hypot(mesh.nodes[:, 0], mesh.nodes[:, 1])
_, A = sys_.free_tangent(U.ravel())
shift = 0.1 * np.abs(A.diagonal())
b = np.random.default_rng(3).standard_normal(A.shape[0])
seq = pardiso.Pardiso()
assert seq.factor(A, shift) and seq._threads == 1
x_seq = seq.solve(b)
pardiso.THREADED_MFLOP = 0          # this small tangent takes the threaded path
xs, ys, negs = [], [], []
for n in (1, 2):
    numba.set_num_threads(n)
    P = pardiso.Pardiso()
    assert P.factor(A, shift) and P._threads == n
    ldl = pardiso.PardisoLDL().ldl(A)   # the unshifted tangent is indefinite
    numba.set_num_threads(3 - n)    # the other count between the factor and the solve
    xs.append(P.solve(b))
    ys.append(ldl[0].solve(b))
    negs.append(ldl[1])
dense = A.toarray() + np.diag(shift)
err = np.abs(xs[0] - x_seq).max() / (np.linalg.cond(dense) * 2.2e-16 * np.abs(x_seq).max())
n_neg = int(np.count_nonzero(np.linalg.eigvalsh(A.toarray()) < 0))
print(int(np.array_equal(xs[0], xs[1]) and np.array_equal(ys[0], ys[1])), int(negs == [n_neg, n_neg]), err)
"""


@pytest.mark.skipif(not pardiso.available(), reason=str(pardiso.unavailable_reason()))
def test_threaded_pardiso_is_the_same_bits_on_one_and_two_threads():
    """A factorisation of at least pardiso.THREADED_MFLOP runs on numba's threads in MKL's
    reproducible mode: on one thread and on two the Cholesky and the LDL^T solutions are the same
    bits (the static solver's path must not depend on the thread count), the LDL^T's inertia is the
    dense eigenvalue count, and a solve after numba's thread count changed keeps the handle's own
    (MKL crashed solving on one thread with a factor made on two).  The Cholesky solution agrees
    with the one-thread factor of smaller systems to 100 cond eps (both backward stable).  In a child
    process, so that a crash fails this test rather than ending the test run."""
    import subprocess
    import sys

    import numba

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs two numba threads (NUMBA_NUM_THREADS >= 2)")
    p = subprocess.run([sys.executable, "-c", _THREADED_CHILD], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    same, inertia, err = p.stdout.split()
    assert same == "1" and inertia == "1"
    assert float(err) <= 100.0


def test_mkl_threading_layer_is_gnu_openmp_only_where_it_is_installed(tmp_path):
    """MKL ends the process when told to use a threading layer it cannot load, so the GNU OpenMP
    layer is chosen only where its library sits beside libmkl_rt (and libgomp loads); else MKL
    runs sequentially."""
    import ctypes

    rt = tmp_path / "libmkl_rt.so.2"
    rt.touch()
    assert not pardiso._has_gnu_layer(str(rt))
    (tmp_path / "libmkl_gnu_thread.so.2").touch()
    try:
        ctypes.CDLL("libgomp.so.1")
        gomp = True
    except OSError:
        gomp = False
    assert pardiso._has_gnu_layer(str(rt)) == gomp


def test_factorization_names_resolve_and_a_missing_mkl_is_one_input_error_line(monkeypatch):
    assert linear.resolve_factorization("cholmod") == "cholmod"
    assert linear.resolve_factorization("auto") == ("pardiso" if pardiso.available() else "cholmod")
    big, small = linear.PARDISO_MIN_DOFS, linear.PARDISO_MIN_DOFS - 1
    assert linear.resolve_factorization("auto", big) == linear.resolve_factorization("auto")
    assert linear.resolve_factorization("auto", small) == "cholmod"  # MKL not loaded for it
    assert linear.resolve_factorization("cholmod", big) == "cholmod"
    with pytest.raises(InputError, match="factorization must be one of"):
        linear.resolve_factorization("mumps")
    monkeypatch.setattr(pardiso, "_LIB", None)
    monkeypatch.setattr(pardiso, "_REASON", "Intel MKL (libmkl_rt) not found: install it")
    assert linear.resolve_factorization("auto") == "cholmod"
    with pytest.raises(InputError, match=r"factorization 'pardiso': Intel MKL \(libmkl_rt\) not found") as e:
        linear.resolve_factorization("pardiso")
    assert "\n" not in str(e.value) and "MKL" in str(e.value)


@pytest.mark.skipif(not pardiso.available(), reason=str(pardiso.unavailable_reason()))
@pytest.mark.parametrize("shift", [0.3, -0.05, -0.9, -2.5])
def test_pardiso_ldl_inertia_equals_the_eigenvalue_count_and_solves(shift):
    # a 2-D grid Laplacian (5-point, 12x12) + a random symmetric perturbation, shifted: the number
    # of negative eigenvalues (dense eigvalsh, exact up to eigenvalues within ~1e-13 of 0, none
    # here: asserted) is what PARDISO's LDL^T must report, as SuperLU's does
    from solidshell.solvers.pardiso import PardisoLDL

    m = 12
    T = laplacian(m)
    A = (sp.kron(sp.eye(m), T) + sp.kron(T, sp.eye(m))).tocsc()
    R = sp.random(m * m, m * m, density=0.02, random_state=4, format="csc")
    A = (A + 0.1 * (R + R.T) + shift * sp.eye(m * m)).tocsc()
    ev = np.linalg.eigvalsh(A.toarray())
    assert np.abs(ev).min() > 1e-6
    lu, neg = PardisoLDL().ldl(A)
    assert neg == int(np.sum(ev < 0)) == ldl_inertia(A)[1]
    b = np.random.default_rng(5).standard_normal(m * m)
    # cond(A) = max|ev| / min|ev|: a backward-stable solve's residual is ~1e-16 * cond
    cond = np.abs(ev).max() / np.abs(ev).min()
    assert np.linalg.norm(A @ lu.solve(b) - b) <= 100 * 2.2e-16 * cond * np.linalg.norm(b)


@pytest.mark.skipif(not pardiso.available(), reason=str(pardiso.unavailable_reason()))
def test_pardiso_ldl_leaves_a_singular_matrix_to_superlu():
    # the Neumann Laplacian is singular: PARDISO perturbs a pivot and returns None (its inertia and
    # solve are not exact), and the static solver's ldl then asks SuperLU, which raises
    from solidshell.solvers.pardiso import PardisoLDL

    n = 50
    N = laplacian(n).tolil()
    N[0, 0] = N[n - 1, n - 1] = 1.0
    assert PardisoLDL().ldl(N.tocsc()) is None
    with pytest.raises(RuntimeError, match="Factor is exactly singular"):  # SuperLU's message
        ldl_inertia(N.tocsc())


@pytest.mark.skipif(not pardiso.available(), reason=str(pardiso.unavailable_reason()))
def test_the_static_systems_ldl_is_pardisos_on_a_pardiso_solve():
    """static.system.System.ldl -- the LDL^T of the paper's scheme and of the arc-length method on
    indefinite tangents -- is PARDISO's where the solve's factorisation is: on the sagged,
    indefinite square-pedestal 12x4x4 tangent its negative-pivot count is SuperLU's (Sylvester: both
    count the negative eigenvalues) and it solves to the backward-stable bound."""
    from solidshell.scenes import load
    from solidshell.scenes.build import build_problem, build_scene_mesh
    from solidshell.solvers.pardiso import PardisoLDL
    from solidshell.solvers.static.system import System

    sc = load("square-pedestal")
    mesh = build_scene_mesh(sc, "12x4x4")[0]
    pb = build_problem(sc, mesh)
    sys_ = System(pb.model, pb.fixed, pb.loads, pb.prescribed, pb.contact, None, "pardiso")
    U = np.zeros((mesh.n_nodes, 6))
    U[:, 2] = -0.05 * np.hypot(mesh.nodes[:, 0], mesh.nodes[:, 1])
    _, A = sys_.free_tangent(U.ravel())
    lu, neg = sys_.ldl(A)
    assert isinstance(sys_._ldl, PardisoLDL)
    assert neg == ldl_inertia(linear.as_csc(A))[1] and neg > 0
    b = np.random.default_rng(4).standard_normal(A.shape[0])
    dense = A.toarray()
    # a backward-stable solve: residual ~ eps * cond(A) |b|, with a factor 100 for the pivoting
    cond = np.linalg.cond(dense)
    assert np.linalg.norm(dense @ lu.solve(b) - b) <= 100 * 2.2e-16 * cond * np.linalg.norm(b)


def test_ldl_inertia_counts_negative_eigenvalues():
    # Sylvester: the number of negative pivots of a symmetric LDL^T equals the number of negative
    # eigenvalues; Laplacian - 0.05 I has exactly the eigenvalues 2 - 2 cos(k pi / 51) < 0.05,
    # i.e. k pi / 51 < arccos(0.975), k = 1..3
    A = laplacian(50, shift=-0.05)
    ev = np.linalg.eigvalsh(A.toarray())
    _, neg = ldl_inertia(A)
    assert neg == int(np.sum(ev < 0)) == 3


def test_lower_csc_product_equals_the_full_symmetric_product():
    from solidshell.solvers.linear import LowerCSC

    rng = np.random.default_rng(1)
    R = sp.random(60, 60, density=0.1, random_state=2, format="csc")
    A = (R + R.T + sp.eye(60) * 5.0).tocsc()
    L = LowerCSC.from_symmetric(A)
    x = rng.standard_normal(60)
    # the same sums in another order: round-off of the entries' size times the row length
    assert np.abs(L.matvec()(x) - A @ x).max() <= 1e-13 * abs(A).max() * np.abs(x).sum()


@pytest.mark.parametrize("kind", KINDS)
def test_pcg_with_a_nearby_factor_converges_and_stops_on_negative_curvature(kind):
    from solidshell.solvers.linear import pcg

    A = laplacian(200)
    b = np.random.default_rng(0).standard_normal(200)
    ch = positive_definite_factor(kind)
    assert ch.factor(A)
    # the exact factor: one iteration, to round-off (cond ~1.6e4 times 1e-16)
    x, k, ok, xAx = pcg(lambda v: A @ v, b, ch.solve, 1e-10, 5)
    assert ok and k == 1 and np.linalg.norm(A @ x - b) <= 1e-10 * np.linalg.norm(b)
    # A + 0.01 I preconditioned by A's factor: the spectrum of A^-1 (A + 0.01 I) is 1 + 0.01 / lambda(A),
    # in [1.0025, 42] (lambda_min(A) = 2 - 2 cos(pi/201) = 2.4e-4), so CG's bound
    # sqrt(42)/2 ln(2/1e-6) = 47 iterations reaches 1e-6 within the 60 allowed; x.A.x is the
    # curvature of the returned x
    A2 = laplacian(200, shift=0.01)
    x, k, ok, xAx = pcg(lambda v: A2 @ v, b, ch.solve, 1e-6, 60)
    assert ok and np.linalg.norm(A2 @ x - b) <= 1e-6 * np.linalg.norm(b)
    assert xAx == pytest.approx(x @ (A2 @ x), rel=1e-10)
    # a too small iteration budget: not converged, never claimed
    x, k, ok, _ = pcg(lambda v: A2 @ v, b, ch.solve, 1e-12, 2)
    assert not ok and k == 2
    # an indefinite matrix: CG meets non-positive curvature and stops, not converged
    A3 = laplacian(200, shift=-1.0)
    _, _, ok, _ = pcg(lambda v: A3 @ v, b, ch.solve, 1e-8, 200)
    assert not ok
