"""Self-contact of the sheet for the static solvers: the IPC barrier between its layers, with steps
kept free of crossings by continuous collision detection (the IPC Toolkit, ``ipctk``).

The law (issue 37: two layers keep their mid-surfaces at least about a thickness h apart)
-----------------------------------------------------------------------------------------
The mid-surface as triangles (layers.triangles: each quad split along its 0-2 diagonal).  Every
pair of primitives sharing no node -- vertex-triangle, vertex-edge, vertex-vertex and edge-edge,
the collision set of Li et al., "Incremental Potential Contact" (SIGGRAPH 2020), built by ipctk --
whose distance d lies below h carries the barrier energy

    B(d) = kappa b(d - d_min),   b(s) = -(s - s_hat)^2 ln(s / s_hat)  for 0 < s < s_hat, else 0

(ipctk's "physical" barrier), with d_min = (1 - LAYER_TOL) h and s_hat = LAYER_TOL h: zero at
and beyond d = h, infinite at d = d_min, so that two layers in contact rest within the band
(1 - LAYER_TOL) h < d < h -- the contract layers.py measures.  B is smooth (C2), its gradient and
Hessian (the consistent tangent, not projected) come from ipctk in the node translations; the
directors feel no self-contact (as with the rigid bodies).

kappa is set so that the barrier's force at the middle of the band equals the heaviest nodal dead
load w (``stiffness``): a layer pressed by its own weight rests about halfway into the band.  The
force at the middle of the band per unit kappa is measured once on a small triangle over a large
one (:func:`band_force`), so the rule holds for whatever form ipctk gives b.

Steps free of crossings: a barrier alone cannot stop a step that jumps a layer through another
(both ends of the step outside the band).  :meth:`SelfContact.free_fraction` is the largest
fraction of a straight step D0 -> D1 along which no pair comes closer than d_min (ipctk's additive
CCD: conservative, the fraction it gives is never beyond the true one); the static solver's
step-length searches cut their trial steps to it (solvers/static/newton.py).  Starting from a state without intersections the iterates then
never intersect (IPC's guarantee).

Frictionless: friction between layers is not modelled (issue 37 item 1 makes it optional).
Cost per evaluation: one broad phase (ipctk's LBVH) and the pairs' barrier terms.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import InputError
from .layers import LAYER_TOL, triangles

CCD_SAFETY = 0.8
"""A trial step is cut to CCD_SAFETY x the collision-free fraction (IPC's conservative rescaling:
the next step starts strictly inside, not on, the minimum distance)."""


def band_force(s_hat: float, d_min: float) -> float:
    """|dB/dd| at the middle of the band d = d_min + s_hat / 2 for kappa = 1 [force per unit kappa]:
    a small triangle parallel to a large one over its middle (three vertex-face pairs and nothing
    else), the force on one of its corners."""
    import ipctk

    F = np.array([[0, 1, 2], [3, 4, 5]], dtype=np.int32)
    X = np.array([[0, 0, 0], [9, 0, 0], [0, 9, 0], [2, 2, 5], [2.5, 2, 5], [2, 2.5, 5]], dtype=float)
    X = X * (d_min + s_hat)  # the upper triangle's edges far from the lower one's, in the distance's scale
    cm = ipctk.CollisionMesh(X, ipctk.edges(F), F)
    V = X.copy()
    V[3:, 2] = d_min + 0.5 * s_hat
    V = np.asfortranarray(V)
    col = ipctk.NormalCollisions()
    col.build(cm, V, s_hat, d_min)
    g = ipctk.BarrierPotential(s_hat, 1.0, True).gradient(col, cm, V).reshape(-1, 3)
    return float(abs(g[3, 2]))


class SelfContact:
    """The barrier between the layers of ``mesh`` (a ShellMesh) of thickness h [length] with the
    force w [force] at the middle of the band (module docstring); works on full flat vectors D
    (6N,) of the static solver."""

    def __init__(self, mesh, h: float, w: float):
        import ipctk

        if not (math.isfinite(h) and h > 0.0 and math.isfinite(w) and w > 0.0):
            raise InputError(f"self-contact needs a positive thickness and load scale, got h = {h!r}, w = {w!r}")
        self.n = mesh.n_nodes
        self.X = np.asarray(mesh.nodes, dtype=float)
        F = triangles(mesh)
        self.mesh = ipctk.CollisionMesh(self.X, ipctk.edges(F), F)
        self.d_min = (1.0 - LAYER_TOL) * float(h)
        self.s_hat = LAYER_TOL * float(h)
        self.stiffness = float(w) / band_force(self.s_hat, self.d_min)
        self.barrier = ipctk.BarrierPotential(self.s_hat, self.stiffness, True)
        self.evaluations = 0
        self.ccd_cuts = 0
        self._ipctk = ipctk
        # additive CCD (Li et al. 2021): conservative and ~1e4 times faster here than the default
        # tight-inclusion CCD with a minimum distance (8x8 two-sheet probe: 6 ms against 179 s)
        self._ccd = ipctk.AdditiveCCD()
        self._bp = ipctk.LBVH()  # the fastest of ipctk's broad phases on square-on-disc 30x240 (15 ms a build)
        rest = self._collisions(np.asfortranarray(self.X))
        if len(rest):
            raise InputError(
                f"self-contact: {len(rest)} pair(s) of the flat mesh's triangles sharing no node lie closer "
                f"than the thickness h = {h:g}: elements smaller than about h cannot take self-contact"
            )

    def _V(self, D) -> np.ndarray:
        return np.asfortranarray(self.X + np.asarray(D, dtype=float).reshape(self.n, 6)[:, :3])

    def _collisions(self, V):
        col = self._ipctk.NormalCollisions()
        col.build(self.mesh, V, self.s_hat, self.d_min, self._bp)
        return col

    def _full(self, g) -> np.ndarray:
        """A (3N,) gradient in the node translations as a (6N,) vector."""
        out = np.zeros((self.n, 6))
        out[:, :3] = np.asarray(g, dtype=float).reshape(self.n, 3)
        return out.ravel()

    def energy_gradient(self, D, want_tangent: bool = False):
        """(barrier energy, its gradient (6N,), tangent entries (rows, cols, vals) in the 6N x 6N
        numbering or None).  inf energy (and a NaN gradient) where a pair is at or below d_min."""
        self.evaluations += 1
        V = self._V(D)
        col = self._collisions(V)
        if not len(col):
            return 0.0, np.zeros(6 * self.n), (([], [], []) if want_tangent else None)
        e = float(self.barrier(col, self.mesh, V))
        g = self._full(self.barrier.gradient(col, self.mesh, V))
        entries = None
        if want_tangent:
            H = self.barrier.hessian(col, self.mesh, V).tocoo()
            r, c = np.asarray(H.row, np.int64), np.asarray(H.col, np.int64)
            entries = ([6 * (r // 3) + r % 3], [6 * (c // 3) + c % 3], [np.asarray(H.data, float)])
        return e, g, entries

    def free_fraction(self, D0, D1) -> float:
        """The largest fraction t in [0, 1] of the straight step D0 -> D1 along which no pair comes
        closer than d_min (ipctk.compute_collision_free_stepsize)."""
        ipctk = self._ipctk
        V0, V1 = self._V(D0), self._V(D1)
        return float(ipctk.compute_collision_free_stepsize(self.mesh, V0, V1, self.d_min, self._bp, self._ccd))

    def cut(self, D0, D1) -> float:
        """1.0 when the step D0 -> D1 is free of crossings, else CCD_SAFETY x its free fraction."""
        t = self.free_fraction(D0, D1)
        if t >= 1.0:
            return 1.0
        self.ccd_cuts += 1
        return CCD_SAFETY * t
