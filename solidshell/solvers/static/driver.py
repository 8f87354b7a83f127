"""The static solver's driver: :func:`solve_static` (the public function), :func:`run` (the registry
entry ``solidshell.solvers.KINDS["static"]``), the load stepping, the saddle check and the report.

The full load is applied at once by default (``increment=1``); with method "newton" a failed step
is cut back and the load then applied in adaptive sub-steps with a path-extrapolating predictor
(``_load_stepping``).  Solvers never raise on non-convergence: they return ``converged=False``, the
last state and a one-line message; Ctrl-C returns the last iterate with status "interrupted".  No
load and nothing prescribed: the unloaded state, converged, 0 iterations.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ... import contact_augment as augment
from ...errors import InputError
from ...problem import SolveResult, no_progress
from ...settings import parse
from ..blas import kernel_threads, single_threaded_blas
from ..linear import resolve_factorization
from .arclength import arc_length
from .newton import newton_level
from .paper import paper_level
from .settings import RUN_SETTINGS, StaticSettings
from .system import System, free_length, seek_minimum, stability

__all__ = ["run", "solve_static"]


# ============================================================================ the public function
@single_threaded_blas
def solve_static(
    model,
    fixed,
    loads,
    load_factors=None,
    method=None,
    prescribed=None,
    *,
    settings=None,
    contact=None,
    progress=None,
    **options,
) -> SolveResult:
    """Static equilibrium of ``model`` under dead ``loads`` and ``prescribed`` fixed dofs.

    model : Model (energy, internal force, tangent; see solidshell.model)
    fixed : (N,6) bool, prescribed dofs;  loads : (N,6) dead nodal forces P [force]
    load_factors, method : the settings of those names, given positionally (None: from
        ``settings``, else their defaults: [1.0] and "newton")
    prescribed : (N,6) values of the fixed dofs at load factor 1 (default 0: clamped), or a
        function load_factor -> (N,6) giving them along the path
    settings : a :class:`~solidshell.solvers.static.settings.StaticSettings` or a dict of its
        fields (a scene's ``[solver.static]``); ``**options`` and the two arguments above override it
    contact : rigid bodies (solidshell.contact), penalty ``contact_stiffness``
    progress : callback(fraction, text): called at the start and at every iteration
    **options : any field of StaticSettings (tol, max_iter, line_search, U0, factorization, ...;
        every option, its default and its meaning are written there once).  An unknown key or a
        bad value is one InputError line naming it.  ``sequence`` belongs to a scene run
        (solidshell run, run_scene) and is refused here.

    Returns a :class:`~solidshell.problem.SolveResult`: U, converged, message, info, and frames =
    ``path``, the (load factor, (N,6) U) of every converged load step / arc-length point.
    info["status"]: "converged", "not_converged", "saddle" (converged to a saddle that could not be
    left) or "interrupted" (Ctrl-C: the last iterate is returned).  info["criterion"]: what ended the
    last Newton loop ("residual", "displacement", "round-off" or "zero load").
    """
    s = _settings(settings, load_factors, method, options)
    with kernel_threads(int(model.mesh.n_elements)):
        return _solve(model, fixed, loads, prescribed, contact, s, progress)


def _settings(settings, load_factors, method, options) -> StaticSettings:
    """``settings`` (StaticSettings, dict or None) overridden by the explicit arguments, parsed."""
    run_only = [k for k in RUN_SETTINGS if k in options]
    if run_only:
        raise InputError(
            f"solve_static: {run_only[0]!r} is a setting of a scene run (solidshell run, run_scene), not of one solve"
        )
    if load_factors is not None:
        options["load_factors"] = np.atleast_1d(load_factors).tolist()
    if method is not None:
        options["method"] = method
    if isinstance(settings, StaticSettings) and not options:
        return settings
    base = settings.as_dict() if isinstance(settings, StaticSettings) else dict(settings or {})
    return parse(StaticSettings, {**base, **options}, "solve_static")


def _solve(model, fixed, loads, prescribed, contact, s, progress):
    """The body of :func:`solve_static` (which sets the kernel threads around it)."""
    t0 = time.perf_counter()
    progress = _monotone(progress)
    progress(0.0, "static: setting up")
    sys, D = _setup(model, fixed, loads, prescribed, contact, s)
    o = s.level(float(s.L_f) if s.L_f is not None else free_length(model.mesh, sys.fixed_mask))
    stats = dict(
        iterations=0,
        load_steps=0,
        cutbacks=0,
        load_factor=0.0,
        shifted_iterations=0,
        max_shift=0.0,
        min_multiplier=1.0,
        final_relative_residual=np.nan,
        D_last=D,
    )
    path, warnings = [], _friction_unused(contact)
    D, ok, msg, rel, status = _equilibrium(sys, D, o, s, stats, progress, path, warnings)
    if ok:
        msg = (
            f"{s.method}: converged to load factor {stats['load_factor']:.4g} in "
            f"{stats['load_steps']} step(s), {stats['iterations']} iterations"
        )
        if stats.get("saddle_eigenvalues"):
            msg += f", {len(stats['saddle_eigenvalues'])} saddle(s) left"
        if stats.get("criterion") == "zero load":
            msg = f"{s.method}: no load and nothing prescribed: the unloaded state, 0 iterations"
        status = "converged"
    else:
        msg = f"{s.method}: {msg}"
        status = status or "not_converged"
    info = _info(sys, o, s, stats, ok, status, rel, warnings)
    if s.check_stability and np.all(np.isfinite(D)) and status != "interrupted":
        lam = stats["load_factor"]
        try:
            pd, lmin = stability(
                sys,
                sys.apply_prescribed(D, lam) if ok else D,
                s.eig_max_dofs,
                known=stats.get("stable_tangent") if ok else None,
            )
        except KeyboardInterrupt:
            pd, lmin = None, None
        info["positive_definite"] = pd
        info["min_tangent_eigenvalue"] = lmin
    info["wall_time_s"] = time.perf_counter() - t0
    progress(1.0, "static: done" if ok else "static: stopped")
    return SolveResult(U=D.reshape(sys.n, 6).copy(), converged=bool(ok), message=msg, info=info, frames=path)


def _friction_unused(contact) -> list[str]:
    """The warning that the bodies' friction is not applied: the static contact is frictionless
    (system.py), friction acts in the explicit solvers only (contact.py)."""
    mu = sorted({float(getattr(b, "friction", 0.0)) for b in contact or ()} - {0.0})
    if not mu:
        return []
    return [
        f"static: the contact is frictionless; the bodies' friction ({', '.join(f'{m:g}' for m in mu)}) acts in the "
        "explicit solvers only (a scene's [supports.static] holds what friction would)"
    ]


def _monotone(progress):
    """The caller's progress callback, never moving back (a cut-back or a saddle escape restarts a
    load step's count)."""
    user = progress or no_progress
    shown = [0.0]

    def report(fraction, text=""):
        shown[0] = max(shown[0], min(float(fraction), 1.0))
        user(shown[0], text)

    return report


def _setup(model, fixed, loads, prescribed, contact, s):
    """(System, starting state D with the prescribed values at load factor 0), inputs checked."""
    n = model.n_nodes
    fixed = np.asarray(fixed, dtype=bool)
    if fixed.size != 6 * n:
        raise InputError(f"fixed must have shape ({n}, 6), got {fixed.shape}")
    loads = np.asarray(loads, dtype=float)
    if loads.size != 6 * n:
        raise InputError(f"loads must have shape ({n}, 6), got {loads.shape}")
    factorization = resolve_factorization(s.factorization, int(np.count_nonzero(~fixed)))
    if s.self_contact and s.method != "newton":
        raise InputError(
            f"self_contact works with method 'newton' (its step searches keep the layers apart), not {s.method!r}"
        )
    sys = System(
        model,
        fixed,
        loads,
        prescribed,
        contact,
        s.contact_stiffness,
        factorization,
        s.contact_face_points,
        s.self_contact,
    )
    if sys.free.size == 0:
        raise InputError("every dof is fixed: nothing to solve")
    if s.U0 is None:
        D = np.zeros(6 * n)
    elif s.U0.size != 6 * n:
        raise InputError(f"U0 must have shape ({n}, 6), got {s.U0.shape}")
    else:
        D = np.asarray(s.U0, dtype=float).reshape(-1).copy()
    return sys, sys.apply_prescribed(D, 0.0)


def _equilibrium(sys, D, o, s, stats, progress, path, warnings):
    """The method of ``s`` to the last load factor, then the saddle check.  Returns (D, ok,
    message, rel, status or None)."""
    factors = s.factors()
    status = None
    zero = not np.any(sys.P) and sys.presc_fn is None and not np.any(sys.presc) and not np.any(D)
    try:
        if zero and not np.any(sys.potential_and_gradient(D, factors[-1])[1][sys.free]):
            # no load, nothing prescribed, no contact force at the start: the unloaded state is
            # the exact equilibrium (and the lowest energy, zero); no iteration is needed
            ok, msg, rel = True, "no load: the unloaded state", 0.0
            stats["load_factor"] = factors[-1]
            stats["criterion"] = "zero load"
            path.append((factors[-1], D.reshape(sys.n, 6).copy()))
        elif s.method == "arclength":
            D, ok, msg, rel = arc_length(sys, D, factors[-1], o, s, stats, progress, path)
        else:
            D, ok, msg, rel = _load_stepping(sys, D, factors, o, s, stats, progress, path)
        if ok and sys.contact and s.contact_augment > 0:
            D, ok, msg, rel = _augment(sys, D, o, s, stats, progress, path)
        if ok and s.check_stability and s.max_saddle_escapes > 0 and not zero:
            lam = stats["load_factor"]
            progress(0.97, "static: checking stability")
            D, ok2, msg2 = seek_minimum(
                sys,
                sys.apply_prescribed(D, lam),
                lam,
                o,
                stats,
                newton_level,
                s.max_saddle_escapes,
                s.saddle_step,
                warnings,
            )
            if stats.get("saddle_eigenvalues"):
                _, G = sys.potential_and_gradient(D, lam)
                rel = float(np.linalg.norm(G[sys.free])) / sys.reference_norm(G + lam * sys.P, lam)
                if path:
                    path[-1] = (lam, D.reshape(sys.n, 6).copy())
            if not ok2:
                ok, msg, status = False, msg2, "saddle"
    except KeyboardInterrupt:
        D = np.asarray(stats.get("D_last", D)).copy()
        ok, msg, rel, status = False, "interrupted (Ctrl-C): the last iterate is returned", np.nan, "interrupted"
        warnings.append("static: interrupted by the user; the state is the last iterate, not an equilibrium")
    except (FloatingPointError, np.linalg.LinAlgError, RuntimeError) as exc:
        ok, msg, rel = False, f"{type(exc).__name__}: {exc}", np.nan
    return D, ok, msg, rel, status


def _info(sys, o, s, stats, ok, status, rel, warnings) -> dict:
    """The JSON-able report of a solve (summary.json's solver keys)."""
    saddles = list(stats.get("saddle_eigenvalues", []))
    info = {
        "solver": "static",
        "method": s.method,
        "converged": bool(ok),
        "status": status,
        "criterion": stats.get("criterion") if ok else None,
        "iterations": int(stats["iterations"]),
        "linear_solves": int(sys.n_solves),
        "factorizations": int(sys.n_factor),
        "factorization": sys.factorization,
        "tangent_assemblies": int(sys.n_tangent),
        "energy_evaluations": int(sys.n_energy),
        "load_steps": int(stats["load_steps"]),
        "load_factor": float(stats["load_factor"]),
        "cutbacks": int(stats["cutbacks"]),
        "final_relative_residual": float(rel) if np.isfinite(rel) else None,
        "free_length": o.L_f,
        "saddles_left": len(saddles),
        "saddle_eigenvalues": saddles,
        "warnings": warnings,
    }
    if sys.contact:  # trial points whose node paths went into a body (contact_paths.py): cut or refused
        info["contact_path_cuts"] = int(sys.body_cuts)
    if sys.selfc is not None:  # contact_self.py: the barrier's kappa, its evaluations, the steps CCD cut
        info["self_contact_stiffness"] = sys.selfc.stiffness
        info["self_contact_evaluations"] = int(sys.selfc.evaluations)
        info["self_contact_ccd_cuts"] = int(sys.selfc.ccd_cuts)
        info["self_contact_builds"] = int(sys.selfc.builds)  # broad phases run (the rest were skipped)
        info["self_contact_ccd_runs"] = int(sys.selfc.ccd_runs)  # CCDs run of the steps checked
    if s.method == "newton":
        info["shifted_iterations"] = int(stats["shifted_iterations"])
        info["max_tangent_shift"] = float(stats["max_shift"])
        # doublings of shifted steps along which Pi was nearly linear (newton.EXTEND_RHO)
        info["extended_steps"] = int(stats.get("extended_steps", 0))
        # Newton steps found by preconditioned CG instead of a factorisation (pcg_iterations)
        info["cg_steps"] = int(stats.get("cg_steps", 0))
        info["cg_iterations"] = int(stats.get("cg_iterations", 0))
        # load factors of critical points the path snapped from (_load_stepping)
        info["snapped_from"] = [float(x) for x in stats.get("snaps", [])]
    if s.method == "arclength":
        # > 1 means the path crossed a bifurcation (a second eigenvalue through zero): there is no
        # branch switching, and the path may turn onto another branch there
        info["max_negative_eigenvalues_on_path"] = int(stats.get("max_negative_eigenvalues", 0))
    if s.method == "paper":
        info["c"] = o.c
        info["min_multiplier"] = float(stats["min_multiplier"])
    if sys.contact:
        info["contact_stiffness"] = sys.k_contact
        if "augment_updates" in stats:  # contact_augment.py
            info["contact_augment_updates"] = int(stats["augment_updates"])
            info["contact_augment_depth"] = float(stats["augment_depth"])
            info["contact_augment_iterations"] = [int(i) for i in stats["augment_iterations"]]
    return info


def _augment(sys, D, o, s, stats, progress, path):
    """Augmented-Lagrangian updates of the contact at the last load factor (contact_augment.py):
    while a node or face point lies deeper than the target, shift and solve again from D, at most
    ``contact_augment`` times, by the trust-region Newton whatever the method (a correction of a
    fraction of h; the paper's lambda-scaled steps would spend hundreds of iterations on it).  A soft drape may answer an update by moving its folds instead of
    lifting (the deepest point moves elsewhere, unshifted): the solves stop after STALLS updates in
    a row that did not make the deepest penetration shallower, and the shallowest solve is kept
    (an equilibrium of its own shifts).  Returns (D, ok, message, rel) of the solve kept."""
    lam = stats["load_factor"]
    target = augment.target(sys.model.material.thickness)
    stats["augment_updates"] = 0
    stats["augment_iterations"] = []
    msg, rel = "", stats.get("final_relative_residual", np.nan)
    best = None  # (depth, D, rel, msg, shifts) of the shallowest converged solve
    shallowest, stalls = math.inf, 0
    while True:
        depth, s_n, s_q = sys.augment(D)
        if depth < shallowest:
            best = (depth, D, rel, msg, (sys.shift_n, sys.shift_q))
        stop, shallowest, stalls = augment.tally(
            depth, shallowest, stalls, stats["augment_updates"], s.contact_augment, target
        )
        if stop:
            depth, D, rel, msg, (sys.shift_n, sys.shift_q) = best
            stats["augment_depth"] = depth
            stats["final_relative_residual"] = rel
            if path:
                path[-1] = (lam, D.reshape(sys.n, 6).copy())
            return D, True, msg or "converged", rel
        sys.shift_n, sys.shift_q = s_n, s_q
        stats["augment_updates"] += 1
        progress(0.95, f"static: contact update {stats['augment_updates']}, deepest {depth:.3g} > {target:.3g}")
        it0 = stats["iterations"]
        Dn, ok, msg, rel = newton_level(sys, D, lam, o, stats)
        stats["augment_iterations"].append(stats["iterations"] - it0)
        if not ok:
            stats["augment_depth"] = depth  # the depth the failed update started from
            return Dn, False, f"after contact update {stats['augment_updates']}: {msg}", rel
        D = Dn


# ============================================================================ load stepping
def _load_stepping(sys, D, factors, o, s, stats, progress, path):
    """Reach every load factor in turn.  Method "paper" goes straight to each factor (as the paper
    does).  Method "newton" sub-steps adaptively: the increment starts at ``increment`` times the
    final factor, doubles after a step that converged in <= 4 iterations, halves after one that
    needed >= 12 (never below ``min_increment``), and a failed step is retried with a quarter of
    the increment (at most ``max_cutbacks`` times in a row, never below ``min_increment``).  The
    start of every step is the lower-potential of two predictions (``_start``).

    A step of the smallest increment that still needs >= 12 iterations marks a critical point of
    the path (a limit or bifurcation point, where K_t turns singular and no increment is small
    enough for Newton to be quick): the next step goes to the target factor at once and the
    energy-minimising Newton snaps to the stable branch beyond it (``stats["snaps"]``, the factors
    it left from; a failed snap is cut back as any failed step).  Without it the halving shrank the
    steps geometrically and the path never got past the point: sphere 60x60 with self-contact held
    at 0.9165 for 700 steps of ~1e-9, ~22 iterations each (docs/notes/contact-history.md); from that
    state the full step to 1 took 191 iterations."""
    newton = s.method == "newton"
    level = newton_level if newton else paper_level
    lam = stats["load_factor"]
    final = factors[-1] if factors else lam
    scale = max(abs(final), 1e-300)
    hist = [(lam, D.copy())]
    msg = ""
    rel = np.nan
    dl = s.increment * scale
    for target in factors:
        cut = 0
        while True:
            if newton:
                step = math.copysign(min(abs(dl), abs(target - lam)), target - lam)
                trial = target if abs(target - (lam + step)) <= 1e-12 * scale else lam + step
            else:
                trial = target
            D0 = _start(sys, D, hist, lam, trial, newton and s.predictor)
            it0 = stats["iterations"]
            stats.pop("rel0", None)
            lo, span = lam, trial - lam
            stats["on_iter"] = lambda q, r, lo=lo, span=span, t=trial: progress(
                min(1.0, abs(lo + q * span) / scale), f"load factor {t:.4g}, residual {r:.1e}"
            )
            Dn, ok, msg, rel = level(sys, D0, trial, o, stats)
            nit = stats["iterations"] - it0
            if ok:
                D, lam = Dn, trial
                hist.append((lam, D.copy()))
                stats["load_steps"] += 1
                stats["load_factor"] = lam
                stats["final_relative_residual"] = rel
                path.append((lam, D.reshape(sys.n, 6).copy()))
                progress(min(1.0, abs(lam) / scale), f"load factor {lam:.4g}")
                cut = 0
                if nit <= 4:
                    dl *= 2.0
                elif nit >= 12:
                    dl = _slow_step(dl, lam, final, s.min_increment * scale, stats)
                if lam == target:
                    break
                continue
            if not newton or cut >= s.max_cutbacks or abs(dl) * 0.25 < s.min_increment * scale:
                stats["final_relative_residual"] = rel
                return (
                    Dn,
                    False,
                    (f"load step to factor {trial:.4g} failed: {msg}" + (f" after {cut} cut-backs" if cut else "")),
                    rel,
                )
            cut += 1
            stats["cutbacks"] += 1
            dl = 0.25 * (trial - lam)
    return D, True, msg, rel


def _slow_step(dl, lam, final, floor, stats):
    """The increment after a step that needed >= 12 iterations: half of ``dl``, not below
    ``floor``; at the floor already, the rest of the way to ``final`` (a snap past a critical
    point, recorded in ``stats["snaps"]``)."""
    if abs(dl) > floor * (1.0 + 1e-12):
        return math.copysign(max(0.5 * abs(dl), floor), dl)
    stats.setdefault("snaps", []).append(lam)
    return final - lam


def _start(sys, D, hist, lam, trial, predict):
    """The start of the load step lam -> trial: D with the prescribed values of ``trial``, or, with
    ``predict`` (newton), the lowest-potential of that, the tangent (linearised) predictor and the
    quadratic extrapolation of the last three converged states -- the latter follows the curved
    path of large rotations, which the linearised step cannot (newton.py's module notes)."""
    cands = [sys.apply_prescribed(D, trial)]
    if predict and trial != lam:
        if len(hist) >= 2:
            cands.append(sys.apply_prescribed(_extrapolate(hist, trial), trial))
        try:
            cands.append(_predictor(sys, D, lam, trial))
        except RuntimeError:
            pass
    if len(cands) == 1:
        return cands[0]
    cands = [cands[0]] + [cd for cd in cands[1:] if sys.step_cut(D, cd) >= 1.0]  # nothing taken through
    pis = [sys.potential_and_gradient(cd, trial)[0] for cd in cands]
    pis = [pi if np.isfinite(pi) and np.all(np.isfinite(cd)) else np.inf for pi, cd in zip(pis, cands)]
    return cands[int(np.argmin(pis))]


def _predictor(sys, D, lam0, lam1):
    """Linearised first guess for a load/prescribed increment lam0 -> lam1 (tangent at D).  Raises
    RuntimeError (``_start`` then goes without it) where the tangent is not positive definite: along
    a zero or negative mode a shifted solve is a step of any length.  The flat sheet resting on the
    sphere (its centre held in-plane only, the contact not pressed yet) is singular in the vertical
    translation, and its "prediction" dropped the whole sheet 1821 cm, through the sphere to where
    the penalty sees no penetration; the lowest potential chose it, and each attempt then fell for
    1000 iterations (tests/test_face_contact.py: 8x8 sheet 5908 iterations and 5 cut-backs -> 153
    and none; sphere 60x60 4978 -> 328)."""
    f, c = sys.free, sys.fixd
    dl = lam1 - lam0
    rhs = dl * sys.P[f]
    dc = (sys.prescribed_at(lam1) - sys.prescribed_at(lam0))[c]
    if c.size and np.any(dc):
        # the free-fixed coupling of K_t is needed: the full tangent
        _, K = sys.force_tangent(D)
        rhs = rhs - K[f][:, c] @ dc
        A = sys.Kff(K)
    else:
        _, A = sys.free_tangent(D)
    sys.n_factor += 1
    if not sys.chol.factor(A):
        raise RuntimeError("the tangent is not positive definite: no linearised prediction")
    sys.n_solves += 1
    Dp = sys.apply_prescribed(D, lam1)
    Dp[f] += sys.chol.solve(rhs)
    return Dp


def _extrapolate(hist, lam):
    """Lagrange extrapolation of the converged path (up to its last 3 points) to load factor lam."""
    pts = hist[-3:]
    out = np.zeros_like(pts[-1][1])
    for i, (li, Di) in enumerate(pts):
        w = 1.0
        for j, (lj, _) in enumerate(pts):
            if j != i:
                w *= (lam - lj) / (li - lj)
        out += w * Di
    return out


# ============================================================================ registry entry
def _other_solver_keys() -> set:
    """Setting names of the other registered solvers (explicit, relax): ``run`` ignores them so that
    one settings dict can serve several solvers."""
    from .. import KINDS

    return {k for name, kind in KINDS.items() if name != "static" for k in kind.settings_model().model_fields}


def _solve_problem(problem, s, progress) -> SolveResult:
    return solve_static(
        problem.model,
        problem.fixed,
        problem.loads,
        prescribed=problem.prescribed,
        contact=problem.contact,
        progress=progress,
        settings=s,
    )


def run(problem, settings: dict | None = None, progress=None) -> SolveResult:
    """Registry entry ``"static"``: solve a :class:`~solidshell.problem.Problem`.

    ``settings`` is parsed by :class:`~solidshell.solvers.static.settings.StaticSettings` (every
    key typed and range-checked; a bad value or an unknown key is one InputError line naming it).
    Settings of the other registered solvers (explicit, relax: e.g. ``t_end``) are ignored, so one
    settings dict can serve several solvers; ``sequence`` is read by solvers/sequence.py.
    """
    settings = dict(settings or {})
    if any(k not in StaticSettings.model_fields for k in settings):
        other = _other_solver_keys()
        settings = {k: v for k, v in settings.items() if k in StaticSettings.model_fields or k not in other}
    s = parse(StaticSettings, settings, "solver.static")
    note = None
    from_scene = False  # the barrier switched on by the problem's self_contact, not by the settings
    if getattr(problem, "self_contact", False) and not s.self_contact:
        # the scene's [self_contact]: the barrier where the method can keep its steps apart
        if s.method == "newton":
            s = parse(StaticSettings, {**s.as_dict(), "self_contact": True}, "solver.static")
            from_scene = True
        else:
            note = f"self-contact is left out: the static method {s.method!r} takes none (method 'newton' does)"
    try:
        res = _solve_problem(problem, s, progress)
    except InputError as exc:
        if not (from_scene and str(exc).startswith("self-contact:")):
            raise
        # the scene's switch on a mesh the barrier cannot take (elements smaller than about h):
        # solved without it, and said so (an explicit solver.static.self_contact = true still refuses)
        s = parse(StaticSettings, {**s.as_dict(), "self_contact": False}, "solver.static")
        note = f"self-contact is left out: {exc}"
        res = _solve_problem(problem, s, progress)
    if note:
        res.info.setdefault("warnings", []).append(note)
    return res
