"""Node paths through rigid bodies: the static solvers' step cut for the contact bodies.

Why: the static solvers' penalty sees only where a trial step ends.  A trial step moves every
node along a straight segment x0 -> x0 + dx, and a segment longer than a body is thick can carry a
node *through* it: the node lands on the far side, where no penalty pushes back, and the lowest
potential may then be that impossible state.  The steps are long enough for it: Newton's steps are
capped at ``max_step`` = L_f / 2 (10.6 cm on the sphere's 60x60 sheet, whose sphere is 10 cm
across), and the sphere's linearised load prediction once dropped the whole sheet 1821 cm through
it (docs/solvers.md, section 2).  The self-contact has the same guard against the sheet's own
layers (contact_self.SelfContact.free_fraction, IPC's continuous collision detection); this is its
counterpart for the bodies (Mirtich's conservative advancement, "Impulse-based dynamic simulation
of rigid body systems", PhD thesis, Berkeley 1996, ch. 2, applied to points against a distance
field).

The test: a path has gone into a body when its gap g(x) - offset (``RigidBody.penetration``) falls
below ``-depth`` (the static solver passes the sheet's thickness h: fifty times the contact
contract's tolerance of 2 % of h, contact.PENETRATION_TOL, so that pressing a node into a body is
left to the penalty; on the paper's scenes a solve meets 0-2 such cuts, docs/solvers.md section 2).
A body thinner than about h is not guarded: no point inside it is h deep.  With L
the body's Lipschitz bound (``lipschitz``: 1 for the exact distances, sqrt(3) for a mesh body's
grid), a node whose gap exceeds -depth by d cannot reach -depth before it has moved d / L along
its path; it advances by that and looks again, until its path ends (free) or it is within
``REACHED`` x depth of -depth (where the path enters).  The fraction returned is never beyond the
first entry of any node, so a step cut to it takes no node through a body.  Nodes that start
deeper than -depth are not followed (the penalty is already pushing them out), nor are bodies
without a Lipschitz bound (a user's own ``signed_distance``).

Cost: one distance pass over the nodes at the step's start; only nodes whose path is longer than
their distance to -depth (over L) are followed, a few distance passes over those.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .interfaces import ContactBody

__all__ = ["free_fraction", "REACHED", "MAX_ADVANCES"]

REACHED = 0.05
"""A followed node has reached the forbidden depth when its gap is within this fraction of ``depth``
of -depth: the returned fraction is then at most 0.05 depth / |dx| before the true entry."""

MAX_ADVANCES = 64
"""Advances of one node before its path is taken as entering where it stands (a path that grazes
the level -depth advances ever more slowly); the fraction stays a lower bound."""


def free_fraction(bodies: Sequence[ContactBody], x0, dx, depth: float) -> float:
    """The largest fraction t in [0, 1] (a lower bound of it) such that no node's straight path
    x0 + s dx, 0 <= s <= t, goes deeper than ``depth`` [length] into any of the ``bodies``
    (module docstring).  x0, dx: (N, 3) [length]."""
    x0 = np.asarray(x0, dtype=float).reshape(-1, 3)
    dx = np.asarray(dx, dtype=float).reshape(-1, 3)
    step = np.linalg.norm(dx, axis=1)
    t = 1.0
    for body in bodies:
        L = body.lipschitz
        if L is None or not L > 0.0:
            continue
        room = body.penetration(x0)[0] + depth  # how far each node is from the forbidden depth
        follow = np.flatnonzero((room > 0.0) & (L * step * t > room))
        if follow.size:
            t = min(t, _advance(body, L, x0[follow], dx[follow], step[follow], room[follow], depth, t))
    return t


def _advance(body, L: float, x0, dx, step, room, depth: float, t_max: float) -> float:
    """The smallest entry fraction (<= t_max) of the followed paths, by conservative advancement."""
    s = np.zeros(len(x0))
    live = np.arange(len(x0))
    entry = t_max
    for _ in range(MAX_ADVANCES):
        s[live] += room[live] / (L * step[live])
        live = live[s[live] < entry]  # past the end, or past an entry already found: done
        if not live.size:
            return entry
        room[live] = body.penetration(x0[live] + s[live, None] * dx[live])[0] + depth
        hit = live[room[live] <= REACHED * depth]
        if hit.size:
            entry = min(entry, float(s[hit].min()))
            live = live[room[live] > REACHED * depth]
    return min(entry, float(s[live].min(initial=entry)))
