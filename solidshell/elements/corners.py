"""n_p . d_p at every element corner (Section 4.3), compiled: the interpenetration test.

n_p is the unit normal of the deformed corner p (the cross product of the edges to its next and its
previous corner), d_p the unit deformed director; n_p . d_p < 0 where the top and bottom surfaces of
the element have passed through each other (and the Eq. 24 branch flag is n_p . d_p <= -mu).

One pass over the corners, no temporaries: the NumPy form (rolled corner arrays, np.cross,
np.linalg.norm) made ~15 arrays of the element blocks' size and took 15-20 ms per call on a 10^4-quad
sheet, which the relaxation evaluates at every energy sample.  No fast-math: each value is formed by
the operations of that NumPy form in its order ((a1 b2 - a2 b1) per component, the squares summed
left to right, sqrt, then a division), so the values are the same bits (tests/test_model.py).
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def corner_alignment(X, Xn, U, conn, out):
    """out[e, p] = n_p . d_p of element e's corner p, for the current nodes X + U[:, :3] and directors
    Xn + U[:, 3:] ((N,3), (N,3), (N,6)); conn (M, nn) counter-clockwise corners."""
    M, nn = conn.shape
    for e in range(M):
        for p in range(nn):
            a = conn[e, p]
            b = conn[e, (p + 1) % nn]
            c = conn[e, (p + nn - 1) % nn]
            px = X[a, 0] + U[a, 0]
            py = X[a, 1] + U[a, 1]
            pz = X[a, 2] + U[a, 2]
            ux = (X[b, 0] + U[b, 0]) - px
            uy = (X[b, 1] + U[b, 1]) - py
            uz = (X[b, 2] + U[b, 2]) - pz
            vx = (X[c, 0] + U[c, 0]) - px
            vy = (X[c, 1] + U[c, 1]) - py
            vz = (X[c, 2] + U[c, 2]) - pz
            nx = uy * vz - uz * vy
            ny = uz * vx - ux * vz
            nz = ux * vy - uy * vx
            ln = math.sqrt(nx * nx + ny * ny + nz * nz)
            dx = Xn[a, 0] + U[a, 3]
            dy = Xn[a, 1] + U[a, 4]
            dz = Xn[a, 2] + U[a, 5]
            ld = math.sqrt(dx * dx + dy * dy + dz * dz)
            out[e, p] = (nx / ln) * (dx / ld) + (ny / ln) * (dy / ld) + (nz / ln) * (dz / ld)
