"""Mesh sequencing for the static solver: solve the same scene on coarser meshes of its recipe
first, and start the requested mesh from the prolonged coarse equilibrium.

Why: the energy Newton spends most of its iterations in the global phase, carrying the flat sheet
to its folded shape with trust-region-limited steps (static.py's module notes).  On a coarse mesh
those iterations cost a fraction (factorisation ~ dofs^1.2-1.5, kernels ~ elements); the fine mesh
then only has to settle the folds it resolves better.  Measured on square-pedestal 48x16x4 (one
run, 2 shared cores): 107 Newton iterations from the flat sheet, 80 + 27 + 51 on 12x4x4 -> 24x8x4
-> 48x16x4, to the same equilibrium (drape coefficient 0.5957, 4 folds, smallest tangent
eigenvalue 1.5728e-4 both ways).

A drape is multi-stable, so the fine equilibrium reached from a coarse start need not be the one
reached from the flat sheet.  Measured: square-pedestal 48x16x4 reaches the same state (max|dU| =
2.5e-10 max|U|, benchmarks/out/issue13_static_startup.md); square-on-disc 30x240 does *not*: from
15x120 (372 iterations) it took 315 iterations on 30x240 -- no saving -- and ended on 12 folds (DC
0.071) instead of the 8 folds (DC 0.058) of the plain solve.  Sequencing is therefore off by default
(``sequence = 0``) and switched on per scene where the verification shows the same equilibrium
(square-pedestal.toml: ``[solver.static] sequence = "auto"``).  It is skipped (the plain solve
runs) for meshes that are not a recipe density, for small meshes and when a coarse level fails.

Coarse densities (``plan``): every letter field of the recipe's density form (``AxBx4``: A and B;
the literal 4 stays) is halved while all of them are even, the recipe accepts the result and the
mesh keeps at least ``MIN_ELEMENTS`` elements; at most ``levels`` coarse meshes.  ``"auto"`` uses
up to 2 levels on meshes of at least ``AUTO_MIN_ELEMENTS`` elements and none below.

Prolongation (``prolong``): each fine node is located in the coarse mesh's undeformed mid-surface
(quads split into two triangles; the nearest candidates of a k-d tree on triangle centroids) and
takes the linear interpolation of the coarse nodal U = [U_o | U_n] (Eq. 1) there; a node outside
every coarse triangle (a curved boundary cut by straight coarse edges) takes the barycentric
extrapolation of the nearest one.  The fixed dofs are then set to their prescribed values by the
solver.  Meshes must be flat (the recipes' are): a curved reference surface is not sequenced.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["plan", "prolong", "solve_sequenced", "AUTO_MIN_ELEMENTS", "MIN_ELEMENTS"]

AUTO_MIN_ELEMENTS = 2000
"""``sequence = "auto"`` sequences meshes of at least this many elements: below it a plain solve
takes seconds and the coarse levels would save little (square-pedestal 24x8x4, 768 quads: 97
iterations, ~2 s on a quiet machine)."""

MIN_ELEMENTS = 150
"""No coarse level below this many elements: such a mesh cannot carry the drape's folds."""

AUTO_LEVELS = 2


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


def _triangles(mesh) -> np.ndarray:
    q = mesh.quads
    tri = [mesh.tris] if len(mesh.tris) else []
    if len(q):
        tri += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
    return np.concatenate(tri).astype(np.int64)


def prolong(coarse, Uc, fine, k: int = 8) -> np.ndarray:
    """(N_fine, 6) linear interpolation of the coarse nodal values Uc on the fine mesh's nodes
    (module notes).  Both meshes flat, in the same plane and units."""
    from scipy.spatial import cKDTree

    Uc = np.asarray(Uc, dtype=float).reshape(coarse.n_nodes, 6)
    T = _triangles(coarse)
    P = coarse.nodes[:, :2]
    A, B, C = P[T[:, 0]], P[T[:, 1]], P[T[:, 2]]
    x = fine.nodes[:, :2]
    k = min(k, len(T))
    _, cand = cKDTree((A + B + C) / 3.0).query(x, k=k)
    cand = cand.reshape(len(x), k)
    # barycentric coordinates of every fine node in each of its k candidate triangles
    a, b, c = A[cand], B[cand], C[cand]
    v0, v1, v2 = b - a, c - a, x[:, None, :] - a
    det = v0[..., 0] * v1[..., 1] - v0[..., 1] * v1[..., 0]
    l1 = (v2[..., 0] * v1[..., 1] - v2[..., 1] * v1[..., 0]) / det
    l2 = (v0[..., 0] * v2[..., 1] - v0[..., 1] * v2[..., 0]) / det
    lam = np.stack([1.0 - l1 - l2, l1, l2], axis=-1)           # (Nf, k, 3)
    best = np.argmax(lam.min(axis=-1), axis=1)                  # inside, or the least outside
    rows = np.arange(len(x))
    tri = T[cand[rows, best]]
    w = lam[rows, best]
    return np.einsum("nj,njc->nc", w, Uc[tri])


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
        # the report of its smallest tangent eigenvalue (ARPACK, ~20 solves) is not needed
        s = dict(settings, eig_max_dofs=0)
        if prev is not None:
            s.update(U0=prolong(prev[0], prev[1], pb.model.mesh), predictor=False)
        t = time.perf_counter()
        r = run(pb, s, lambda f, text="", i=i, d=d: progress((i + f) / n, f"mesh {d}: {text}"))
        rec = {"mesh": d, "converged": bool(r.converged), "iterations": r.info.get("iterations"),
               "factorizations": r.info.get("factorizations"), "wall_time_s": time.perf_counter() - t}
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
    t = time.perf_counter()
    res = run(problem, s, lambda f, text="": progress((n - 1 + f) / n, f"mesh {density}: {text}"))
    records.append({"mesh": density, "converged": bool(res.converged),
                    "iterations": res.info.get("iterations"),
                    "factorizations": res.info.get("factorizations"),
                    "wall_time_s": time.perf_counter() - t, "from_coarse": prev is not None})
    res.info["sequence"] = records
    res.info["fine_wall_time_s"] = res.info.get("wall_time_s")
    res.info["wall_time_s"] = time.perf_counter() - t0
    return res
