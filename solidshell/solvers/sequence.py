"""Mesh sequencing for the static solver: solve the same scene on coarser meshes of its recipe
first, and start the requested mesh from the prolonged coarse equilibrium.

Why: the energy Newton spends most of its iterations in the global phase, carrying the flat sheet
to its folded shape with trust-region-limited steps (static/newton.py's module notes).  On a coarse mesh
those iterations cost a fraction (factorisation ~ dofs^1.2-1.5, kernels ~ elements); the fine mesh
then only has to settle the folds it resolves better (iteration counts: docs/solvers.md, section 6).

A drape is multi-stable, so the fine equilibrium reached from a coarse start need not be the one
reached from the flat sheet: square-pedestal 48x16x4 reaches the same state, square-on-disc 30x240
does *not* (12 folds instead of the plain solve's 8, and no saving; docs/solvers.md, section 6).
Sequencing is therefore off by default (``sequence = 0``) and switched on per scene where the
verification shows the same equilibrium (square-pedestal.toml: ``[solver.static] sequence = "auto"``).  It is skipped (the plain solve
runs) for meshes that are not a recipe density, for small meshes and when a coarse level fails.

Coarse densities (``plan``): every letter field of the recipe's density form (``AxBx4``: A and B;
the literal 4 stays) is halved while all of them are even, the recipe accepts the result and the
mesh keeps at least ``MIN_ELEMENTS`` elements; at most ``levels`` coarse meshes.  ``"auto"`` uses
up to 2 levels on meshes of at least ``AUTO_MIN_ELEMENTS`` elements and none below.

Prolongation (``prolong``): each fine node is located in the coarse mesh's undeformed mid-surface
(quads split into two triangles to find the element; candidates from a bucket grid on triangle
centroids) and takes the coarse element's interpolation of the nodal U = [U_o | U_n] (Eq. 1) there:
bilinear in a quad (the parametric point by Newton on the bilinear map), linear in a triangle; a
node outside every coarse element (a curved boundary cut by straight coarse edges) takes the
extrapolation of the nearest one.  On the recipes' nested meshes this is the coarse finite-element
field itself (the triangle-wise interpolation used before put each coarse quad's centre node on one
diagonal); each director then gets the interpolated length of the coarse ones.  The prolonged
state is still far from equilibrium in energy (the O(h^2) interpolation error of the positions is
membrane strain): the first fine iterations, shifted and short, relax it (docs/solvers.md,
section 6).  Meshes must be flat (the recipes' are): a curved reference surface is not sequenced.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["plan", "prolong", "solve_sequenced", "AUTO_MIN_ELEMENTS", "MIN_ELEMENTS"]

AUTO_MIN_ELEMENTS = 2000
"""``sequence = "auto"`` sequences meshes of at least this many elements: below it a plain solve
takes seconds and the coarse levels would save little (docs/solvers.md, section 6)."""

MIN_ELEMENTS = 150
"""No coarse level below this many elements: such a mesh cannot carry the drape's folds."""

AUTO_LEVELS = 2

FINE_PCG_ITERATIONS = 6
"""The static ``pcg_iterations`` of the fine mesh started from a coarse level (unless the settings
give one): square-pedestal 48x16x4, 35-39 factorisations instead of 59 on the fine mesh and 10-19 %
less process CPU in interleaved runs at load ~6 (3 gave 49 and 13 %); one CG iteration (a
back-substitution and a product) costs ~1/9 of a factorisation there.  From the flat sheet the same
steps cost more than they save (static/newton.py, ``_cg_step``)."""

COARSE_TOLERANCES = dict(tol=1e-5, energy_tol=1e-8, disp_tol=1e-6)
"""Convergence of a coarse level (static/settings.py's tol, energy_tol, disp_tol): its state is only the
start of the next level, which differs from it by the discretisation (~1 cm on square-pedestal
24x8x4 -> 48x16x4), so the last quadratic Newton iterations of a coarse level buy nothing."""


def _halve(density: str, form: str) -> str | None:
    parts = [int(p) for p in density.split("x")]
    toks = form.split("x")
    if len(toks) != len(parts):
        return None
    out = []
    for p, t in zip(parts, toks):
        if t.isdigit():
            out.append(p)
        elif p % 2 or p < 2:
            return None
        else:
            out.append(p // 2)
    return "x".join(map(str, out))


def plan(scene, density, n_elements: int, setting) -> list[str]:
    """Coarse densities to solve first, coarsest first ([] = no sequencing).  ``setting`` is the
    static setting ``sequence``: "auto" or the number of coarse levels (0: none)."""
    if setting == "auto":
        if n_elements < AUTO_MIN_ELEMENTS:
            return []
        levels = AUTO_LEVELS
    else:
        levels = int(setting)
    if levels <= 0 or not isinstance(density, str) or "file" in scene.geometry:
        return []
    from .. import meshing

    recipe = meshing.RECIPES.get(str(scene.recipe).replace("-", "_"))
    if recipe is None or recipe.form is None:
        return []
    out = []
    d, n = density, n_elements
    for _ in range(levels):
        d = _halve(d, recipe.form)
        n //= 4
        if d is None or n < MIN_ELEMENTS:
            break
        out.append(d)
    return out[::-1]


def _triangles(mesh):
    """(T,3) triangles covering the mesh (each quad split along its 0-2 diagonal) and, per triangle,
    its quad (or -1 for a mesh triangle)."""
    q, t = mesh.quads, mesh.tris
    tri = np.concatenate([t.reshape(-1, 3), q[:, [0, 1, 2]], q[:, [0, 2, 3]]]).astype(np.int64)
    iq = np.arange(len(q), dtype=np.int64)
    parent = np.concatenate([np.full(len(t), -1, dtype=np.int64), iq, iq])
    return tri, parent


def _candidates(lo, hi, x):
    """(Nx, m) indices of the triangles whose bounding box [lo, hi] (widened by a quarter cell)
    shares a grid cell with each point of x, padded with -1; the cell width is the median box
    diagonal, so a point meets a few triangles (2-8 on the recipes' meshes).  A point inside a
    triangle always meets it.  A bucket grid in numpy: no scipy.spatial import (0.25-0.6 s, more
    than the whole prolongation) and no (points x all triangles) arrays."""
    h = max(float(np.median(np.hypot(*(hi - lo).T))), 1e-300)
    lo, hi = lo - 0.25 * h, hi + 0.25 * h
    o = np.minimum(lo.min(axis=0), x.min(axis=0))
    i0 = np.floor((lo - o) / h).astype(np.int64)
    i1 = np.floor((hi - o) / h).astype(np.int64)
    ix = np.floor((x - o) / h).astype(np.int64)
    ny = int(max(i1[:, 1].max(), ix[:, 1].max())) + 1
    n = i1 - i0 + 1  # cells per box along x and y
    cnt = n[:, 0] * n[:, 1]
    tri = np.repeat(np.arange(len(lo)), cnt)
    k = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    key = (i0[tri, 0] + k // n[tri, 1]) * ny + i0[tri, 1] + k % n[tri, 1]
    order = np.argsort(key, kind="stable")
    skey, tri = key[order], tri[order]
    near = ix[:, 0] * ny + ix[:, 1]
    a = np.searchsorted(skey, near, "left")
    c = np.searchsorted(skey, near, "right") - a
    j = np.arange(int(c.max(initial=0)))
    return np.where(j < c[:, None], tri[np.minimum(a[:, None] + j, len(tri) - 1)], -1)


def _barycentric(A, B, C, x, cand):
    """(Nx, m, 3) barycentric coordinates of the points x in the candidate triangles cand (Nx, m)."""
    a, b, c = A[cand], B[cand], C[cand]
    v0, v1, v2 = b - a, c - a, x[:, None, :] - a
    det = v0[..., 0] * v1[..., 1] - v0[..., 1] * v1[..., 0]
    l1 = (v2[..., 0] * v1[..., 1] - v2[..., 1] * v1[..., 0]) / det
    l2 = (v0[..., 0] * v2[..., 1] - v0[..., 1] * v2[..., 0]) / det
    return np.stack([1.0 - l1 - l2, l1, l2], axis=-1)


def _locate(A, B, C, x):
    """(triangle, barycentric weights (Nx, 3)) for every point of x: the triangle containing it,
    or the least outside one (largest smallest barycentric coordinate)."""
    cand = _candidates(np.minimum(np.minimum(A, B), C), np.maximum(np.maximum(A, B), C), x)
    valid = cand >= 0
    c0 = np.where(valid, cand, 0)
    lam = _barycentric(A, B, C, x, c0)
    score = np.where(valid, lam.min(axis=-1), -np.inf)
    best = np.argmax(score, axis=1)
    rows = np.arange(len(x))
    t, w, sc = c0[rows, best], lam[rows, best], score[rows, best]
    far = np.flatnonzero(sc < -1e-9)
    for chunk in np.array_split(far, max(1, far.size // 64)) if far.size else ():
        # outside every nearby triangle (a curved boundary cut by straight coarse edges): the
        # least outside triangle of all, a few points at a time
        allc = np.broadcast_to(np.arange(len(A)), (chunk.size, len(A)))
        lam = _barycentric(A, B, C, x[chunk], allc)
        bi = np.argmax(lam.min(axis=-1), axis=1)
        r = np.arange(chunk.size)
        better = lam[r, bi].min(axis=-1) > sc[chunk]
        t[chunk[better]], w[chunk[better]] = bi[better], lam[r, bi][better]
    return t, w


def _bilinear_coords(Xq, x, xi, iters=8):
    """(Nx, 2) parametric coordinates (xi, eta) in [-1, 1]^2 of the points x in the bilinear quads
    Xq (Nx, 4, 2): Newton on x(xi, eta) = sum_a N_a X_a from the start ``xi`` (exact in one step
    for a parallelogram; a few for the trapezoids of the recipes)."""
    sx = np.array([-1.0, 1.0, 1.0, -1.0])
    sy = np.array([-1.0, -1.0, 1.0, 1.0])
    for _ in range(iters):
        a = 1.0 + sx[None, :] * xi[:, 0, None]
        b = 1.0 + sy[None, :] * xi[:, 1, None]
        r = np.einsum("na,nac->nc", 0.25 * a * b, Xq) - x
        jx = np.einsum("na,nac->nc", 0.25 * sx * b, Xq)  # d x / d xi
        jy = np.einsum("na,nac->nc", 0.25 * sy * a, Xq)  # d x / d eta
        det = jx[:, 0] * jy[:, 1] - jx[:, 1] * jy[:, 0]
        d0 = (r[:, 0] * jy[:, 1] - r[:, 1] * jy[:, 0]) / det
        d1 = (jx[:, 0] * r[:, 1] - jx[:, 1] * r[:, 0]) / det
        xi = xi - np.column_stack([d0, d1])
        if max(float(np.abs(d0).max(initial=0.0)), float(np.abs(d1).max(initial=0.0))) <= 1e-14:
            break
    return xi


def prolong(coarse, Uc, fine) -> np.ndarray:
    """(N_fine, 6) interpolation of the coarse nodal values Uc on the fine mesh's nodes with the
    coarse elements' own shape functions (module notes): bilinear in a quad, linear in a triangle.
    On a nested fine mesh this is the coarse finite-element field itself (a node at a coarse quad's
    centre takes the mean of its four corners, not of two across a diagonal), so the fine solve
    starts from the coarse equilibrium's shape without the spurious kinks of a triangle-wise
    interpolation.  Both meshes flat, in the same plane and units."""
    Uc = np.asarray(Uc, dtype=float).reshape(coarse.n_nodes, 6)
    T, parent = _triangles(coarse)
    P = coarse.nodes[:, :2]
    A, B, C = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
    x = fine.nodes[:, :2]
    t, w = _locate(A, B, C, x)
    out = np.einsum("nj,njc->nc", w, Uc[T[t]])
    q = parent[t]
    inq = np.flatnonzero(q >= 0)
    if inq.size:
        # the quad's parametric point: start from the triangle's affine map (corners 0-1-2 or 0-2-3
        # of the quad at (xi, eta) = (-1,-1), (1,-1), (1,1), (-1,1)), then Newton on the bilinear map
        corners = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
        first = t[inq] < len(coarse.tris) + len(coarse.quads)
        tc = np.where(first[:, None], np.array([0, 1, 2]), np.array([0, 2, 3]))
        xi = np.einsum("nj,njc->nc", w[inq], corners[tc])
        quad = coarse.quads[q[inq]]
        xi = _bilinear_coords(P[quad], x[inq], xi)
        sx, sy = corners[:, 0], corners[:, 1]
        N = 0.25 * (1.0 + sx * xi[:, 0, None]) * (1.0 + sy * xi[:, 1, None])
        out[inq] = np.einsum("na,nac->nc", N, Uc[quad])
    return _director_lengths(coarse, Uc, fine, out, T, t, w, inq, quad if inq.size else None, N if inq.size else None)


def _director_lengths(coarse, Uc, fine, out, T, t, w, inq, quad, N):
    """Give every prolonged director x_n = X_n + U_n the interpolated *length* of the coarse
    directors (its direction stays the interpolated one): interpolating the vectors shortens a
    director wherever the coarse ones turn (by cos(theta/2) between two that differ by theta), a
    spurious thickness strain (Eq. 3) in the fine elements whose corners are new nodes."""
    xc = coarse.directors + Uc[:, 3:]
    lc = np.linalg.norm(xc, axis=1)
    lf = np.einsum("nj,nj->n", w, lc[T[t]])
    if inq.size:
        lf[inq] = np.einsum("na,na->n", N, lc[quad])
    xf = fine.directors + out[:, 3:]
    n = np.linalg.norm(xf, axis=1)
    out[:, 3:] = xf * (lf / np.maximum(n, 1e-300))[:, None] - fine.directors
    return out


def _flat(mesh) -> bool:
    z = mesh.nodes[:, 2]
    span = float(np.ptp(mesh.nodes[:, :2], axis=0).max())
    return bool(np.ptp(z) <= 1e-12 * max(span, 1e-300))


def _interpenetrates(model, U) -> bool:
    """Whether any element corner of the state U has n_p . d_p < 0 (Section 4.3)."""
    return any(bool(np.any(a < 0.0)) for a in model.interpenetration(np.asarray(U).reshape(-1, 6)))


def solve_sequenced(run, problem, settings: dict, progress, scene, density, make_problem):
    """The static solve of ``problem`` (the mesh of ``density``), preceded by the coarse levels of
    ``plan``.  ``run`` is the static registry entry, ``make_problem(density)`` builds the scene's
    Problem on another density.  Returns the fine SolveResult with info["sequence"]: one record per
    level (mesh, iterations, factorizations, converged, wall time), info["wall_time_s"] the whole
    time and info["iterations"] the fine mesh's own."""
    setting = settings.pop("sequence", 0)
    mesh = problem.model.mesh
    # a given start (U0, e.g. a scene's [perturbation]) is the fine mesh's: no coarse levels then
    given = settings.get("U0") is not None
    levels = plan(scene, density, mesh.n_elements, setting) if _flat(mesh) and not given else []
    if not levels:
        return run(problem, settings, progress)
    t0 = time.perf_counter()
    records = []
    prev = None
    n = len(levels) + 1
    for i, d in enumerate(levels):
        pb = make_problem(d)
        # a coarse state is only a start: its saddle check stays (a saddle would be a poor start),
        # the report of its smallest tangent eigenvalue (ARPACK, ~20 solves) is not needed, nor
        # the contact's augmented-Lagrangian updates (the fine mesh's penetrations are what count)
        s = dict(settings, eig_max_dofs=0, contact_augment=0, **COARSE_TOLERANCES)
        if prev is not None:
            s.update(U0=prolong(prev[0], prev[1], pb.model.mesh), predictor=False)
        t = time.perf_counter()
        r = run(pb, s, lambda f, text="", i=i, d=d: progress((i + f) / n, f"mesh {d}: {text}"))
        rec = {
            "mesh": d,
            "converged": bool(r.converged),
            "iterations": r.info.get("iterations"),
            "factorizations": r.info.get("factorizations"),
            "wall_time_s": time.perf_counter() - t,
        }
        records.append(rec)
        bad = not r.converged or _interpenetrates(pb.model, r.U)
        rec["interpenetrated"] = bool(r.converged and bad)
        if bad or r.info.get("status") == "interrupted":
            # a failed coarse level, or one whose sheet passes through itself (Section 4.3; from such
            # a 12x4x4 state the ANS, graded 48x16x4 landed in another state, DC 0.5307 with 19
            # interpenetrated nodes against 0.5515 from flat): the fine mesh starts from flat
            prev = None
            if r.info.get("status") == "interrupted":
                return r
            break
        prev = (pb.model.mesh, r.U)
    s = dict(settings)
    if prev is not None:
        s.update(U0=prolong(prev[0], prev[1], mesh), predictor=False)
        # settling a prolonged equilibrium, the tangent changes slowly: inexact Newton steps by CG
        # preconditioned with the last factorisation pay here (static/newton.py, ``_cg_step``)
        s.setdefault("pcg_iterations", FINE_PCG_ITERATIONS)
    t = time.perf_counter()
    res = run(problem, s, lambda f, text="": progress((n - 1 + f) / n, f"mesh {density}: {text}"))
    records.append(
        {
            "mesh": density,
            "converged": bool(res.converged),
            "iterations": res.info.get("iterations"),
            "factorizations": res.info.get("factorizations"),
            "wall_time_s": time.perf_counter() - t,
            "from_coarse": prev is not None,
        }
    )
    res.info["sequence"] = records
    res.info["fine_wall_time_s"] = res.info.get("wall_time_s")
    res.info["wall_time_s"] = time.perf_counter() - t0
    return res
