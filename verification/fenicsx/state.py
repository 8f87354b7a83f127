"""Drape states between the two codes (venv side, numpy only).

solidshell's state is an (N, 6) array per node [U_o | U_n] (Eq. 1): the mid-surface translation
U_o [cm] and the change U_n of the director, whose current value x_n = X_n + U_n starts as the unit
normal X_n; h x_n spans the thickness, so |x_n| - 1 is the thickness stretch (Eq. 5).

The DOLFINx model's state (a job's ``initial_state``, a result's ``U`` and ``director``) is the
translation u [cm] and the director d at the same nodes (solidshell's numbering).  Its shell is
Naghdi with an inextensible director: the result's d is a unit vector, and a director handed to it
is normalised (model.py, rotation_vector_from_director).

So the maps are
    solidshell -> DOLFINx:  u = U_o,  d = X_n + U_n       (the model keeps only its direction)
    DOLFINx -> solidshell:  U_o = u,  U_n = d - X_n       (a unit d: no thickness stretch; the
                                                           solidshell solve finds its own)
and a solidshell state goes to the DOLFINx format and back unchanged up to the round-off of
(X_n + U_n) - X_n.
"""

from __future__ import annotations

import numpy as np

__all__ = ["to_fenicsx_state", "from_fenicsx_state", "max_translation_change"]


def _directors(mesh, n):
    X = np.asarray(mesh.directors, dtype=float)
    if X.shape != (n, 3):
        raise ValueError(f"state has {n} nodes, the mesh {len(X)}")
    return X


def to_fenicsx_state(mesh, U, lam: float = 1.0) -> dict:
    """A DOLFINx ``initial_state`` (U, director, lambda) from solidshell's (N, 6) state on ``mesh``."""
    U = np.asarray(U, dtype=float).reshape(-1, 6)
    X = _directors(mesh, len(U))
    return {"U": U[:, :3].tolist(), "director": (X + U[:, 3:6]).tolist(), "lambda": float(lam)}


def from_fenicsx_state(mesh, u, director) -> np.ndarray:
    """solidshell's (N, 6) state [U_o | U_n] from the DOLFINx translations u and directors d (N, 3)."""
    u = np.asarray(u, dtype=float)
    d = np.asarray(director, dtype=float)
    if u.shape != d.shape or u.ndim != 2 or u.shape[1] != 3:
        raise ValueError(f"u and director must both be (N, 3), got {u.shape} and {d.shape}")
    X = _directors(mesh, len(u))
    return np.hstack([u, d - X])


def max_translation_change(Ua, Ub) -> float:
    """max over nodes of |U_o,a - U_o,b| [cm] (the first three columns of each state)."""
    Ua, Ub = np.asarray(Ua, dtype=float), np.asarray(Ub, dtype=float)
    return float(np.max(np.linalg.norm(Ua[:, :3] - Ub[:, :3], axis=1)))
