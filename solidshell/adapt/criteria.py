"""Split and merge marking (paper §5.2, Eqs. 25-26).

A leaf element of level i is split where         ||eps_b|| L_i     >  const         (Eq. 25)
four sibling leaves of level i are merged where all  ||eps_b|| L_(i-1) <= const - eps   (Eq. 26)

||eps_b|| is the bending strain of Eq. (6) (``Model.bending_strain``), a curvature [1/length], and
L_i the element's average side length in the initial geometry [length], so ||eps_b|| L_i is about
the angle [rad] through which the sheet turns across one element: for a cylindrical bend of
curvature kappa, ||eps_b|| = kappa (1 - (kappa L)^2 / 12 + ...) (tests/test_adapt_transfer.py).

Defaults (the paper gives no values).  ``const`` is the largest bending angle per element accepted
before splitting.  DEFAULT_CONST = 0.5 rad (29 deg): a flat 4-node element spanning a bend of angle
theta misses the arc by a sagitta of ~theta L / 8, 6 % of its side at theta = 0.5, and the DK
transfer's mid-node error, kappa^3 L^4 / 384 = theta^3 L / 384, is 3e-4 L there.  On wool, whose folds
have radii of ~0.3-1 cm (kappa ~ 1-3 /cm), this splits a level-0 element of the square-pedestal
scene (mean side L ~ 2.5 cm) wherever the radius of curvature falls below 5 cm, and asks for the
finest level (L ~ 0.3 cm at level 3) wherever it falls below ~1.2 cm, i.e. across every fold.
Measured on the static square-pedestal drape at 24x8x4 (= level 2 of its 48-quad level 0; kappa up
to 1.5 /cm, median 0.22 /cm): 17 % of its elements need level 3 and the active elements come to ~24 %
of the uniform 48x16x4 mesh before 2:1 balance and transition patterns (const 0.3: 31 % and 38 %;
0.8: 4 % and 11 %, leaving up to 0.8 rad per element in the folds), inside the paper's "only half".
DEFAULT_EPS = 0.2 is the hysteresis: just after a split, the children have the parent's curvature,
so they merge back only once ||eps_b|| L_(i-1) has fallen from above 0.5 to 0.3 or less, a 40 % drop of
the curvature; a small eps makes elements near the threshold split and merge at every remesh.

Per-leaf strains.  A transition leaf (§5.3) holds several computational elements; its
||eps_b|| is the maximum over them (``leaf_bending_strain``): a fold that crosses only one of its
triangles must still split it (Eq. 25 is "sufficient" for splitting), and Eq. (26) asks that all of
the merged area be flat, which the maximum enforces and a mean would dilute.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = [
    "DEFAULT_CONST",
    "DEFAULT_EPS",
    "GUARD_OFF",
    "check_thresholds",
    "side_lengths",
    "level_side_lengths",
    "leaf_bending_strain",
    "leaf_alignment",
    "Marks",
    "mark",
    "guard",
]

DEFAULT_CONST = 0.5
DEFAULT_EPS = 0.2
GUARD_OFF = -1.0
"""The interpenetration guard's threshold that turns it off: n_p . d_p >= -1 everywhere."""


def check_thresholds(const: float, eps: float) -> tuple[float, float]:
    """(const, eps) as floats; InputError unless const > eps > 0 and both finite (Eqs. 25-26)."""
    try:
        c, e = float(const), float(eps)
    except (TypeError, ValueError):
        raise InputError(f"adapt const = {const!r}, eps = {eps!r}: numbers expected") from None
    if not (np.isfinite(c) and c > 0.0):
        raise InputError(f"adapt const = {const!r}: must be a positive number (Eq. 25)")
    if not (np.isfinite(e) and e > 0.0):
        raise InputError(f"adapt eps = {eps!r}: must be a positive number (Eq. 26)")
    if not e < c:
        raise InputError(f"adapt eps = {eps!r} must be less than const = {const!r} (Eq. 26)")
    return c, e


def side_lengths(Xo, conn) -> np.ndarray:
    """(M,) average side length of each element (rows of ``conn``, corners in order) [length]."""
    P = np.asarray(Xo, float)[np.asarray(conn)]
    return np.mean(np.linalg.norm(np.roll(P, -1, axis=1) - P, axis=-1), axis=1)


def level_side_lengths(bg) -> list[np.ndarray]:
    """L_i of every element of every level of a background mesh, from its initial geometry:
    ``[side_lengths(bg.Xo, bg.conn[l]) for l in 0..bg.levels]``."""
    return [side_lengths(bg.Xo, bg.conn[l]) for l in range(len(bg.conn))]


def leaf_bending_strain(eps_b_elem, elem_leaf):
    """Reduce per-element ||eps_b|| to per-leaf values by the maximum (see the module docstring).

    eps_b_elem : (n_elements,) e.g. ``Model.bending_strain(U)`` on the active mesh
    elem_leaf : (n_elements, 2) the (level, index) leaf of each element
    Returns (leaves (n_leaf,2) sorted by level then index, eps_b_leaf (n_leaf,))."""
    return _per_leaf(eps_b_elem, elem_leaf, np.maximum, -np.inf)


def leaf_alignment(nd_elem, elem_leaf):
    """Per-leaf lowest corner alignment n_p . d_p (Section 4.3; ``Model.interpenetration`` reduced
    over each element's corners), for :func:`guard`.  Same arguments and leaf order as
    :func:`leaf_bending_strain`."""
    return _per_leaf(nd_elem, elem_leaf, np.minimum, np.inf)


def _per_leaf(values, elem_leaf, ufunc, start):
    v = np.asarray(values, float)
    el = np.asarray(elem_leaf, dtype=np.int64)
    if el.shape != (len(v), 2):
        raise ValueError(f"elem_leaf has shape {el.shape}, expected ({len(v)}, 2)")
    leaves, inv = _unique_items(el)
    out = np.full(len(leaves), start)
    ufunc.at(out, inv, v)
    return leaves, out


_INDEX_BITS = 40
"""Bits of an element index in the 1-d key of a (level, index) pair (4^20 elements per level)."""


def _unique_items(items) -> tuple[np.ndarray, np.ndarray]:
    """np.unique(items, axis=0, return_inverse=True) for (K,2) (level, index) pairs (rows sorted
    by level then index), by the 1-d key level * 2^40 + index: np.unique over rows sorts a
    structured view, ~10x slower (0.4 s of the paper path's remeshing)."""
    keys, inv = np.unique(_keys(items), return_inverse=True)
    return np.column_stack([keys >> _INDEX_BITS, keys & ((1 << _INDEX_BITS) - 1)]), inv.ravel()


def _keys(items) -> np.ndarray:
    """(K,) int64 key level * 2^40 + index of each (level, index) pair."""
    it = np.asarray(items, dtype=np.int64).reshape(-1, 2)
    if it.size and (it.min() < 0 or it[:, 1].max() >= 1 << _INDEX_BITS):
        raise ValueError("element (level, index) pairs out of range")
    return (it[:, 0] << _INDEX_BITS) | it[:, 1]


@dataclass(frozen=True)
class Marks:
    """split: (n_leaf,) bool, leaves to split (Eq. 25); merge: (k,2) int, the (level, index) parents
    whose four children are all leaves satisfying Eq. (26).  Balance (2:1) is the mesh's job."""

    split: np.ndarray
    merge: np.ndarray


def mark(
    eps_b_leaf, leaves, L, const: float = DEFAULT_CONST, eps: float = DEFAULT_EPS, max_level: int | None = None
) -> Marks:
    """Split/merge marks of Eqs. (25)-(26).

    eps_b_leaf : (n_leaf,) ||eps_b|| per leaf [1/length]
    leaves : (n_leaf,2) (level, index) of each leaf
    L : per-level element side lengths, ``L[l][e]`` [length] (``level_side_lengths(bg)``)
    const, eps : thresholds, const > eps > 0 (InputError otherwise)
    max_level : no split beyond it (default: the finest level of L)
    """
    c, e = check_thresholds(const, eps)
    eb = np.asarray(eps_b_leaf, float)
    lv = np.asarray(leaves, dtype=np.int64)
    if lv.shape != (len(eb), 2):
        raise ValueError(f"leaves has shape {lv.shape}, expected ({len(eb)}, 2)")
    top = len(L) - 1 if max_level is None else min(int(max_level), len(L) - 1)
    lev, idx = lv[:, 0], lv[:, 1]
    Li = np.zeros(len(eb))
    for l in np.unique(lev):  # a handful of levels, vectorised within each
        sel = lev == l
        Li[sel] = L[l][idx[sel]]
    split = (eb * Li > c) & (lev < top)

    child = lev >= 1
    parents = np.stack([lev[child] - 1, idx[child] // 4], axis=1)
    if len(parents) == 0:
        return Marks(split, np.zeros((0, 2), dtype=np.int64))
    Lp = np.zeros(len(parents))
    for l in np.unique(parents[:, 0]):
        sel = parents[:, 0] == l
        Lp[sel] = L[l][parents[sel, 1]]
    ok = (eb[child] * Lp <= c - e) & ~split[child]
    uniq, inv = _unique_items(parents)
    n_children = np.bincount(inv, minlength=len(uniq))
    n_ok = np.bincount(inv, weights=ok, minlength=len(uniq))
    return Marks(split, uniq[(n_children == 4) & (n_ok == 4)])


def guard(marks: Marks, nd_leaf, leaves, threshold: float, max_level: int) -> Marks:
    """The interpenetration guard (``adapt.guard_alignment``) on top of Eqs. (25)-(26).

    Section 4.3 flags a corner whose deformed normal n_p and director d_p point apart, n_p . d_p < 0:
    the top and bottom surfaces cross there.  It happens where a fold turns the sheet through more
    than an element can follow (the crease of a folded-shut corner "ear"), well before Eq. (25)'s
    per-element angle says so on a mesh capped at its finest curvature level.  The guard splits a
    leaf whose lowest corner alignment falls below ``threshold`` (up to ``max_level``), and vetoes
    the merge of four siblings unless each has n_p . d_p >= cos(acos(threshold) / 2): halving a
    leaf about halves the angle between a corner's normal and its director, so this is Eq. (26)'s
    hysteresis in the same measure (a parent would be back at the threshold).

    marks : Eq. (25)-(26)'s marks of the same leaves
    nd_leaf : (n_leaf,) lowest n_p . d_p per leaf (``leaf_alignment``)
    threshold : in [-1, 1); GUARD_OFF (-1) returns ``marks`` unchanged
    """
    g = float(threshold)
    if not -1.0 <= g < 1.0:
        raise ValueError(f"guard threshold {threshold!r} must lie in [-1, 1)")
    if g <= GUARD_OFF:
        return marks
    nd = np.asarray(nd_leaf, float)
    lv = np.asarray(leaves, dtype=np.int64)
    if lv.shape != (len(nd), 2):
        raise ValueError(f"leaves has shape {lv.shape}, expected ({len(nd)}, 2)")
    split = np.asarray(marks.split, bool) | ((nd < g) & (lv[:, 0] < int(max_level)))
    merge = np.asarray(marks.merge, dtype=np.int64).reshape(-1, 2)
    if len(merge):
        keep_above = np.cos(0.5 * np.arccos(g))
        low = lv[(lv[:, 0] >= 1) & (nd < keep_above)]
        merge = merge[~np.isin(_keys(merge), _keys(np.stack([low[:, 0] - 1, low[:, 1] // 4], axis=1)))]
    return Marks(split, merge)
