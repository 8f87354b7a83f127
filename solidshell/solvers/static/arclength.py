"""Crisfield's cylindrical arc-length method (``method="arclength"``).

The load factor is an extra unknown with the quadratic constraint |Delta D| = Delta l; the root is
chosen by the smallest angle with the previous increment, and the predictor's sign from the
previous increment, sign(Delta D_prev . K^-1 P).  It follows the equilibrium path through limit
points; the last step lands exactly on the requested final load factor by a load-controlled Newton
correction (newton.newton_level).  No bifurcation handling: where a second eigenvalue crosses zero
the path may turn onto another branch (``max_negative_eigenvalues_on_path`` > 1 in info flags
this).  Dead loads only.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import InputError
from .newton import newton_level

__all__ = ["arc_length"]

DESIRED_ITERATIONS = 6
"""Corrector iterations per arc-length step aimed at: the next arc length is scaled by
sqrt(DESIRED_ITERATIONS / iterations taken), within [0.5, 2]."""


def arc_length(sys, D, lam_target, o, s, stats, progress, path):
    """The path from D (at ``stats["load_factor"]``) to load factor ``lam_target``, with the level
    options ``o`` and the settings ``s`` (arc_length_initial: the first step as a fraction of the
    target; max_arc_step: the largest arc length, as a fraction of the linear path length to the
    target |lam_target| |K_0^-1 P|, so a load-deflection curve can be drawn as finely as wanted;
    max_arc_steps).  Every converged point is appended to ``path``.  Returns (D, ok, message, rel)."""
    f = sys.free
    Pf = sys.P[f]
    if not np.any(Pf):
        raise InputError("arc-length needs a non-zero load on the free dofs")
    if sys.presc_fn is not None or np.any(sys.presc):
        raise InputError("arc-length supports dead loads only (prescribed values must be zero)")
    lam = stats["load_factor"]
    dl, dl_cap = _first_arc(sys, D, lam_target, s)
    dl_min = dl * 1e-6
    prev = None
    rel = np.nan
    for step in range(s.max_arc_steps):
        _, A = sys.free_tangent(D)
        try:
            lu, neg = sys.ldl(A)
        except RuntimeError:
            return D, False, f"singular tangent at load factor {lam:.4g} (bifurcation point?)", rel
        if neg is not None:
            stats["max_negative_eigenvalues"] = max(stats.get("max_negative_eigenvalues", 0), neg)
        sys.n_solves += 1
        sys.n_factor += 1
        dt = lu.solve(Pf)
        sign = 1.0 if prev is None else (1.0 if np.dot(prev, dt) >= 0.0 else -1.0)
        dlam = sign * dl / float(np.linalg.norm(dt))
        ok, Dt, dD, dlam, it, rel = _corrector(sys, D, lam, dlam * dt, dlam, dl, o, stats)
        if not ok:
            dl *= 0.5
            if dl < dl_min:
                return D, False, f"arc-length step could not converge at load factor {lam:.4g}", rel
            continue
        stats["load_steps"] += 1
        lam_new = lam + dlam
        if (lam_new - lam_target) * (lam - lam_target) <= 0.0 and lam_new != lam:
            # crossed the target: interpolate and land on it by load control
            t = (lam_target - lam) / (lam_new - lam)
            Dg = D.copy()
            Dg[f] += t * dD
            Dn, okn, msg, rel = newton_level(sys, Dg, lam_target, o, stats)
            if not okn:
                return Dn, False, f"final correction to load factor {lam_target:.4g} failed: {msg}", rel
            path.append((lam_target, Dn.reshape(sys.n, 6).copy()))
            stats["load_factor"] = lam_target
            return Dn, True, f"arc-length reached load factor {lam_target:.4g} in {step + 1} steps", rel
        D = Dt
        lam = lam_new
        prev = dD.copy()
        stats["load_factor"] = lam
        path.append((lam, D.reshape(sys.n, 6).copy()))
        progress(min(1.0, max(0.0, lam / lam_target)), f"arc-length load factor {lam:.4g}")
        dl = min(dl * min(2.0, max(0.5, math.sqrt(DESIRED_ITERATIONS / max(it, 1)))), dl_cap)
    return D, False, f"arc-length stopped after {s.max_arc_steps} steps at load factor {lam:.4g}", rel


def _first_arc(sys, D, lam_target, s):
    """(first arc length, largest arc length) from the tangent at D: ``arc_length_initial`` of the
    target and ``max_arc_step`` of the linear path length |lam_target| |K_0^-1 P|."""
    _, A = sys.free_tangent(D)
    lu, _ = sys.ldl(A)
    sys.n_solves += 1
    sys.n_factor += 1
    dt = lu.solve(sys.P[sys.free])
    dl_ref = abs(lam_target) * float(np.linalg.norm(dt))
    dl_cap = np.inf if s.max_arc_step is None else float(s.max_arc_step) * dl_ref
    dlam0 = s.arc_length_initial * lam_target
    return min(abs(dlam0) * float(np.linalg.norm(dt)), dl_cap), dl_cap


def _corrector(sys, D, lam, dD, dlam, dl, o, stats):
    """Newton iterations on (D, lambda) from the predictor (dD, dlam) on the cylinder
    |Delta D| = dl, the root nearer the previous increment kept.  Returns (ok, D + dD, dD, dlam,
    iterations, rel)."""
    f = sys.free
    Pf = sys.P[f]
    ok = False
    for it in range(o.max_iter):
        Dt = D.copy()
        stats["D_last"] = D
        Dt[f] += dD
        lt = lam + dlam
        F, A = sys.free_tangent(Dt)
        R = F[f] - lt * Pf
        rel = float(np.linalg.norm(R)) / sys.reference_norm(F, lt)
        if not np.isfinite(rel):
            break
        if it > 0 and rel <= o.tol:
            ok = True
            break
        stats["iterations"] += 1
        try:
            lu, _ = sys.ldl(A)
        except RuntimeError:
            break
        sys.n_solves += 2
        sys.n_factor += 1
        dt = lu.solve(Pf)
        dr = -lu.solve(R)
        u = dD + dr
        a = float(np.dot(dt, dt))
        b = 2.0 * float(np.dot(dt, u))
        cc = float(np.dot(u, u)) - dl * dl
        disc = b * b - 4.0 * a * cc
        if disc < 0.0:
            break
        sq = math.sqrt(disc)
        roots = ((-b + sq) / (2 * a), (-b - sq) / (2 * a))
        cands = [u + r_ * dt for r_ in roots]
        k = int(np.argmax([np.dot(cd, dD) for cd in cands]))
        dD = cands[k]
        dlam += roots[k]
    return ok, Dt, dD, dlam, it, rel
