"""Static equilibrium: the paper's lambda-scaled Newton-Raphson, an energy-minimising Newton, and
Crisfield's arc-length method.

Equilibrium (Eq. 16): F(D) = P on the free dofs, with D the global displacements [U_o | U_n] per
node, F = dU/dD the internal force (Eq. 9) and P the dead external loads.  Because P is dead,
equilibrium is a stationary point of the total potential Pi(D) = U(D) - P.D, and a *stable*
equilibrium is a minimum of Pi: a positive-definite K_t on the free dofs.

Methods (``method=``)
---------------------
``"paper"``  Section 3, Eqs. (16)-(18): full Newton-Raphson K_t dD = P - F with the multiplier
    lambda = c L_f / max|dD| (capped at 1) on every update, D <- D + lambda dD.  ``c`` is the
    paper's 1e-3 ... 1e-2 (default 1e-2); L_f the free-hanging length (default: the largest
    distance from a free node to the nearest fixed node).  No line search, no safeguard: the
    paper's scheme, kept as a reference (it needs at least ~ (max displacement)/(c L_f) iterations).
``"newton"`` (default)  Newton on Pi globalised by a trust region on the step (``line_search=
    "trust"``: the Newton step is cut to a max-norm radius that starts at 0.02 L_f and grows/shrinks
    with the ratio of actual to predicted decrease of Pi; ``"armijo"``: backtracking line search;
    ``"none"``), and a tangent shift K_t + sigma diag|K_t| whenever K_t is not positive definite
    (detected by its Cholesky factorisation failing: MKL PARDISO or CHOLMOD, solvers/linear.py; or,
    with ``factorization="superlu"``, by the inertia of SuperLU's LDL^T, Sylvester's law); sigma grows
    tenfold from 1e-8 until the factorisation succeeds and starts from a tenth of it on the next
    iteration.  A full shifted step whose actual decrease of Pi is at least ``EXTEND_RHO`` (1.8)
    times the predicted one -- Pi nearly linear along it, its length set by the shift -- is doubled
    while Pi falls, within the trust radius (``info["extended_steps"]``).  Every step is therefore a
    descent step of Pi and the iteration cannot settle on a saddle or a maximum (the paper's scheme
    can: see ``positive_definite``).
    The full load is applied at once by default (``increment=1``); a failed step is cut back and
    the load then applied in adaptive sub-steps with a path-extrapolating predictor.
    Why it still takes tens to a hundred iterations on a drape: with translations as the only
    unknowns a straight Newton step cannot rotate a material line without stretching it, and the
    membrane rigidity of a fabric is 1e5-1e6 times its bending rigidity over L^2, so the quadratic
    convergence radius of Newton is tiny and the global phase is governed by the step control (the
    curvilinear ``curvilinear=True`` option, a second-order "geodesic acceleration" correction of the
    step, did not help on the strip and is off by default).  On the fine mesh of a mesh sequence
    (>= 10 000 free dofs, ``pcg_iterations``) a Newton step is first sought by conjugate gradients
    on the new tangent, preconditioned by the last factorisation.  What was tried and dropped, and
    the iteration counts of every method: docs/solvers.md, sections 2 and 10.
``"arclength"``  Crisfield's cylindrical arc-length method (load factor as an extra unknown, the
    quadratic constraint |Delta D| = Delta l, root chosen by the smallest angle with the previous
    increment; predictor sign from the previous increment, sign(Delta D_prev . K^-1 P)), which
    follows the equilibrium path through limit points; the last step lands exactly on the requested
    final load factor by a load-controlled Newton correction.  No bifurcation handling: where a
    second eigenvalue crosses zero the path may turn onto another branch
    (``max_negative_eigenvalues_on_path`` > 1 in info flags this).

Convergence (all methods): relative residual |P - F|_free / max(|P|, |reactions|, |F_free|) <=
``tol`` (default 1e-8) and energy norm |dD . (P - F)| of the last update <= ``energy_tol`` (1e-12)
times that of the first iteration of the step.  Newton also stops (``info["criterion"]``) when
- "displacement": the Newton correction of a positive-definite, unshifted K_t is below ``disp_tol``
  (1e-10) of max|D| -- to first order it *is* the error of D, so this test is free of any force or
  length scale;
- "round-off": neither the potential nor the residual can be lowered any more because the predicted
  decrease is below the round-off of Pi (1e-11 of |Pi| + |lam P.D|), K_t is positive definite and
  the Newton correction is below 1e-6 of max|D|.
Step sizes (trust radius, max_step, the paper's max|dD|, the tests above) are measured in length:
a director dof (unit-free) counts as the face motion h/2 |dU_n|.  With the strains formed in the
displacement form of Eq. (3) (elements/core.py), the iteration is then the same in any consistent
unit system and at any load level (verification/static_units.py: identical iteration counts in
gf-cm, N-m and N-mm from 1e-8 to 1 of the working load; <= 3 iterations in the linear regime).

Stability (``check_stability``): the final state must be a minimum of Pi.  If the Cholesky
factorisation of the free-dof K_t fails, the state is a saddle: the solver leaves it along the
eigenvector of the most negative eigenvalue (ARPACK shift-invert, LOBPCG fallback; both signs and
five step lengths up to ``saddle_step`` L_f tried, the lowest potential kept) and continues Newton,
at most ``max_saddle_escapes`` times; each escape is recorded (``saddles_left``,
``saddle_eigenvalues``, a line in ``warnings``), and a run that cannot reach a minimum returns
converged=False with status "saddle".  The report of the final state: ``positive_definite``
(inertia of K_t on the free dofs) and ``min_tangent_eigenvalue`` (eigsh, shift-invert, when the
problem has at most ``eig_max_dofs`` free dofs).  Solvers never raise on non-convergence: they return
``converged=False``, the last state and a one-line message; Ctrl-C returns the last iterate with
status "interrupted".  No load and nothing prescribed: the unloaded state, converged, 0 iterations.

Displacement control: the fixed dofs take ``load_factor * prescribed``; dead loads are
``load_factor * loads``.  ``prescribed`` may also be a function ``load_factor -> (N,6)`` for
non-proportional paths (e.g. a director rotated by an angle proportional to the load factor:
U_n = R(lambda phi) X_n - X_n, which a linear scaling of one array would shrink).

Rigid contact bodies (``contact=`` or ``Problem.contact``) enter as the penalty energy
1/2 k p^2 on the mid-surface nodes (frictionless, Gauss-Newton tangent k n n^T); k defaults to
``contact_stiffness`` = 1e3 * (heaviest nodal dead load) / h, i.e. a node carrying its own weight
sinks 1e-3 h.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..problem import SolveResult, no_progress
from .blas import kernel_threads, single_threaded_blas
from .linear import (CHOLESKY_KINDS, Cholesky, LowerCSC, as_csc, ldl_inertia, pcg,
                     positive_definite_factor, resolve_factorization)

__all__ = ["StaticResult", "solve_static", "run", "METHODS"]

METHODS = ("newton", "paper", "arclength")


@dataclass
class StaticResult:
    """Result of :func:`solve_static`.

    U : (N,6) final displacements;  converged : bool;  message : one line;
    info : JSON-able numbers (solver, method, iterations, linear_solves, final_relative_residual,
    positive_definite, min_tangent_eigenvalue, wall_time_s, ...);
    path : list of (load factor, (N,6) U) of every converged load step / arc-length point.
    """

    U: np.ndarray
    converged: bool
    message: str = ""
    info: dict = field(default_factory=dict)
    path: list = field(default_factory=list)

    @property
    def frames(self):
        return self.path


# ============================================================================ the discrete system
class _System:
    """Model + constraints + loads + contact, with counters.  Works on full flat vectors D (6N)."""

    def __init__(self, model, fixed, loads, prescribed, contact, contact_stiffness,
                 factorization="cholmod"):   # a resolved kind (linear.resolve_factorization)
        n = model.n_nodes
        self.model = model
        self.n = n
        self.fixed_mask = np.asarray(fixed, dtype=bool).reshape(n, 6).ravel()
        self.free = np.flatnonzero(~self.fixed_mask)
        self.fixd = np.flatnonzero(self.fixed_mask)
        self.P = np.asarray(loads, dtype=float).reshape(n, 6).ravel().copy()
        self.presc_fn = prescribed if callable(prescribed) else None
        if self.presc_fn is not None:
            self.presc = self._presc_at(1.0)
        else:
            self.presc = (np.zeros(6 * n) if prescribed is None
                          else np.asarray(prescribed, dtype=float).reshape(n, 6).ravel().copy())
        if not (np.all(np.isfinite(self.P)) and np.all(np.isfinite(self.presc))):
            raise InputError("loads and prescribed values must be finite")
        self.contact = list(contact or [])
        self.k_contact = 0.0
        if self.contact:
            if contact_stiffness is None:
                h = float(getattr(model.material, "thickness", 1.0))
                w = np.abs(self.P.reshape(n, 6)[:, :3]).max()
                contact_stiffness = 1e3 * max(w, 1e-12) / h
            self.k_contact = float(contact_stiffness)
        self.n_energy = 0
        self.n_tangent = 0
        self.n_solves = 0
        self.n_factor = 0
        # positive-definite factorisations: PARDISO or CHOLMOD (the symbolic analysis shared by
        # every tangent of this solve) or, for comparison, SuperLU's LDL^T
        self.factorization = factorization
        self.chol = positive_definite_factor(factorization)
        self._ldl = None
        self._has_ef = hasattr(model, "energy_and_force")
        # step sizes are measured in length: a director dof (unit-free, Eq. 1) counts as the motion
        # h/2 |dU_n| of the shell's faces, so that every step control is the same in any unit
        # system (a max over raw dofs would mix cm and 1 and change with the length unit)
        h = float(getattr(model.material, "thickness", 1.0))
        w = np.ones((n, 6))
        w[:, 3:] = 0.5 * h
        self.w = w.ravel()
        self.w_free = self.w[self.free]

    def maxnorm(self, v, free=False):
        """max |w v| [length]: translations as they are, director dofs times h/2."""
        return float(np.abs((self.w_free if free else self.w) * v).max(initial=0.0))

    # -- vectors
    def _presc_at(self, lam):
        v = np.asarray(self.presc_fn(lam), dtype=float)
        if v.size != 6 * self.n:
            raise InputError(f"prescribed(load_factor) must return an ({self.n}, 6) array")
        return v.reshape(-1).copy()

    def prescribed_at(self, lam):
        """Full vector whose fixed entries are the prescribed values at load factor lam."""
        return self._presc_at(lam) if self.presc_fn is not None else lam * self.presc

    def apply_prescribed(self, D, lam):
        D = D.copy()
        D[self.fixd] = self.prescribed_at(lam)[self.fixd]
        return D

    def U(self, D):
        return D.reshape(self.n, 6)

    # -- contact (mid-surface nodes; forces on U_o only)
    def _contact(self, D, want_tangent=False):
        """(penalty energy, its gradient (6N,), tangent blocks): the blocks are a list of (active
        nodes (A,), k n n^T (A,3,3)) per body, None without ``want_tangent``."""
        x = self.model.mesh.nodes + D.reshape(self.n, 6)[:, :3]
        f = np.zeros((self.n, 6))
        e = 0.0
        blocks = [] if want_tangent else None
        k = self.k_contact
        for b in self.contact:
            fb, eb = b.forces(x, k)              # penalty force k p n on the sheet, energy k p^2/2
            e += eb
            f[:, :3] -= fb                       # the gradient of the penalty energy is -k p n
            if want_tangent:
                gap, nrm = b.penetration(x)
                act = np.flatnonzero(gap < 0.0)
                if act.size:
                    blocks.append((act, k * nrm[act][:, :, None] * nrm[act][:, None, :]))
        return e, f.ravel(), blocks

    def _contact_matrix(self, blocks):
        """The contact tangent blocks as a (6N, 6N) CSR matrix, or None."""
        if not blocks:
            return None
        import scipy.sparse as sp   # scipy.sparse only where a 6N x 6N matrix is formed: a small
                                    # run on the free-tangent path does not import it at all
        rows, cols, vals = [], [], []
        for act, nn in blocks:
            base = 6 * act
            r = (base[:, None, None] + np.arange(3)[None, :, None]).repeat(3, axis=2)
            c = (base[:, None, None] + np.arange(3)[None, None, :]).repeat(3, axis=1)
            rows.append(r.ravel()); cols.append(c.ravel()); vals.append(nn.ravel())
        m = 6 * self.n
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(m, m))

    # -- evaluations
    def potential_and_gradient(self, D, lam):
        """(Pi, dPi/dD full vector) at D; Pi = U(D) - lam P.D (+ contact)."""
        self.n_energy += 1
        U = self.U(D)
        if self._has_ef:
            W, F = self.model.energy_and_force(U)
        else:
            W, F = self.model.energy(U), self.model.internal_force(U)
        F = np.asarray(F, dtype=float).ravel()
        if self.contact:
            ec, fc, _ = self._contact(D)
            W += ec
            F = F + fc
        return float(W) - lam * float(np.dot(self.P, D)), F - lam * self.P

    def force_tangent(self, D):
        """(F internal (+contact) full vector, K (6N,6N) CSR)."""
        import scipy.sparse as sp

        self.n_tangent += 1
        F, K = self.model.force_and_tangent(self.U(D))
        F = np.asarray(F, dtype=float).ravel()
        K = sp.csr_matrix(K)
        if self.contact:
            _, fc, blocks = self._contact(D, want_tangent=True)
            F = F + fc
            Kc = self._contact_matrix(blocks)
            if Kc is not None:
                K = K + Kc
        return F, K

    def free_tangent(self, D):
        """(F internal (+contact) full vector, K_t on the free dofs as a :class:`LowerCSC`).

        The tangent is assembled straight into the lower triangle of its free-dof pattern, the
        form CHOLMOD factorises (assembly.FreeLowerPattern): no 6N x 6N matrix, no restriction
        and no conversion per iteration.  Same values, to the last bit, as ``Kff(force_tangent)``."""
        if not hasattr(self.model, "force_and_free_tangent"):
            F, K = self.force_tangent(D)
            return F, LowerCSC.from_symmetric(self.Kff(K))
        self.n_tangent += 1
        lw = getattr(self, "_lower", None)
        if lw is None:
            lw = self._lower = self.model.free_lower_pattern(self.free)
        F, data = self.model.force_and_free_tangent(self.U(D), lw)
        F = np.asarray(F, dtype=float).ravel()
        if self.contact:
            _, fc, blocks = self._contact(D, want_tangent=True)
            F = F + fc
            for act, nn in blocks:
                pos = lw.node_pos[act]
                m = pos >= 0
                np.add.at(data, pos[m], nn[m])
        return F, LowerCSC(lw.indptr, lw.indices, data, lw.diag_pos, lw)

    def ldl(self, A):
        """(solver, number of negative eigenvalues or None) of the symmetric free tangent ``A``:
        PARDISO's LDL^T (pardiso.PardisoLDL, its analysis kept for the pattern) where the
        factorisation is "pardiso" and no pivot had to be perturbed, else SuperLU's
        (linear.ldl_inertia; RuntimeError when singular).  The solver holds until the next call."""
        if self.factorization == "pardiso":
            if self._ldl is None:
                from .pardiso import PardisoLDL

                self._ldl = PardisoLDL()
            out = self._ldl.ldl(A)
            if out is not None:
                return out
        return ldl_inertia(as_csc(A))

    def reference_norm(self, F, lam):
        """max(|lam P|, |reactions|, |F_int on the free dofs|, tiny): the scale of the relative
        residual.  The internal force enters so that a problem driven by prescribed values alone
        (P = 0, reactions ~ 0 in a rigid motion) is still measured against the forces in play."""
        r = F[self.fixd] - lam * self.P[self.fixd]
        return max(float(np.linalg.norm(lam * self.P)), float(np.linalg.norm(r)),
                   float(np.linalg.norm(F[self.free])), 1e-300)

    def Kff(self, K):
        """K restricted to the free dofs, CSC.  The tangents of a solve share one sparsity pattern,
        so the restriction is a gather of K.data through a map built once per pattern (slicing
        and converting ~1e6 entries every iteration cost ~10 % of a drape solve); K is symmetric,
        so the CSR arrays of the restriction serve as its CSC arrays."""
        import scipy.sparse as sp

        f = self.free
        K = K.tocsr()
        cache = getattr(self, "_kff_cache", None)
        if (cache is None or not np.array_equal(cache[0], K.indptr)
                or not np.array_equal(cache[1], K.indices)):
            probe = sp.csr_matrix((np.arange(1, K.nnz + 1, dtype=float), K.indices, K.indptr),
                                  shape=K.shape)[f][:, f]
            probe.sort_indices()
            cache = (K.indptr.copy(), K.indices.copy(), probe.data.astype(np.int64) - 1,
                     probe.indices.copy(), probe.indptr.copy())
            self._kff_cache = cache
        _, _, gather, indices, indptr = cache
        n = f.size
        return sp.csc_matrix((K.data[gather], indices, indptr), shape=(n, n))


# ============================================================================ linear algebra
def _shifted_factor(chol, A, scale, sigma0, sigma_max=1e12):
    """Cholesky of A + sigma diag(scale) with the smallest sigma >= sigma0 (tenfold steps from
    1e-8) that is positive definite.  Returns (chol, sigma, n_factorisations)."""
    sigma = sigma0
    nf = 0
    while True:
        nf += 1
        if chol.factor(A, None if sigma == 0.0 else sigma * scale):
            return chol, sigma, nf
        sigma = 1e-8 if sigma == 0.0 else 10.0 * sigma
        if sigma > sigma_max:
            raise RuntimeError("no positive-definite shift of the tangent found")


EXTEND_RHO = 1.8
"""A full step of a *shifted* tangent whose actual decrease of Pi is at least this multiple of the
predicted one is doubled while Pi falls, within the trust radius (``_newton_level``).  The model
decrease of a step p = -(K + sigma S)^-1 g is g.p/2; rho -> 2 means Pi is nearly linear along p, whose
length the shift, not the curvature, has set (circle-pedestal, square-on-disc: runs of 10-20 such
steps of alpha 1 and rho 1.9-2.1 at an unchanging sigma 1e-3; docs/solvers.md, section 2)."""


# ============================================================================ one load level
@dataclass
class _Opts:
    tol: float = 1e-8
    energy_tol: float = 1e-12
    disp_tol: float = 1e-10
    max_iter: int = 100
    c: float = 1e-2
    L_f: float = 1.0
    max_step: float = 1.0
    armijo: float = 1e-4
    curvilinear: bool = True
    accel_ratio: float = 1.0
    line_search: str = "armijo"
    radius0: float = 0.02
    radius_min: float = 1e-9
    tr_shrink: float = 0.25
    tr_grow: float = 0.75
    reuse: int = 0
    pcg_iterations: int = 0


def _converged(rel, e_ratio, o):
    return rel <= o.tol and e_ratio <= o.energy_tol


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

_ROUNDOFF = 1e-11
"""An energy change below this fraction of the energy scale |Pi| + |lam P.D| is round-off: Pi is a
sum of terms of that size, each exact to ~1e-16, over up to ~1e5 elements."""


def _energy_scale(sys, D, lam, Pi):
    """|Pi| + |lam P.D|: the size of the terms whose difference Pi is (Pi itself may be ~0)."""
    return abs(Pi) + abs(lam * float(np.dot(sys.P, D))) + 1e-300


def _iteration_report(stats, rel, o):
    """Progress within a load step: the fraction of the way (in log of the residual) from the first
    residual of the step to ``tol``, kept monotone, handed to the driver's callback."""
    cb = stats.get("on_iter")
    if cb is None or not np.isfinite(rel) or rel <= 0.0:
        return
    r0 = stats.setdefault("rel0", rel)
    q = 0.0 if r0 <= o.tol else math.log(max(r0 / rel, 1.0)) / math.log(r0 / o.tol)
    cb(min(max(q, 0.0), 1.0), rel)


def _newton_level(sys, D, lam, o, stats):
    """Energy-minimising Newton at load factor lam, starting from D (fixed dofs already set).
    Returns (D, ok, message, rel).

    ``o.reuse`` > 0 reuses the factorisation of the (shifted) tangent for up to that many further
    iterations while the trust region cuts the step (refreshing it after a full Newton step, a poor
    model ratio or a non-descent direction).  It costs more than it saves on the strip (docs/solvers.md,
    section 2): the tangent changes too fast with the rotating geometry.  Default 0: a fresh
    factorisation every iteration.

    ``o.pcg_iterations`` > 0 (an inexact Newton step): after an iteration whose tangent factorised
    without a shift, the next Newton step is first sought by conjugate gradients on the *new*
    tangent, preconditioned by the last factor (linear.pcg), to a relative residual
    min(PCG_FORCING, sqrt(rel)) in at most that many CG iterations; only if CG does not get there
    (or meets non-positive curvature) is the new tangent factorised.  A CG iteration costs one
    back-substitution and one product with the tangent, ~1/9 of a factorisation at 18 432 dofs, and
    the trust region's model uses the step's own curvature p.K.p.  A CG step that needed more than
    half the iterations allowed is followed by a factorisation.  It pays where the tangent changes
    slowly from one iteration to the next: the fine level of a mesh sequence, which settles a
    prolonged coarse equilibrium (square-pedestal 48x16x4, load ~6, 2-3 rounds interleaved in one
    process: 35-39 factorisations instead of 59 on the fine mesh, the same 51 iterations, process
    CPU 10-19 % lower (medians 7.3-8.1 s against 9.0 s), the same state to 2e-8 of max|U|; 3 CG
    iterations at most: 49 factorisations, 13 %).  From the flat sheet, where the folds form, CG
    fails too often: 6 CG iterations cost 7 % more CPU on large-square-pedestal 45x15x4 (176
    iterations, 165 factorisations against 167 and 193) and 15 % more on circle-pedestal; hence off
    by default (``pcg_iterations = 0``) and switched on by solvers/sequence.py for the fine mesh."""
    f = sys.free
    sigma = 0.0
    e_first = None
    e_ratio = np.inf
    Pi, G = sys.potential_and_gradient(D, lam)
    rel = np.inf
    lu = None
    A = None
    since = 0
    refresh = True
    it = 0
    try_cg = o.pcg_iterations > 0 and sys.factorization in CHOLESKY_KINDS and f.size >= PCG_MIN_DOFS
    cg_next = False        # the last factor is unshifted and the last CG step (if any) was quick
    while True:
        g = G[f]
        stats["D_last"] = D
        ref = sys.reference_norm(G + lam * sys.P, lam)
        rel = float(np.linalg.norm(g)) / ref
        if not np.isfinite(rel):
            return D, False, "non-finite residual", rel
        _iteration_report(stats, rel, o)
        if _converged(rel, e_ratio if it else (0.0 if rel <= o.tol else np.inf), o):
            stats["criterion"] = "residual"
            return D, True, f"converged in {it} iterations", rel
        if it >= o.max_iter:
            break
        it += 1
        stats["iterations"] += 1
        inexact = False
        new_tangent = False
        if try_cg and cg_next and lu is not None and sigma == 0.0 and rel >= PCG_BELOW:
            # the last tangent is not needed any more: dropped before the new one is assembled,
            # so that two are never alive at once next to the factor (3.9 MB of the static
            # solver's memory peak on square-pedestal 48x16x4, docs/solvers.md section 5)
            A = None
            _, A = sys.free_tangent(D)
            new_tangent = True
            x, k, inexact, pKp = pcg(A.matvec(), g, lu.solve, min(PCG_FORCING, math.sqrt(rel)),
                                     o.pcg_iterations)
            sys.n_solves += k
            stats["cg_iterations"] = stats.get("cg_iterations", 0) + k
            cg_next = inexact and 2 * k <= o.pcg_iterations
        else:
            cg_next = True
        if inexact:
            fresh = False
            stats["cg_steps"] = stats.get("cg_steps", 0) + 1
        elif refresh or lu is None or since >= o.reuse:
            if not new_tangent:
                A = None
                _, A = sys.free_tangent(D)
            scale = np.abs(A.diagonal())
            scale[scale == 0.0] = max(float(scale.max(initial=0.0)), 1.0)
            try:
                lu, sigma, nf = _shifted_factor(sys.chol, A, scale,
                                                0.0 if sigma < 1e-7 else sigma / 10.0)
            except RuntimeError as exc:
                return D, False, f"tangent could not be factorised ({exc})", rel
            sys.n_factor += nf
            since = 0
            fresh = True
            stats["max_shift"] = max(stats["max_shift"], sigma)
            if sigma > 0.0:
                stats["shifted_iterations"] += 1
        else:
            since += 1
            fresh = False
        p = np.zeros_like(D)
        if inexact:
            p[f] = -x
        else:
            p[f] = -lu.solve(g)
            sys.n_solves += 1
        gp = float(np.dot(g, p[f]))
        if not np.isfinite(gp) or gp >= 0.0:
            if not fresh:
                refresh = True
                cg_next = False
                continue
            if gp == 0.0 and rel <= o.tol:
                stats["criterion"] = "residual"
                return D, True, f"converged in {it} iterations", rel
            return D, False, "no descent direction (non-finite or uphill Newton step)", rel
        pmax = sys.maxnorm(p)
        dmax = sys.maxnorm(D)
        if fresh and sigma == 0.0 and pmax <= o.disp_tol * dmax:
            # scale-free test: with a positive-definite (unshifted) K_t the Newton correction p is
            # the error of D to first order, and it is below disp_tol of the displacement
            D = D + p
            Pi, G = sys.potential_and_gradient(D, lam)
            rel = float(np.linalg.norm(G[f])) / sys.reference_norm(G + lam * sys.P, lam)
            stats["criterion"] = "displacement"
            stats["D_last"] = D
            return D, True, f"converged in {it} iterations (Newton correction {pmax / dmax:.1e} of |D|)", rel
        alpha = min(1.0, o.max_step / pmax) if pmax > 0 else 1.0
        acc = None
        if o.curvilinear and pmax > 0:
            # second-order ("geodesic acceleration") correction of the Newton step: with
            # r_pp = d^2 g(D + t p)/dt^2 at t = 0 (finite difference of one extra force evaluation),
            # acc = -K^-1 r_pp and the search runs along D + t p + t^2/2 acc.  A displacement-only
            # shell cannot rotate along a straight line without stretching; acc bends the step
            # onto the rotation arc and removes that spurious membrane strain.
            hs = min(1.0, 1e-2 * o.L_f / pmax)
            _, Gh = sys.potential_and_gradient(D + hs * p, lam)
            Kp = A @ p[f]
            rpp = 2.0 / (hs * hs) * (Gh[f] - g - hs * Kp)
            if np.all(np.isfinite(rpp)):
                acc = np.zeros_like(D)
                acc[f] = -lu.solve(rpp)
                sys.n_solves += 1     # back-substitution with the same factorisation
                if not (np.all(np.isfinite(acc)) and
                        0.5 * np.linalg.norm(acc) <= o.accel_ratio * np.linalg.norm(p)):
                    acc = None
        accepted = False
        rho = 1.0
        gnorm = float(np.linalg.norm(g))
        trust = o.line_search == "trust"
        if trust and pmax > 0:
            radius = max(stats.get("radius", o.radius0), o.radius_min)
            alpha = min(1.0, radius / pmax)
        for _ in range(40):
            Dt = D + alpha * p if acc is None else D + alpha * p + 0.5 * alpha * alpha * acc
            Pit, Gt = sys.potential_and_gradient(Dt, lam)
            if trust and np.isfinite(Pit):
                # 1-D trust region along the (shifted) Newton step, radius in max-norm:
                # model decrease m(a) = g.p (a - a^2/2) since p = -(K + sigma S)^-1 g (a CG step:
                # g.p a + p.K.p a^2/2 with its own curvature)
                dec = Pit - Pi
                pred = (gp * (alpha - 0.5 * alpha * alpha) if not inexact
                        else gp * alpha + 0.5 * alpha * alpha * pKp)
                rho = dec / pred if pred < 0.0 else 0.0
                step = alpha * pmax
                if abs(pred) <= _ROUNDOFF * _energy_scale(sys, D, lam, Pi):
                    # the decrease is below the round-off of Pi: judge the step by the residual.
                    # A step that lowers it is the local phase, where the radius must not hold
                    # Newton back: it grows as after a good model (frozen, it had square-on-disc
                    # 30x240 take 17 steps of alpha 0.25-0.66 at 5.3e-4 cm before the full ones)
                    accepted = bool(np.linalg.norm(Gt[f]) < gnorm or dec <= 0.0)
                    if not accepted:
                        alpha *= 0.25
                        continue
                    if alpha < 1.0:
                        radius = min(2.0 * radius, o.max_step)
                elif rho > 1e-4:
                    accepted = True
                    if rho < o.tr_shrink:
                        radius = 0.5 * step
                    elif rho > o.tr_grow and alpha < 1.0:
                        radius = min(2.0 * radius, o.max_step)
                else:
                    radius = 0.25 * step
                radius = max(radius, o.radius_min)
                stats["radius"] = radius
                if accepted:
                    if (sigma > 0.0 and alpha >= 1.0 and rho >= EXTEND_RHO and acc is None
                            and not inexact):
                        # Pi nearly linear along the shifted step: double it while Pi falls
                        # (energy evaluations only, no factorisation)
                        while 2.0 * alpha * pmax <= radius:
                            D2 = D + 2.0 * alpha * p
                            Pi2, G2 = sys.potential_and_gradient(D2, lam)
                            if not (np.isfinite(Pi2) and Pi2 < Pit):
                                break
                            alpha, Dt, Pit, Gt = 2.0 * alpha, D2, Pi2, G2
                            stats["extended_steps"] = stats.get("extended_steps", 0) + 1
                    break
                alpha = min(1.0, radius / pmax)
                continue
            if np.isfinite(Pit):
                dec = Pit - Pi
                if o.line_search == "none":
                    accepted = True
                elif dec <= o.armijo * alpha * gp:
                    accepted = True
                elif abs(alpha * gp) <= _ROUNDOFF * _energy_scale(sys, D, lam, Pi) and \
                        np.linalg.norm(Gt[f]) < gnorm:
                    # decrease below the round-off of Pi: accept on the residual instead
                    accepted = True
            if accepted:
                break
            # quadratic interpolation of Pi along p, safeguarded to [0.1, 0.5] alpha
            if np.isfinite(Pit):
                den = 2.0 * (Pit - Pi - alpha * gp)
                a_new = -gp * alpha * alpha / den if den > 0 else 0.5 * alpha
                alpha = min(max(a_new, 0.1 * alpha), 0.5 * alpha)
            else:
                alpha *= 0.25
        if not accepted:
            if (abs(gp) <= _ROUNDOFF * _energy_scale(sys, D, lam, Pi) and sigma == 0.0
                    and pmax <= 1e-6 * max(dmax, 1e-300)):
                # stagnation at round-off: neither the energy nor the residual can decrease any
                # more, the tangent is positive definite and the Newton correction is below 1e-6
                # of |D|: the residual has reached the round-off floor of the internal force
                stats["criterion"] = "round-off"
                return D, True, (f"converged at the round-off floor in {it} iterations (relative "
                                 f"residual {rel:.1e}, Newton correction {pmax / max(dmax, 1e-300):.1e} of |D|)"), rel
            return D, False, "line search failed (no decrease of the potential along the Newton step)", rel
        e_step = abs(alpha * gp)
        e_first = e_step if e_first is None else e_first
        e_ratio = e_step / e_first if e_first > 0 else 0.0
        # refresh the factorisation in the local phase (full step) or when the model was poor
        refresh = alpha >= 1.0 or (trust and rho < o.tr_shrink) or (not trust and alpha < 0.1)
        D, Pi, G = Dt, Pit, Gt
    return D, False, f"no convergence in {o.max_iter} iterations (relative residual {rel:.2e})", rel


def _paper_level(sys, D, lam, o, stats):
    """The paper's Eqs. (16)-(18) at load factor lam.  Returns (D, ok, message, rel)."""
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
        _iteration_report(stats, rel, o)
        if _converged(rel, e_ratio if it else (0.0 if rel <= o.tol else np.inf), o):
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
            return D, False, (f"singular tangent K_t at iteration {it} (relative residual {rel:.2e}); "
                              "the paper's scheme cannot proceed"), rel
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
    return D, False, (f"paper scheme stopped after {o.max_iter} iterations at relative residual "
                      f"{rel:.2e}{stall}"), rel


# ============================================================================ drivers
def _predictor(sys, D, lam0, lam1):
    """Linearised first guess for a load/prescribed increment lam0 -> lam1 (tangent at D)."""
    f, c = sys.free, sys.fixd
    dl = lam1 - lam0
    rhs = dl * sys.P[f]
    dc = (sys.prescribed_at(lam1) - sys.prescribed_at(lam0))[c]
    if c.size and np.any(dc):
        # the free-fixed coupling of K_t is needed: the full tangent
        F, K = sys.force_tangent(D)
        rhs = rhs - K[f][:, c] @ dc
        A = sys.Kff(K)
    else:
        F, A = sys.free_tangent(D)
    scale = np.abs(A.diagonal())
    scale[scale == 0.0] = 1.0
    lu, _, nf = _shifted_factor(sys.chol, A, scale, 0.0)
    sys.n_factor += nf
    sys.n_solves += 1
    Dp = sys.apply_prescribed(D, lam1)
    Dp[f] += lu.solve(rhs)
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


def _load_stepping(sys, D, factors, o, method, stats, progress, path, max_cutbacks, predictor,
                   increment, min_increment):
    """Reach every load factor in turn.  Method "paper" goes straight to each factor (as the paper
    does).  Method "newton" sub-steps adaptively: the increment starts at ``increment`` times the
    final factor, doubles after a step that converged in <= 4 iterations, halves after one that
    needed >= 12, and a failed step is retried with a quarter of the increment (at most
    ``max_cutbacks`` times in a row, never below ``min_increment``).  The start of every step is
    the lower-potential of two predictions: the tangent (linearised) predictor and the quadratic
    extrapolation of the last three converged states -- the latter follows the curved path of large
    rotations, which the linearised step cannot (see the module notes)."""
    level = _newton_level if method == "newton" else _paper_level
    lam = stats["load_factor"]
    final = factors[-1] if factors else lam
    scale = max(abs(final), 1e-300)
    hist = [(lam, D.copy())]
    msg = ""
    rel = np.nan
    dl = increment * scale
    for target in factors:
        cut = 0
        while True:
            if method == "newton":
                step = math.copysign(min(abs(dl), abs(target - lam)), target - lam)
                trial = target if abs(target - (lam + step)) <= 1e-12 * scale else lam + step
            else:
                trial = target
            cands = [sys.apply_prescribed(D, trial)]
            if method == "newton" and predictor and trial != lam:
                if len(hist) >= 2:
                    cands.append(sys.apply_prescribed(_extrapolate(hist, trial), trial))
                try:
                    cands.append(_predictor(sys, D, lam, trial))
                except RuntimeError:
                    pass
            D0 = cands[0]
            if len(cands) > 1:
                pis = [sys.potential_and_gradient(cd, trial)[0] for cd in cands]
                pis = [pi if np.isfinite(pi) and np.all(np.isfinite(cd)) else np.inf
                       for pi, cd in zip(pis, cands)]
                D0 = cands[int(np.argmin(pis))]
            it0 = stats["iterations"]
            stats.pop("rel0", None)
            lo, span = lam, trial - lam
            stats["on_iter"] = lambda q, r, lo=lo, span=span, t=trial: progress(
                min(1.0, abs(lo + q * span) / scale), f"load factor {t:.4g}, residual {r:.1e}")
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
                    dl *= 0.5
                if lam == target:
                    break
                continue
            if method != "newton" or cut >= max_cutbacks or abs(dl) * 0.25 < min_increment * scale:
                stats["final_relative_residual"] = rel
                return Dn, False, (f"load step to factor {trial:.4g} failed: {msg}"
                                   + (f" after {cut} cut-backs" if cut else "")), rel
            cut += 1
            stats["cutbacks"] += 1
            dl = 0.25 * (trial - lam)
    return D, True, msg, rel


def _arc_length(sys, D, lam_target, o, stats, progress, path, dlam0, max_steps, desired_iter=6,
                max_arc_step=None):
    """Crisfield's cylindrical arc-length method to load factor ``lam_target`` (module notes).
    ``max_arc_step``: the largest arc length, as a fraction of the linear path length to the target
    (|lam_target| |K_0^-1 P|), so a load-deflection curve can be drawn as finely as wanted."""
    f = sys.free
    Pf = sys.P[f]
    if not np.any(Pf):
        raise InputError("arc-length needs a non-zero load on the free dofs")
    if sys.presc_fn is not None or np.any(sys.presc):
        raise InputError("arc-length supports dead loads only (prescribed values must be zero)")
    lam = stats["load_factor"]
    F, A = sys.free_tangent(D)
    lu, _ = sys.ldl(A)
    sys.n_solves += 1
    sys.n_factor += 1
    dt = lu.solve(Pf)
    dl_ref = abs(lam_target) * float(np.linalg.norm(dt))
    dl_cap = np.inf if max_arc_step is None else float(max_arc_step) * dl_ref
    dl = min(abs(dlam0) * float(np.linalg.norm(dt)), dl_cap)
    dl_min = dl * 1e-6
    prev = None
    rel = np.nan
    for step in range(max_steps):
        F, A = sys.free_tangent(D)
        try:
            lu, neg = sys.ldl(A)
        except RuntimeError:
            return D, False, f"singular tangent at load factor {lam:.4g} (bifurcation point?)", rel
        if neg is not None:
            stats["max_negative_eigenvalues"] = max(stats.get("max_negative_eigenvalues", 0), neg)
        sys.n_solves += 1
        sys.n_factor += 1
        dt = lu.solve(Pf)
        s = 1.0 if prev is None else (1.0 if np.dot(prev, dt) >= 0.0 else -1.0)
        dlam = s * dl / float(np.linalg.norm(dt))
        dD = dlam * dt
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
            Dn, okn, msg, rel = _newton_level(sys, Dg, lam_target, o, stats)
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
        dl = min(dl * min(2.0, max(0.5, math.sqrt(desired_iter / max(it, 1)))), dl_cap)
    return D, False, f"arc-length stopped after {max_steps} steps at load factor {lam:.4g}", rel


def _free_length(mesh, fixed_mask):
    """Largest distance from a free node to the nearest node with any fixed dof (L_f of Eq. 18)."""
    X = mesh.nodes
    fixed_nodes = np.flatnonzero(np.asarray(fixed_mask).reshape(len(X), 6).any(axis=1))
    if fixed_nodes.size == 0 or fixed_nodes.size == len(X):
        return float(mesh.characteristic_length())
    Y = X[fixed_nodes]
    if len(X) * len(Y) > 2e7:
        from scipy.spatial import cKDTree
        d, _ = cKDTree(Y).query(X)
        return float(d.max())
    # direct distances: importing scipy.spatial costs more than this on the usual meshes
    d2 = ((X[:, None, :] - Y[None, :, :]) ** 2).sum(axis=-1).min(axis=1)
    return float(np.sqrt(d2.max()))


_DENSE_EIG = 600
"""Up to this many free dofs the smallest tangent eigenvalue is computed densely (LAPACK, exact):
faster than ARPACK there, and a small run does not import scipy.sparse.linalg at all."""


def _stability(sys, D, eig_max_dofs, known=None):
    """(positive_definite or None, min eigenvalue or None) of K_t on the free dofs at D.

    Positive definite = the Cholesky factorisation succeeds; otherwise the inertia of SuperLU's
    LDL^T says so (None when its pivoting was not symmetric).  The smallest eigenvalue comes from
    ARPACK in shift-invert mode: about 0 with the inverse applied by the Cholesky factor of A where
    A is positive definite, else about -s (s = 1e-10 of the mean diagonal) with ARPACK's own LU.
    ``known``: the free tangent at D whose positive-definite Cholesky factor ``sys.chol`` holds
    (the last test of ``_seek_minimum``): then neither the tangent nor its factor is formed again
    (a tangent and two factorisations saved at the end of every solve)."""
    chol = sys.chol if sys.factorization in CHOLESKY_KINDS else Cholesky()   # reuse its analysis
    if known is not None and chol is sys.chol:
        A, pd = known, True
    else:
        _, A = sys.free_tangent(D)
        pd = chol.factor(A)
    n = A.shape[0]
    s = 1e-10 * float(np.abs(A.diagonal()).mean())
    if not pd:
        try:
            _, neg = sys.ldl(A)
            pd = None if neg is None else bool(neg == 0)
        except RuntimeError:
            pd = False
    lmin = None
    if _DENSE_EIG < n <= eig_max_dofs:
        from scipy.sparse.linalg import LinearOperator, eigsh
        try:
            if pd:
                # A itself is positive definite: shift-invert about 0 with its Cholesky factor (A
                # is only an operator here: ARPACK's mode 3 applies nothing but OPinv)
                vals = eigsh(LinearOperator((n, n), matvec=lambda x: A @ x, dtype=float), k=1,
                             sigma=0.0, which="LM", return_eigenvectors=False, tol=1e-8,
                             maxiter=2000, OPinv=LinearOperator((n, n), matvec=chol.solve, dtype=float))
            else:
                vals = eigsh(as_csc(A), k=1, sigma=-s, which="LM", return_eigenvectors=False,
                             tol=1e-8, maxiter=2000)
            lmin = float(vals[0])
        except Exception:  # noqa: BLE001 - a diagnostic, never fatal
            lmin = None
    elif n <= _DENSE_EIG:
        lmin = float(np.linalg.eigvalsh(A.toarray()).min())
    return pd, lmin


# ============================================================================ saddles
def _lowest_mode(A, k_max=6):
    """(eigenvalue, eigenvector) of the most negative eigenvalue found of the symmetric CSC ``A``,
    or (None, None).  ARPACK in shift-invert mode about -s (s = 1e-10 of the mean |diagonal|; the
    LU of A + s I is indefinite-safe) with a few eigenpairs so that a small positive eigenvalue near
    the shift does not hide the negative one; LOBPCG (smallest algebraic) if ARPACK fails."""
    A = as_csc(A)
    n = A.shape[0]
    if n <= 200:
        w, V = np.linalg.eigh(A.toarray())
        return float(w[0]), V[:, 0]
    from scipy.sparse.linalg import eigsh
    s = 1e-10 * float(np.abs(A.diagonal()).mean())
    try:
        w, V = eigsh(A, k=min(k_max, n - 2), sigma=-s, which="LM", tol=1e-8, maxiter=5000)
        i = int(np.argmin(w))
        if w[i] < 0.0:
            return float(w[i]), V[:, i]
    except Exception:  # noqa: BLE001 - fall through to LOBPCG
        pass
    try:
        from scipy.sparse.linalg import lobpcg
        X = np.random.default_rng(0).standard_normal((n, 2))
        w, V = lobpcg(A, X, largest=False, tol=1e-8, maxiter=2000)
        i = int(np.argmin(w))
        return float(w[i]), V[:, i]
    except Exception:  # noqa: BLE001
        return None, None


def _leave_saddle(sys, D, lam, o, stats, step_frac):
    """One escape from a converged state D whose free-dof tangent is not positive definite.

    Finds the eigenvector v of the most negative eigenvalue, scales it to max|v| = 1 and evaluates
    the potential at D +- t v for t = step_frac L_f x (1, 1/4, 1/16, 1/64, 1/256): along v the
    energy falls as lam_min t^2 / 2 near D and the quartic terms turn it up again further out, so
    the lowest of these ten candidates (below Pi(D)) is kept.  Returns (D_new or None, lam_min)."""
    f = sys.free
    _, A = sys.free_tangent(D)
    lmin, v = _lowest_mode(A)
    if lmin is None:
        return None, None
    diag = float(np.abs(A.diagonal()).max())
    if lmin >= -1e-13 * diag:
        return None, lmin                  # singular, not indefinite: nothing to leave along
    v = v / sys.maxnorm(v, free=True)
    Pi0, _ = sys.potential_and_gradient(D, lam)
    best, Dbest = Pi0, None
    for t in step_frac * o.L_f * 0.25 ** np.arange(5):
        for sgn in (1.0, -1.0):
            Dt = D.copy()
            Dt[f] += sgn * t * v
            Pit, _ = sys.potential_and_gradient(Dt, lam)
            if np.isfinite(Pit) and Pit < best - _ROUNDOFF * _energy_scale(sys, D, lam, Pi0):
                best, Dbest = Pit, Dt
    return Dbest, lmin


def _seek_minimum(sys, D, lam, o, stats, max_escapes, step_frac, info_w):
    """Leave saddles until the free-dof tangent at the converged state D is positive definite
    (Cholesky succeeds), continuing the energy Newton from each escape.  Returns (D, ok, message);
    on success ``stats["stable_tangent"]`` is the free tangent at D, whose Cholesky factor
    ``sys.chol`` then holds (``_stability`` reports from it)."""
    stats.setdefault("saddle_eigenvalues", [])
    for _ in range(max_escapes + 1):
        _, A = sys.free_tangent(D)
        if sys.chol.factor(A):
            stats["stable_tangent"] = A
            return D, True, ""
        if len(stats["saddle_eigenvalues"]) >= max_escapes:
            break
        Dn, lmin = _leave_saddle(sys, D, lam, o, stats, step_frac)
        if Dn is None:
            if lmin is not None and lmin >= 0.0:
                return D, True, ""         # singular but not indefinite (a free mode): not a saddle
            return D, False, (f"the equilibrium found is a saddle (min eigenvalue {lmin:.3g}) and no "
                              "step along its negative-curvature direction lowers the energy")
        stats["saddle_eigenvalues"].append(float(lmin))
        info_w.append(f"static: left a saddle at load factor {lam:.4g} (tangent eigenvalue "
                      f"{lmin:.3g}) along its negative-curvature direction")
        stats.pop("rel0", None)
        stats["on_iter"] = None
        D, ok, msg, _ = _newton_level(sys, Dn, lam, o, stats)
        if not ok:
            return D, False, f"after leaving a saddle (eigenvalue {lmin:.3g}) Newton failed: {msg}"
    lm = stats["saddle_eigenvalues"][-1] if stats["saddle_eigenvalues"] else float("nan")
    return D, False, (f"no stable equilibrium reached: still a saddle after leaving "
                      f"{len(stats['saddle_eigenvalues'])} (last eigenvalue {lm:.3g}); raise "
                      "max_saddle_escapes or check the supports")


# ============================================================================ driver
@single_threaded_blas
def solve_static(model, fixed, loads, load_factors=None, method="newton", prescribed=None, *,
                 tol=1e-8, energy_tol=1e-12, disp_tol=1e-10, max_iter=None, c=1e-2, L_f=None,
                 max_step=None, U0=None, predictor=True, increment=1.0, min_increment=1e-6,
                 max_cutbacks=8, curvilinear=False, line_search="trust", trust_radius=0.02,
                 arc_length_initial=0.1, max_arc_step=None, max_arc_steps=500,
                 check_stability=True, eig_max_dofs=60000, max_saddle_escapes=5, saddle_step=0.05,
                 contact=None, contact_stiffness=None, factorization="auto", pcg_iterations=0,
                 progress=None) -> StaticResult:
    """Static equilibrium of ``model`` under dead ``loads`` and ``prescribed`` fixed dofs.

    Parameters
    ----------
    model : Model (energy, internal force, tangent; see solidshell.model)
    fixed : (N,6) bool, prescribed dofs;  loads : (N,6) dead nodal forces P [force]
    load_factors : increasing list of load factors (default [1.0]); each is a converged state in
        ``path``; loads and prescribed values are scaled by the factor.  For ``arclength`` only the
        last factor matters (the target) and the path is chosen by the method.
    method : "newton" (default) | "paper" (Eqs. 16-18) | "arclength" (Crisfield)
    prescribed : (N,6) values of the fixed dofs at load factor 1 (default 0: clamped), or a
        function load_factor -> (N,6) giving them along the path
    tol, energy_tol : relative residual and energy-norm tolerances (module notes)
    disp_tol : newton also stops when the Newton correction of a positive-definite, unshifted K_t
        is below disp_tol max|D| (scale-free; the error of D is then ~ disp_tol |D|)
    max_iter : iterations per load step (default 1000 for newton/arclength -- newton then cuts the
        step back --, 5000 for paper): well above the iterations the trust-region Newton needs on the
        paper's drapes, since a cap near that count cuts back a converging run (docs/solvers.md,
        section 8)
    c, L_f : the paper's multiplier constant (1e-3..1e-2) and free-hanging length (default: largest
        distance from a free node to the nearest fixed one)
    max_step : cap on max|dD| per Newton update [length] (default L_f / 2), method newton
    U0 : (N,6) starting state (default zero)
    predictor : predict the start of every new load level (newton; tangent or path extrapolation)
    increment, min_increment : first and smallest automatic sub-step, as fractions of the final
        load factor (newton sub-steps adaptively between the requested factors)
    max_cutbacks : consecutive cut-backs of a failed sub-step (newton)
    arc_length_initial : first arc-length step as a fraction of the target load factor
    max_arc_step : largest arc length as a fraction of the linear path length to the target
        (default: unlimited); e.g. 0.02 draws a load-deflection curve with >= 50 points
    check_stability : report positive_definite and min_tangent_eigenvalue of the final state, and
        leave saddles: a converged state whose free-dof tangent is not positive definite is left
        along the eigenvector of its most negative eigenvalue (both signs, the lower potential
        kept) and Newton continues to a minimum, at most ``max_saddle_escapes`` times
        (``saddle_step``: the largest escape step as a fraction of L_f).  A run that cannot reach a
        minimum returns converged=False.  info: saddles_left, saddle_eigenvalues, warnings.
    contact, contact_stiffness : rigid bodies (solidshell.contact) and the penalty [force/length]
    factorization : "auto" (default: "pardiso" where Intel MKL is installed and the system has at
        least linear.PARDISO_MIN_DOFS free dofs, else "cholmod"),
        "cholmod" (CHOLMOD supernodal Cholesky of the positive-definite tangents, SuperLU where
        the paper's scheme meets an indefinite one), "pardiso" (the same on MKL PARDISO's
        Cholesky, solvers/pardiso.py: about twice as fast; InputError without MKL) or "superlu"
        (SuperLU's LDL^T throughout, as before CHOLMOD was added; 3-5 times slower
        factorisations).  info["factorization"] names the one used
    pcg_iterations : newton: conjugate-gradient iterations on a new tangent, preconditioned by the
        last factorisation, tried before factorising it (an inexact Newton step; default 0: every
        iteration factorises; cholmod and pardiso only, >= PCG_MIN_DOFS free dofs; see
        ``_newton_level``).  The mesh sequencing sets 6 on the fine mesh, started from the
        prolonged coarse equilibrium
    progress : callback(fraction, text): called at the start and at every iteration

    info["status"]: "converged", "not_converged", "saddle" (converged to a saddle that could not be
    left) or "interrupted" (Ctrl-C: the last iterate is returned).  info["criterion"]: what ended
    the last Newton loop ("residual", "displacement", "round-off" or "zero load").
    """
    with kernel_threads(int(getattr(getattr(model, "mesh", None), "n_elements", 1 << 30))):
        return _solve_static(model, fixed, loads, load_factors, method, prescribed, tol=tol,
                             energy_tol=energy_tol, disp_tol=disp_tol, max_iter=max_iter, c=c, L_f=L_f,
                             max_step=max_step, U0=U0, predictor=predictor, increment=increment,
                             min_increment=min_increment, max_cutbacks=max_cutbacks,
                             curvilinear=curvilinear, line_search=line_search,
                             trust_radius=trust_radius, arc_length_initial=arc_length_initial,
                             max_arc_step=max_arc_step, max_arc_steps=max_arc_steps,
                             check_stability=check_stability, eig_max_dofs=eig_max_dofs,
                             max_saddle_escapes=max_saddle_escapes, saddle_step=saddle_step,
                             contact=contact, contact_stiffness=contact_stiffness,
                             factorization=factorization, pcg_iterations=pcg_iterations,
                             progress=progress)


def _solve_static(model, fixed, loads, load_factors, method, prescribed, *, tol, energy_tol,
                  disp_tol, max_iter, c, L_f, max_step, U0, predictor, increment, min_increment,
                  max_cutbacks, curvilinear, line_search, trust_radius, arc_length_initial,
                  max_arc_step, max_arc_steps, check_stability, eig_max_dofs, max_saddle_escapes,
                  saddle_step, contact, contact_stiffness, factorization, pcg_iterations, progress):
    """The body of :func:`solve_static` (which sets the kernel threads around it)."""
    t0 = time.perf_counter()
    user_progress = progress or no_progress
    shown = [0.0]

    def progress(fraction, text=""):
        # the bar never moves back (a cut-back or a saddle escape restarts a load step's count)
        shown[0] = max(shown[0], min(float(fraction), 1.0))
        user_progress(shown[0], text)

    progress(0.0, "static: setting up")
    if method not in METHODS:
        raise InputError(f"unknown static method {method!r}; choose one of: {', '.join(METHODS)}")
    n = model.n_nodes
    fixed = np.asarray(fixed, dtype=bool)
    if fixed.size != 6 * n:
        raise InputError(f"fixed must have shape ({n}, 6), got {fixed.shape}")
    loads = np.asarray(loads, dtype=float)
    if loads.size != 6 * n:
        raise InputError(f"loads must have shape ({n}, 6), got {loads.shape}")
    factors = [1.0] if load_factors is None else [float(x) for x in np.atleast_1d(load_factors)]
    if not factors or not all(np.isfinite(factors)):
        raise InputError("load_factors must be a non-empty list of finite numbers")
    factorization = resolve_factorization(factorization, int(np.count_nonzero(~fixed)))
    for name, v in (("tol", tol), ("energy_tol", energy_tol), ("disp_tol", disp_tol)):
        if not (math.isfinite(float(v)) and float(v) > 0.0):
            raise InputError(f"{name} must be a positive number, got {v!r}")
    if max_iter is not None and int(max_iter) < 1:
        raise InputError(f"max_iter must be an integer >= 1, got {max_iter!r}")
    sys = _System(model, fixed, loads, prescribed, contact, contact_stiffness, factorization)
    if sys.free.size == 0:
        raise InputError("every dof is fixed: nothing to solve")
    Lf = float(L_f) if L_f is not None else _free_length(model.mesh, fixed)
    o = _Opts(tol=float(tol), energy_tol=float(energy_tol), disp_tol=float(disp_tol),
              max_iter=int(max_iter if max_iter is not None else (5000 if method == "paper" else 1000)),
              c=float(c), L_f=Lf, max_step=float(max_step) if max_step is not None else 0.5 * Lf,
              curvilinear=bool(curvilinear), line_search=str(line_search),
              radius0=float(trust_radius) * Lf, radius_min=1e-9 * Lf,
              pcg_iterations=int(pcg_iterations))
    if not (o.c > 0.0):
        raise InputError(f"c must be positive, got {c!r}")
    D = np.zeros(6 * n) if U0 is None else np.asarray(U0, dtype=float).reshape(-1).copy()
    D = sys.apply_prescribed(D, 0.0)
    stats = dict(iterations=0, load_steps=0, cutbacks=0, load_factor=0.0, shifted_iterations=0,
                 max_shift=0.0, min_multiplier=1.0, final_relative_residual=np.nan, D_last=D)
    path = []
    warnings = []
    status = None
    zero = (not np.any(sys.P) and sys.presc_fn is None and not np.any(sys.presc)
            and not np.any(D))
    try:
        if zero and not np.any(sys.potential_and_gradient(D, factors[-1])[1][sys.free]):
            # no load, nothing prescribed, no contact force at the start: the unloaded state is
            # the exact equilibrium (and the lowest energy, zero); no iteration is needed
            ok, msg, rel = True, "no load: the unloaded state", 0.0
            stats["load_factor"] = factors[-1]
            stats["criterion"] = "zero load"
            path.append((factors[-1], D.reshape(n, 6).copy()))
        elif method == "arclength":
            D, ok, msg, rel = _arc_length(sys, D, factors[-1], o, stats, progress, path,
                                          arc_length_initial * factors[-1], max_arc_steps,
                                          max_arc_step=max_arc_step)
        else:
            D, ok, msg, rel = _load_stepping(sys, D, factors, o, method, stats, progress, path,
                                             max_cutbacks, predictor, increment, min_increment)
        if ok and check_stability and max_saddle_escapes > 0 and not zero:
            lam = stats["load_factor"]
            progress(0.97, "static: checking stability")
            D2, ok2, msg2 = _seek_minimum(sys, sys.apply_prescribed(D, lam), lam, o, stats,
                                          int(max_saddle_escapes), float(saddle_step), warnings)
            D = D2
            if stats.get("saddle_eigenvalues"):
                Pi2, G2 = sys.potential_and_gradient(D, lam)
                rel = float(np.linalg.norm(G2[sys.free])) / sys.reference_norm(G2 + lam * sys.P, lam)
                if path:
                    path[-1] = (lam, D.reshape(n, 6).copy())
            if not ok2:
                ok, msg, status = False, msg2, "saddle"
    except KeyboardInterrupt:
        D = np.asarray(stats.get("D_last", D)).copy()
        ok, msg, rel, status = False, "interrupted (Ctrl-C): the last iterate is returned", np.nan, "interrupted"
        warnings.append("static: interrupted by the user; the state is the last iterate, not an equilibrium")
    except (FloatingPointError, np.linalg.LinAlgError, RuntimeError) as exc:
        ok, msg, rel = False, f"{type(exc).__name__}: {exc}", np.nan
    if ok:
        msg = (f"{method}: converged to load factor {stats['load_factor']:.4g} in "
               f"{stats['load_steps']} step(s), {stats['iterations']} iterations")
        if stats.get("saddle_eigenvalues"):
            msg += f", {len(stats['saddle_eigenvalues'])} saddle(s) left"
        if stats.get("criterion") == "zero load":
            msg = f"{method}: no load and nothing prescribed: the unloaded state, 0 iterations"
        status = "converged"
    else:
        msg = f"{method}: {msg}"
        status = status or "not_converged"
    info = {
        "solver": "static",
        "method": method,
        "converged": bool(ok),
        "status": status,
        "criterion": stats.get("criterion") if ok else None,
        "iterations": int(stats["iterations"]),
        "linear_solves": int(sys.n_solves),
        "factorizations": int(sys.n_factor),
        "factorization": factorization,
        "tangent_assemblies": int(sys.n_tangent),
        "energy_evaluations": int(sys.n_energy),
        "load_steps": int(stats["load_steps"]),
        "load_factor": float(stats["load_factor"]),
        "cutbacks": int(stats["cutbacks"]),
        "final_relative_residual": float(rel) if np.isfinite(rel) else None,
        "free_length": Lf,
        "saddles_left": len(stats.get("saddle_eigenvalues", [])),
        "saddle_eigenvalues": list(stats.get("saddle_eigenvalues", [])),
        "warnings": warnings,
    }
    if method == "newton":
        info["shifted_iterations"] = int(stats["shifted_iterations"])
        info["max_tangent_shift"] = float(stats["max_shift"])
        # doublings of shifted steps along which Pi was nearly linear (EXTEND_RHO)
        info["extended_steps"] = int(stats.get("extended_steps", 0))
        # Newton steps found by preconditioned CG instead of a factorisation (pcg_iterations)
        info["cg_steps"] = int(stats.get("cg_steps", 0))
        info["cg_iterations"] = int(stats.get("cg_iterations", 0))
    if method == "arclength":
        # > 1 means the path crossed a bifurcation (a second eigenvalue through zero): there is no
        # branch switching, and the path may turn onto another branch there
        info["max_negative_eigenvalues_on_path"] = int(stats.get("max_negative_eigenvalues", 0))
    if method == "paper":
        info["c"] = o.c
        info["min_multiplier"] = float(stats["min_multiplier"])
    if sys.contact:
        info["contact_stiffness"] = sys.k_contact
    if check_stability and np.all(np.isfinite(D)) and status != "interrupted":
        lam = stats["load_factor"]
        try:
            pd, lmin = _stability(sys, sys.apply_prescribed(D, lam) if ok else D, eig_max_dofs,
                                  known=stats.get("stable_tangent") if ok else None)
        except KeyboardInterrupt:
            pd, lmin = None, None
        info["positive_definite"] = pd
        info["min_tangent_eigenvalue"] = lmin
    info["wall_time_s"] = time.perf_counter() - t0
    progress(1.0, "static: done" if ok else "static: stopped")
    return StaticResult(U=D.reshape(n, 6).copy(), converged=bool(ok), message=msg, info=info, path=path)


# ============================================================================ registry entry
def _other_solver_keys() -> set:
    """Setting names of the other registered solvers (explicit, relax): ``run`` ignores them so that
    one settings dict can serve several solvers."""
    from . import KINDS

    return {k for name, kind in KINDS.items() if name != "static" for k in kind.settings_model().model_fields}


def run(problem, settings: dict | None = None, progress=None) -> SolveResult:
    """Registry entry ``"static"``: solve a :class:`~solidshell.problem.Problem`.

    ``settings`` is parsed by :class:`solidshell.solvers.static_settings.StaticSettings` (every key
    typed and range-checked; a bad value or an unknown key is one InputError line naming it):
    method, tol, energy_tol, disp_tol, max_iter, load_steps (n -> factors 1/n, ..., 1) or
    load_factors, c, L_f, max_step, predictor, increment, min_increment, max_cutbacks,
    line_search, trust_radius, curvilinear, arc_length_initial, max_arc_step, max_arc_steps,
    check_stability, eig_max_dofs, max_saddle_escapes, saddle_step, contact_stiffness,
    factorization.  Settings of the other registered solvers (explicit, relax: e.g. ``t_end``) are
    ignored, so one settings dict can serve several solvers.
    """
    from ..settings import parse
    from .static_settings import StaticSettings
    settings = dict(settings or {})
    unknown = [k for k in settings if k not in StaticSettings.model_fields]
    if unknown:
        other = _other_solver_keys()
        settings = {k: v for k, v in settings.items() if k in StaticSettings.model_fields or k not in other}
    s = parse(StaticSettings, settings, "solver.static").solver_kwargs()
    res = solve_static(problem.model, problem.fixed, problem.loads, prescribed=problem.prescribed,
                       contact=problem.contact, progress=progress, **s)
    return SolveResult(U=res.U, converged=res.converged, message=res.message, info=res.info,
                       frames=res.path)
