"""Cross-check of solidshell against an independent DOLFINx Naghdi shell model (issue 14).

Runs under the project venv.  For each problem it builds the solidshell mesh (gmsh) and section,
solves it with solidshell, writes the same mesh and rigidities to a JSON job that the DOLFINx model
(``verification/fenicsx/model.py``, system python3 + python3-dolfinx) solves in a subprocess, and
compares the two and the references:

* strip 5x1 cm, warp and weft cut, self-weight: tip position vs the heavy elastica
  (reference/elastica_strip.json) and vs each other, on a mesh series of both codes;
* isotropic end-shear cantilever (L/h = 100, P L^2/EI = 4): tip deflection vs Mattiasson (1981);
* square-pedestal 12x4x4 ... 48x16x4, static: drape coefficient, fold count, the distance between
  the two projected boundaries, whether each state is stable (tangent inertia / positive definite),
  the Richardson limit of the DOLFINx DC against solidshell's stored convergence study, and on
  24x8x4 each code restarted from the other's state (state.py maps the states);
* 2 MPI ranks vs 1 rank (DOLFINx) on the strip and the 12x4x4 drape.

    python -m verification.fenicsx.crosscheck --out DIR [--quick] [--problems strip shear pedestal mpi]
        [--pedestal-meshes MESH ...] [--restart-both [MESH ...]] [--reuse]

``main(out_dir)`` returns the records (name, reference, source, quantity, value, reference_value,
error, tolerance, passed, wall_time_s, error_kind; why where a tolerance is derived; passed None for a
skipped row) and writes ``DIR/fenicsx_crosscheck.json`` and ``.md``.
Without DOLFINx it prints one line and exits with status 3.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from ..checks.record import skipped
from .jobs import DolfinxMissing, check_dolfinx, make_job
from .jobs import run_model as _run_model
from .state import from_fenicsx_state, max_translation_change, to_fenicsx_state

_REUSE = {"on": False}


def run_model(job, work, **kw):
    """jobs.run_model with the --reuse switch of this run."""
    kw.setdefault("reuse", _REUSE["on"])
    return _run_model(job, work, **kw)


OUT = Path(__file__).resolve().parents[1] / "out"  # verification/out (a checkout's; not in the wheel)

STRIP_TOL = 2e-3  # issue 14: strip tip within 0.2 % of each other and of the elastica
DC_TOL = 1e-2  # issue 14: pedestal DC within 1 % where both codes reach the same state
# a restarted code is back in its own state when within 1e-6 cm of it: three orders above solidshell's
# stopping test (disp_tol 1e-10 x max|D| ~ 1e-9 cm), six below the 1-2 cm between the codes' states
RESTART_TOL_CM = 1e-6
MPI_TOL = 1e-8  # 1 vs 2 ranks: the same equations solved to rtol 1e-9 -> agreement to round-off
SHEAR_TOL = 2e-3  # end shear vs the elliptic-integral closed form, as for the strip
PEDESTAL_STEPS = {"initial": 0.02, "max": 0.2}
# proximal continuation of the DOLFINx drape (model.py, solve()): the shift c starts at 2.6 x the
# weight per area per cm and halves after every easy step; the end state is solved with c = 0
PEDESTAL_PROX = {"c0": 0.05, "relax": 0.5, "c_min_ratio": 1e-5}
# the pedestal mesh series of both codes; the DOLFINx DC's Richardson limit uses the last three
PEDESTAL_MESHES = ("12x4x4", "24x8x4", "36x12x4", "48x16x4")
# meshes on which each code is also started from the other's state (issue 14: the paper's 24x8x4,
# where the two codes' DCs differ most on a mesh of the paper's); a restart of DOLFINx on 48x16x4
# would cost as much as its drape
RESTART_MESHES = ("24x8x4",)


def _elastica():
    from verification.checks import references

    return references.module("elastica")


def record(name, reference, source, quantity, value, reference_value, tolerance, wall_time_s, relative=True, **extra):
    """One comparison row; error is relative to |reference_value| unless ``relative`` is False."""
    err = abs(value - reference_value)
    if relative:
        err /= abs(reference_value)
    r = dict(
        name=name,
        reference=reference,
        source=source,
        quantity=quantity,
        value=float(value),
        reference_value=float(reference_value),
        error=float(err),
        tolerance=float(tolerance),
        passed=bool(np.isfinite(err) and err <= tolerance),
        wall_time_s=float(wall_time_s),
        error_kind="rel" if relative else "abs",
    )
    r.update(extra)
    return r


def tip_position_error(x, z, ref_x, ref_z, L=5.0):
    """|tip - tip_ref| / |tip_ref displacement|: the tip position error relative to the tip travel."""
    return float(np.hypot(x - ref_x, z - ref_z) / np.hypot(ref_x - L, ref_z))


# ----------------------------------------------------------------------------- strip
def _fenicsx_strip(n, cut, work, ranks=1):
    from solidshell.material import Fabric
    from solidshell.meshing import build_mesh

    mesh = build_mesh("strip", f"{n}x1", length=5.0, width=1.0)
    mat = Fabric.wool(warp_angle=0.0 if cut == "warp" else 90.0)
    res = run_model(make_job(f"strip-{cut}-{n}x1", mesh, mat), work, ranks=ranks)
    if not res.get("converged") or "U" not in res:
        return res, None
    tip = mesh.node_set("tip")
    x = np.asarray(mesh.nodes) + np.asarray(res["U"])
    return res, x[tip].mean(axis=0)


def strip_problem(work, meshes_fx, meshes_ss, log):
    from verification.checks import references
    from verification.strip import solve_strip

    ref = references.elastica_strip()["strip"]
    recs, table = [], []
    for cut in ("warp", "weft"):
        rx, rz = ref[cut]["tip_x"], ref[cut]["tip_z"]
        ss = {}
        for n in meshes_ss:
            sol = solve_strip(n, cut, "newton")
            r = sol["result"]
            ss[n] = (sol["tip_x"], sol["tip_z"])
            e = tip_position_error(sol["tip_x"], sol["tip_z"], rx, rz)
            table.append(
                dict(
                    problem=f"strip-{cut}",
                    code="solidshell",
                    mesh=f"{n}x1",
                    tip_x=sol["tip_x"],
                    tip_z=sol["tip_z"],
                    tip_error_vs_elastica=e,
                    converged=r.converged,
                    iterations=r.info["iterations"],
                    wall_time_s=sol["wall"],
                )
            )
            log(
                f"strip-{cut} solidshell {n}x1: tip ({sol['tip_x']:.5f}, {sol['tip_z']:.5f}) err {e:.2e} "
                f"its {r.info['iterations']} {sol['wall']:.1f}s"
            )
        fx = {}
        for n in meshes_fx:
            res, tip = _fenicsx_strip(n, cut, work)
            if tip is None:
                log(f"strip-{cut} fenicsx {n}x1: FAILED {res['status']}")
                table.append(
                    dict(problem=f"strip-{cut}", code="fenicsx", mesh=f"{n}x1", converged=False, note=res["status"])
                )
                continue
            fx[n] = (tip[0], tip[2], res)
            e = tip_position_error(tip[0], tip[2], rx, rz)
            table.append(
                dict(
                    problem=f"strip-{cut}",
                    code="fenicsx",
                    mesh=f"{n}x1",
                    tip_x=tip[0],
                    tip_z=tip[2],
                    tip_error_vs_elastica=e,
                    converged=res["converged"],
                    iterations=res["newton_iterations"],
                    steps=res["steps"],
                    wall_time_s=res["wall_time_s"],
                    process_wall_time_s=res["process_wall_time_s"],
                    n_dofs=res["n_dofs"],
                    stable=res.get("stable"),
                )
            )
            log(
                f"strip-{cut} fenicsx {n}x1: tip ({tip[0]:.5f}, {tip[2]:.5f}) err {e:.2e} "
                f"steps {res['steps']} its {res['newton_iterations']} {res['wall_time_s']:.1f}s"
            )
        # records at the finest mesh of each code
        if fx:
            nf = max(fx)
            x, z, res = fx[nf]
            e = tip_position_error(x, z, rx, rz)
            recs.append(
                record(
                    f"strip-{cut} {nf}x1 tip position",
                    "elastica (reference/elastica_strip.json)",
                    "fenicsx",
                    "tip position error / tip travel",
                    e,
                    0.0,
                    STRIP_TOL,
                    res["wall_time_s"],
                    relative=False,
                )
            )
            recs.append(
                record(
                    f"strip-{cut} {nf}x1 tip z",
                    "elastica",
                    "fenicsx",
                    "tip_z [cm]",
                    z,
                    rz,
                    STRIP_TOL,
                    res["wall_time_s"],
                )
            )
        if ss:
            ns = max(ss)
            x, z = ss[ns]
            e = tip_position_error(x, z, rx, rz)
            recs.append(
                record(
                    f"strip-{cut} {ns}x1 tip position",
                    "elastica (reference/elastica_strip.json)",
                    "solidshell",
                    "tip position error / tip travel",
                    e,
                    0.0,
                    STRIP_TOL,
                    0.0,
                    relative=False,
                )
            )
        if fx and ss:
            nf, ns = max(fx), max(ss)
            e = tip_position_error(fx[nf][0], fx[nf][1], ss[ns][0], ss[ns][1])
            recs.append(
                record(
                    f"strip-{cut} tip position, fenicsx {nf}x1 vs solidshell {ns}x1",
                    "solidshell",
                    "fenicsx",
                    "tip position difference / tip travel",
                    e,
                    0.0,
                    STRIP_TOL,
                    fx[nf][2]["wall_time_s"],
                    relative=False,
                )
            )
    return recs, table


# ----------------------------------------------------------------------------- end shear
def shear_problem(work, meshes_fx, meshes_ss, log, alpha=4):
    from solidshell.material import IsotropicShell
    from solidshell.meshing import build_mesh
    from verification.checks.cantilevers import L
    from verification.checks.cantilevers import large_end_shear as end_shear

    ela = _elastica()
    u_ref, w_ref, _ = ela.MATTIASSON_1981[alpha]
    recs, table = [], []
    for n in meshes_ss:
        r = end_shear(n, alpha)
        table.append(
            dict(
                problem=f"end-shear PL2/EI={alpha}",
                code="solidshell",
                mesh=f"{n}x1",
                w_over_L=r["w_over_L"],
                u_over_L=r["u_over_L"],
                w_rel_error=r["w_rel_error"],
                converged=r["converged"],
                iterations=r["iterations"],
                wall_time_s=r["wall_time_s"],
            )
        )
        log(f"end-shear solidshell {n}x1: w/L {r['w_over_L']:.6f} (ref {w_ref}) its {r['iterations']}")
    if meshes_ss:
        recs.append(
            record(
                f"end-shear PL2/EI={alpha} {meshes_ss[-1]}x1 w/L",
                "Mattiasson 1981",
                "solidshell",
                "w/L",
                r["w_over_L"],
                w_ref,
                SHEAR_TOL,
                r["wall_time_s"],
            )
        )
    mat = IsotropicShell(E=1.2e6, nu=0.0, h=0.1)
    last = None
    for n in meshes_fx:
        mesh = build_mesh("strip", f"{n}x1", length=L, width=1.0)
        P = alpha * mat.C_b[0, 0] / L**2  # width 1: B = C_b[0,0]
        job = make_job(
            f"end-shear-{alpha}-{n}x1",
            mesh,
            mat,
            gravity=False,
            line_load={"set": "tip", "force_per_length": [0.0, 0.0, -P / 1.0]},
        )
        res = run_model(job, work)
        if not res.get("converged") or "U" not in res:
            log(f"end-shear fenicsx {n}x1: FAILED {res['status']}")
            continue
        u = np.asarray(res["U"])[mesh.node_set("tip")].mean(axis=0)
        w, uu = -u[2] / L, -u[0] / L
        table.append(
            dict(
                problem=f"end-shear PL2/EI={alpha}",
                code="fenicsx",
                mesh=f"{n}x1",
                w_over_L=w,
                u_over_L=uu,
                w_rel_error=(w - w_ref) / w_ref,
                converged=res["converged"],
                iterations=res["newton_iterations"],
                steps=res["steps"],
                wall_time_s=res["wall_time_s"],
                n_dofs=res["n_dofs"],
            )
        )
        log(
            f"end-shear fenicsx {n}x1: w/L {w:.6f} u/L {uu:.6f} (ref {w_ref}, {u_ref}) "
            f"its {res['newton_iterations']} {res['wall_time_s']:.1f}s"
        )
        last = (n, w, uu, res)
    if last:
        n, w, uu, res = last
        recs.append(
            record(
                f"end-shear PL2/EI={alpha} {n}x1 w/L",
                "Mattiasson 1981",
                "fenicsx",
                "w/L",
                w,
                w_ref,
                SHEAR_TOL,
                res["wall_time_s"],
            )
        )
        recs.append(
            record(
                f"end-shear PL2/EI={alpha} {n}x1 u/L",
                "Mattiasson 1981",
                "fenicsx",
                "u/L",
                uu,
                u_ref,
                SHEAR_TOL,
                res["wall_time_s"],
            )
        )
    return recs, table


# ----------------------------------------------------------------------------- pedestal
def boundary_distance(poly_a, poly_b, center=(0.0, 0.0)):
    """max over theta of |r_a(theta) - r_b(theta)| of the two projected boundaries [cm]."""
    from solidshell.analysis import radius_profile

    _, ra = radius_profile(np.asarray(poly_a), center)
    _, rb = radius_profile(np.asarray(poly_b), center)
    return float(np.max(np.abs(ra - rb)))


def _restart_fenicsx(job, ss_mesh, U_ss, U_fx, work, ranks, dens, log):
    """DOLFINx started at full load from solidshell's state U_ss; a table row with where it went
    (DC, folds, stability) and how far: from its start (the solidshell state) and from DOLFINx's
    own state U_fx reached from the flat sheet [cm]."""
    from solidshell.analysis import drape_summary

    rjob = dict(job, name=f"{job['name']}-from-solidshell", initial_state=to_fenicsx_state(ss_mesh, U_ss))
    rr = run_model(rjob, work, ranks=ranks, timeout=5400)
    row = dict(problem="square-pedestal", code="fenicsx from solidshell state", mesh=dens)
    if not (rr.get("converged") and "U" in rr):
        log(f"square-pedestal fenicsx {dens} restart from solidshell: FAILED {rr.get('status')}")
        return dict(row, converged=False, note=rr.get("status"))
    Ur = np.asarray(rr["U"])
    ds_r = drape_summary(ss_mesh, Ur, pedestal_area=100.0)
    row.update(
        drape_coefficient=ds_r["drape_coefficient"],
        fold_count=ds_r["fold_count"],
        converged=True,
        stable=rr.get("stable"),
        negative_eigenvalues=rr.get("negative_eigenvalues"),
        iterations=rr["newton_iterations"],
        steps=rr["steps"],
        wall_time_s=rr["wall_time_s"],
        n_dofs=rr["n_dofs"],
        moved_from_start_cm=max_translation_change(Ur, U_ss),
        distance_to_own_state_cm=max_translation_change(Ur, U_fx),
        **_provenance(rr),
    )
    log(
        f"square-pedestal fenicsx {dens} restarted from the solidshell state: DC {row['drape_coefficient']:.4f} "
        f"folds {row['fold_count']} stable {row['stable']} steps {rr['steps']} its {rr['newton_iterations']} "
        f"{rr['wall_time_s']:.1f}s; moved {row['moved_from_start_cm']:.4f} cm, ends "
        f"{row['distance_to_own_state_cm']:.2e} cm from DOLFINx's own state"
    )
    return row


def _provenance(res):
    """Whether a DOLFINx result was reused (--reuse) and the load average of its solve, for the report:
    a reused result's wall time is that of the run that computed it."""
    out = {"reused": bool(res.get("reused", False))}
    if res.get("load_average") is not None:
        out["load_average"] = res["load_average"]
    return out


def _restart_record(row, code):
    """The comparison of a restart: how far from its own code's state it ended [cm]."""
    if "distance_to_own_state_cm" not in row:
        return []
    other = "solidshell" if code == "fenicsx" else "fenicsx"
    return [
        record(
            f"square-pedestal {row['mesh']}: {code} started from {other}'s state returns to its own state",
            f"{code} from the flat sheet",
            f"{code} from {other}'s state",
            "max nodal distance from its own state [cm]",
            row["distance_to_own_state_cm"],
            0.0,
            RESTART_TOL_CM,
            row["wall_time_s"],
            relative=False,
            moved_from_start_cm=row["moved_from_start_cm"],
            fold_count=row["fold_count"],
            stable=row["stable"],
        )
    ]


def _restart_solidshell(dens, out, res, log):
    """solidshell started at full load from the DOLFINx result ``res`` (state.from_fenicsx_state);
    a table row as _restart_fenicsx's, distances measured to the DOLFINx state and to solidshell's
    own state ``out.U`` [cm]."""
    from solidshell.analysis import drape_summary
    from solidshell.run import run_scene

    U0 = from_fenicsx_state(out.mesh, res["U"], res["director"])
    t0 = time.perf_counter()
    # predictor off: the start is already at the full load (as the mesh sequencing's prolonged starts)
    r = run_scene("square-pedestal", mesh=dens, solver="static", progress=False, U0=U0, predictor=False)
    wall = time.perf_counter() - t0
    s = r.summary
    row = dict(
        problem="square-pedestal",
        code="solidshell from fenicsx state",
        mesh=dens,
        converged=s.get("converged"),
        stable=s.get("positive_definite"),
        iterations=s.get("iterations"),
        wall_time_s=s.get("wall_time_s", wall),
    )
    if not s.get("converged"):
        log(f"square-pedestal solidshell {dens} restart from DOLFINx: FAILED {s.get('message')}")
        return dict(row, note=s.get("message"))
    ds = drape_summary(r.mesh, r.U, pedestal_area=100.0)
    row.update(
        drape_coefficient=ds["drape_coefficient"],
        fold_count=ds["fold_count"],
        moved_from_start_cm=max_translation_change(r.U, U0),
        distance_to_own_state_cm=max_translation_change(r.U, out.U),
    )
    log(
        f"square-pedestal solidshell {dens} restarted from the DOLFINx state: DC {row['drape_coefficient']:.4f} "
        f"folds {row['fold_count']} pos.def. {row['stable']} its {row['iterations']} {row['wall_time_s']:.1f}s; "
        f"moved {row['moved_from_start_cm']:.4f} cm, ends {row['distance_to_own_state_cm']:.2e} cm from "
        f"solidshell's own state"
    )
    return row


def pedestal_problem(work, meshes, log, ranks=1, restart=True, restart_both=()):
    """Both codes on the square-pedestal meshes.  ``restart``: start DOLFINx from solidshell's
    state where the two reached different states (fold count or stability); ``restart_both``: the
    meshes on which each code is started from the other's state whatever they reached."""
    from solidshell.analysis import drape_summary
    from solidshell.material import Fabric
    from solidshell.meshing import build_mesh
    from solidshell.run import run_scene

    recs, table = [], []
    ped_area = 100.0
    for dens in meshes:
        t0 = time.perf_counter()
        out = run_scene("square-pedestal", mesh=dens, solver="static", progress=False)
        t_ss = time.perf_counter() - t0
        s = out.summary
        ds_ss = drape_summary(out.mesh, out.U, pedestal_area=ped_area)
        row_ss = dict(
            problem="square-pedestal",
            code="solidshell",
            mesh=dens,
            drape_coefficient=ds_ss["drape_coefficient"],
            fold_count=ds_ss["fold_count"],
            converged=s.get("converged"),
            stable=s.get("positive_definite"),
            iterations=s.get("iterations"),
            wall_time_s=s.get("wall_time_s", s.get("solver_wall_time_s", t_ss)),
        )
        if s.get("sequence"):
            # mesh sequencing (square-pedestal.toml, sequence = "auto"): "iterations" are the fine
            # mesh's own; the coarse levels' come on top
            row_ss["sequence"] = [
                dict(mesh=q["mesh"], iterations=q["iterations"], wall_time_s=q["wall_time_s"]) for q in s["sequence"]
            ]
            row_ss["iterations_all_levels"] = int(sum(q["iterations"] or 0 for q in s["sequence"]))
        table.append(row_ss)
        log(
            f"square-pedestal solidshell {dens}: DC {ds_ss['drape_coefficient']:.4f} folds {ds_ss['fold_count']} "
            f"pos.def. {s.get('positive_definite')} its {s.get('iterations')} {t_ss:.1f}s"
        )
        mesh = build_mesh("square_on_square", dens, sheet=20.0, pedestal=10.0)
        if not np.array_equal(np.asarray(mesh.nodes), np.asarray(out.mesh.nodes)):
            # states are exchanged node by node: both codes must number the same mesh alike
            raise RuntimeError(f"square-pedestal {dens}: the scene's mesh and the job's mesh differ")
        # a hanging plate bends in two directions at once (Gaussian curvature stretches it): the
        # load path from the flat sheet needs smaller first increments than the strip
        job = make_job(
            f"square-pedestal-{dens}",
            mesh,
            Fabric.wool(),
            steps=PEDESTAL_STEPS,
            snes={"max_it": 30},
            prox=PEDESTAL_PROX,
        )
        res = run_model(job, work, ranks=ranks, timeout=5400)
        if not res.get("converged") or "U" not in res:
            log(f"square-pedestal fenicsx {dens}: FAILED {res['status']}")
            table.append(
                dict(problem="square-pedestal", code="fenicsx", mesh=dens, converged=False, note=res["status"])
            )
            continue
        U = np.asarray(res["U"])
        ds_fx = drape_summary(mesh, U, pedestal_area=ped_area)
        x = np.asarray(mesh.nodes) + U
        inside = int(np.sum((np.abs(x[:, 0]) < 5.0 - 1e-9) & (np.abs(x[:, 1]) < 5.0 - 1e-9) & (x[:, 2] < -1e-9)))
        dist = boundary_distance(ds_fx["projected_boundary"], ds_ss["projected_boundary"])
        row = dict(
            problem="square-pedestal",
            code="fenicsx",
            mesh=dens,
            drape_coefficient=ds_fx["drape_coefficient"],
            fold_count=ds_fx["fold_count"],
            converged=res["converged"],
            stable=res.get("stable"),
            negative_eigenvalues=res.get("negative_eigenvalues"),
            iterations=res["newton_iterations"],
            steps=res["steps"],
            wall_time_s=res["wall_time_s"],
            n_dofs=res["n_dofs"],
            nodes_inside_pedestal=inside,
            boundary_distance_cm=dist,
            **_provenance(res),
        )
        table.append(row)
        log(
            f"square-pedestal fenicsx {dens}: DC {ds_fx['drape_coefficient']:.4f} folds {ds_fx['fold_count']} "
            f"stable {res.get('stable')} steps {res['steps']} its {res['newton_iterations']} "
            f"{res['wall_time_s']:.1f}s; boundary distance {dist:.3f} cm; nodes inside pedestal {inside}"
        )
        same = ds_fx["fold_count"] == ds_ss["fold_count"] and bool(res.get("stable")) == bool(
            s.get("positive_definite")
        )
        if dens in restart_both or (restart and not same):
            # is solidshell's state an equilibrium of the DOLFINx model?  Start DOLFINx from it at
            # the full load and see where Newton goes
            table.append(_restart_fenicsx(job, out.mesh, out.U, U, work, ranks, dens, log))
            recs += _restart_record(table[-1], "fenicsx")
        if dens in restart_both:
            # and the other way: solidshell started from the DOLFINx state
            table.append(_restart_solidshell(dens, out, res, log))
            recs += _restart_record(table[-1], "solidshell")
        # on equal meshes the codes' DCs differ by their discretisation errors (solidshell's 4-node
        # elements are far from converged here; the restarts show each returns to its own state):
        # what must agree mesh by mesh is the state -- same folds, both stable -- and the DC within
        # DC_TOL plus both series' own discretisation errors (converged_dc_records); the DC difference
        # on equal meshes is reported
        dc_fx, dc_ss = ds_fx["drape_coefficient"], ds_ss["drape_coefficient"]
        recs.append(
            record(
                f"square-pedestal {dens}: same state (folds, both stable)",
                "solidshell",
                "fenicsx",
                "same state (1 = yes)",
                float(same),
                1.0,
                0.0,
                res["wall_time_s"],
                relative=False,
                drape_coefficient=dc_fx,
                drape_coefficient_reference=dc_ss,
                dc_relative_difference=(dc_fx - dc_ss) / dc_ss,
                fold_count=ds_fx["fold_count"],
                fold_count_reference=ds_ss["fold_count"],
                stable=res.get("stable"),
                stable_reference=s.get("positive_definite"),
                boundary_distance_cm=dist,
            )
        )
    recs += converged_dc_records([t for t in table if t["code"] == "fenicsx" and "drape_coefficient" in t], log)
    return recs, table


STORED_CONVERGENCE = OUT / "static_convergence.json"


def converged_dc_records(fx_rows, log, stored=None):
    """fenicsx's DC against solidshell's own mesh-convergence study of the same scene
    (verification/static_convergence.py, stored in verification/out/static_convergence.json: finest
    mesh 96x32x4 and its Richardson limit, per element variant) -- the comparison at converged
    meshes, since solidshell's elements are far from converged at the paper's 24x8x4 and 48x16x4.
    ``fx_rows``: the DOLFINx pedestal rows, coarse to fine (the limit uses the last three);
    ``stored``: the study's dict (default: read from STORED_CONVERGENCE)."""
    if not fx_rows:
        return []
    if stored is None:
        if not STORED_CONVERGENCE.exists():
            return []
        stored = json.loads(STORED_CONVERGENCE.read_text())
    fx = fx_rows[-1]
    lim = (
        richardson([int(r["mesh"].split("x")[0]) for r in fx_rows[-3:]], [r["drape_coefficient"] for r in fx_rows[-3:]])
        if len(fx_rows) >= 3
        else None
    )
    if lim is not None:
        log(f"fenicsx DC Richardson limit from {[r['mesh'] for r in fx_rows[-3:]]}: {lim[0]:.4f} (order {lim[1]:.2f})")
    fx_series = dict(
        mesh=fx["mesh"],
        dc=fx["drape_coefficient"],
        limit=None if lim is None else lim[0],
        order=None if lim is None else lim[1],
        meshes=[r["mesh"] for r in fx_rows[-3:]],
        wall_time_s=fx["wall_time_s"],
    )
    recs = []
    for v in stored.get("variants", []):
        rows = dc_series_rows(fx_series, v)
        if rows:
            log(
                "; ".join(
                    f"{r['name']}: {r['value']:.4f} vs {r['reference_value']:.4f} (error {r['error']:.2e}, "
                    f"tolerance {r['tolerance']:.2e})"
                    if r["passed"] is not None
                    else f"{r['name']}: skipped"
                    for r in rows
                )
            )
        recs += rows
    return recs


def dc_series_rows(fx, variant):
    """The three DC rows of one solidshell element variant against the DOLFINx series, each comparing
    like with like: a value and the discretisation error of the mesh series it comes from.

    ``fx``: dict(mesh, dc, limit, order, meshes, wall_time_s) -- DOLFINx's finest mesh, its DC and the
    Richardson limit (None when the series has no asymptotic range); ``variant``: one entry of
    static_convergence.json (variant, rows [mesh, drape_coefficient, converged], richardson_limit,
    observed_order).

    Each series' discretisation error is its own Richardson estimate d = |DC_finest - DC_limit|: the
    finest mesh's error, and a bound on the limit's (the correction the extrapolation applies: the
    exact DC lies between the finest DC and the limit when the order rises towards its asymptotic
    value, and Roache's GCI, 1.25 d around the finest DC, leaves it within d/4 beyond the limit when
    the order falls).  Two codes that solve the same equations can then differ by d_solidshell +
    d_fenicsx on top of the 1 % that issue 14 allows between two models of the same shell:
    tolerance = DC_TOL + (d_ss + d_fx) / |reference value|.  A row of a series without a limit (fewer
    than three meshes, not monotone) is skipped with its reason, neither passed nor failed."""
    name = variant["variant"]
    rows = [r for r in variant.get("rows", []) if r.get("converged")]
    if not rows:
        return []
    src, ref = "fenicsx", "solidshell (stored static_convergence.json)"
    labels = [
        (f"square-pedestal DC, fenicsx {fx['mesh']} vs solidshell {rows[-1]['mesh']} ({name})", "drape coefficient"),
        (f"square-pedestal DC, fenicsx {fx['mesh']} vs solidshell Richardson limit ({name})", "drape coefficient"),
        (f"square-pedestal DC Richardson limits, fenicsx vs solidshell ({name})", "drape coefficient (extrapolated)"),
    ]
    q_lim = variant.get("richardson_limit")
    why_missing = []
    if q_lim is None:
        why_missing.append(f"solidshell's {name} series has no Richardson limit (not monotone / under three meshes)")
    if fx.get("limit") is None:
        why_missing.append(
            f"the DOLFINx series {', '.join(fx.get('meshes') or [fx['mesh']])} has no Richardson limit "
            "(needs three monotone meshes)"
        )
    if why_missing:
        why = "; ".join(why_missing) + ": without both series' discretisation errors the DCs cannot be compared"
        return [skipped_record(n, ref, src, q, why, fx["wall_time_s"], note="no Richardson limit") for n, q in labels]
    q_fin = rows[-1]["drape_coefficient"]
    d_ss, d_fx = abs(q_fin - q_lim), abs(fx["dc"] - fx["limit"])
    pairs = [(fx["dc"], q_fin), (fx["dc"], q_lim), (fx["limit"], q_lim)]
    out = []
    for (n, q), (value, reference_value) in zip(labels, pairs):
        tol = DC_TOL + (d_ss + d_fx) / abs(reference_value)
        why = (
            f"like with like: each side's DC carries its series' own discretisation error (Richardson estimate "
            f"|finest - limit|): solidshell {name} {rows[-1]['mesh']} {q_fin:.4f} -> {q_lim:.4f} "
            f"(order {variant.get('observed_order', float('nan')):.2f}), d_ss = {d_ss:.4f}; DOLFINx {fx['mesh']} "
            f"{fx['dc']:.4f} -> {fx['limit']:.4f} (order {fx['order']:.2f}), d_fx = {d_fx:.4f}; tolerance = "
            f"{DC_TOL:g} (issue 14, two models of one shell) + (d_ss + d_fx) / reference = {tol:.4f}"
        )
        out.append(
            record(
                n,
                ref,
                src,
                q,
                value,
                reference_value,
                tol,
                fx["wall_time_s"],
                why=why,
                d_solidshell=d_ss,
                d_fenicsx=d_fx,
            )
        )
    return out


def skipped_record(name, reference, source, quantity, why, wall_time_s=0.0, note=""):
    """A comparison that could not be made (its reason in ``why``, in short in ``note``): the
    verification record's ``skipped`` (no value, neither passed nor failed) with this row's time."""
    rec = skipped(name, quantity, reference=reference, source=source, why=why, note=note).to_dict()
    return {**rec, "wall_time_s": float(wall_time_s)}


def richardson(n, q):
    """Limit and order of q(h) = q_inf + C h^p, h = 1/n, from three meshes (any ratios); None if the
    sequence is not monotone (no asymptotic range)."""
    from scipy.optimize import brentq

    h = 1.0 / np.asarray(n, dtype=float)
    q = np.asarray(q, dtype=float)
    d1, d2 = q[0] - q[1], q[1] - q[2]
    if d1 * d2 <= 0.0:
        return None
    r = d1 / d2

    def f(p):
        return (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - r

    try:
        p = brentq(f, 0.05, 8.0)
    except ValueError:
        return None
    C = d2 / (h[1] ** p - h[2] ** p)
    return float(q[2] - C * h[2] ** p), float(p)


# ----------------------------------------------------------------------------- MPI
def mpi_problem(work, log, n=20, cut="warp", pedestal="12x4x4"):
    r1, t1 = _fenicsx_strip(n, cut, work, ranks=1)
    r2, t2 = _fenicsx_strip(n, cut, work, ranks=2)
    if t1 is None or t2 is None:
        log(f"mpi: FAILED ({r1.get('status')} / {r2.get('status')})")
        return [], []
    U1, U2 = np.asarray(r1["U"]), np.asarray(r2["U"])
    diff = float(np.max(np.abs(U1 - U2)) / np.max(np.abs(U1)))
    log(
        f"mpi strip-{cut} {n}x1: max |U_2ranks - U_1rank| / max|U| = {diff:.2e}; its {r1['newton_iterations']} "
        f"vs {r2['newton_iterations']}; {r1['wall_time_s']:.1f}s vs {r2['wall_time_s']:.1f}s"
    )
    rec = record(
        f"strip-{cut} {n}x1, 2 MPI ranks vs 1",
        "fenicsx 1 rank",
        "fenicsx 2 ranks",
        "max nodal displacement difference / max displacement",
        diff,
        0.0,
        MPI_TOL,
        r2["wall_time_s"],
        relative=False,
    )
    table = [
        dict(
            problem=f"strip-{cut} mpi",
            code="fenicsx",
            mesh=f"{n}x1",
            ranks=k,
            tip_x=t[0],
            tip_z=t[2],
            iterations=r["newton_iterations"],
            wall_time_s=r["wall_time_s"],
        )
        for k, r, t in ((1, r1, t1), (2, r2, t2))
    ]
    recs = [rec]
    if pedestal:
        recs += mpi_pedestal(work, log, pedestal, table)
    return recs, table


def mpi_pedestal(work, log, dens, table):
    """The drape on 1 and 2 ranks.  The partition changes only the round-off (MUMPS is a direct
    solver); the step sequence is then the same and the DC agrees to round-off -- 1e-6 leaves room
    for a different step sequence should a Newton count near the growth threshold flip."""
    from solidshell.analysis import drape_summary
    from solidshell.material import Fabric
    from solidshell.meshing import build_mesh

    mesh = build_mesh("square_on_square", dens, sheet=20.0, pedestal=10.0)
    job = make_job(
        f"square-pedestal-{dens}", mesh, Fabric.wool(), steps=PEDESTAL_STEPS, snes={"max_it": 30}, prox=PEDESTAL_PROX
    )
    res = {k: run_model(job, work, ranks=k, timeout=5400) for k in (1, 2)}
    if not all(r.get("converged") and "U" in r for r in res.values()):
        log(f"mpi square-pedestal {dens}: FAILED ({res[1].get('status')} / {res[2].get('status')})")
        return []
    dc = {k: drape_summary(mesh, np.asarray(r["U"]), pedestal_area=100.0)["drape_coefficient"] for k, r in res.items()}
    diff = float(np.max(np.abs(np.asarray(res[1]["U"]) - np.asarray(res[2]["U"]))))
    log(
        f"mpi square-pedestal {dens}: DC {dc[1]:.6f} (1 rank) vs {dc[2]:.6f} (2 ranks); max |dU| {diff:.2e} cm; "
        f"its {res[1]['newton_iterations']} vs {res[2]['newton_iterations']}"
    )
    for k in (1, 2):
        table.append(
            dict(
                problem="square-pedestal mpi",
                code="fenicsx",
                mesh=dens,
                ranks=k,
                drape_coefficient=dc[k],
                fold_count=drape_summary(mesh, np.asarray(res[k]["U"]), pedestal_area=100.0)["fold_count"],
                converged=True,
                stable=res[k].get("stable"),
                steps=res[k]["steps"],
                iterations=res[k]["newton_iterations"],
                wall_time_s=res[k]["wall_time_s"],
                n_dofs=res[k]["n_dofs"],
            )
        )
    return [
        record(
            f"square-pedestal {dens} DC, 2 MPI ranks vs 1",
            "fenicsx 1 rank",
            "fenicsx 2 ranks",
            "drape coefficient",
            dc[2],
            dc[1],
            1e-6,
            res[2]["wall_time_s"],
            max_abs_dU_cm=diff,
        )
    ]


# ----------------------------------------------------------------------------- report
def write_report(out_dir: Path, records, table, meta):
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "fenicsx_crosscheck.json").write_text(
        json.dumps(dict(meta=meta, records=records, runs=table), indent=1, default=float)
    )
    lines = [
        "# Cross-check: solidshell vs an independent DOLFINx Naghdi shell (issue 14)",
        "",
        f"DOLFINx {meta.get('dolfinx')}; generated by `python -m verification.fenicsx.crosscheck`. "
        f"Load average at start {meta.get('load_start')}, at end {meta.get('load_end')} (2 cores, shared); "
        f"a wall time marked (reused) is that of the earlier run that computed the result (--reuse).",
        "",
        "## Comparisons",
        "",
        "| name | source | reference | quantity | value | reference value | error | tolerance | passed |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in records:
        verdict = "skipped" if r["passed"] is None else "yes" if r["passed"] else "NO"
        cells = [
            ("-" if r[k] is None else format(r[k], f))
            for k, f in (("value", ".6g"), ("reference_value", ".6g"), ("error", ".2e"), ("tolerance", ".3g"))
        ]
        lines.append(
            f"| {r['name']} | {r['source']} | {r['reference']} | {r['quantity']} | {' | '.join(cells)} | {verdict} |"
        )
    notes = [r for r in records if r.get("why")]
    if notes:
        lines += ["", "Why the tolerances and skips of the rows that state one:", ""]
        lines += [f"* {r['name']}: {r['why']}" for r in notes]
    lines += [
        "",
        "## Runs",
        "",
        "| problem | code | mesh | result | converged | stable | steps | Newton its | solver wall [s] | dofs |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for t in table:
        if "drape_coefficient" in t:
            res = f"DC {t['drape_coefficient']:.4f}, {t['fold_count']} folds"
            if "boundary_distance_cm" in t:
                res += f", boundary distance {t['boundary_distance_cm']:.3f} cm"
            if "moved_from_start_cm" in t:
                res += (
                    f"; moved max\\|ΔU\\| {t['moved_from_start_cm']:.3f} cm from the other code's state, "
                    f"ends {t['distance_to_own_state_cm']:.2e} cm from its own"
                )
            if "ranks" in t:
                res += f", {t['ranks']} rank(s)"
            if "sequence" in t:
                res += "; sequenced " + " -> ".join(
                    f"{q['mesh']} ({q['iterations']} its, {q['wall_time_s']:.0f} s)" for q in t["sequence"]
                )
        elif "tip_z" in t:
            res = f"tip ({t['tip_x']:.5f}, {t['tip_z']:.5f})"
            if "tip_error_vs_elastica" in t:
                res += f", err {t['tip_error_vs_elastica']:.2e}"
            if "ranks" in t:
                res += f", {t['ranks']} rank(s)"
        elif "w_over_L" in t:
            res = f"w/L {t['w_over_L']:.6f}, u/L {t['u_over_L']:.6f}"
        else:
            res = t.get("note", "")
        wt = t.get("wall_time_s")
        wts = "" if wt is None else f"{wt:.1f}"
        if wt is not None and t.get("reused"):
            wts += " (reused)"
        if wt is not None and t.get("load_average"):
            wts += " (load {:.1f}-{:.1f})".format(*t["load_average"])
        lines.append(
            f"| {t['problem']} | {t['code']} | {t['mesh']} | {res} | {t.get('converged', '')} | "
            f"{t.get('stable', '')} | {t.get('steps', '')} | {t.get('iterations', '')} | "
            f"{wts} | {t.get('n_dofs', '')} |"
        )
    (out_dir / "fenicsx_crosscheck.md").write_text("\n".join(lines) + "\n")


def _load():
    try:
        with open("/proc/loadavg") as fh:
            return fh.read().split()[0]
    except OSError:
        return "?"


def _log(msg):
    print(msg, flush=True)


def main(
    out_dir,
    problems=("strip", "shear", "pedestal", "mpi"),
    quick=False,
    log=_log,
    reuse=False,
    pedestal_meshes=PEDESTAL_MESHES,
    restart_both=RESTART_MESHES,
):
    """Run the cross-check; returns the comparison records (raises DolfinxMissing without DOLFINx).
    ``restart_both``: pedestal meshes on which each code is also started from the other's state."""
    out = Path(out_dir)
    version = check_dolfinx()
    _REUSE["on"] = bool(reuse)
    work = out / "fenicsx_work"
    meta = dict(dolfinx=version, load_start=_load(), quick=quick)
    records, table = [], []
    t0 = time.perf_counter()
    if "strip" in problems:
        r, t = strip_problem(work, [10, 20] if quick else [10, 20, 40], [20, 40] if quick else [20, 40, 80], log)
        records += r
        table += t
    if "shear" in problems:
        r, t = shear_problem(work, [16] if quick else [16, 32], [16] if quick else [16, 32], log)
        records += r
        table += t
    if "pedestal" in problems:
        r, t = pedestal_problem(
            work, ["12x4x4"] if quick else list(pedestal_meshes), log, restart_both=tuple(restart_both)
        )
        records += r
        table += t
    if "mpi" in problems:
        r, t = mpi_problem(work, log)
        records += r
        table += t
    meta.update(load_end=_load(), total_wall_time_s=time.perf_counter() - t0)
    write_report(out, records, table, meta)
    return records


def cli(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(OUT / "fenicsx"))
    ap.add_argument(
        "--problems",
        nargs="+",
        default=["strip", "shear", "pedestal", "mpi"],
        choices=["strip", "shear", "pedestal", "mpi"],
    )
    ap.add_argument("--quick", action="store_true", help="coarser meshes only (about a tenth of the time)")
    ap.add_argument(
        "--pedestal-meshes",
        nargs="+",
        default=list(PEDESTAL_MESHES),
        help="square-pedestal meshes (default %(default)s; docs/fenicsx.md has the DOLFINx run times)",
    )
    ap.add_argument(
        "--reuse", action="store_true", help="reuse converged DOLFINx results of identical jobs in OUT/fenicsx_work"
    )
    ap.add_argument(
        "--restart-both",
        nargs="*",
        default=list(RESTART_MESHES),
        metavar="MESH",
        help="start each code from the other's pedestal state (DC, folds, stability reached and "
        "max |dU|) on these meshes (default %(default)s; the option alone: none)",
    )
    a = ap.parse_args(argv)
    rb = a.restart_both
    try:
        recs = main(
            a.out, tuple(a.problems), a.quick, reuse=a.reuse, pedestal_meshes=a.pedestal_meshes, restart_both=rb
        )
    except DolfinxMissing as exc:
        print(str(exc), file=sys.stderr)
        return 3
    bad = [r["name"] for r in recs if r["passed"] is False]
    skip = [r["name"] for r in recs if r["passed"] is None]
    done = len(recs) - len(skip)
    print(
        f"{done - len(bad)}/{done} comparisons within tolerance"
        + (f", {len(skip)} skipped (reason in the report)" if skip else "")
        + f"; report in {a.out}/fenicsx_crosscheck.md"
    )
    return 0 if not bad else 1


if __name__ == "__main__":
    sys.exit(cli())
