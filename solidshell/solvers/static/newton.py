"""The energy-minimising Newton (``method="newton"``, the default) at one load level.

Newton on the potential Pi, globalised by a trust region on the step (``line_search="trust"``,
``_trust_step``: the Newton step is cut to a max-norm radius that starts at ``trust_radius`` L_f and
grows/shrinks with the ratio of actual to predicted decrease of Pi), a backtracking Armijo line
search (``"armijo"``, ``_armijo_step``) or none (``"none"``, ``_full_step``: the step capped at
``max_step``), and a tangent shift K_t + sigma diag|K_t| whenever K_t is not positive definite
(``_factorise``: detected by its Cholesky factorisation failing -- MKL PARDISO or CHOLMOD,
solvers/linear.py; or, with ``factorization="superlu"``, by the inertia of SuperLU's LDL^T,
Sylvester's law; sigma grows tenfold from 1e-8 until the factorisation succeeds and starts from a
tenth of it on the next iteration).  A full shifted step whose actual decrease of Pi is at least
``EXTEND_RHO`` times the predicted one -- Pi nearly linear along it, its length set by the shift --
is doubled while Pi falls, within the trust radius (``info["extended_steps"]``).  Every step is
therefore a descent step of Pi and the iteration cannot settle on a saddle or a maximum (the
paper's scheme can).  Every iteration factorises its own tangent: reusing a factorisation while
the trust region cuts the step cost more than it saved on the strip, the tangent changing too fast
with the rotating geometry (docs/solvers.md, section 2).

Why it still takes tens to a hundred iterations on a drape: with translations as the only unknowns
a straight Newton step cannot rotate a material line without stretching it, and the membrane
rigidity of a fabric is 1e5-1e6 times its bending rigidity over L^2, so the quadratic convergence
radius of Newton is tiny and the global phase is governed by the step control (the curvilinear
``curvilinear=True`` option, a second-order "geodesic acceleration" correction of the step, did not
help on the strip and is off by default).  On the fine mesh of a mesh sequence (>= PCG_MIN_DOFS
free dofs, ``pcg_iterations``) a Newton step is first sought by conjugate gradients on the new
tangent, preconditioned by the last factorisation (``_cg_step``).  What was tried and dropped, and
the iteration counts of every method: docs/solvers.md, sections 2 and 10.

Besides the tolerances of ``system.converged``, Newton stops (``info["criterion"]``) when
- "displacement": the Newton correction of a positive-definite, unshifted K_t is below ``disp_tol``
  of max|D| -- to first order it *is* the error of D, so this test is free of any force or length
  scale;
- "round-off": neither the potential nor the residual can be lowered any more because the predicted
  decrease is below the round-off of Pi (``system.ROUNDOFF`` of |Pi| + |lam P.D|), K_t is positive
  definite and the Newton correction is below 1e-6 of max|D|.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..linear import CHOLESKY_KINDS, pcg
from .system import ROUNDOFF, converged, energy_scale, iteration_report, shifted_factor

__all__ = ["EXTEND_RHO", "PCG_BELOW", "PCG_FORCING", "PCG_MIN_DOFS", "newton_level"]

EXTEND_RHO = 1.8
"""A full step of a *shifted* tangent whose actual decrease of Pi is at least this multiple of the
predicted one is doubled while Pi falls, within the trust radius (``_extend``).  The model
decrease of a step p = -(K + sigma S)^-1 g is g.p/2; rho -> 2 means Pi is nearly linear along p, whose
length the shift, not the curvature, has set (circle-pedestal, square-on-disc: runs of 10-20 such
steps of alpha 1 and rho 1.9-2.1 at an unchanging sigma 1e-3; docs/solvers.md, section 2)."""

PCG_FORCING = 0.1
"""Largest relative residual of the preconditioned-CG Newton step (``pcg_iterations``): the forcing
term of an inexact Newton method, min(PCG_FORCING, sqrt(rel)) -- a step exact to 10 % in the
global phase, tighter as the residual falls."""

PCG_BELOW = 1e-4
"""Below this relative residual every Newton step factorises: the quadratic phase is one or two
exact steps from the tolerance, and a CG step there needed more iterations than it saved."""

PCG_MIN_DOFS = 10000
"""CG steps only on problems with at least this many free dofs: a factorisation's cost grows faster
with the size than a back-substitution's.  Measured (load ~6): square-pedestal 24x8x4 (4608 dofs)
from flat took 104 iterations and 2.64 s CPU with CG steps against 97 and 2.40 s without; the
20-element strips and 12x4x4 gained nothing either."""

ARMIJO = 1e-4
"""Sufficient decrease of the Armijo line search: Pi(D + a p) - Pi(D) <= ARMIJO a g.p."""

TR_SHRINK, TR_GROW = 0.25, 0.75
"""The trust radius is set to half the step taken when the model ratio rho is below TR_SHRINK and
doubled (up to max_step) when it is above TR_GROW and the step was cut."""

ACCEL_RATIO = 1.0
"""curvilinear: the second-order term acc is dropped when |acc|/2 exceeds this multiple of |p|."""

MAX_TRIALS = 40
"""Trial points of one line search or trust-region step before it fails."""


@dataclass
class _Tangent:
    """The factor of the last iteration, carried to the next."""

    lu: object = None  # the positive-definite factor of the (shifted) tangent (sys.chol)
    A: object = None  # the free tangent last assembled
    sigma: float = 0.0  # its shift
    cg_next: bool = False  # the last factor is unshifted and the last CG step (if any) was quick


@dataclass
class _Step:
    """A Newton direction p (full vector) with g.p, its max-norm [length] and how it was found."""

    p: np.ndarray
    gp: float
    sigma: float  # the shift of the factor behind it
    inexact: bool = False  # a CG step, whose curvature p.K.p is pKp
    pKp: float = 0.0
    pmax: float = 0.0
    acc: np.ndarray | None = None  # the curvilinear second-order term


def newton_level(sys, D, lam, o, stats):
    """Energy-minimising Newton at load factor lam, starting from D (fixed dofs already set), with
    the options ``o`` (settings.LevelOptions).  Returns (D, ok, message, rel)."""
    f = sys.free
    t = _Tangent()
    try_cg = o.pcg_iterations > 0 and sys.factorization in CHOLESKY_KINDS and f.size >= PCG_MIN_DOFS
    search = _SEARCHES[o.line_search]
    e_first = None
    e_ratio = np.inf
    Pi, G = sys.potential_and_gradient(D, lam)
    it = 0
    while True:
        g = G[f]
        stats["D_last"] = D
        rel = float(np.linalg.norm(g)) / sys.reference_norm(G + lam * sys.P, lam)
        if not np.isfinite(rel):
            return D, False, "non-finite residual", rel
        iteration_report(stats, rel, o)
        if converged(rel, e_ratio if it else (0.0 if rel <= o.tol else np.inf), o):
            stats["criterion"] = "residual"
            return D, True, f"converged in {it} iterations", rel
        if it >= o.max_iter:
            return D, False, f"no convergence in {o.max_iter} iterations (relative residual {rel:.2e})", rel
        it += 1
        stats["iterations"] += 1
        step = _direction(sys, D, g, rel, o, stats, t, try_cg)
        if isinstance(step, str):
            return D, False, step, rel
        if not np.isfinite(step.gp) or step.gp >= 0.0:
            if step.inexact:  # a CG step that does not descend: factorise this tangent
                t.cg_next = False
                continue
            if step.gp == 0.0 and rel <= o.tol:
                stats["criterion"] = "residual"
                return D, True, f"converged in {it} iterations", rel
            return D, False, "no descent direction (non-finite or uphill Newton step)", rel
        dmax = sys.maxnorm(D)
        if not step.inexact and step.sigma == 0.0 and step.pmax <= o.disp_tol * dmax:
            return _displacement_converged(sys, D, lam, step, dmax, it, stats)
        if o.curvilinear:
            step.acc = _curvilinear(sys, D, lam, g, step, t, o)
        found = search(sys, D, lam, Pi, g, step, o, stats)
        if found is None:
            return _stalled(sys, D, lam, Pi, step, dmax, rel, it, stats)
        alpha, D, Pi, G = found
        e_step = abs(alpha * step.gp)
        e_first = e_step if e_first is None else e_first
        e_ratio = e_step / e_first if e_first > 0 else 0.0


# ============================================================================ the direction
def _direction(sys, D, g, rel, o, stats, t, try_cg):
    """The Newton step of this iteration: by CG on the new tangent preconditioned with the last
    factor where that may pay (``_cg_step``), else from a new factorisation (``_factorise``).
    Returns a _Step, or a message when the tangent cannot be factorised."""
    f = sys.free
    step = None
    assembled = False
    if try_cg and t.cg_next and t.lu is not None and t.sigma == 0.0 and rel >= PCG_BELOW:
        step = _cg_step(sys, D, g, rel, o, stats, t)
        assembled = True
    else:
        t.cg_next = True
    if step is None:
        failed = _factorise(sys, D, t, stats, assembled)
        if failed:
            return failed
        p = np.zeros_like(D)
        p[f] = -t.lu.solve(g)
        sys.n_solves += 1
        step = _Step(p, float(np.dot(g, p[f])), t.sigma)
    step.pmax = sys.maxnorm(step.p)
    return step


def _cg_step(sys, D, g, rel, o, stats, t):
    """An inexact Newton step (``pcg_iterations`` > 0): after an iteration whose tangent factorised
    without a shift, the step is first sought by conjugate gradients on the *new* tangent,
    preconditioned by the last factor (linear.pcg), to a relative residual min(PCG_FORCING,
    sqrt(rel)) in at most that many CG iterations.  Returns the _Step, or None when CG does not get
    there (or meets non-positive curvature): the new tangent, in ``t.A``, is then factorised.

    A CG iteration costs one back-substitution and one product with the tangent, ~1/9 of a
    factorisation at 18 432 dofs, and the trust region's model uses the step's own curvature p.K.p.
    A CG step that needed more than half the iterations allowed is followed by a factorisation.
    It pays where the tangent changes slowly from one iteration to the next: the fine level of a
    mesh sequence, which settles a prolonged coarse equilibrium (square-pedestal 48x16x4, load ~6,
    2-3 rounds interleaved in one process: 35-39 factorisations instead of 59 on the fine mesh, the
    same 51 iterations, process CPU 10-19 % lower (medians 7.3-8.1 s against 9.0 s), the same state
    to 2e-8 of max|U|; 3 CG iterations at most: 49 factorisations, 13 %).  From the flat sheet,
    where the folds form, CG fails too often: 6 CG iterations cost 7 % more CPU on
    large-square-pedestal 45x15x4 (176 iterations, 165 factorisations against 167 and 193) and 15 %
    more on circle-pedestal; hence off by default (``pcg_iterations = 0``) and switched on by
    solvers/sequence.py for the fine mesh."""
    # the last tangent is not needed any more: dropped before the new one is assembled, so that
    # two are never alive at once next to the factor (3.9 MB of the static solver's memory peak
    # on square-pedestal 48x16x4, docs/solvers.md section 5)
    t.A = None
    _, t.A = sys.free_tangent(D)
    x, k, inexact, pKp = pcg(t.A.matvec(), g, t.lu.solve, min(PCG_FORCING, math.sqrt(rel)), o.pcg_iterations)
    sys.n_solves += k
    stats["cg_iterations"] = stats.get("cg_iterations", 0) + k
    t.cg_next = inexact and 2 * k <= o.pcg_iterations
    if not inexact:
        return None
    stats["cg_steps"] = stats.get("cg_steps", 0) + 1
    p = np.zeros_like(D)
    p[sys.free] = -x
    return _Step(p, float(np.dot(g, p[sys.free])), t.sigma, inexact=True, pKp=pKp)


def _factorise(sys, D, t, stats, assembled):
    """Factorise the free tangent at D (``assembled``: already in ``t.A``), shifted by
    sigma diag|K_t| with the smallest sigma, in tenfold steps from a tenth of the last one (0 when
    that was below 1e-7), that makes it positive definite.  Returns None, or a message when no
    shift does."""
    if not assembled:
        t.A = None
        _, t.A = sys.free_tangent(D)
    scale = np.abs(t.A.diagonal())
    scale[scale == 0.0] = max(float(scale.max(initial=0.0)), 1.0)
    try:
        t.lu, t.sigma, nf = shifted_factor(sys.chol, t.A, scale, 0.0 if t.sigma < 1e-7 else t.sigma / 10.0)
    except RuntimeError as exc:
        return f"tangent could not be factorised ({exc})"
    sys.n_factor += nf
    stats["max_shift"] = max(stats["max_shift"], t.sigma)
    if t.sigma > 0.0:
        stats["shifted_iterations"] += 1
    return None


def _curvilinear(sys, D, lam, g, step, t, o):
    """The second-order ("geodesic acceleration") correction of the Newton step, or None: with
    r_pp = d^2 g(D + s p)/ds^2 at s = 0 (finite difference of one extra force evaluation),
    acc = -K^-1 r_pp and the search runs along D + a p + a^2/2 acc.  A displacement-only shell
    cannot rotate along a straight line without stretching; acc bends the step onto the rotation
    arc and removes that spurious membrane strain."""
    f = sys.free
    hs = min(1.0, 1e-2 * o.L_f / step.pmax)
    _, Gh = sys.potential_and_gradient(D + hs * step.p, lam)
    Kp = t.A @ step.p[f]
    rpp = 2.0 / (hs * hs) * (Gh[f] - g - hs * Kp)
    if not np.all(np.isfinite(rpp)):
        return None
    acc = np.zeros_like(D)
    acc[f] = -t.lu.solve(rpp)
    sys.n_solves += 1  # back-substitution with the same factorisation
    if not (np.all(np.isfinite(acc)) and 0.5 * np.linalg.norm(acc) <= ACCEL_RATIO * np.linalg.norm(step.p)):
        return None
    return acc


# ============================================================================ the step length
def _trial(D, alpha, step):
    """D + a p (+ a^2/2 acc): the trial point at step length ``alpha``."""
    if step.acc is None:
        return D + alpha * step.p
    return D + alpha * step.p + 0.5 * alpha * alpha * step.acc


def _free_trial(sys, D, alpha, step):
    """(alpha, trial point) with the step cut until the straight path from D to the trial point
    takes no two layers of the sheet through each other and no node through a contact body
    (System.step_cut: continuous collision detection of the self-contact, conservative advancement
    against the bodies; a free step is taken unchanged).  A curvilinear trial is checked again
    after each cut, its path being no longer a part of the first one."""
    Dt = _trial(D, alpha, step)
    for _ in range(MAX_TRIALS):
        c = sys.step_cut(D, Dt)
        if c >= 1.0:
            break
        alpha *= c
        Dt = _trial(D, alpha, step)
    return alpha, Dt


def _trust_step(sys, D, lam, Pi, g, step, o, stats):
    """A 1-D trust region along the (shifted) Newton step, radius in max-norm (kept in
    ``stats["radius"]`` from one iteration and load level to the next).  Model decrease
    m(a) = g.p (a - a^2/2) since p = -(K + sigma S)^-1 g (a CG step: g.p a + p.K.p a^2/2 with its own
    curvature); ratio rho of actual to predicted decrease: the step is accepted when rho > 1e-4, the
    radius halved to the step when rho < TR_SHRINK, doubled when rho > TR_GROW and the step was cut,
    a quarter of the step on rejection.  Returns (alpha, D, Pi, G) of the accepted point or None."""
    f = sys.free
    gp, pmax = step.gp, step.pmax
    gnorm = float(np.linalg.norm(g))
    radius = max(stats.get("radius", o.radius0), o.radius_min)
    alpha = min(1.0, radius / pmax)
    for _ in range(MAX_TRIALS):
        alpha, Dt = _free_trial(sys, D, alpha, step)
        Pit, Gt = sys.potential_and_gradient(Dt, lam)
        if not np.isfinite(Pit):
            alpha *= 0.25
            continue
        dec = Pit - Pi
        pred = gp * (alpha - 0.5 * alpha * alpha) if not step.inexact else gp * alpha + 0.5 * alpha * alpha * step.pKp
        rho = dec / pred if pred < 0.0 else 0.0
        taken = alpha * pmax
        if abs(pred) <= ROUNDOFF * energy_scale(sys, D, lam, Pi):
            # the decrease is below the round-off of Pi: judge the step by the residual.  A step
            # that lowers it is the local phase, where the radius must not hold Newton back: it
            # grows as after a good model (frozen, it had square-on-disc 30x240 take 17 steps of
            # alpha 0.25-0.66 at 5.3e-4 cm before the full ones)
            if not (np.linalg.norm(Gt[f]) < gnorm or dec <= 0.0):
                alpha *= 0.25
                continue
            accepted = True
            if alpha < 1.0:
                radius = min(2.0 * radius, o.max_step)
        elif rho > 1e-4:
            accepted = True
            if rho < TR_SHRINK:
                radius = 0.5 * taken
            elif rho > TR_GROW and alpha < 1.0:
                radius = min(2.0 * radius, o.max_step)
        else:
            accepted = False
            radius = 0.25 * taken
        radius = max(radius, o.radius_min)
        stats["radius"] = radius
        if accepted:
            if step.sigma > 0.0 and alpha >= 1.0 and rho >= EXTEND_RHO and step.acc is None and not step.inexact:
                return _extend(sys, D, lam, step, radius, (alpha, Dt, Pit, Gt), stats)
            return alpha, Dt, Pit, Gt
        alpha = min(1.0, radius / pmax)
    return None


def _extend(sys, D, lam, step, radius, point, stats):
    """Pi nearly linear along the full shifted step ``point`` (alpha, D, Pi, G): double it while Pi
    falls, within the trust radius (energy evaluations only, no factorisation)."""
    alpha, Dt, Pit, Gt = point
    while 2.0 * alpha * step.pmax <= radius:
        D2 = D + 2.0 * alpha * step.p
        if sys.step_cut(D, D2) < 1.0:
            break  # the longer step would take layers through each other or a node through a body
        Pi2, G2 = sys.potential_and_gradient(D2, lam)
        if not (np.isfinite(Pi2) and Pi2 < Pit):
            break
        alpha, Dt, Pit, Gt = 2.0 * alpha, D2, Pi2, G2
        stats["extended_steps"] = stats.get("extended_steps", 0) + 1
    return alpha, Dt, Pit, Gt


def _armijo_step(sys, D, lam, Pi, g, step, o, stats):
    """Backtracking from the step capped at ``max_step`` until Pi falls by ARMIJO a g.p (or, below
    the round-off of Pi, the residual falls), by quadratic interpolation of Pi along p safeguarded
    to [0.1, 0.5] a.  Returns (alpha, D, Pi, G) of the accepted point or None."""
    f = sys.free
    gp = step.gp
    gnorm = float(np.linalg.norm(g))
    alpha = min(1.0, o.max_step / step.pmax)
    for _ in range(MAX_TRIALS):
        alpha, Dt = _free_trial(sys, D, alpha, step)
        Pit, Gt = sys.potential_and_gradient(Dt, lam)
        if not np.isfinite(Pit):
            alpha *= 0.25
            continue
        if Pit - Pi <= ARMIJO * alpha * gp or (
            abs(alpha * gp) <= ROUNDOFF * energy_scale(sys, D, lam, Pi) and np.linalg.norm(Gt[f]) < gnorm
        ):
            return alpha, Dt, Pit, Gt
        den = 2.0 * (Pit - Pi - alpha * gp)
        a_new = -gp * alpha * alpha / den if den > 0 else 0.5 * alpha
        alpha = min(max(a_new, 0.1 * alpha), 0.5 * alpha)
    return None


def _full_step(sys, D, lam, Pi, g, step, o, stats):
    """No line search: the step capped at ``max_step``, quartered only where Pi is not finite.
    Returns (alpha, D, Pi, G) or None."""
    alpha = min(1.0, o.max_step / step.pmax)
    for _ in range(MAX_TRIALS):
        alpha, Dt = _free_trial(sys, D, alpha, step)
        Pit, Gt = sys.potential_and_gradient(Dt, lam)
        if np.isfinite(Pit):
            return alpha, Dt, Pit, Gt
        alpha *= 0.25
    return None


_SEARCHES = {"trust": _trust_step, "armijo": _armijo_step, "none": _full_step}


# ============================================================================ the ends
def _displacement_converged(sys, D, lam, step, dmax, it, stats):
    """Scale-free stop: with a positive-definite (unshifted) K_t the Newton correction p is the
    error of D to first order, and it is below disp_tol of the displacement.  Takes it."""
    f = sys.free
    D = D + step.p
    _, G = sys.potential_and_gradient(D, lam)
    rel = float(np.linalg.norm(G[f])) / sys.reference_norm(G + lam * sys.P, lam)
    stats["criterion"] = "displacement"
    stats["D_last"] = D
    return (D, True, f"converged in {it} iterations (Newton correction {step.pmax / dmax:.1e} of |D|)", rel)


def _stalled(sys, D, lam, Pi, step, dmax, rel, it, stats):
    """No trial point accepted.  At round-off -- neither the energy nor the residual can decrease
    any more, the tangent is positive definite and the Newton correction is below 1e-6 of |D|: the
    residual has reached the round-off floor of the internal force -- that is convergence;
    otherwise the line search failed."""
    scale = max(dmax, 1e-300)
    if abs(step.gp) <= ROUNDOFF * energy_scale(sys, D, lam, Pi) and step.sigma == 0.0 and step.pmax <= 1e-6 * scale:
        stats["criterion"] = "round-off"
        return (
            D,
            True,
            (
                f"converged at the round-off floor in {it} iterations (relative "
                f"residual {rel:.1e}, Newton correction {step.pmax / scale:.1e} of |D|)"
            ),
            rel,
        )
    return D, False, "line search failed (no decrease of the potential along the Newton step)", rel
