"""The paper's scheme (``method="paper"``): Section 3, Eqs. (16)-(18).

Full Newton-Raphson K_t dD = P - F with the multiplier lambda = c L_f / max|dD| (capped at 1) on
every update, D <- D + lambda dD.  ``c`` is the paper's 1e-3 ... 1e-2; L_f the free-hanging length
(default: the largest distance from a free node to the nearest fixed node, system.free_length).
No line search, no safeguard: the paper's scheme, kept as a reference (it needs at least
~ (max displacement)/(c L_f) iterations).  The solve uses Cholesky where K_t is positive definite
and LDL^T elsewhere (Eq. 17 also solves with indefinite tangents); a singular tangent stops it with
a message.  It goes straight to each requested load factor and can settle on a saddle
(docs/solvers.md, sections 2 and 4).
"""

from __future__ import annotations

import numpy as np

from ..linear import CHOLESKY_KINDS
from .system import converged, iteration_report

__all__ = ["paper_level"]


def paper_level(sys, D, lam, o, stats):
    """The paper's Eqs. (16)-(18) at load factor lam from D, with the options ``o``
    (settings.LevelOptions).  Returns (D, ok, message, rel)."""
    f = sys.free
    e_first = None
    e_ratio = np.inf
    rel = np.inf
    best = np.inf
    since_best = 0
    for it in range(o.max_iter + 1):
        F, A = sys.free_tangent(D)
        stats["D_last"] = D
        r = lam * sys.P[f] - F[f]
        rel = float(np.linalg.norm(r)) / sys.reference_norm(F, lam)
        if not np.isfinite(rel):
            return D, False, "non-finite residual (the lambda-scaled Newton iteration diverged)", rel
        iteration_report(stats, rel, o)
        if converged(rel, e_ratio if it else (0.0 if rel <= o.tol else np.inf), o):
            stats["criterion"] = "residual"
            return D, True, f"converged in {it} iterations", rel
        if it == o.max_iter:
            break
        if rel < 0.999 * best:
            best, since_best = rel, 0
        else:
            since_best += 1
        stats["iterations"] += 1
        try:
            # Cholesky where K_t is positive definite (most iterations), SuperLU LDL^T elsewhere
            if sys.factorization in CHOLESKY_KINDS and sys.chol.factor(A):
                dD = sys.chol.solve(r)
            else:
                dD = sys.ldl(A)[0].solve(r)
        except RuntimeError:
            return (
                D,
                False,
                (
                    f"singular tangent K_t at iteration {it} (relative residual {rel:.2e}); "
                    "the paper's scheme cannot proceed"
                ),
                rel,
            )
        sys.n_solves += 1
        sys.n_factor += 1
        if not np.all(np.isfinite(dD)):
            return D, False, f"singular tangent K_t at iteration {it} (non-finite increment)", rel
        m = sys.maxnorm(dD, free=True)
        mult = min(1.0, o.c * o.L_f / m) if m > 0 else 1.0
        stats["min_multiplier"] = min(stats["min_multiplier"], mult)
        D = D.copy()
        D[f] += mult * dD
        e_step = abs(mult * float(np.dot(dD, r)))
        e_first = e_step if e_first is None else e_first
        e_ratio = e_step / e_first if e_first > 0 else 0.0
    stall = f"; no progress in the last {since_best} iterations" if since_best > 50 else ""
    return D, False, (f"paper scheme stopped after {o.max_iter} iterations at relative residual {rel:.2e}{stall}"), rel
