"""Small pieces the verification problems share: structured meshes, the small-deflection solve,
linearised buckling and the observed order of convergence."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as spla


def rect_grid(nx: int, ny: int, lx: float, ly: float, x0: float = 0.0, y0: float = 0.0):
    """(nodes (N,3), quads (nx*ny,4)) of a structured grid on [x0,x0+lx] x [y0,y0+ly], counter-
    clockwise quads; node (i, j) has index j*(nx+1) + i."""
    x = x0 + np.linspace(0.0, lx, nx + 1)
    y = y0 + np.linspace(0.0, ly, ny + 1)
    X, Y = np.meshgrid(x, y)  # (ny+1, nx+1)
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    n0 = (j * (nx + 1) + i).ravel()
    quads = np.column_stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1])
    return nodes, quads


def split_quads(quads: np.ndarray, pattern: str = "/") -> np.ndarray:
    """Triangles from counter-clockwise quads (1,2,3,4): "/" cuts along 1-3, "\\" along 2-4,
    "x" alternates the two in a checkerboard (needs the structured numbering only for looks)."""
    q = np.asarray(quads)
    t13 = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    t24 = np.concatenate([q[:, [0, 1, 3]], q[:, [1, 2, 3]]])
    if pattern == "/":
        return t13
    if pattern == "\\":
        return t24
    if pattern == "x":
        alt = (np.arange(len(q)) % 2).astype(bool)
        return np.concatenate(
            [q[~alt][:, [0, 1, 2]], q[~alt][:, [0, 2, 3]], q[alt][:, [0, 1, 3]], q[alt][:, [1, 2, 3]]]
        )
    raise ValueError(f"unknown split pattern {pattern!r}")


def linear_solve(model, fixed: np.ndarray, loads: np.ndarray, prescribed: np.ndarray | None = None):
    """Small-deflection solution: K(0) u = f on the free dofs, with u = prescribed on the fixed
    ones.  Returns U (N,6) and the reactions R (N,6) = K u - f (zero on free dofs up to round-off)."""
    N = model.n_nodes
    K = model.tangent(np.zeros((N, 6))).tocsr()
    fixed = np.asarray(fixed, dtype=bool).ravel()
    f = np.asarray(loads, dtype=float).ravel()
    u = np.zeros(6 * N) if prescribed is None else np.asarray(prescribed, dtype=float).ravel().copy()
    u[~fixed] = 0.0
    free = np.flatnonzero(~fixed)
    rhs = f[free] - K[free][:, fixed] @ u[fixed] if fixed.any() else f[free]
    Kff = K[free][:, free].tocsc()
    u[free] = spla.spsolve(Kff, rhs)
    R = K @ u - f
    return u.reshape(N, 6), R.reshape(N, 6)


def rate(e_coarse: float, e_fine: float, ratio: float = 2.0):
    """Observed order log(|e_coarse/e_fine|)/log(ratio) (None if either is zero)."""
    if e_coarse == 0 or e_fine == 0:
        return None
    return float(np.log(abs(e_coarse / e_fine)) / np.log(ratio))


def buckling_factors(model, fixed: np.ndarray, loads: np.ndarray, k: int = 3, eps: float = 1e-6):
    """Linearised buckling: the smallest load factors lambda with (K_0 + lambda K_G) phi = 0, where the
    pre-buckling state is the linear solution u_1 under ``loads`` and the load-stiffness
    K_G = (K_t(eps u_1) - K_t(-eps u_1)) / (2 eps) is taken from the element's own tangent (so this
    checks the geometric -- Green-strain -- part of Eq. (9)).  The initial-displacement terms that
    the difference quotient also contains are O(h^2/L^2) relative for thin plates.
    Solved densely as -K_G phi = mu K_0 phi on the free dofs, lambda = 1/mu for the largest mu > 0.
    Returns (lambdas (k,), modes (N,6,k))."""
    import scipy.linalg as sla

    U1, _ = linear_solve(model, fixed, loads)
    K0 = model.tangent(np.zeros_like(U1)).toarray()
    KG = (model.tangent(eps * U1).toarray() - model.tangent(-eps * U1).toarray()) / (2.0 * eps)
    free = np.flatnonzero(~np.asarray(fixed, dtype=bool).ravel())
    A = -KG[np.ix_(free, free)]
    A = 0.5 * (A + A.T)
    B = K0[np.ix_(free, free)]
    mu, vec = sla.eigh(A, 0.5 * (B + B.T))
    order = np.argsort(mu)[::-1][:k]
    lam = 1.0 / mu[order]
    modes = np.zeros((6 * model.n_nodes, k))
    modes[free] = vec[:, order]
    return lam, modes.reshape(model.n_nodes, 6, k)
