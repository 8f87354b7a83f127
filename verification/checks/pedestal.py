"""``square-pedestal`` (paper Section 3.2): mesh convergence of the drape coefficient, and the
cross-check against an independent code (KratosMultiphysics) when its reference file is present.

Convergence: the static energy Newton on 24x8x4 -> 48x16x4 -> 96x32x4 with the assumed membrane
field on meshes graded towards the pedestal corners (``model.membrane = "ans"``,
``geometry.grading = 8``: the configuration that converges; the paper's element on uniform meshes
changes DC by 5.9 % between the two finest meshes, docs and verification/static_convergence.py).
The reference is the Richardson limit of the three meshes themselves -- a self-convergence study,
not an independent reference -- with the observed order p = log2(d1/d2).

Kratos: ``reference/pedestal_kratos.json`` is a list of records, one per mesh and state::

    {"mesh": "24x8x4", "dc": 0.62, "projected_boundary": [[x, y], ...], "fold_count": 4,
     "state": "stable equilibrium ...",            # compared only if it starts with "stable"
     "material": {"isotropic": {"E": ..., "nu": ..., "h": ..., "density": ...}},   # optional
     "section": {"E": ..., "nu": ..., "h": ..., "weight": ...},    # optional, used when no material
     "code": "kratos",                             # optional; records of other codes are skipped
     "overrides": {"model.membrane": "ans"},        # optional scene keys for our run
     "script": "benchmarks/peers/pedestal_kratos.py", "source": "KratosMultiphysics 10.x MITC4 ..."}

``material`` replaces the scene's [material] table (a matched isotropic section), ``overrides``
are dotted scene keys applied to our run.  Without the file the check is reported as skipped.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from . import references
from .record import check, measure, observed_order, skipped, timed

SCENE = "square-pedestal"
# every mesh from the flat sheet (sequence 0): from the 12x4x4 state, mesh sequencing lands 48x16x4
# in another stable state (DC 0.5307 with 19 interpenetrated nodes, against 0.5515 from flat)
CONVERGED = {"model.membrane": "ans", "geometry.grading": 8.0, "solver.static.sequence": 0}
SELF = "Richardson limit of 24x8x4, 48x16x4, 96x32x4 (our own meshes: self-convergence)"


def solve_pedestal(mesh: str, overrides: dict | None = None, material: dict | None = None):
    """Static Newton solve of square-pedestal; returns (RunOutput, projected boundary (P,2), wall s)."""
    from solidshell import scenes
    from solidshell.run import run_scene

    sc = scenes.load(SCENE)
    if material is not None:
        raw = copy.deepcopy(sc.raw)
        raw["material"] = copy.deepcopy(material)
        sc = scenes.Scene.from_dict(raw, source=f"{sc.source} (matched material)", base_dir=sc.base_dir)
    with timed() as t:
        out = run_scene(
            sc, mesh=mesh, solver="static", out_dir=None, progress=False, overrides=overrides, method="newton"
        )
    return out, out.projected_boundary[:, :2], t()


@check(
    "pedestal-convergence",
    "pedestal",
    "square-pedestal DC on 24x8x4, 48x16x4, 96x32x4 (assumed membrane, graded): observed order and Richardson limit",
    quick=False,
)
def check_pedestal_convergence(ctx):
    meshes = ("24x8x4", "48x16x4", "96x32x4")
    dcs, walls, ok = [], [], True
    for m in meshes:
        ctx.log(f"  square-pedestal {m} ...")
        out, _, wall = solve_pedestal(m, CONVERGED)
        dcs.append(out.summary["drape_coefficient"])
        walls.append(wall)
        ok = ok and bool(out.summary.get("converged"))
    d1, d2 = dcs[0] - dcs[1], dcs[1] - dcs[2]
    p = math.log2(d1 / d2) if d1 * d2 > 0 else float("nan")
    lim = dcs[2] - d2 / (2.0**p - 1.0) if math.isfinite(p) else float("nan")
    note = "" if ok else "a mesh did NOT converge"
    recs = [
        measure(
            "pedestal-convergence/change-48-96",
            "|DC_96 - DC_48| / DC_96",
            abs(d2) / dcs[2],
            0.0,
            1e-2,
            error_kind="abs",
            wall_time_s=walls[1] + walls[2],
            reference="mesh-converged DC",
            source=SELF,
            why="the issue's target (< 1 %); measured 0.56 %; the paper's element on uniform meshes gives 5.9 %",
            note=note,
        ),
        measure(
            "pedestal-convergence/order",
            "observed order of DC (three meshes)",
            p,
            2.0,
            1.0,
            error_kind="abs",
            wall_time_s=sum(walls),
            reference="O(h^2) expected of bilinear elements in the asymptotic range",
            source=SELF,
            why="measured 2.78 (the singular pedestal corners and folds make it erratic); below 1 "
            "the meshes are not in the asymptotic range and the limit means little",
            note=note,
        ),
        measure(
            "pedestal-convergence/96x32x4-vs-limit",
            "DC on 96x32x4",
            dcs[2],
            lim,
            5e-3,
            wall_time_s=sum(walls),
            reference="Richardson limit",
            source=SELF,
            why="measured +0.10 %; 0.5 % is half the issue's 1 % convergence target",
            note=note,
        ),
    ]
    h = [1.0 / 24, 1.0 / 48, 1.0 / 96]
    ctx.convergence(
        "square-pedestal (assumed membrane, grading 8): DC vs its Richardson limit",
        [
            {
                "label": "|DC - DC_limit| / DC_limit",
                "h": h,
                "error": [abs(d - lim) / lim for d in dcs],
                "rate": observed_order(h, [d - lim for d in dcs])[-1],
            }
        ],
        "1 / (elements along the pedestal edge)",
        "relative DC error",
    )
    ctx.cache["pedestal-dc"] = dict(zip(meshes, dcs))
    return recs


def kratos_records() -> list[dict] | None:
    p = references.reference_dir() / "pedestal_kratos.json"
    return json_load(p) if p.exists() else None


def json_load(p):
    import json

    return json.loads(p.read_text())


def boundary_distance(ours, theirs, n_theta: int = 720) -> float:
    """max over theta of |r_ours(theta) - r_theirs(theta)| [cm], r the outermost crossing of the ray
    from the pedestal centre with the projected boundary (analysis.radius_profile)."""
    from solidshell.analysis import radius_profile

    _, ra = radius_profile(np.asarray(ours, float), n_theta=n_theta)
    _, rb = radius_profile(np.asarray(theirs, float), n_theta=n_theta)
    return float(np.abs(ra - rb).max())


def _matched(section: dict | None) -> dict | None:
    """The scene [material] table of a record's matched isotropic ``section`` {E, nu, h, weight}:
    density = weight / (h g0) so that the weight per area is the fabric's (units.G0)."""
    if not section:
        return None
    from solidshell.units import G0

    return {
        "isotropic": {
            "E": float(section["E"]),
            "nu": float(section["nu"]),
            "h": float(section["h"]),
            "density": float(section["weight"]) / (float(section["h"]) * G0),
        }
    }


@check(
    "pedestal-kratos",
    "pedestal",
    "square-pedestal 24x8x4 and 48x16x4 DC, folds and projected boundary vs "
    "KratosMultiphysics (reference/pedestal_kratos.json)",
    quick=False,
)
def check_pedestal_kratos(ctx):
    src = "reference/pedestal_kratos.json (KratosMultiphysics, its script named in the file)"
    ref_desc = "KratosMultiphysics MITC4 shell, same mesh"
    recs = kratos_records()
    if recs is None:
        return [
            skipped(
                "pedestal-kratos/24x8x4",
                "DC and projected boundary",
                reference=ref_desc,
                source=src,
                why="an independent code on the same scene",
                note="reference/pedestal_kratos.json not present",
            )
        ]
    out = []
    for r in recs:
        if r.get("code", "kratos") != "kratos":  # the file also holds the script's own solidshell runs
            continue
        mesh = r["mesh"]
        if mesh != "24x8x4" and ctx.quick:
            continue
        name = f"pedestal-kratos/{mesh}"
        src_r = r.get("source") or src
        if not str(r.get("state", "")).lower().startswith("stable"):
            out.append(
                skipped(
                    name,
                    "DC",
                    reference=ref_desc,
                    source=src_r,
                    why="only stable equilibria compare",
                    note=f"Kratos state: {r.get('state')!r}",
                )
            )
            continue
        res, poly, wall = solve_pedestal(mesh, r.get("overrides"), r.get("material") or _matched(r.get("section")))
        s = res.summary
        note = "" if s.get("positive_definite") else f"our state is not a stable equilibrium ({s.get('message')})"
        coarse = mesh == "24x8x4"
        tol_dc, tol_b = (0.10, 1.0) if coarse else (0.05, 0.5)
        why_dc = (
            "on 24x8x4 each code is still 4-8 % from its own 48x16x4 DC for this section (Kratos 0.681 -> "
            "0.652, ours 0.730 -> 0.677), so 10 %"
            if coarse
            else "two different elements (MITC4 vs ANS solid-shell) on the same mesh: our own DC moves 4-14 % "
            "from 24x8x4 to 48x16x4 depending on the membrane, so 5 % on the finer one"
        )
        out.append(
            measure(
                f"{name}/dc",
                "drape coefficient",
                s["drape_coefficient"],
                r["dc"],
                tol_dc,
                wall_time_s=wall,
                reference=ref_desc,
                source=src_r,
                note=note,
                why=why_dc,
            )
        )
        out.append(
            measure(
                f"{name}/boundary",
                "max |r_ours(theta) - r_kratos(theta)| [cm]",
                boundary_distance(poly, r["projected_boundary"]),
                0.0,
                tol_b,
                error_kind="abs",
                wall_time_s=wall,
                reference=ref_desc,
                source=src_r,
                note=note,
                why=f"{tol_dc:.0%} of the 10 cm overhang: the same allowance as for DC, in the boundary's radius",
            )
        )
        out.append(
            measure(
                f"{name}/folds",
                "fold count",
                s["fold_count"],
                r["fold_count"],
                0,
                error_kind="abs",
                wall_time_s=wall,
                reference=ref_desc,
                source=src_r,
                note=note,
                why="a count: the same stable state has the same folds",
            )
        )
    return out
