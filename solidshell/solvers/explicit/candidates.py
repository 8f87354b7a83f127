"""The nodes that can touch a contact body: contact and friction of one step evaluated only there.

A body's gap g(x) - offset (``contact.RigidBody.penetration``) changes by at most L |dx| when a
point moves by dx, L = ``body.lipschitz`` (1 for the exact distances of the sphere, plane and
pedestal).  The candidates are the nodes whose gap to some body was at most ``margin`` when they
were selected.  While no node has moved more than margin / L since the selection (checked every
step, one pass over the nodes), a node that is not a candidate has a gap > margin - L |dx| > 0 to
every body: no penalty force, no friction, no anchor -- so contact evaluated at the candidates
gives the forces, anchors, counts and deepest penetration of all nodes exactly, and the energies
too (contact_kernels.body_forces sums over the nodes in contact only).  Once a node has moved that far
the candidates are selected anew at the current state.

Face points (contact_faces.py) lie inside their elements, so a point moves no farther than the
farthest of its element's nodes and lies within the element's diameter d of each of them: with
the nodes selected at margin + d, every element with a selected node is a candidate element
(its face points are evaluated), and the nodes of those elements join the candidate nodes (so that the forces the points
put on their element's nodes land on candidates only).

Cost: a selection is one signed-distance pass over all nodes; between selections a step costs one
compiled pass over the nodes' translations plus one compiled contact pass over the candidates
(contact_kernels.contact_pass; on the sphere 100x100 draped: ~1.5 k of 10 k nodes).  Bodies without a Lipschitz bound make every node a
candidate, always.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numba import njit

from ...interfaces import ContactBody
from ...mesh import ShellMesh

SAFETY = 0.999
"""Re-select at SAFETY x margin / L: the gaps at the selection are rounded (relative 1e-16 of the
coordinates), far inside this 1e-3 slack."""


@njit(cache=True)
def moved_beyond(D, Dsel, limit2):
    """True when some node's translation D[6 i : 6 i + 3] differs from Dsel[i] by more than
    sqrt(limit2) (stops at the first)."""
    for i in range(Dsel.shape[0]):
        a = D[6 * i] - Dsel[i, 0]
        b = D[6 * i + 1] - Dsel[i, 1]
        c = D[6 * i + 2] - Dsel[i, 2]
        if not a * a + b * b + c * c <= limit2:  # NaN moves too
            return True
    return False


@njit(cache=True)
def contact_power(C, Dn1, Dp, nodes):
    """sum over ``nodes`` (ascending) of C . (Dn1 - Dp) on their translation dofs, in node order: the
    same sum bit for bit for any superset of the nodes where C is non-zero (the added terms are
    zeros)."""
    s = 0.0
    for k in range(nodes.size):
        o = 6 * nodes[k]
        for c in range(3):
            s += C[o + c] * (Dn1[o + c] - Dp[o + c])
    return s


def default_margin(mesh: ShellMesh) -> float:
    """2 x the mean edge length of the mesh [length]: a few rows of nodes around the contact zone,
    re-selected after a node has moved that far."""
    P = np.asarray(mesh.nodes, dtype=float)
    edges = []
    for conn in (mesh.quads, mesh.tris):
        if len(conn):
            c = np.asarray(conn)
            edges.append(np.linalg.norm(P[np.roll(c, -1, axis=1)] - P[c], axis=-1).ravel())
    return 2.0 * float(np.mean(np.concatenate(edges))) if edges else 0.0


class Candidates:
    """The candidate nodes of ``bodies`` for a sheet with initial positions X0 (N,3)."""

    def __init__(self, bodies: Sequence[ContactBody], X0, margin: float, faces=None):
        self.bodies = list(bodies)
        self.faces = faces if faces is not None and len(faces) else None
        self.elements = np.zeros(0, dtype=np.int64)  # the candidate elements of the face points (ascending)

        self.X0 = np.asarray(X0, dtype=float)
        self.N = len(self.X0)
        L = [b.lipschitz for b in self.bodies]
        self.enabled = bool(self.bodies) and margin > 0.0 and all(v is not None and v > 0.0 for v in L)
        self.margin = float(margin)
        self.limit2 = (SAFETY * self.margin / max(L)) ** 2 if self.enabled else 0.0
        self.Dsel = np.zeros((self.N, 3))
        self.nodes = np.arange(self.N)
        if self.faces is not None:
            self.elements = np.arange(len(self.faces.conn4))
        self.selections = 0
        self.extra = 0.0  # the largest augmented-Lagrangian shift (contact_augment.py) [length]
        self._fresh = True

    def widen(self, extra: float) -> None:
        """Contact now reaches ``extra`` beyond the offset (the largest augmented-Lagrangian shift: a
        point feels the body while its gap is below its shift); select anew at the next update."""
        self.extra = max(float(extra), 0.0)
        self._fresh = True

    def update(self, D) -> bool:
        """Bring the candidates up to the state D (6N,); True when they were selected anew."""
        if not self.enabled:
            return False
        if not self._fresh and not moved_beyond(D, self.Dsel, self.limit2):
            return False
        D6 = D.reshape(self.N, 6)
        x = self.X0 + D6[:, :3]
        near = np.zeros(self.N, dtype=bool)
        reach = 0.0  # the largest element diameter now (face points)
        if self.faces is not None:
            xe = x[self.faces.conn4]
            reach = float(np.max(np.linalg.norm(xe[:, :, None] - xe[:, None], axis=-1), initial=0.0))
        for b in self.bodies:
            gap, _ = b.penetration(x)
            near |= ~(gap > self.margin + reach + self.extra)  # NaN gaps stay candidates
        if self.faces is not None:
            elems = np.flatnonzero(near[self.faces.conn4].any(axis=1))
            near[self.faces.conn4[elems].ravel()] = True
            self.elements = elems
        self.nodes = np.flatnonzero(near)
        self.Dsel[:] = D6[:, :3]
        self.selections += 1
        self._fresh = False
        return True
