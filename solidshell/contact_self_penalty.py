"""Self-contact of the sheet in explicit dynamics and relaxation: a penalty between its layers,
evaluated on candidate pairs found by a compiled grid and kept while no node has moved far.

The law (issue 37: two layers keep their mid-surfaces about a thickness h apart)
--------------------------------------------------------------------------------
The mid-surface as triangles (layers.triangles).  Every vertex-triangle pair and every edge-edge
pair sharing no node whose distance d lies below h carries the energy

    E = k/2 (h - d)^2                                                       [force x length]

and pushes its two closest points apart along the line joining them with k (h - d), spread on the
nodes by the closest points' weights (the exact gradient of E).  A vertex meets a triangle where
its closest point lies inside the triangle, and an edge or a corner shared by several triangles
once, by the triangle that owns it; an edge meets an edge where both closest points lie inside the
edges (at an end point the pair is a vertex's): the collision set of Incremental Potential Contact
(Li et al., SIGGRAPH 2020) with a penalty in place of its barrier.  Both faces of the sheet alike:
the distance is unsigned.  Frictionless.

The edge pairs are what keeps two folded layers apart between their nodes: on square-on-disc
10x80 relaxed with vertex-triangle pairs alone, the vertices stayed 0.97 h from the other layer
while the chords of the curved layers came to 0.66 h of each other (layers.py's gap, 18 pairs
below 0.9 h).

Pairs closer than REST_MIN h = 2h in the flat reference state are neighbours in the sheet, not
layers, and never take part: two such points face each other across a fold only if its radius is
below 2h / pi < h, tighter than two layers of thickness h can fold (on the meshes this code makes
they are the pairs sharing a node, hanging nodes on their coarse neighbours' edges, and in refined
regions the next ring).

k: the penalty of the rigid bodies scaled down, k_pair = SELF_SHARE x k_pen per node
(contact.penalty_stiffness: contact_penalty_factor x m omega_max^2), a pair taking the smallest of
its nodes'.  A node of one of two resting layers sits in about BUDGET_PAIRS pair springs' worth of
row sum (its own vertex pairs, two or three near the other layer's edges, its triangles' share of
the other layer's vertex pairs, and some six crossing edge pairs, each with row sum <= 2 k_pair),
so the critical step budgets BUDGET_PAIRS x SELF_SHARE x k_pen = k_pen per node for it
(solvers/explicit/stepcontrol.limit): the price of one more rigid body.

A penalty, not a barrier: nothing forbids a layer from passing through another, it is only pushed
back, with k (h - d).  Two layers meeting at speed v come within about v / omega_c of each other,
omega_c = sqrt(2 k_pair / m) ~ 0.11 omega_max; at the speeds of a drape (a fall of a few cm,
~1 m/s) that is a small fraction of h.  benchmarks/self_contact_cost.py drops a sheet onto another
from random heights, angles and places and counts the drops that end with crossing triangles.

Candidates (a Verlet list): at a search, every pair within h + margin by its true distance (and
not neighbours).  The search is repeated once some node has moved more than margin / 2 since the
last one, moves measured from their common part (the middle of their bounding box:
contact_self_kernels.relative_move), so that a sheet falling as a whole needs none: a pair's vertex
and closest point then moved apart or together by at most margin, so a pair that was beyond
h + margin is still beyond h and the pass over the candidates gives the forces of all pairs
exactly.  The margin is as wide as the mesh allows (MARGIN_MIN h ... MARGIN_MAX h): up to the
nearest flat-sheet pair that is not a neighbour (contact_self_kernels.nearest_rest_pair), so that in
a region without folds no pair is a candidate and a sheet without folds pays only the searches.
The search is a compiled uniform grid (contact_self_kernels.vf_candidates and ee_candidates):
measured against the IPC Toolkit's LBVH on two 70 x 70 sheets resting on each other (10^4 nodes,
the heaviest case), the library's broad phase takes 35-50 ms and handing its 5 x 10^5 candidate
objects to numpy another 300 ms; the grid gives both kinds of pair in 87 ms (vertex pairs alone:
30 ms) and takes ~4 ms on a 60 x 60 sheet without folds.
"""

from __future__ import annotations

import math

import numpy as np

from . import contact_self_kernels as sk
from .layers import triangles

SELF_SHARE = 1.0 / 16.0
"""A pair's penalty as a share of the rigid bodies' per-node penalty k_pen."""

BUDGET_PAIRS = 16
"""Pair springs per node the critical step allows for (module docstring): SELF_SHARE x BUDGET_PAIRS = 1."""

MARGIN_MIN, MARGIN_MAX = 1.0, 8.0
"""The candidates' margin in multiples of h (module docstring): as wide as the mesh allows within
these bounds."""

REST_MIN = 2.0
"""Pairs closer than REST_MIN x h in the flat reference state are neighbours, never layers
(module docstring)."""


def _stacked_edges(tri: np.ndarray) -> np.ndarray:
    """(3T, 2) the edges ab of every triangle, then bc, then ca, each as (i < j)."""
    return np.sort(np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)


def edges_of(tri: np.ndarray) -> np.ndarray:
    """(E, 2) the unique edges (i < j) of the triangles tri (T, 3)."""
    return np.unique(_stacked_edges(tri), axis=0)


def ownership(tri: np.ndarray, n_nodes: int) -> np.ndarray:
    """(T,) bit masks: a triangle owns an edge (bits 0-2: ab, bc, ca) and a corner (bits 3-5: a, b,
    c) when it holds the feature's first occurrence in the stacked order: each feature has exactly
    one owner."""
    T = len(tri)
    own = np.zeros(T, dtype=np.int64)
    e = _stacked_edges(tri)
    key = e[:, 0].astype(np.int64) * n_nodes + e[:, 1]
    _, first = np.unique(key, return_index=True)
    for bit in range(3):
        sel = first[(first >= bit * T) & (first < (bit + 1) * T)] - bit * T
        own[sel] |= 1 << bit
    flat = tri.T.ravel()  # corner a of every triangle, then b, then c
    _, first = np.unique(flat, return_index=True)
    for bit in range(3):
        sel = first[(first >= bit * T) & (first < (bit + 1) * T)] - bit * T
        own[sel] |= 1 << (3 + bit)
    return own


class SelfPenalty:
    """The penalty self-contact of ``mesh`` (a ShellMesh) of thickness h [length] with per-node
    stiffness k (N,) [force/length] (already scaled by SELF_SHARE); works on flat dof vectors D (6N,)."""

    def __init__(self, mesh, h: float, k):
        self.X0 = np.ascontiguousarray(mesh.nodes, dtype=float)
        self.N = len(self.X0)
        self.tri = np.ascontiguousarray(triangles(mesh), dtype=np.int64)
        self.own = ownership(self.tri, self.N)
        self.edges = np.ascontiguousarray(edges_of(self.tri), dtype=np.int64)
        self.h = float(h)
        self.k = np.ascontiguousarray(np.broadcast_to(np.asarray(k, dtype=float), (self.N,)))
        self.rest_min = REST_MIN * self.h
        # the widest margin that keeps a flat sheet's neighbours out of the candidates
        near = sk.nearest_rest_pair(self.X0, self.tri, self.edges, (1.0 + MARGIN_MAX) * self.h, self.rest_min)
        self.margin = min(max(0.99 * (near - self.h), MARGIN_MIN * self.h), MARGIN_MAX * self.h)
        self.vf = np.zeros((0, 2), dtype=np.int64)
        self.ee = np.zeros((0, 2), dtype=np.int64)
        self.Xb = self.X0.copy()  # positions at the last search (none before the first: searches = 0)
        self.searches = 0
        self.min_gap = np.inf  # smallest distance of a pair in contact seen by the passes [length]

    # ------------------------------------------------------------------ candidates
    def search(self, x: np.ndarray) -> None:
        """Candidate pairs within h + margin at positions x (N, 3)."""
        r = self.h + self.margin
        x = np.ascontiguousarray(x, dtype=float)
        vf = sk.vf_candidates(x, self.X0, self.tri, r, self.rest_min)
        # in (triangle, vertex) order: the pairs in contact are then summed in the same order
        # whatever state the search saw, so a restart gives the forces bit for bit
        self.vf = np.ascontiguousarray(vf[np.argsort(vf[:, 1] * self.N + vf[:, 0], kind="stable")])
        ee = sk.ee_candidates(x, self.X0, self.edges, r, self.rest_min)
        self.ee = np.ascontiguousarray(ee[np.argsort(ee[:, 0] * len(self.edges) + ee[:, 1], kind="stable")])
        self.Xb = x.copy()
        self.searches += 1

    # ------------------------------------------------------------------ forces
    def add_forces(self, D, C):
        """Add the penalty forces at D (6N,) into C (6N,); (energy, pairs in contact)."""
        if not self.refresh(D):
            return 0.0, 0
        return self.forces(D, C)

    def refresh(self, D) -> bool:
        """Search anew if some node has moved too far since the last search (module docstring):
        whether any candidate pair stands at D (False too when a position is not finite: no
        forces then, the integrator stops on it)."""
        move = sk.relative_move(self.X0, D, self.Xb) if self.searches else 0.0
        if math.isnan(move):
            return False
        if not self.searches or move > 0.5 * self.margin:
            self.search(self.X0 + D.reshape(self.N, 6)[:, :3])
        return bool(len(self.vf) or len(self.ee))

    def forces(self, D, C):
        """Add the candidates' penalty forces at D into C, the candidates current (:meth:`refresh`);
        (energy, pairs in contact)."""
        E, n, dmin = sk.self_pass(self.X0, D, self.tri, self.own, self.vf, self.edges, self.ee, self.k, self.h, C)
        if dmin < self.min_gap:
            self.min_gap = dmin
        return E, n
