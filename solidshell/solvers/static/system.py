"""The discrete system of the static solver: the potential, its gradient and tangent on the free
dofs (with the rigid contact bodies), the factorisations, the convergence measures, and the
stability of a converged state (the saddle check and escape, the smallest tangent eigenvalue).

Equilibrium (Eq. 16): F(D) = P on the free dofs, with D the global displacements [U_o | U_n] per
node, F = dU/dD the internal force (Eq. 9) and P the dead external loads.  Because P is dead,
equilibrium is a stationary point of the total potential Pi(D) = U(D) - P.D, and a *stable*
equilibrium is a minimum of Pi: a positive-definite K_t on the free dofs.

Convergence (all methods, ``converged``): relative residual |P - F|_free / max(|P|, |reactions|,
|F_free|) <= ``tol`` and energy norm |dD . (P - F)| of the last update <= ``energy_tol`` times that
of the first iteration of the step.  Step sizes (trust radius, max_step, the paper's max|dD|, the
displacement test) are measured in length: a director dof (unit-free) counts as the face motion
h/2 |dU_n| (``System.maxnorm``).  With the strains formed in the displacement form of Eq. (3)
(elements/core.py), the iteration is then the same in any consistent unit system and at any load
level (verification/static_units.py: identical iteration counts in gf-cm, N-m and N-mm from 1e-8
to 1 of the working load; <= 3 iterations in the linear regime).

Stability (``check_stability``): the final state must be a minimum of Pi.  If the Cholesky
factorisation of the free-dof K_t fails, the state is a saddle: ``seek_minimum`` leaves it along
the eigenvector of the most negative eigenvalue (ARPACK shift-invert, LOBPCG fallback; both signs
and five step lengths up to ``saddle_step`` L_f tried, the lowest potential kept) and continues
Newton from there, at most ``max_saddle_escapes`` times; each escape is recorded (``saddles_left``,
``saddle_eigenvalues``, a line in ``warnings``), and a run that cannot reach a minimum returns
converged=False with status "saddle".  ``stability`` reports the final state: positive_definite
(inertia of K_t on the free dofs) and min_tangent_eigenvalue (eigsh, shift-invert, when the
problem has at most ``eig_max_dofs`` free dofs).

Displacement control: the fixed dofs take ``load_factor * prescribed``; dead loads are
``load_factor * loads``.  ``prescribed`` may also be a function ``load_factor -> (N,6)`` for
non-proportional paths (e.g. a director rotated by an angle proportional to the load factor:
U_n = R(lambda phi) X_n - X_n, which a linear scaling of one array would shrink).

Rigid contact bodies (``contact=`` or ``Problem.contact``) enter as the penalty energy
1/2 k p^2 on the mid-surface nodes and face points (frictionless; tangent its exact Hessian
k (n n^T - p grad n), contact.normal_gradient); k
defaults to ``contact_stiffness`` = CONTACT_STIFFNESS_FACTOR * (heaviest nodal dead load) / h, and
the driver's augmented-Lagrangian updates (contact_augment.py) take the rest of the penetration.
"""

from __future__ import annotations

import math

import numpy as np

from ... import contact_augment as augment
from ...contact import normal_gradient
from ...contact_faces import DEFAULT_FACE_POINTS, FacePoints, contact_terms, spacing
from ...contact_paths import free_fraction
from ...contact_self import CCD_SAFETY
from ...errors import InputError
from ...model import Model
from ..linear import CHOLESKY_KINDS, Cholesky, LowerCSC, arpack_start, as_csc, ldl_inertia, positive_definite_factor

__all__ = [
    "ROUNDOFF",
    "System",
    "converged",
    "energy_scale",
    "free_length",
    "iteration_report",
    "seek_minimum",
    "shifted_factor",
    "stability",
]


CONTACT_STIFFNESS_FACTOR = 1e4
"""Default penalty k = factor x (heaviest nodal dead load) / h: a node carrying its own weight sinks
1e-4 h.  Over pedestal edges and in folds the contact carries many nodes' weight; 1e4 against the
former 1e3 measured on square-on-disc 30x240 (docs/contact.md): flat start 249 against 255 Newton
iterations, twelve-fold start 162 against 544 (the softer spring needs 10 augmented-Lagrangian
updates where the stiffer needs one)."""


# ============================================================================ the discrete system
class System:
    """Model + constraints + loads + contact, with counters.  Works on full flat vectors D (6N)."""

    def __init__(
        self,
        model,
        fixed,
        loads,
        prescribed,
        contact,
        contact_stiffness,
        factorization,
        face_points=DEFAULT_FACE_POINTS,
        self_contact=False,
    ):
        # factorization: a resolved kind (linear.resolve_factorization); face_points: per element edge
        # (contact_faces.py, 0: contact on the nodes only); self_contact: the barrier between the
        # sheet's layers (contact_self.py; a shell Model only)
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
            self.presc = (
                np.zeros(6 * n)
                if prescribed is None
                else np.asarray(prescribed, dtype=float).reshape(n, 6).ravel().copy()
            )
        if not (np.all(np.isfinite(self.P)) and np.all(np.isfinite(self.presc))):
            raise InputError("loads and prescribed values must be finite")
        self.contact = list(contact or [])
        self.body_cuts = 0
        self.k_contact = 0.0
        if self.contact:
            if contact_stiffness is None:
                h = float(model.material.thickness)
                w = np.abs(self.P.reshape(n, 6)[:, :3]).max()
                contact_stiffness = CONTACT_STIFFNESS_FACTOR * max(w, 1e-12) / h
            self.k_contact = float(contact_stiffness)
        self.faces = None
        self.shift_n, self.shift_q = augment.NONE, augment.NONE  # contact_augment.py; set by the driver
        if self.contact and isinstance(model, Model) and face_points:
            sp = spacing(self.contact, model.material.thickness)
            self.faces = FacePoints(model.mesh, model.nodal_areas(), face_points, sp)
            self.k_faces = self.faces.stiffness(np.full(n, self.k_contact))
        self.selfc = None
        if self_contact:
            if not isinstance(model, Model):
                raise InputError("self_contact needs a shell Model (its mesh's triangles)")
            from ...contact_self import SelfContact

            w = float(np.abs(self.P.reshape(n, 6)[:, :3]).max())
            self.selfc = SelfContact(model.mesh, float(model.material.thickness), max(w, 1e-12))
        self.n_energy = 0
        self.n_tangent = 0
        self.n_solves = 0
        self.n_factor = 0
        # positive-definite factorisations: PARDISO or CHOLMOD (the symbolic analysis shared by
        # every tangent of this solve) or, for comparison, SuperLU's LDL^T
        self.factorization = factorization
        self.chol = positive_definite_factor(factorization)
        self._ldl = None
        self._lower = None  # the free-dof lower-triangle pattern (free_tangent)
        self._kff_cache = None  # the gather map of Kff
        # step sizes are measured in length: a director dof (unit-free, Eq. 1) counts as the motion
        # h/2 |dU_n| of the shell's faces, so that every step control is the same in any unit
        # system (a max over raw dofs would mix cm and 1 and change with the length unit)
        h = float(model.material.thickness)
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

    # -- contact (mid-surface nodes and face points; forces on U_o only)
    def positions(self, D) -> np.ndarray:
        """(N, 3) the mid-surface nodes' positions X + u at the full vector D (6N,) [length]."""
        return self.model.mesh.nodes + np.asarray(D, dtype=float).reshape(self.n, 6)[:, :3]

    def _contact(self, D, want_tangent=False):
        """(penalty energy, its gradient (6N,), tangent blocks, face entries): the blocks are a list
        of (active nodes (A,), k (n n^T - p grad n) (A,3,3)) per body, the face entries (rows, cols,
        vals) of the face points' tangent in the full 6N x 6N numbering (contact_faces.contact_terms);
        both None without ``want_tangent``.  Penetrations count from each body's offset raised by the
        augmented-Lagrangian shifts (contact_augment.py)."""
        x = self.positions(D)
        f = np.zeros((self.n, 6))
        e = 0.0
        blocks = [] if want_tangent else None
        k = self.k_contact
        for j, b in enumerate(self.contact):
            gap, nrm = b.penetration(x)
            p = -gap + (self.shift_n[j] if self.shift_n.size else 0.0)
            act = np.flatnonzero(p > 0.0)
            if not act.size:
                continue
            e += 0.5 * k * float(np.sum(p[act] ** 2))  # penalty energy k p^2 / 2, force k p n
            f[act, :3] -= (k * p[act])[:, None] * nrm[act]  # its gradient is -k p n
            if want_tangent:
                # the exact Hessian k (n n^T - p grad n) (contact.normal_gradient)
                J = normal_gradient(b, x[act])
                blocks.append((act, k * (nrm[act][:, :, None] * nrm[act][:, None, :] - p[act][:, None, None] * J)))
        entries = None
        if self.faces is not None:
            ef, Ff, entries = contact_terms(self.faces, self.contact, x, self.k_faces, want_tangent, self.shift_q)
            e += ef
            f[:, :3] += Ff
        return e, f.ravel(), blocks, entries

    def augment(self, D):
        """One Uzawa update of the contact at D (contact_augment.update): (deepest raw penetration
        [length], node shifts, face-point shifts); the caller sets ``shift_n``, ``shift_q``."""
        x = self.positions(D)
        xq = self.faces.positions(x) if self.faces is not None else np.zeros((0, 3))
        return augment.update(self.contact, x, xq, self.shift_n, self.shift_q)

    def _contact_matrix(self, blocks, entries=None):
        """The contact tangent blocks (and face entries) as a (6N, 6N) CSR matrix, or None."""
        blocks = list(blocks or [])
        if not blocks and not (entries and entries[0]):
            return None
        import scipy.sparse as sp  # scipy.sparse only where a 6N x 6N matrix is formed: a small

        # run on the free-tangent path does not import it at all
        rows, cols, vals = [], [], []
        for act, nn in blocks:
            base = 6 * act
            r = (base[:, None, None] + np.arange(3)[None, :, None]).repeat(3, axis=2)
            c = (base[:, None, None] + np.arange(3)[None, None, :]).repeat(3, axis=1)
            rows.append(r.ravel())
            cols.append(c.ravel())
            vals.append(nn.ravel())
        if entries:
            rows += entries[0]
            cols += entries[1]
            vals += entries[2]
        m = 6 * self.n
        return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, m))

    # -- evaluations
    def potential_and_gradient(self, D, lam):
        """(Pi, dPi/dD full vector) at D; Pi = U(D) - lam P.D (+ contact)."""
        self.n_energy += 1
        U = self.U(D)
        W, F = self.model.energy_and_force(U)
        F = np.asarray(F, dtype=float).ravel()
        if self.contact:
            ec, fc, _, _ = self._contact(D)
            W += ec
            F = F + fc
        if self.selfc is not None:
            es, fs, _ = self.selfc.energy_gradient(D)
            W += es
            F = F + fs
        return float(W) - lam * float(np.dot(self.P, D)), F - lam * self.P

    def step_cut(self, D0, D1) -> float:
        """The factor a trial step D0 -> D1 is cut by so that no two layers cross or come closer
        than the self-contact's minimum distance (contact_self.SelfContact.cut) and no node's path
        passes into a contact body deeper than the thickness h (contact_paths.free_fraction), with
        CCD_SAFETY to spare in both; 1.0 for a free step."""
        c = 1.0 if self.selfc is None else self.selfc.cut(D0, D1)
        if self.contact:
            dU = (np.asarray(D1) - np.asarray(D0)).reshape(self.n, 6)[:, :3]
            h = float(self.model.material.thickness)  # the depth a node's path may not pass into a body
            t = free_fraction(self.contact, self.positions(D0), dU, h)
            if t < 1.0:
                self.body_cuts += 1
                c = min(c, CCD_SAFETY * t)
        return c

    def force_tangent(self, D, self_terms=None):
        """(F internal (+contact) full vector, K (6N,6N) CSR).  ``self_terms``: the self-contact's
        energy_gradient(D, want_tangent=True) when the caller has it already."""
        import scipy.sparse as sp

        self.n_tangent += 1
        F, K = self.model.force_and_tangent(self.U(D))
        F = np.asarray(F, dtype=float).ravel()
        K = sp.csr_matrix(K)
        if self.contact:
            _, fc, blocks, entries = self._contact(D, want_tangent=True)
            F = F + fc
            Kc = self._contact_matrix(blocks, entries)
            if Kc is not None:
                K = K + Kc
        if self.selfc is not None:
            _, fs, entries = self_terms or self.selfc.energy_gradient(D, want_tangent=True)
            F = F + fs
            Ks = self._contact_matrix([], entries)
            if Ks is not None:
                K = K + Ks
        return F, K

    def free_tangent(self, D):
        """(F internal (+contact) full vector, K_t on the free dofs as a :class:`LowerCSC`).

        The tangent is assembled straight into the lower triangle of its free-dof pattern, the
        form CHOLMOD factorises (assembly.FreeLowerPattern): no 6N x 6N matrix, no restriction
        and no conversion per iteration.  Same values, to the last bit, as ``Kff(force_tangent)``.
        With layers in contact the self-contact barrier couples nodes of elements far apart, outside
        that pattern: then the 6N x 6N path, its pattern changing with the collision set."""
        if self.selfc is not None:
            terms = self.selfc.energy_gradient(D, want_tangent=True)
            if terms[2][0]:  # layers in contact
                F, K = self.force_tangent(D, terms)
                return F, LowerCSC.from_symmetric(self.Kff(K))
        self.n_tangent += 1
        lw = self._lower
        if lw is None:
            lw = self._lower = self.model.free_lower_pattern(self.free)
        F, data = self.model.force_and_free_tangent(self.U(D), lw)
        F = np.asarray(F, dtype=float).ravel()
        if self.contact:
            _, fc, blocks, entries = self._contact(D, want_tangent=True)
            F = F + fc
            for act, nn in blocks:
                pos = lw.node_pos[act]
                m = pos >= 0
                np.add.at(data, pos[m], nn[m])
            self._add_entries(lw, data, entries)
        return F, LowerCSC(lw.indptr, lw.indices, data, lw.diag_pos, lw)

    @staticmethod
    def _add_entries(lw, data, entries) -> None:
        """Add tangent entries (rows, cols, vals) of the 6N x 6N numbering into the free lower
        pattern's data (entries off the pattern -- fixed dofs, the upper triangle -- dropped)."""
        if entries and entries[0]:
            r, c, v = (np.concatenate(a) for a in entries)
            pos, ok = lw.entry_positions(r, c)
            np.add.at(data, pos, v[ok])

    def ldl(self, A):
        """(solver, number of negative eigenvalues or None) of the symmetric free tangent ``A``:
        PARDISO's LDL^T (pardiso.PardisoLDL, its analysis kept for the pattern) where the
        factorisation is "pardiso" and no pivot had to be perturbed, else SuperLU's
        (linear.ldl_inertia; RuntimeError when singular).  The solver holds until the next call."""
        if self.factorization == "pardiso":
            if self._ldl is None:
                from ..pardiso import PardisoLDL

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
        return max(
            float(np.linalg.norm(lam * self.P)), float(np.linalg.norm(r)), float(np.linalg.norm(F[self.free])), 1e-300
        )

    def Kff(self, K):
        """K restricted to the free dofs, CSC.  The tangents of a solve share one sparsity pattern,
        so the restriction is a gather of K.data through a map built once per pattern (slicing
        and converting ~1e6 entries every iteration cost ~10 % of a drape solve); K is symmetric,
        so the CSR arrays of the restriction serve as its CSC arrays."""
        import scipy.sparse as sp

        f = self.free
        K = K.tocsr()
        cache = self._kff_cache
        if cache is None or not np.array_equal(cache[0], K.indptr) or not np.array_equal(cache[1], K.indices):
            probe = sp.csr_matrix((np.arange(1, K.nnz + 1, dtype=float), K.indices, K.indptr), shape=K.shape)[f][:, f]
            probe.sort_indices()
            cache = (
                K.indptr.copy(),
                K.indices.copy(),
                probe.data.astype(np.int64) - 1,
                probe.indices.copy(),
                probe.indptr.copy(),
            )
            self._kff_cache = cache
        _, _, gather, indices, indptr = cache
        n = f.size
        return sp.csc_matrix((K.data[gather], indices, indptr), shape=(n, n))


# ============================================================================ factorisation
def shifted_factor(chol, A, scale, sigma0, sigma_max=1e12):
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


# ============================================================================ measures
def converged(rel, e_ratio, o):
    """The tolerances of ``o`` (LevelOptions) met: relative residual and energy-norm ratio."""
    return rel <= o.tol and e_ratio <= o.energy_tol


ROUNDOFF = 1e-11
"""An energy change below this fraction of the energy scale |Pi| + |lam P.D| is round-off: Pi is a
sum of terms of that size, each exact to ~1e-16, over up to ~1e5 elements."""


def energy_scale(sys, D, lam, Pi):
    """|Pi| + |lam P.D|: the size of the terms whose difference Pi is (Pi itself may be ~0)."""
    return abs(Pi) + abs(lam * float(np.dot(sys.P, D))) + 1e-300


def iteration_report(stats, rel, o):
    """Progress within a load step: the fraction of the way (in log of the residual) from the first
    residual of the step to ``tol``, kept monotone, handed to the driver's callback."""
    cb = stats.get("on_iter")
    if cb is None or not np.isfinite(rel) or rel <= 0.0:
        return
    r0 = stats.setdefault("rel0", rel)
    q = 0.0 if r0 <= o.tol else math.log(max(r0 / rel, 1.0)) / math.log(r0 / o.tol)
    cb(min(max(q, 0.0), 1.0), rel)


def free_length(mesh, fixed_mask):
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


# ============================================================================ stability
_DENSE_EIG = 600
"""Up to this many free dofs the smallest tangent eigenvalue is computed densely (LAPACK, exact):
faster than ARPACK there, and a small run does not import scipy.sparse.linalg at all."""


def stability(sys, D, eig_max_dofs, known=None):
    """(positive_definite or None, min eigenvalue or None) of K_t on the free dofs at D.

    Positive definite = the Cholesky factorisation succeeds; otherwise the inertia of SuperLU's
    LDL^T says so (None when its pivoting was not symmetric).  The smallest eigenvalue comes from
    ARPACK in shift-invert mode: about 0 with the inverse applied by the Cholesky factor of A where
    A is positive definite, else about -s (s = 1e-10 of the mean diagonal) with ARPACK's own LU.
    ``known``: the free tangent at D whose positive-definite Cholesky factor ``sys.chol`` holds
    (the last test of ``seek_minimum``): then neither the tangent nor its factor is formed again
    (a tangent and two factorisations saved at the end of every solve)."""
    chol = sys.chol if sys.factorization in CHOLESKY_KINDS else Cholesky()  # reuse its analysis
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
                vals = eigsh(
                    LinearOperator((n, n), matvec=lambda x: A @ x, dtype=float),
                    k=1,
                    sigma=0.0,
                    which="LM",
                    return_eigenvectors=False,
                    tol=1e-8,
                    v0=arpack_start(n),
                    maxiter=2000,
                    OPinv=LinearOperator((n, n), matvec=chol.solve, dtype=float),
                )
            else:
                vals = eigsh(
                    as_csc(A),
                    k=1,
                    sigma=-s,
                    which="LM",
                    return_eigenvectors=False,
                    tol=1e-8,
                    maxiter=2000,
                    v0=arpack_start(n),
                )
            lmin = float(vals[0])
        except Exception:  # noqa: BLE001 - a diagnostic, never fatal
            lmin = None
    elif n <= _DENSE_EIG:
        lmin = float(np.linalg.eigvalsh(A.toarray()).min())
    return pd, lmin


SINGULAR_EIGENVALUE = 1e-13
"""A smallest tangent eigenvalue above -SINGULAR_EIGENVALUE x the largest diagonal entry is zero to
round-off (``_leave_saddle``): the state is singular, not a saddle."""


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
        w, V = eigsh(A, k=min(k_max, n - 2), sigma=-s, which="LM", tol=1e-8, maxiter=5000, v0=arpack_start(n))
        i = int(np.argmin(w))
        # ARPACK's answer stands whatever its sign: a zero eigenvalue (a free mode) is one, and
        # LOBPCG, asked instead, does not converge on it and returns an eigenvalue of any sign
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


def _leave_saddle(sys, D, lam, L_f, step_frac):
    """One escape from a converged state D whose free-dof tangent is not positive definite.

    Finds the eigenvector v of the most negative eigenvalue, scales it to max|v| = 1 and evaluates
    the potential at D +- t v for t = step_frac L_f x (1, 1/4, 1/16, 1/64, 1/256): along v the
    energy falls as lam_min t^2 / 2 near D and the quartic terms turn it up again further out, so
    the lowest of these ten candidates (below Pi(D)) is kept.  Returns (D_new or None, lam_min,
    indefinite): ``indefinite`` is False when lam_min is zero to round-off (above -SINGULAR_EIGENVALUE
    times the largest diagonal entry): a free mode, nothing to leave along -- such as the turn of a
    sheet held at one node over an axisymmetric body, which the exact contact Hessian has as a zero
    eigenvalue."""
    f = sys.free
    _, A = sys.free_tangent(D)
    lmin, v = _lowest_mode(A)
    if lmin is None:
        return None, None, True
    diag = float(np.abs(A.diagonal()).max())
    if lmin >= -SINGULAR_EIGENVALUE * diag:
        return None, lmin, False  # singular, not indefinite: nothing to leave along
    v = v / sys.maxnorm(v, free=True)
    Pi0, _ = sys.potential_and_gradient(D, lam)
    best, Dbest = Pi0, None
    for t in step_frac * L_f * 0.25 ** np.arange(5):
        for sgn in (1.0, -1.0):
            Dt = D.copy()
            Dt[f] += sgn * t * v
            if sys.step_cut(D, Dt) < 1.0:
                continue  # the escape would take layers through each other or a node through a body
            Pit, _ = sys.potential_and_gradient(Dt, lam)
            if np.isfinite(Pit) and Pit < best - ROUNDOFF * energy_scale(sys, D, lam, Pi0):
                best, Dbest = Pit, Dt
    return Dbest, lmin, True


def seek_minimum(sys, D, lam, o, stats, settle, max_escapes, step_frac, warnings):
    """Leave saddles until the free-dof tangent at the converged state D is positive definite
    (Cholesky succeeds), continuing from each escape with ``settle`` (newton.newton_level, called as
    the load levels are).  At most ``max_escapes`` escapes, each of at most ``step_frac`` L_f; a
    line per escape is appended to ``warnings``.  Returns (D, ok, message); on success
    ``stats["stable_tangent"]`` is the free tangent at D, whose Cholesky factor ``sys.chol`` then
    holds (``stability`` reports from it)."""
    stats.setdefault("saddle_eigenvalues", [])
    for _ in range(max_escapes + 1):
        _, A = sys.free_tangent(D)
        if sys.chol.factor(A):
            stats["stable_tangent"] = A
            return D, True, ""
        if len(stats["saddle_eigenvalues"]) >= max_escapes:
            break
        Dn, lmin, indefinite = _leave_saddle(sys, D, lam, o.L_f, step_frac)
        if Dn is None:
            if not indefinite:
                return D, True, ""  # singular but not indefinite (a free mode): not a saddle
            return (
                D,
                False,
                (
                    f"the equilibrium found is a saddle (min eigenvalue {lmin:.3g}) and no "
                    "step along its negative-curvature direction lowers the energy"
                ),
            )
        stats["saddle_eigenvalues"].append(float(lmin))
        warnings.append(
            f"static: left a saddle at load factor {lam:.4g} (tangent eigenvalue "
            f"{lmin:.3g}) along its negative-curvature direction"
        )
        stats.pop("rel0", None)
        stats["on_iter"] = None
        D, ok, msg, _ = settle(sys, Dn, lam, o, stats)
        if not ok:
            return D, False, f"after leaving a saddle (eigenvalue {lmin:.3g}) Newton failed: {msg}"
    lm = stats["saddle_eigenvalues"][-1] if stats["saddle_eigenvalues"] else float("nan")
    return (
        D,
        False,
        (
            f"no stable equilibrium reached: still a saddle after leaving "
            f"{len(stats['saddle_eigenvalues'])} (last eigenvalue {lm:.3g}); raise "
            "max_saddle_escapes or check the supports"
        ),
    )
