"""Forces of one explicit step at D_n: internal (the model's compiled kernel), penalty contact and
Coulomb friction (``solidshell.contact``), and the interpenetration counts the samples watch.

Flat (6N,) dof vectors as in Eq. (1); forces in the model's force unit, energies in force x length.
"""

from __future__ import annotations

import numpy as np

from ...contact import contact_forces, frictional_contact


class Forces:
    """Force evaluations for one problem.  ``k_pen`` (N,) is the normal penalty stiffness per node,
    ``k_t`` the tangential stick stiffness (None without friction), ``fric_of`` the friction
    coefficient of each contact body (0: frictionless); ``fused`` the model's FusedForces (None:
    the model's own methods)."""

    def __init__(self, problem, k_pen, k_t, fric_of, fused=None):
        self.model = model = problem.model
        self.N = model.n_nodes
        self.shape = (self.N, 6)
        self.X0 = model.mesh.nodes if hasattr(model, "mesh") else np.zeros((self.N, 3))
        self.bodies = list(problem.contact or [])
        self.k_pen, self.k_t, self.fric_of = k_pen, k_t, list(fric_of)
        self.n_fric = sum(1 for mu in self.fric_of if mu > 0.0)
        self.has_energy_force = hasattr(model, "energy_and_force")
        self.quasi = bool(getattr(model, "quasi", False)) and hasattr(model, "interpenetration")
        self.q_mu = float(getattr(model, "mu", 0.5))
        self.fused = fused

    def internal(self, D, want_energy):
        """(F(D) flat, strain energy or None)."""
        model, shape = self.model, self.shape
        if self.fused is not None:
            return self.fused.internal(D, want_energy)
        if want_energy:
            if self.has_energy_force:
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

    def contact(self, D, nodes=None, C=None):
        """Frictionless penalty contact: (C flat, energy, active nodes, deepest penetration).
        ``nodes``: evaluate only these (sorted; every node in contact must be among them,
        candidates.py), ``C``: the output buffer (see _into)."""
        x, k, _ = self._points(D, nodes)
        fc, ec, nact = contact_forces(self.bodies, x, k)
        pen = float(np.max(np.linalg.norm(fc, axis=1) / k)) if nact else 0.0
        return self._into(fc, nodes, C), ec, nact, pen

    def contact_friction(self, D, anchors, nodes=None, C=None, new=None):
        """As :meth:`contact`, with Coulomb friction on the bodies with mu > 0
        (contact.frictional_contact): also [(idx, f_t)] per frictional body, the stick energy, the
        new anchors and the slip count.  ``anchors`` is not modified (a restart must see the saved
        ones).  With ``nodes`` the new anchors go into ``new`` (n_fric, N, 3), NaN elsewhere."""
        x, k, kt = self._points(D, nodes)
        fc = np.zeros_like(x)
        ec = et = pen = 0.0
        nact = nslip = 0
        fr = []
        a_in = anchors if nodes is None else anchors[:, nodes]
        a_new = np.empty_like(a_in)
        j = 0
        for b, mu in zip(self.bodies, self.fric_of):
            if mu > 0.0:
                fb, eb, idx, ft, etb, a_new[j], ns = frictional_contact(b, x, k, kt, a_in[j])
                j += 1
                fr.append((idx if nodes is None else nodes[idx], ft))
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
        return self._into(fc, nodes, C), ec, nact, pen, fr, et, a_new, nslip

    def contact_energy(self, D, anchors):
        """(C flat, contact energy incl. friction stick energy, the stick energy) at D (no books)."""
        if self.n_fric:
            C, ec, _, _, _, et, _, _ = self.contact_friction(D, anchors)
            return C, ec, et
        if self.bodies:
            C, ec, _, _ = self.contact(D)
            return C, ec, 0.0
        return np.zeros(6 * self.N), 0.0, 0.0

    def interp_count(self, D) -> int:
        """Nodes with n_p.d_p < 0 (interpenetrated faces), 0 for models that cannot tell."""
        if hasattr(self.model, "interpenetrated_nodes"):
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
