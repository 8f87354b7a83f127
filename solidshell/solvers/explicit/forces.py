"""Forces of one explicit step at D_n: internal (the model's compiled kernel), penalty contact and
Coulomb friction (``solidshell.contact``), and the interpenetration counts the samples watch.

Flat (6N,) dof vectors as in Eq. (1); forces in the model's force unit, energies in force x length.
"""

from __future__ import annotations

import numpy as np

from ... import contact_augment as augment
from ... import contact_kernels as ck
from ...contact import contact_forces, frictional_contact
from ...contact_faces import face_pass, reach
from ...contact_mesh import pack_grid
from ...contact_rims import NONE as NO_RIM_SHIFT
from ...contact_rims import pass_args, rim_pass
from ...contact_rims import update as rim_update
from ...interfaces import QuasiStrainModel, SolverProblem
from ...model import Model


class Forces:
    """Force evaluations for one problem.  ``k_pen`` (N,) is the normal penalty stiffness per node,
    ``k_t`` the tangential stick stiffness (None without friction), ``fric_of`` the friction
    coefficient of each contact body (0: frictionless); ``fused`` the model's FusedForces (None:
    the model's own methods).  A library Model (``shell``) has a mesh, energy_and_force and the
    interpenetration counts; any other model (interfaces.ExplicitModel) its force and energy, its
    nodes at the origin, and Eq. (24)'s books when it is an interfaces.QuasiStrainModel.
    ``faces``: the mesh's contact_faces.FacePoints (None or empty: contact on the nodes only); they
    take part when every body is one of the compiled kinds (a user's own RigidBody: nodes only).
    ``selfc``: the sheet's self-contact (contact_self_penalty.SelfPenalty), None without; ``rims``: the
    bodies' sharp edges against the faces (contact_rims.Rims; with the face points only), None without."""

    def __init__(self, problem: SolverProblem, k_pen, k_t, fric_of, fused=None, faces=None, selfc=None, rims=None):
        self.model = model = problem.model
        self.N = model.n_nodes
        self.shape = (self.N, 6)
        self.shell = isinstance(model, Model)
        self.X0 = model.mesh.nodes if self.shell else np.zeros((self.N, 3))
        self.bodies = list(problem.contact or [])
        self.k_pen, self.k_t, self.fric_of = k_pen, k_t, list(fric_of)
        self.n_fric = sum(1 for mu in self.fric_of if mu > 0.0)
        self.quasi = isinstance(model, QuasiStrainModel) and bool(model.quasi)
        self.q_mu = float(model.mu) if self.quasi else None  # Eq. (24)'s threshold
        self.fused = fused
        self.selfc = selfc
        self._Cs = np.zeros(6 * self.N) if selfc is not None else np.zeros(0)
        self._all = np.arange(self.N)
        # every body one of the kernels' (contact_kernels): one compiled pass over the nodes
        self.compiled = bool(self.bodies) and all(b.code >= 0 for b in self.bodies)
        if self.compiled:
            self.X0 = np.ascontiguousarray(self.X0, dtype=float)
            self.codes = np.array([b.code for b in self.bodies], dtype=np.int64)
            self.params = np.array([b.params for b in self.bodies], dtype=float)
            self.grid = pack_grid(self.bodies, self.params)  # the mesh bodies' distance grids; None: no mesh body
            self.offsets = np.array([b.offset for b in self.bodies], dtype=float)
            self.mus = np.array(self.fric_of, dtype=float)
            self.k_pen = np.ascontiguousarray(k_pen, dtype=float)
            self._kt = np.ascontiguousarray(k_t, dtype=float) if k_t is not None else np.zeros(0)
            self._ft = np.zeros((self.n_fric, self.N, 3))  # the friction forces of one pass
            self._no_anchor = np.zeros((0, self.N, 3))
        self.faces = faces if self.compiled and faces is not None and len(faces) else None
        # the augmented-Lagrangian shifts of the nodes and face points (contact_augment.py): set
        # by the integrator from its state; NONE: the plain penalty
        self.shift_n = augment.NONE
        self.shift_q = augment.NONE  # (a property: sets the points' reach too)
        if self.faces is not None:
            self.kq = self.faces.stiffness(self.k_pen)
            self._all_els = np.arange(len(self.faces.conn4))
            self._fx = np.zeros((self.n_fric, self.N))  # the face points' normal load on the nodes
            self._Ff = np.zeros((self.N, 3))  # the face points' forces on the nodes
        else:
            self._fx, self._Ff = np.zeros((0, 0)), np.zeros((0, 3))
        self.rims = rims if self.faces is not None and rims is not None and len(rims) else None
        if self.rims is not None:
            self.kr = self.rims.stiffness(self.kq)
        self.shift_r = NO_RIM_SHIFT  # the rim points' augmented-Lagrangian shifts (R,) (contact_rims.update)

    @property
    def shift_q(self) -> np.ndarray:
        """The face points' augmented-Lagrangian shifts (n_bodies, P), or augment.NONE."""
        return self._shift_q

    @shift_q.setter
    def shift_q(self, s) -> None:
        self._shift_q = s
        self._reach = reach(self.bodies, s) if self.faces is not None else np.zeros(0)

    def internal(self, D, want_energy):
        """(F(D) flat, strain energy or None)."""
        model, shape = self.model, self.shape
        if self.fused is not None:
            return self.fused.internal(D, want_energy)
        if want_energy:
            if self.shell:
                E, F = model.energy_and_force(D.reshape(shape))
            else:
                F = model.internal_force(D.reshape(shape))
                E = model.energy(D.reshape(shape))
            return np.asarray(F, float).reshape(-1), float(E)
        return np.asarray(model.internal_force(D.reshape(shape)), float).reshape(-1), None

    def _points(self, D, nodes):
        """Mid-surface positions x (m,3) and stiffnesses (k, k_t) of ``nodes`` (None: all)."""
        D6 = D.reshape(self.shape)
        if nodes is None:
            return self.X0 + D6[:, :3], self.k_pen, self.k_t
        kt = self.k_t[nodes] if self.k_t is not None else None
        return self.X0[nodes] + D6[nodes, :3], self.k_pen[nodes], kt

    def _into(self, fc, nodes, C):
        """The contact forces fc of ``nodes`` as a flat (6N,) C: a new array when C is None, else
        written into C, whose other entries the caller keeps zero."""
        if C is None:
            C = np.zeros(6 * self.N)
        C6 = C.reshape(self.shape)
        if nodes is None:
            C6[:, :3] = fc
        else:
            C6[nodes, :3] = fc
        return C

    def contact(self, D, nodes=None, C=None, elements=None):
        """Frictionless penalty contact: (C flat, energy, active nodes and face points, deepest
        penetration).  ``nodes``: evaluate only these and the face points of ``elements`` (sorted;
        every node and element in contact must be among them, and the nodes of the elements,
        candidates.py; elements None: those whose nodes are all among ``nodes``),
        ``C``: the output buffer (see _into)."""
        if self.compiled:
            C, ec, _, nact, _, pen = self._pass(D, None, nodes, C, None, elements=elements)
            return C, ec, nact, pen
        x, k, _ = self._points(D, nodes)
        fc, ec, nact = contact_forces(self.bodies, x, k)
        pen = float(np.max(np.linalg.norm(fc, axis=1) / k)) if nact else 0.0
        return self._into(fc, nodes, C), ec, nact, pen

    def contact_friction(self, D, anchors, nodes=None, C=None, new=None, elements=None):
        """As :meth:`contact`, with Coulomb friction on the bodies with mu > 0
        (contact.frictional_contact): also (FT (n_fric, m, 3), node indices (m,)), the friction
        forces of the m nodes evaluated per frictional body, the stick energy, the new anchors and
        the slip count.  ``anchors`` is not modified (a restart must see the saved ones).  With
        ``nodes`` the new anchors go into ``new`` (n_fric, N, 3), NaN elsewhere."""
        if self.compiled:
            C, ec, et, nact, nslip, pen, FT, idx, a_new = self._pass(
                D, anchors, nodes, C, new, friction=True, elements=elements
            )
            return C, ec, nact, pen, (FT, idx), et, a_new, nslip
        x, k, kt = self._points(D, nodes)
        m = len(x)
        fc = np.zeros_like(x)
        ec = et = pen = 0.0
        nact = nslip = 0
        FT = np.zeros((self.n_fric, m, 3))
        a_in = anchors if nodes is None else anchors[:, nodes]
        a_new = np.empty_like(a_in)
        j = 0
        for b, mu in zip(self.bodies, self.fric_of):
            if mu > 0.0:
                fb, eb, idx, ft, etb, a_new[j], ns = frictional_contact(b, x, k, kt, a_in[j])
                FT[j, idx] = ft
                j += 1
                et += etb
                nslip += ns
                if idx.size:
                    fn = fb[idx] - ft
                    pen = max(pen, float(np.max(np.sqrt(np.einsum("ij,ij->i", fn, fn)) / k[idx])))
                    nact += idx.size
            else:
                fb, eb = b.forces(x, k)
                act = np.any(fb != 0.0, axis=1)
                if np.any(act):
                    nact += int(np.count_nonzero(act))
                    pen = max(pen, float(np.max(np.linalg.norm(fb[act], axis=1) / k[act])))
            fc += fb
            ec += eb
        if nodes is not None:
            new.fill(np.nan)
            new[:, nodes] = a_new
            a_new = new
        fr = (FT, self._all if nodes is None else nodes)
        return self._into(fc, nodes, C), ec, nact, pen, fr, et, a_new, nslip

    def _pass(self, D, anchors, nodes, C, new, friction=False, elements=None):
        """contact_faces.face_pass on the face points of ``elements`` and contact_kernels.contact_pass on
        ``nodes`` (None: all of both): (C, contact energy, stick energy, nodes and points in contact,
        slipping, deepest penetration[, FT, nodes, new anchors])."""
        idx = self._all if nodes is None else nodes
        ef, nf, pf = 0.0, 0, 0.0
        if self.faces is not None:
            els = self._all_els if nodes is None else elements
            if els is None:  # the elements whose nodes are all among ``nodes``
                inn = np.zeros(self.N, dtype=bool)
                inn[nodes] = True
                els = np.flatnonzero(inn[self.faces.conn4].all(axis=1))
            f = self.faces
            ef, nf, pf = face_pass(
                self.codes,
                self.params,
                self.offsets,
                self.mus,
                self.X0,
                D,
                els,
                f.estart,
                f.nodes,
                f.w,
                self.kq,
                idx,
                self._fx,
                self._Ff,
                self._shift_q,
                self._reach,
                self.grid,
            )
            if self.rims is not None:
                args = pass_args(self.rims, self.X0, D, self.kr, els)
                er, nr, pr = rim_pass(*args, self.shift_r, NO_RIM_SHIFT, self._Ff)
                ef, nf, pf = ef + er, nf + nr, max(pf, pr)
        if C is None:
            C = np.zeros(6 * self.N)
        if friction:
            # the step's call (it passes its anchor buffer) reuses one FT buffer; any other call (a
            # damper's finite difference between the step's contact and its friction work) gets its own
            if new is None:
                new = np.full((self.n_fric, self.N, 3), np.nan)
                FT = np.zeros((self.n_fric, idx.size, 3))
            else:
                new.fill(np.nan)
                FT = self._ft[:, : idx.size]
            anc = anchors
        else:
            FT, anc, new = self._ft[:, :0], self._no_anchor, self._no_anchor
        ec, et, nact, nslip, pen = ck.contact_pass(
            self.codes,
            self.params,
            self.offsets,
            self.mus,
            self.X0,
            D,
            idx,
            self.k_pen,
            self._kt,
            anc,
            new,
            C,
            FT,
            self._fx,
            self._Ff,
            self.shift_n,
            self.grid,
        )
        ec, nact, pen = ec + ef, nact + nf, max(pen, pf)
        if friction:
            return C, ec, et, nact, nslip, pen, FT, idx, new
        return C, ec, et, nact, nslip, pen

    @property
    def augmentable(self) -> bool:
        """Whether the contact takes augmented-Lagrangian shifts (every body a compiled kind)."""
        return self.compiled

    def augment(self, D):
        """One Uzawa update at D (contact_augment.update, contact_rims.update): (deepest raw
        penetration, node shifts (n_bodies, N), face-point shifts (n_bodies, P), rim shifts (R,))."""
        x = self.X0 + D.reshape(self.shape)[:, :3]
        xq = self.faces.positions(x) if self.faces is not None else np.zeros((0, 3))
        depth, s_n, s_q = augment.update(self.bodies, x, xq, self.shift_n, self.shift_q)
        if self.rims is None:
            return depth, s_n, s_q, NO_RIM_SHIFT
        d_r, s_r = rim_update(self.rims, self.X0, D, self.shift_r)
        return max(depth, d_r), s_n, s_q, s_r

    def with_self(self, D, C):
        """(C + the self-contact forces at D (6N,), self-contact energy, pairs in contact); C None:
        no body forces.  The sum is the step's buffer, valid until the next call; C itself when
        no candidate pair stands (or without self-contact), so a sheet without folds pays no
        pass over its dofs."""
        sc = self.selfc
        if sc is None or not sc.refresh(D):
            return C, 0.0, 0
        Cs = self._Cs
        Cs.fill(0.0)
        es, ns = sc.forces(D, Cs)
        if C is not None:
            Cs += C
        return Cs, es, ns

    def contact_energy(self, D, anchors):
        """(C flat, contact energy incl. friction stick energy and self-contact, the stick energy)
        at D (no books; C a new array)."""
        et = 0.0
        if self.n_fric:
            C, ec, _, _, _, et, _, _ = self.contact_friction(D, anchors)
        elif self.bodies:
            C, ec, _, _ = self.contact(D)
        else:
            C, ec = np.zeros(6 * self.N), 0.0
        C, es, _ = self.with_self(D, C)
        return (C.copy() if C is self._Cs else C), ec + es, et

    def contact_stiffness(self, D, anchors, eps: float = 1e-7):
        """(rows, cols, vals) of the contact stiffness -dC/dx on the translation dofs at D, anchors
        held (stick springs count, slipping nodes only through their normal spring); None without
        bodies.  Central differences: a node's own contact force depends on its own position only,
        so three perturbed pairs give every 3x3 nodal block; the face points (contact_faces.py)
        couple the nodes of an element, and moving all nodes at once lumps that coupling onto the
        diagonal blocks (its row sums: the bound the critical step uses too)."""
        N = self.N
        if not self.bodies:
            return None
        D = D.copy()
        cols = []
        for j in range(3):
            Dp_, Dm_ = D.copy(), D.copy()
            Dp_[j::6] += eps
            Dm_[j::6] -= eps
            if self.n_fric:
                Cp = self.contact_friction(Dp_, anchors)[0]
                Cm = self.contact_friction(Dm_, anchors)[0]
            else:
                Cp = self.contact(Dp_)[0]
                Cm = self.contact(Dm_)[0]
            cols.append(-(np.asarray(Cp) - np.asarray(Cm)).reshape(N, 6)[:, :3] / (2 * eps))
        B = np.stack(cols, axis=2)  # (N, 3 rows i, 3 cols j): d(-C_i)/dx_j
        nodes = np.flatnonzero(np.any(B != 0.0, axis=(1, 2)))
        ii, jj = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
        rows = (6 * nodes[:, None, None] + ii[None]).ravel()
        colz = (6 * nodes[:, None, None] + jj[None]).ravel()
        return rows, colz, B[nodes].ravel()

    def interp_count(self, D) -> int:
        """Nodes with n_p.d_p < 0 (interpenetrated faces), 0 for models that cannot tell (not a Model)."""
        if self.shell:
            return int(np.count_nonzero(self.model.interpenetrated_nodes(D.reshape(self.shape))))
        return 0

    def interp_and_branches(self, D):
        """(interpenetrated node count n_p.d_p < 0, Eq. (24) branch flags n_p.d_p <= -mu per element
        corner) from one evaluation of model.interpenetration."""
        nds = self.model.interpenetration(D.reshape(self.shape))
        flag = np.zeros(self.N, dtype=bool)
        for b, nd in zip(self.model.blocks, nds):
            flag[b.conn[nd < 0.0]] = True
        return int(np.count_nonzero(flag)), np.concatenate([nd.ravel() <= -self.q_mu for nd in nds])

    def interp_flags(self, D):
        """(interpenetrated count, Eq. (24) flags or an empty array when not quasi)."""
        if self.quasi:
            return self.interp_and_branches(D)
        return self.interp_count(D), np.zeros(0, bool)
