"""Augmented-Lagrangian (Uzawa) updates of the penalty contact: the contract without a stiffer spring.

Why
---
A penalty spring lets a point sink p = f / k into a body under a contact force f.  On curved bodies
the sink is set less by the sheet's weight than by geometry: a bilinear element cannot follow a
sphere, so with its corners on the surface its centre lies L^2 / (4 R) inside (0.0125 cm, 21 % of
the wool's h, for L = 0.5 cm on the 5 cm sphere); the element must float on its central face points,
which carry the whole pressure.  Measured on the sphere scene 60x60 (relaxation): 0.0053 cm (8.9 %
of h) with the default penalty factor 0.1, 0.0016 cm with 1.0 -- at 0.63 of the time step, 3.2x the
steps and a different drape.  A stiffer spring buys depth with the critical step; the multipliers
below buy it with a few re-relaxations at the same step.

The method
----------
The augmented Lagrangian of Uzawa's algorithm (Simo & Laursen 1992, Comput. Struct. 42: 97-116;
Wriggers, Computational Contact Mechanics, 2nd ed., Sec. 6.3.3): every contact point (node or face
point, per body) carries a multiplier lambda >= 0 and feels the force max(0, lambda + k p) n.  Here
lambda is stored as the *shift* s = lambda / k, a length: the force is k max(0, p + s) n, the penalty
law with the offset raised by s.  When a solve has converged (a relaxation's steady state, a static
Newton solve) with some raw penetration p = offset - g(x) above the target, every point's shift
becomes

    s <- max(0, s + p)                                             (lambda <- max(0, lambda + k p))

(the force it carried, now held by the multiplier) and the solve continues from that state.  At
convergence of the updates the multipliers are the contact forces and p -> 0 wherever they are
positive; the spring k only sets how fast the updates converge (ratio ~ K_sheet / (K_sheet + k) per
update for a sheet of local stiffness K_sheet), not how deep the point lies.  The target is
``TARGET`` x the contract's tolerance (contact.PENETRATION_TOL h): the other half is the room the
face-point spacing leaves between points (contact_faces.spacing).

With the shifts fixed the contact is still a potential, 1/2 k max(0, p + s)^2, so the energy ledger
and the tangent stay as they are; an update changes that potential at a fixed state, and the
explicit ledger books the jump apart (like a remesh's).  The shifts live on one mesh: a remesh
starts them at zero (the relaxation on the new mesh converges and updates again).
"""

from __future__ import annotations

import numpy as np

from .contact import PENETRATION_TOL

TARGET = 0.5
"""Updates stop once no node and no face point lies deeper than TARGET x contact.PENETRATION_TOL x h."""

DEFAULT_UPDATES = 10
"""The most updates of one solve (``contact_augment``; 0: plain penalty).  Measured: 2-4 reach the
target on the paper's scenes (docs/contact.md)."""

STALLS = 2
"""Updates in a row that do not make the deepest penetration shallower before the updates stop: a
soft drape (folds over an edge) may answer an update by moving its folds, the deepest point then an
unshifted one elsewhere; measured on a sheet folding over a rounded pedestal edge (docs/contact.md)."""

NONE = np.zeros((0, 0))
"""No shifts (the kernels' plain penalty path)."""


def raw_penetration(bodies, x) -> np.ndarray:
    """(n_bodies, M) raw penetrations p = offset - g(x) of the points x (M, 3) (negative: a gap)."""
    if not len(bodies):
        return np.zeros((0, len(x)))
    # a mesh body measures against its triangles, not the grid the kernels interpolate: the updates
    # then also take up the grid's interpolation error (contact_mesh.MeshBody.exact_penetration)
    return np.stack([-np.asarray(getattr(b, "exact_penetration", b.penetration)(x)[0], dtype=float) for b in bodies])


def update(bodies, x, xq, shift_n, shift_q):
    """One Uzawa update at node positions x (N, 3) and face-point positions xq (P, 3) with the current
    shifts (NONE or (n_bodies, N) / (n_bodies, P)): (deepest raw penetration of any point [length],
    new node shifts, new face-point shifts)."""
    p_n, p_q = raw_penetration(bodies, x), raw_penetration(bodies, xq)
    deepest = max(float(p_n.max(initial=0.0)), float(p_q.max(initial=0.0)))
    s_n = p_n if not shift_n.size else shift_n + p_n
    s_q = p_q if not shift_q.size else shift_q + p_q
    return deepest, np.ascontiguousarray(np.maximum(s_n, 0.0)), np.ascontiguousarray(np.maximum(s_q, 0.0))


def tally(depth: float, best: float, stalls: int, updates: int, limit: int, goal: float):
    """After a converged solve whose deepest raw penetration is ``depth``, with ``updates`` made so
    far (at most ``limit``) and the shallowest depth ``best`` and ``stalls`` before it: (stop?, best,
    stalls) -- stop once at the goal, out of updates, or after STALLS updates without a shallower
    deepest point."""
    if depth < best:
        best, stalls = depth, 0
    elif updates:
        stalls += 1
    return depth <= goal or updates >= limit or stalls >= STALLS, best, stalls


def target(h: float) -> float:
    """The depth [length] the updates aim below for a sheet of thickness h."""
    return TARGET * PENETRATION_TOL * float(h)
