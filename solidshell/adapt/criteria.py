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

__all__ = ["DEFAULT_CONST", "DEFAULT_EPS", "check_thresholds", "side_lengths",
           "level_side_lengths", "leaf_bending_strain", "Marks", "mark"]

DEFAULT_CONST = 0.5
DEFAULT_EPS = 0.2


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
    eb = np.asarray(eps_b_elem, float)
    el = np.asarray(elem_leaf, dtype=np.int64)
    if el.shape != (len(eb), 2):
        raise ValueError(f"elem_leaf has shape {el.shape}, expected ({len(eb)}, 2)")
    leaves, inv = _unique_items(el)
    out = np.full(len(leaves), -np.inf)
    np.maximum.at(out, inv, eb)
    return leaves, out


_INDEX_BITS = 40
"""Bits of an element index in the 1-d key of a (level, index) pair (4^20 elements per level)."""


def _unique_items(items) -> tuple[np.ndarray, np.ndarray]:
    """np.unique(items, axis=0, return_inverse=True) for (K,2) (level, index) pairs (rows sorted
    by level then index), by the 1-d key level * 2^40 + index: np.unique over rows sorts a
    structured view, ~10x slower (0.4 s of the paper path's remeshing)."""
    it = np.asarray(items, dtype=np.int64).reshape(-1, 2)
    if it.size and (it.min() < 0 or it[:, 1].max() >= 1 << _INDEX_BITS):
        raise ValueError("element (level, index) pairs out of range")
    keys, inv = np.unique((it[:, 0] << _INDEX_BITS) | it[:, 1], return_inverse=True)
    return np.column_stack([keys >> _INDEX_BITS, keys & ((1 << _INDEX_BITS) - 1)]), inv.ravel()


@dataclass(frozen=True)
class Marks:
    """split: (n_leaf,) bool, leaves to split (Eq. 25); merge: (k,2) int, the (level, index) parents
    whose four children are all leaves satisfying Eq. (26).  Balance (2:1) is the mesh's job."""

    split: np.ndarray
    merge: np.ndarray


def mark(eps_b_leaf, leaves, L, const: float = DEFAULT_CONST, eps: float = DEFAULT_EPS,
         max_level: int | None = None) -> Marks:
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
    for l in np.unique(lev):                    # a handful of levels, vectorised within each
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
