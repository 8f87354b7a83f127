"""Selective mass scaling of an adapted mesh for a relaxation (``adapt.step_level``).

An explicit step is bounded by the mesh's smallest element.  The paper's premise for adaptivity
(§5: the critical step of its solid-shell elements is set by the thickness stretching mode, not by
the element's size) does not hold for elements whose thickness strain is condensed (plane stress):
their top frequency grows as 1/size, and a finer finest level costs steps.  A relaxation seeks a
static state, which the masses do not enter (the paper scales all of them by 100 for this, §4.2),
so the elements finer than a chosen level get mass enough for that level's step:

    w_e = max(1, (h_k / h_e)^2),   h = area / longest side (quads), 2 area / longest side (triangles)

h is the explicit codes' characteristic length of a shell element (a quad's: area over its longest
side; a triangle's: its smallest altitude), h_k the smallest of level k's quads.  The top frequency of
an element goes as c / h, so w_e brings the element's to level k's.
"""

from __future__ import annotations

import numpy as np


def characteristic_lengths(X, conn) -> np.ndarray:
    """(M,) characteristic length of each element of ``conn`` (M, 3 or 4) on the points X [length]."""
    P = np.asarray(X, float)[np.asarray(conn)]
    longest = np.max(np.linalg.norm(np.roll(P, -1, axis=1) - P, axis=-1), axis=1)
    if P.shape[1] == 3:
        area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
        return 2.0 * area / longest
    area = 0.5 * np.linalg.norm(np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1]), axis=1)
    return area / longest


def level_length(bg, level: int) -> float:
    """h_k: the smallest characteristic length of the background mesh's level-``level`` quads."""
    return float(np.min(characteristic_lengths(bg.Xo, bg.conn[level])))


def step_weights(mesh, h_target: float) -> np.ndarray:
    """(n_elements,) mass factors of a mesh (quads first, then triangles) that raise every element
    shorter than ``h_target`` to its step: (h_target / h_e)^2, else 1."""
    h = np.concatenate([characteristic_lengths(mesh.nodes, c) for c in (mesh.quads, mesh.tris) if len(c)])
    return np.maximum(1.0, (h_target / h) ** 2)
