"""Supports and loads on a mesh: clamps, prescribed dofs, self-weight, point, line and surface loads.

All loads are dead (fixed in direction and size) and returned as (N,6) nodal force arrays on the
U_o dofs, in the model's force unit (gf for the paper's scenes).  Distributed loads are lumped with
the same trapezoidal-rule areas as the mass (Section 4), so gravity and inertia stay consistent.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError

_DOF_GROUPS = {"all": slice(0, 6), "translations": slice(0, 3), "directors": slice(3, 6)}


def clamp(mesh, nodes, dofs: str = "all") -> np.ndarray:
    """(N,6) bool mask fixing ``dofs`` ("all": U_o and U_n, as on a pedestal edge; "translations":
    U_o only, a pin; "directors": U_n only) of the given node indices or node-set name."""
    idx = mesh.node_set(nodes) if isinstance(nodes, str) else np.unique(np.asarray(nodes, dtype=np.int64))
    if idx.size == 0:
        raise InputError("the clamped set selects no node")
    try:
        sl = _DOF_GROUPS[dofs]
    except KeyError:
        raise InputError(f"dofs must be one of {', '.join(_DOF_GROUPS)}, got {dofs!r}") from None
    fixed = np.zeros((mesh.n_nodes, 6), dtype=bool)
    fixed[idx, sl] = True
    return fixed


def _direction(direction) -> np.ndarray:
    d = np.asarray(direction, dtype=float)
    n = np.linalg.norm(d)
    if d.shape != (3,) or not np.isfinite(n) or n == 0:
        raise InputError(f"a load direction must be a non-zero 3-vector, got {direction!r}")
    return d / n


def surface_load(model, pressure: float, direction=(0.0, 0.0, -1.0)) -> np.ndarray:
    """Uniform dead load ``pressure`` [force/area] along ``direction``, lumped by nodal area."""
    P = np.zeros((model.n_nodes, 6))
    P[:, :3] = pressure * model.nodal_areas()[:, None] * _direction(direction)
    return P


def gravity_loads(model, direction=(0.0, 0.0, -1.0)) -> np.ndarray:
    """Self-weight: the section's weight per area [force/area] (0.019 gf/cm^2 for wool) on the nodal
    areas.  Independent of any mass scaling (Section 4.2)."""
    return surface_load(model, model.material.weight_per_area, direction)


def point_load(n_nodes: int, nodes, force) -> np.ndarray:
    """Nodal force vector ``force`` (3,) [force] at each of ``nodes``."""
    P = np.zeros((n_nodes, 6))
    P[np.asarray(nodes, dtype=np.int64), :3] += np.asarray(force, dtype=float)
    return P


def line_load(mesh, nodes, force_per_length) -> np.ndarray:
    """Dead load ``force_per_length`` (3,) [force/length] along the mesh edges joining ``nodes``
    (both ends in the set); each edge gives half its resultant to each end."""
    idx = mesh.node_set(nodes) if isinstance(nodes, str) else np.asarray(nodes, dtype=np.int64)
    inset = np.zeros(mesh.n_nodes, dtype=bool)
    inset[idx] = True
    e = mesh.edges()
    e = e[inset[e[:, 0]] & inset[e[:, 1]]]
    if len(e) == 0:
        raise InputError("the line load's node set contains no mesh edge")
    L = np.linalg.norm(mesh.nodes[e[:, 1]] - mesh.nodes[e[:, 0]], axis=1)
    w = np.zeros(mesh.n_nodes)
    np.add.at(w, e.ravel(), np.repeat(0.5 * L, 2))
    P = np.zeros((mesh.n_nodes, 6))
    P[:, :3] = w[:, None] * np.asarray(force_per_length, dtype=float)
    return P


def director_rotation(mesh, nodes, axis, angle: float) -> np.ndarray:
    """(N,6) displacement that turns the directors of ``nodes`` by ``angle`` [rad] about ``axis``
    (right-hand rule), U_n = R X_n - X_n, all else zero: a prescribed end rotation for displacement
    control.  For a rotation path pass ``lambda lam: director_rotation(mesh, nodes, axis, lam*phi)``
    as ``prescribed`` (a linear scaling of one array would shrink the director)."""
    from scipy.spatial.transform import Rotation

    idx = mesh.node_set(nodes) if isinstance(nodes, str) else np.asarray(nodes, dtype=np.int64)
    R = Rotation.from_rotvec(float(angle) * _direction(axis)).as_matrix()
    U = np.zeros((mesh.n_nodes, 6))
    U[idx, 3:] = mesh.directors[idx] @ R.T - mesh.directors[idx]
    return U
