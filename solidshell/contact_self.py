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

Cost: nothing while no two layers are near (issue 41)
-----------------------------------------------------
A broad phase (ipctk's LBVH and the pairs' distances) costs 15-25 ms on square-on-disc 30x240, a CCD
20-35 ms, and a static solve asks for ~600 and ~340 of them -- on a drape whose layers never come
within h, where every one of them finds nothing.  So each broad phase that is run searches a little
further than the barrier reaches, to h + ``reach`` (``reach`` = REACH x the flat sheet's clearance, so
that the sheet's own neighbours in the plane stay out of the search), and its point becomes the
*reference*: its vertices V_r and its clearance c (every pair sharing no node is at least h + c apart
there; c = reach when the search found nothing).  Since a pair's distance is a distance between
convex combinations of its vertices, it changes by at most 2 R between V_r and V, with
R = max_k |V_k - V_r,k - t| for any common translation t (``_radius``: t the centre of the
displacements' bounding box; distances do not see translations).  Then

* energy, gradient and tangent at V (``energy_gradient``): when 2 R < c no pair is within h, the
  collision set is empty and the answer is the exact zero the broad phase would give -- it is not run;
* CCD of a step V0 -> V1 (``free_fraction``): every pair's gap to d_min at V0 is at least
  g = h + c - 2 R0 - d_min, and ipctk's additive CCD (Li et al. 2021) first advances a pair of relative
  motion l_p by 0.9 g / l_p of the step, returning "no collision" when that exceeds the step; l_p
  (the pair's largest vertex displacement about the pair's mean, plus the other side's) is at most
  3 R_step with R_step the step's own radius (``_radius`` of V1 - V0).  When 3 R_step < 0.9 g for
  every pair the library's answer is 1.0 for certain, and it is not run.

Both tests give the library's own answer (the same iterates, bit for bit:
tests/test_self_contact.py compares whole solves with and without them).  Where a test fails the
broad phase or CCD runs as before.  The last point's answer is also kept (``_last``): the solver
asks for Pi and its gradient at an accepted point and then again for the tangent there, once.

Reproducible: the barrier's collision set and its sums (energy, gradient, Hessian) are taken on one
of ipctk's threads (``_serial``).  On its default thread pool their order of summation varied from
run to run, and so did a solve whose layers press: square-on-disc 10x80 without the skips gave 267,
267 and 265 iterations in three runs of one process (ipctk 1.6.1, 2 threads; 268 each time on one
thread).  The reference searches and the CCD stay parallel: a minimum does not depend on the order.
"""

from __future__ import annotations

import math
from contextlib import contextmanager, nullcontext

import numpy as np

from .errors import InputError
from .layers import LAYER_TOL, triangles

REACH = 0.9
"""The broad phase of a reference point searches pairs to h + REACH x (the flat sheet's clearance
beyond h): as far as it can while the sheet's neighbours in the plane (the nearest pairs sharing no
node, ~a triangle's height apart) stay out of the search -- with them in it a build costs ~1.5x (30x240:
26 ms against 19 ms), without them it costs what the barrier's own does."""

ADDITIVE_ADVANCE = 0.9
"""ipctk's AdditiveCCD conservative rescaling (its default, the one ``SelfContact`` constructs): its
first advance of a pair is this fraction of the pair's gap over its relative motion."""

SKIP = True
"""Whether a new ``SelfContact`` uses the skip tests (module docstring); False runs the library's
broad phase and CCD at every point, the reference the tests compare with."""

SKIP_SAFETY = 0.99
"""The skip tests hold with this factor to spare, far beyond the round-off of the bounds (~1e-15)."""

CCD_SAFETY = 0.8
"""A trial step is cut to CCD_SAFETY x the collision-free fraction (IPC's conservative rescaling:
the next step starts strictly inside, not on, the minimum distance)."""


@contextmanager
def _serial(ipctk):
    """ipctk on one thread inside the block (its pool's size restored after): sums in one order."""
    n = ipctk.get_num_threads()
    ipctk.set_num_threads(1)
    try:
        yield
    finally:
        ipctk.set_num_threads(n)


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
    (6N,) of the static solver.  ``skip``: the tests that spare the broad phase and the CCD where no
    pair can be near (module docstring; None: ``SKIP``; False runs the library every time)."""

    def __init__(self, mesh, h: float, w: float, skip: bool | None = None):
        import ipctk

        if not (math.isfinite(h) and h > 0.0 and math.isfinite(w) and w > 0.0):
            raise InputError(f"self-contact needs a positive thickness and load scale, got h = {h!r}, w = {w!r}")
        self.n = mesh.n_nodes
        self.X = np.asarray(mesh.nodes, dtype=float)
        F = triangles(mesh)
        self.mesh = ipctk.CollisionMesh(self.X, ipctk.edges(F), F)
        self.h = float(h)
        self.d_min = (1.0 - LAYER_TOL) * float(h)
        self.s_hat = LAYER_TOL * float(h)
        self.stiffness = float(w) / band_force(self.s_hat, self.d_min)
        self.barrier = ipctk.BarrierPotential(self.s_hat, self.stiffness, True)
        self.evaluations = 0  # energy_gradient calls
        self.builds = 0  # broad phases run (the barrier's and the references')
        self.ccd_calls = 0  # free_fraction calls
        self.ccd_runs = 0  # of which ran the library's CCD
        self.ccd_cuts = 0
        self.skip = SKIP if skip is None else bool(skip)
        self._ipctk = ipctk
        # additive CCD (Li et al. 2021): conservative and ~1e4 times faster here than the default
        # tight-inclusion CCD with a minimum distance (8x8 two-sheet probe: 6 ms against 179 s)
        self._ccd = ipctk.AdditiveCCD(conservative_rescaling=ADDITIVE_ADVANCE)
        self._bp = ipctk.LBVH()  # the fastest of ipctk's broad phases on square-on-disc 30x240 (15 ms a build)
        V = np.asfortranarray(self.X)
        rest = self._collisions(V)
        if len(rest):
            raise InputError(
                f"self-contact: {len(rest)} pair(s) of the flat mesh's triangles sharing no node lie closer "
                f"than the thickness h = {h:g}: elements smaller than about h cannot take self-contact"
            )
        # the flat sheet's clearance beyond h: searched from its shortest edge in doubling distances
        # up to its longest (a vertex and the triangle across its own triangle's opposite edge are
        # closer than that), each search as cheap as the few pairs it finds (30x240: 3 s for one
        # search to the longest edge, 0.1 s this way)
        edges = np.asarray(ipctk.edges(F))
        length = np.linalg.norm(self.X[edges[:, 0]] - self.X[edges[:, 1]], axis=1)
        r, longest = float(length.min(initial=np.inf)), float(length.max(initial=0.0))
        clear = self._clearance(V, r)
        while clear >= r and 0.0 < r < longest:
            r = min(2.0 * r, longest)
            clear = self._clearance(V, r)
        self.reach = REACH * clear if math.isfinite(clear) else 0.0  # no edge: nothing to search
        self._ref: np.ndarray | None = None  # the reference point's vertices (N, 3)
        self._clear = 0.0  # its clearance beyond h [length]
        self._last: tuple | None = None  # (V, collision set or None when empty, e, g) of the last point

    def _V(self, D) -> np.ndarray:
        return np.asfortranarray(self.X + np.asarray(D, dtype=float).reshape(self.n, 6)[:, :3])

    def _collisions(self, V, reach: float = 0.0):
        """ipctk's collision set at V: the pairs sharing no node closer than h + reach (the
        barrier's own, reach 0, in one order: ``_serial``)."""
        self.builds += 1
        col = self._ipctk.NormalCollisions()
        with nullcontext() if reach > 0.0 else _serial(self._ipctk):
            col.build(self.mesh, V, self.s_hat + reach, self.d_min, self._bp)
        return col

    def _clearance(self, V, reach: float) -> float:
        """How far beyond h the closest pair sharing no node lies at V, searched to h + reach
        (reach when none is within)."""
        col = self._collisions(V, reach)
        if not len(col):
            return reach
        return math.sqrt(col.compute_minimum_distance(self.mesh, V)) - self.h  # ipctk's is squared

    @staticmethod
    def _radius(dV) -> float:
        """max_k |dV_k - t| [length] with t the centre of the (N, 3) displacements' bounding box: a
        bound on how far any vertex moved apart from a common translation."""
        t = 0.5 * (dV.max(axis=0) + dV.min(axis=0))
        return float(np.sqrt(((dV - t) ** 2).sum(axis=1).max()))

    def _set_at(self, V):
        """The collision set at V, or None when it is empty: known from the reference's clearance
        where that settles it, else from a broad phase to h + reach, whose
        point becomes the reference; only when that finds a pair within h the barrier's own."""
        if self.skip and self._ref is not None and 2.0 * self._radius(V - self._ref) < SKIP_SAFETY * self._clear:
            return None  # every pair sharing no node is still beyond h (module docstring)
        if self.skip:
            self._clear = self._clearance(V, self.reach)  # negative when a pair is within h
            self._ref = V
            if self._clear > 1e-9 * self.h:
                return None  # the nearest pair lies beyond h (not on it): the barrier's set is empty
        col = self._collisions(V)
        return col if len(col) else None

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
        last = self._last
        hit = last is not None and np.array_equal(last[0], V)
        col = last[1] if hit else self._set_at(V)
        if col is None:
            self._last = (V, None, 0.0, None)
            return 0.0, np.zeros(6 * self.n), (([], [], []) if want_tangent else None)
        if hit:
            e, g = last[2], last[3]
        else:
            with _serial(self._ipctk):
                e = float(self.barrier(col, self.mesh, V))
                g = self._full(self.barrier.gradient(col, self.mesh, V))
            self._last = (V, col, e, g)
        entries = None
        if want_tangent:
            with _serial(self._ipctk):
                H = self.barrier.hessian(col, self.mesh, V).tocoo()
            r, c = np.asarray(H.row, np.int64), np.asarray(H.col, np.int64)
            entries = ([6 * (r // 3) + r % 3], [6 * (c // 3) + c % 3], [np.asarray(H.data, float)])
        return e, g.copy(), entries

    def free_fraction(self, D0, D1) -> float:
        """The largest fraction t in [0, 1] of the straight step D0 -> D1 along which no pair comes
        closer than d_min (ipctk.compute_collision_free_stepsize); 1.0 without running it where
        the additive CCD's first advance of every pair passes the step's end (module docstring)."""
        ipctk = self._ipctk
        self.ccd_calls += 1
        V0, V1 = self._V(D0), self._V(D1)
        if self.skip and self._ref is not None:
            gap = self.h + self._clear - 2.0 * self._radius(V0 - self._ref) - self.d_min  # every pair's at V0
            if gap > 0.0 and 3.0 * self._radius(V1 - V0) < SKIP_SAFETY * ADDITIVE_ADVANCE * gap:
                return 1.0
        self.ccd_runs += 1
        return float(ipctk.compute_collision_free_stepsize(self.mesh, V0, V1, self.d_min, self._bp, self._ccd))

    def cut(self, D0, D1) -> float:
        """1.0 when the step D0 -> D1 is free of crossings, else CCD_SAFETY x its free fraction."""
        t = self.free_fraction(D0, D1)
        if t >= 1.0:
            return 1.0
        self.ccd_cuts += 1
        return CCD_SAFETY * t
