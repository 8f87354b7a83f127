"""Local physical frame and strain transformations of Eq. (6), vectorised over points.

z is the mid-surface normal A1 x A2; x is the warp direction (global X turned by the warp angle about
global Z) projected on the tangent plane; y = z x x.  Where the warp is (nearly) normal to the
surface, x falls back to A1 (the natural xi direction), so any orientation of a shell is valid.
"""

from __future__ import annotations

import numpy as np


def local_frame(A1: np.ndarray, A2: np.ndarray, warp_angle: float):
    """(ex, ey, ez), each (...,3), at points with mid-surface tangents A1, A2 (...,3)."""
    ez = np.cross(A1, A2)
    ez /= np.linalg.norm(ez, axis=-1, keepdims=True)
    w = np.array([np.cos(warp_angle), np.sin(warp_angle), 0.0])
    ex = w - np.sum(w * ez, axis=-1, keepdims=True) * ez
    nx = np.linalg.norm(ex, axis=-1, keepdims=True)
    a1 = A1 / np.linalg.norm(A1, axis=-1, keepdims=True)
    ex = np.where(nx > 1e-6, ex / np.maximum(nx, 1e-300), a1)
    ey = np.cross(ez, ex)
    return ex, ey, ez


def covariant_maps(A1, A2, ex, ey):
    """Q = J2^-1 (...,2,2) with J2 = [[A1.ex, A1.ey], [A2.ex, A2.ey]], and the Voigt map T (...,3,3)
    taking natural (e_11, e_22, gamma_12) to local (eps_xx, eps_yy, gamma_xy): E_loc = Q E_nat Q^T.
    The same Q maps natural transverse shears (gamma_z1, gamma_z2) to (gamma_zx, gamma_zy)."""
    J2 = np.stack(
        [
            np.stack([np.sum(A1 * ex, -1), np.sum(A1 * ey, -1)], -1),
            np.stack([np.sum(A2 * ex, -1), np.sum(A2 * ey, -1)], -1),
        ],
        -2,
    )
    Q = np.linalg.inv(J2)
    q00, q01, q10, q11 = Q[..., 0, 0], Q[..., 0, 1], Q[..., 1, 0], Q[..., 1, 1]
    T = np.stack(
        [
            np.stack([q00 * q00, q01 * q01, q00 * q01], -1),
            np.stack([q10 * q10, q11 * q11, q10 * q11], -1),
            np.stack([2 * q00 * q10, 2 * q01 * q11, q00 * q11 + q01 * q10], -1),
        ],
        -2,
    )
    return Q, T


def fold(T: np.ndarray, C: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """T^T C T * scale over leading axes: the rigidity acting on natural strains (batched matrix
    products: the three-operand einsum took 6x as long)."""
    return (np.swapaxes(T, -1, -2) @ C @ T) * scale[..., None, None]
