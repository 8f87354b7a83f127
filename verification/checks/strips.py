"""Section 3.1: the 5 x 1 cm wool strip clamped at one end, drooping under its own weight, against the
heavy elastica of ``reference/elastica_strip.json`` (an ODE solved to 1e-10 by reference/elastica.py,
independent of the shell code).

The weft-cut strip is ``Fabric.wool(warp_angle=90)``.  The tip deflection converges as h^2 to a
floor of ~1e-4 relative: the shell stretches (tensile rigidity 1118 gf/cm against 0.095 gf of
weight) and has a thickness, which the inextensible, unshearable elastica lacks -- a model
difference, not a discretisation error.
"""

from __future__ import annotations

import time

import numpy as np

from . import references
from .record import check, measure, observed_order

ELASTICA_SRC = "reference/elastica.py (solve_bvp tol 1e-10, checked by shooting) -> elastica_strip.json"


def strip_problem(n: int, cut: str, membrane: str = "full", kind: str = "quad"):
    """Mesh, model, fixed mask and gravity loads of the n x 1 strip (warp- or weft-cut); ``kind``
    "tri" cuts every quad into two triangles, the diagonals alternating (common.split_quads "x")."""
    from solidshell.boundary import clamp, gravity_loads
    from solidshell.material import Fabric
    from solidshell.mesh import ShellMesh
    from solidshell.meshing import build_mesh
    from solidshell.model import Model

    from .common import split_quads

    mesh = build_mesh("strip", f"{n}x1", length=5.0, width=1.0)
    if kind == "tri":
        mesh = ShellMesh(mesh.nodes, tris=split_quads(mesh.quads, "x"), node_sets=mesh.node_sets)
    model = Model(mesh, Fabric.wool(warp_angle=0.0 if cut == "warp" else 90.0), membrane=membrane)
    return mesh, model, clamp(mesh, "clamped"), gravity_loads(model)


def solve_strip(n: int, cut: str, method: str = "newton", membrane: str = "full", kind: str = "quad", **kw):
    """Solve the strip; returns dict(tip_x, tip_z, centreline (x, z) sorted by x, result, wall)."""
    from solidshell.solvers.static import solve_static

    mesh, model, fixed, loads = strip_problem(n, cut, membrane, kind)
    t0 = time.perf_counter()
    res = solve_static(model, fixed, loads, method=method, **kw)
    wall = time.perf_counter() - t0
    x = mesh.nodes + res.U[:, :3]
    tip = mesh.node_set("tip")
    # centreline: the mean of the nodes across the width at every station along the strip
    X0 = np.round(mesh.nodes[:, 0], 9)
    st, inv = np.unique(X0, return_inverse=True)
    cnt = np.bincount(inv)
    cx = np.bincount(inv, weights=x[:, 0]) / cnt
    cz = np.bincount(inv, weights=x[:, 2]) / cnt
    return {
        "tip_x": float(x[tip, 0].mean()),
        "tip_z": float(x[tip, 2].mean()),
        "s": st,
        "cx": cx,
        "cz": cz,
        "result": res,
        "wall": wall,
    }


def shape_error(sol, ref):
    """max over the nodal stations s of |(x,z)_shell(s) - (x,z)_elastica(s)| [cm]."""
    s = np.asarray(ref["curve"]["s"])
    xr = np.interp(sol["s"], s, ref["curve"]["x"])
    zr = np.interp(sol["s"], s, ref["curve"]["z"])
    return float(np.max(np.hypot(sol["cx"] - xr, sol["cz"] - zr)))


def _solved(ctx, n, cut):
    key = ("strip", n, cut)
    if key not in ctx.cache:
        ctx.cache[key] = solve_strip(n, cut)
    return ctx.cache[key]


@check("strip", "strips", "wool strip under self-weight (warp, weft; 10x1, 20x1) vs the heavy elastica (Fig. 4)")
def check_strip(ctx):
    ref = references.elastica_strip()["strip"]
    recs, series = [], []
    cases = (
        [("warp", 10), ("warp", 20), ("weft", 20)]
        if ctx.quick
        else [("warp", 10), ("warp", 20), ("weft", 10), ("weft", 20)]
    )
    for cut, n in cases:
        sol = _solved(ctx, n, cut)
        tol = 5e-3 if n >= 20 else 2e-2
        recs.append(
            measure(
                f"strip/{cut}/{n}x1/tip_z",
                "tip height z [cm]",
                sol["tip_z"],
                ref[cut]["tip_z"],
                tol,
                wall_time_s=sol["wall"],
                reference=f"heavy elastica, {cut} (B = {ref[cut]['B']} gf cm^2)",
                source=ELASTICA_SRC,
                why=(
                    "measured 0.12 %, O(h^2) down to a 1e-4 floor (shell extensibility); 0.5 % still catches "
                    "warp/weft swapped (2.5 %) or 1 % of weight lost (0.3 %)"
                    if n >= 20
                    else "measured 0.45 %; the paper's 10x1 is visibly off the reference too (Fig. 4b)"
                ),
                note="" if sol["result"].converged else "NOT converged",
            )
        )
        recs.append(
            measure(
                f"strip/{cut}/{n}x1/shape",
                "max centreline distance from the elastica / L",
                shape_error(sol, ref[cut]) / 5.0,
                0.0,
                6e-3 if n >= 20 else 2e-2,
                error_kind="abs",
                wall_time_s=sol["wall"],
                reference="heavy elastica curve (101 stations)",
                source=ELASTICA_SRC,
                why="measured 2.4e-3 / 2.6e-3 L (warp / weft, 20x1) and 9.5e-3 / 1.0e-2 L (10x1), O(h^2); about "
                "2x margin, and the warp and weft tips lie 6e-2 L apart",
            )
        )
        series.append(
            {"label": f"{cut}: {n}x1 solid-shell", "x": sol["cx"].tolist(), "y": sol["cz"].tolist(), "role": "ours"}
        )
    for cut in ("warp", "weft"):
        series.insert(
            0,
            {
                "label": f"{cut}: elastica",
                "x": ref[cut]["curve"]["x"],
                "y": ref[cut]["curve"]["z"],
                "role": "reference",
            },
        )
    ctx.curves("5x1 cm wool strip under self-weight, side view (paper Fig. 4b)", series, "x [cm]", "z [cm]", equal=True)
    return recs


@check("strip-refinement", "strips", "warp strip 10x1 ... 160x1: observed order and limit vs the elastica", quick=False)
def check_strip_refinement(ctx):
    ref = references.elastica_strip()["strip"]["warp"]
    ns = (10, 20, 40, 80, 160)
    sols = [_solved(ctx, n, "warp") for n in ns]
    e = [(s["tip_z"] - ref["tip_z"]) / ref["tip_z"] for s in sols]
    h = [5.0 / n for n in ns]
    wall = sum(s["wall"] for s in sols)
    # three-mesh order from the coarse end, where the discretisation error dominates the floor
    p3 = float(np.log2((e[0] - e[1]) / (e[1] - e[2])))
    d1, d2 = e[-3] - e[-2], e[-2] - e[-1]
    pf = float(np.log2(d1 / d2))
    e_inf = e[-1] - d2 / (2.0**pf - 1.0)
    recs = [
        measure(
            "strip-refinement/warp/order",
            "three-mesh order of the tip error, 10x1-20x1-40x1",
            p3,
            2.0,
            0.3,
            error_kind="abs",
            wall_time_s=wall,
            reference="O(h^2) (bilinear interpolation)",
            source=ELASTICA_SRC,
            why="measured 2.01; an order below 1.7 means a consistency error (e.g. in "
            "the load lumping or the ANS tying)",
        ),
        measure(
            "strip-refinement/warp/160x1",
            "relative tip-height error at 160x1",
            e[-1],
            0.0,
            3e-4,
            error_kind="abs",
            wall_time_s=sols[-1]["wall"],
            reference="heavy elastica",
            source=ELASTICA_SRC,
            why="the floor: measured 1.1e-4 (extensible shell with thickness vs inextensible elastica); "
            "3e-4 admits it and fails for a 0.1 % rigidity or load error",
        ),
        measure(
            "strip-refinement/warp/limit",
            "Richardson limit of the relative error (40-80-160)",
            e_inf,
            0.0,
            3e-4,
            error_kind="abs",
            wall_time_s=wall,
            reference="heavy elastica",
            source=ELASTICA_SRC,
            why="the mesh-converged model difference; ~1e-4 (axial strain of the strip under its weight)",
        ),
    ]
    ctx.convergence(
        "Warp strip: tip height vs the heavy elastica",
        [
            {"label": "|relative error|", "h": h, "error": [abs(x) for x in e], "rate": observed_order(h, e)[1]},
            {
                "label": "|error - Richardson limit|",
                "h": h[:-1],
                "error": [abs(x - e_inf) for x in e[:-1]],
                "rate": observed_order(h[:-1], [x - e_inf for x in e[:-1]])[-1],
            },
        ],
        "element length h [cm]",
        "relative error of tip z",
    )
    return recs
