"""The static solvers' factorisations (solidshell/solvers/linear.py): CHOLMOD Cholesky with a reused
symbolic analysis, and SuperLU's LDL^T-type inertia."""

import numpy as np
import pytest
import scipy.sparse as sp

from solidshell.solvers.linear import Cholesky, ldl_inertia


def laplacian(n, shift=0.0):
    """1-D Dirichlet Laplacian (eigenvalues 2 - 2 cos(k pi / (n + 1)), all in (0, 4)) + shift I."""
    main = np.full(n, 2.0 + shift)
    off = -np.ones(n - 1)
    return sp.diags([off, main, off], [-1, 0, 1], format="csc")


def test_cholesky_solves_positive_definite_systems_and_reuses_the_analysis():
    A = laplacian(200)
    b = np.random.default_rng(0).standard_normal(200)
    ch = Cholesky()
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


def test_cholesky_reports_indefinite_and_singular_matrices():
    n = 50
    ch = Cholesky()
    # smallest eigenvalue of the Laplacian is 2 - 2 cos(pi/51) = 3.8e-3: a shift of -0.01 makes
    # one eigenvalue negative, which the factorisation must refuse (no solve afterwards)
    assert not ch.factor(laplacian(n, shift=-0.01))
    with pytest.raises(RuntimeError):
        ch.solve(np.ones(n))
    # ... and a diagonal shift back to positive definite is accepted
    assert ch.factor(laplacian(n, shift=-0.01), np.full(n, 0.02))
    # singular: the Neumann Laplacian (constant null vector) fails or is caught by the pivot test
    N = laplacian(n).tolil()
    N[0, 0] = N[n - 1, n - 1] = 1.0
    assert not ch.factor(N.tocsc())


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


def test_pcg_with_a_nearby_factor_converges_and_stops_on_negative_curvature():
    from solidshell.solvers.linear import pcg

    A = laplacian(200)
    b = np.random.default_rng(0).standard_normal(200)
    ch = Cholesky()
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
