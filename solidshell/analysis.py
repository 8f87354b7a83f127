"""Drape measures of a deformed shell mesh: projected boundary, drape coefficient, folds, asymmetry.

Everything here works on plain arrays (pure numpy/scipy); nothing knows about solvers or scenes.

Definitions (the paper's Section 3 and the usual drape-tester conventions)
---------------------------------------------------------------------------
projected boundary
    The mesh's boundary edges (edges of exactly one element) are chained into closed loops; each
    loop is projected on the X-Y plane with the deformed positions X_o + U_o.  The *outer* loop is the
    one enclosing the largest |area|; it is returned counter-clockwise (positive shoelace area).  A
    pedestal scene models only the hanging part, so its mesh has a hole over the pedestal: that
    inner loop is ignored, i.e. the hole counts as covered, as the shadow of a drape tester does.
drape coefficient
    DC = (A_projected - A_pedestal) / (A_sheet - A_pedestal), A_projected the shoelace area inside
    the outer projected boundary, A_sheet the area of the flat (undeformed) sheet including the
    pedestal part.  A flat, undeformed sheet gives DC = 1; a sheet hanging straight down gives
    DC -> 0.  If folds make the projected boundary overlap itself the shoelace counts overlapping
    lobes with their winding number; :func:`radius_profile` gives the star-shaped envelope instead
    (``envelope_area`` in :func:`drape_summary`), and the two agree whenever the boundary is
    star-shaped about the centre, which is the case for every paper scene.
radius profile r(theta)
    Distance from the pedestal centre to the outermost crossing of the boundary with the ray at
    polar angle theta, on a uniform grid of ``n_theta`` angles.
fold count
    The number of local maxima of r(theta) after smoothing with a circular Gaussian window of
    standard deviation ``smooth_deg`` degrees, keeping only maxima whose topographic prominence
    is at least ``min_prominence`` times the mean radius.  Defaults: 720 angles (0.5 deg),
    smooth_deg = 2 deg, min_prominence = 0.01.  Rationale: the paper's finest fold pattern is 12
    folds (30 deg period); a 2 deg Gaussian keeps exp(-(k sigma)^2 / 2) = 0.96 of a k = 12 wave
    but damps mesh-scale wiggles (30x240 mesh: 1.5 deg per element) and measurement noise; a fold
    shallower than 1 % of the radius (2.5 mm on the 25 cm drapes) is not a fold anyone would
    count.  A circle (and any shape whose r(theta) varies by less than the threshold) has 0 folds;
    an ellipse has 2; a rounded square 4.
asymmetry
    With rbar the mean radius: ``mirror_x`` = max |r(theta) - r(-theta)| / rbar (mirror about the
    X axis, the warp), ``mirror_y`` = max |r(theta) - r(pi - theta)| / rbar (about the Y axis),
    ``rot90`` = max |r(theta) - r(theta + pi/2)| / rbar (four-fold rotational symmetry).  0 for
    a shape with that symmetry.  The paper's FE drapes are symmetric; experiments are not.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = [
    "boundary_loops",
    "polygon_area",
    "projected_boundary",
    "drape_coefficient",
    "radius_profile",
    "fold_count",
    "asymmetry",
    "drape_summary",
]


# --------------------------------------------------------------------------- boundary loops
def boundary_loops(directed_edges) -> list[np.ndarray]:
    """Chain directed boundary edges (B,2) into closed loops of node indices.

    Each loop is returned as an array of node indices in edge order (not repeated at the end).
    The mesh's :meth:`ShellMesh.boundary_edges` keeps the element orientation, so on a flat
    counter-clockwise mesh the outer loop runs counter-clockwise and holes clockwise.  A node where
    two loops touch (two outgoing boundary edges) is handled by consuming edges, not nodes.
    """
    e = np.asarray(directed_edges, dtype=np.int64).reshape(-1, 2)
    if len(e) == 0:
        return []
    order = np.argsort(e[:, 0], kind="stable")
    starts = e[order, 0]
    used = np.zeros(len(e), dtype=bool)
    loops = []
    for first in range(len(e)):
        if used[first]:
            continue
        loop = []
        k = first
        while not used[k]:
            used[k] = True
            loop.append(e[k, 0])
            nxt = e[k, 1]
            lo, hi = np.searchsorted(starts, [nxt, nxt + 1])
            cand = order[lo:hi]
            cand = cand[~used[cand]]
            if cand.size == 0:
                break
            k = cand[0]
        loops.append(np.asarray(loop, dtype=np.int64))
    return loops


def polygon_area(xy) -> float:
    """Signed shoelace area of a closed polygon (P,2) (positive when counter-clockwise)."""
    p = np.asarray(xy, dtype=float)
    if p.ndim != 2 or p.shape[1] < 2 or len(p) < 3:
        return 0.0
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _positions(mesh, U):
    X = np.asarray(mesh.nodes, dtype=float)
    if U is None:
        return X
    U = np.asarray(U, dtype=float).reshape(len(X), -1)
    return X + U[:, :3]


def projected_boundary(mesh, U=None, return_nodes=False):
    """The outer boundary loop of the deformed mesh projected on X-Y, counter-clockwise.

    mesh : ShellMesh (uses ``nodes`` and ``boundary_edges()``); U : (N,6) or (N,3) displacements
    or None (undeformed).  Returns a (P,2) array (and the (P,) node indices if ``return_nodes``).
    """
    loops = boundary_loops(mesh.boundary_edges())
    if not loops:
        raise InputError("the mesh has no boundary edge (a closed surface has no projected boundary)")
    x = _positions(mesh, U)[:, :2]
    areas = np.array([polygon_area(x[lp]) for lp in loops])
    i = int(np.argmax(np.abs(areas)))
    nodes = loops[i] if areas[i] >= 0.0 else loops[i][::-1]
    poly = x[nodes]
    return (poly, nodes) if return_nodes else poly


def drape_coefficient(projected_area: float, sheet_area: float, pedestal_area: float = 0.0) -> float:
    """DC = (A_projected - A_pedestal) / (A_sheet - A_pedestal)."""
    den = float(sheet_area) - float(pedestal_area)
    if not den > 0.0:
        raise InputError(f"sheet area ({sheet_area}) must exceed the pedestal area ({pedestal_area})")
    return (float(projected_area) - float(pedestal_area)) / den


# --------------------------------------------------------------------------- radius profile
def radius_profile(polygon, center=(0.0, 0.0), n_theta: int = 720):
    """r(theta) of a closed polygon about ``center`` on a uniform grid theta_j = 2 pi j / n_theta.

    r is the distance to the outermost crossing of the ray from the centre at angle theta with the
    polygon (the star-shaped envelope when the boundary folds back).  Rays that miss the polygon
    (centre outside it) give 0.  Vectorised: (n_theta x n_segments) ray/segment intersections.
    Returns (theta, r).
    """
    p = np.asarray(polygon, dtype=float)[:, :2] - np.asarray(center, dtype=float)[:2]
    q = np.roll(p, -1, axis=0)
    theta = 2.0 * np.pi * np.arange(n_theta) / n_theta
    d = np.column_stack([np.cos(theta), np.sin(theta)])  # (T,2)
    s = q - p  # (S,2)
    # solve t d = p + u s  ->  t (d x s) ... use 2-D cross products
    cross_ds = d[:, 0:1] * s[None, :, 1] - d[:, 1:2] * s[None, :, 0]  # (T,S) d x s
    cross_ps = p[None, :, 0] * s[None, :, 1] - p[None, :, 1] * s[None, :, 0]  # p x s
    cross_pd = p[None, :, 0] * d[:, 1:2] - p[None, :, 1] * d[:, 0:1]  # p x d
    with np.errstate(divide="ignore", invalid="ignore"):
        t = cross_ps / cross_ds
        u = cross_pd / cross_ds
    ok = (np.abs(cross_ds) > 0) & (u >= -1e-12) & (u <= 1.0 + 1e-12) & (t >= 0.0)
    r = np.where(ok, t, 0.0).max(axis=1)
    return theta, r


def _gaussian_wrap(r, sigma: float):
    """scipy.ndimage.gaussian_filter1d(r, sigma, mode="wrap") (truncate = 4, the kernel normalised
    to sum 1), in numpy: importing scipy.ndimage and scipy.signal for the two calls of this module
    cost ~1.9 s CPU and 54 MB per run; equal to round-off (tests/test_analysis.py)."""
    radius = int(4.0 * sigma + 0.5)
    k = np.arange(-radius, radius + 1)
    w = np.exp(-0.5 / (sigma * sigma) * k * k)
    w /= w.sum()
    idx = (np.arange(len(r))[:, None] + k[None, :]) % len(r)
    return (np.asarray(r, dtype=float)[idx] * w).sum(axis=1)


def _prominent_peaks(x, min_prominence: float) -> np.ndarray:
    """Indices of the local maxima of x with topographic prominence >= min_prominence: the peaks
    of scipy.signal.find_peaks(x, prominence=min_prominence), same definitions -- a flat top counts
    once, at its middle sample (rounded down); the end samples are no peaks; the prominence is the
    height above the higher of the lowest points on either side before a higher sample or the end."""
    x = np.asarray(x, dtype=float)
    n = len(x)
    peaks = []
    i = 1
    while i < n - 1:  # a scan of the n = 3 x 720 samples of r(theta), not of mesh entities
        if x[i - 1] < x[i]:
            j = i + 1
            while j < n - 1 and x[j] == x[i]:
                j += 1
            if x[j] < x[i]:
                peaks.append((i + j - 1) // 2)
                i = j
        i += 1
    out = []
    for p in peaks:
        h = x[p]
        left = x[: p + 1][::-1]
        stop = np.flatnonzero(left > h)
        lmin = left[: stop[0] if stop.size else None].min()
        right = x[p:]
        stop = np.flatnonzero(right > h)
        rmin = right[: stop[0] if stop.size else None].min()
        if h - max(lmin, rmin) >= min_prominence:
            out.append(p)
    return np.asarray(out, dtype=np.intp)


def _smooth(r, smooth_deg: float):
    n = len(r)
    sigma = smooth_deg / 360.0 * n
    return _gaussian_wrap(r, sigma) if sigma > 0 else r.copy()


def fold_count(
    polygon,
    center=(0.0, 0.0),
    n_theta: int = 720,
    smooth_deg: float = 2.0,
    min_prominence: float = 0.01,
    return_angles: bool = False,
):
    """Number of folds: prominent local maxima of the smoothed r(theta) (see module docstring).

    Returns an int (and the fold angles in radians if ``return_angles``).  A circle returns 0.
    """
    theta, r = radius_profile(polygon, center, n_theta)
    rs = _smooth(r, smooth_deg)
    rbar = float(rs.mean())
    if rbar <= 0.0:
        return (0, np.zeros(0)) if return_angles else 0
    n = len(rs)
    tiled = np.concatenate([rs, rs, rs])  # periodic: peaks of the middle copy see both sides
    pk = _prominent_peaks(tiled, min_prominence * rbar)
    pk = pk[(pk >= n) & (pk < 2 * n)] - n
    return (int(pk.size), theta[pk]) if return_angles else int(pk.size)


def asymmetry(polygon, center=(0.0, 0.0), n_theta: int = 720) -> dict:
    """Normalised symmetry defects of r(theta) (see module docstring); n_theta a multiple of 4."""
    if n_theta % 4:
        raise InputError("n_theta must be a multiple of 4")
    _, r = radius_profile(polygon, center, n_theta)
    rbar = float(r.mean())
    if rbar <= 0.0:
        return {"mirror_x": 0.0, "mirror_y": 0.0, "rot90": 0.0}
    j = np.arange(n_theta)
    mx = r[(-j) % n_theta]  # r(-theta)
    my = r[(n_theta // 2 - j) % n_theta]  # r(pi - theta)
    r90 = r[(j + n_theta // 4) % n_theta]  # r(theta + pi/2)
    return {
        "mirror_x": float(np.max(np.abs(r - mx)) / rbar),
        "mirror_y": float(np.max(np.abs(r - my)) / rbar),
        "rot90": float(np.max(np.abs(r - r90)) / rbar),
    }


# --------------------------------------------------------------------------- one-stop summary
def drape_summary(
    mesh,
    U=None,
    pedestal_area: float = 0.0,
    center=None,
    sheet_area=None,
    n_theta: int = 720,
    smooth_deg: float = 2.0,
    min_prominence: float = 0.01,
) -> dict:
    """All drape measures of a deformed mesh as plain numbers (summary.json keys).

    pedestal_area : area of the pedestal top [length^2] (0 for no pedestal).
    center : (x,y) of the pedestal centre; default the centroid of the *undeformed* inner (hole)
        loop when the mesh has one, else of the undeformed outer loop.
    sheet_area : area of the whole flat sheet; default the mesh's area plus the pedestal area
        (pedestal scenes mesh only the hanging part).
    Returns projected_area, envelope_area, drape_coefficient, fold_count, fold_angles_deg,
    mean_radius, asymmetry_mirror_x/_mirror_y/_rot90, and the boundary polygon (list of [x, y]).
    """
    poly = projected_boundary(mesh, U)
    if center is None:
        loops = boundary_loops(mesh.boundary_edges())
        X = np.asarray(mesh.nodes, dtype=float)[:, :2]
        areas = np.array([polygon_area(X[lp]) for lp in loops])
        pick = loops[int(np.argmin(np.abs(areas)))] if len(loops) > 1 else loops[0]
        center = _centroid(X[pick])
    if sheet_area is None:
        sheet_area = float(mesh.area()) + float(pedestal_area)
    A = polygon_area(poly)
    theta, r = radius_profile(poly, center, n_theta)
    env = 0.5 * float(np.mean(r**2)) * 2.0 * np.pi
    nf, ang = fold_count(poly, center, n_theta, smooth_deg, min_prominence, return_angles=True)
    asym = asymmetry(poly, center, n_theta - n_theta % 4)
    return {
        "projected_area": A,
        "envelope_area": env,
        "sheet_area": float(sheet_area),
        "pedestal_area": float(pedestal_area),
        "drape_coefficient": drape_coefficient(A, sheet_area, pedestal_area),
        "fold_count": nf,
        "fold_angles_deg": [float(a) for a in np.degrees(ang)],
        "mean_radius": float(r.mean()),
        "center": [float(center[0]), float(center[1])],
        "asymmetry_mirror_x": asym["mirror_x"],
        "asymmetry_mirror_y": asym["mirror_y"],
        "asymmetry_rot90": asym["rot90"],
        "projected_boundary": poly.tolist(),
    }


def _centroid(xy):
    """Area centroid of a polygon (vertex mean if degenerate)."""
    p = np.asarray(xy, dtype=float)
    x, y = p[:, 0], p[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    c = x * yn - xn * y
    A = 0.5 * c.sum()
    if abs(A) < 1e-300:
        return p.mean(axis=0)
    return np.array([((x + xn) * c).sum() / (6 * A), ((y + yn) * c).sum() / (6 * A)])
