"""The paper's dynamic scenes (Section 4) run by name, against the static solver where it applies.

Each case is one ``run_scene`` call; its figures are cached in ``verification/out/dynamic_scenes/
<case>.json`` so that cases can be run one at a time (they are long on a shared 2-core machine) and
the report assembled from whatever has been measured:

    python -m verification.dynamic_scenes --case sp48-kin-dir      # run one case (cached)
    python -m verification.dynamic_scenes --report                 # tables from the cache
    python -m verification.dynamic_scenes --list

The report (``verification/out/dynamic_scenes.md`` / ``.json``) says, for each case, the settings
used, whether it reached a steady state (relax) or t_end (explicit), steps, step size, simulated and
wall time, drape coefficient, fold count, max interpenetrated nodes (n_p . d_p < 0, Sec. 4.3) and the
energy balance error; cases never run are listed as such.  Wall times are from a shared machine:
the load average at the start and end of each run is recorded next to it.

Settings names used in the tables:

* ``paper``    Rayleigh mass damping alpha = 5 1/s, all masses x100 (Section 4.2);
* ``kin-uni``  kinetic (Cundall) damping, all masses x100 ("uniform" mass scaling);
* ``kin-dir``  kinetic damping, only the director (U_n) masses x1e4 ("director" mass scaling).
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

from verification import cases
from verification.cases import cell

HERE = Path(__file__).resolve().parent
OUT = HERE / "out"
CACHE = OUT / "dynamic_scenes"
RUNS = Path(os.environ.get("DYNAMIC_SCENES_RUNS", "/tmp/dynamic_scenes_runs"))


def _log_progress(every_s: float = 60.0):
    """A run_scene progress callback printing one line per ``every_s`` seconds (for a log file)."""
    last = [0.0]

    def cb(fraction, text=""):
        now = time.perf_counter()
        if now - last[0] >= every_s:
            last[0] = now
            print(f"{time.strftime('%H:%M:%S')} {100 * fraction:5.1f} % {text}", flush=True)

    return cb


# DYNAMIC_SCENES_PROGRESS=1: a progress line a minute on stdout (the runs are long)
PROGRESS = _log_progress() if os.environ.get("DYNAMIC_SCENES_PROGRESS") else False

PAPER = dict(damping="rayleigh", alpha=5.0, mass_scaling=100, mass_scaling_mode="uniform")
KIN_UNI = dict(damping="kinetic", mass_scaling=100, mass_scaling_mode="uniform")
KIN_DIR = dict(damping="kinetic", mass_scaling=1e4, mass_scaling_mode="director")
# The sphere cases below were measured on the paper's frictionless sphere; the scene now has Coulomb
# friction 0.3 (issue #5), so they say friction = 0 to stay what they were.  The frictional sphere
# study is verification/dynamic_sphere.py.
MU0 = {"contact.0.friction": 0.0}

# name -> (scene, mesh, solver, solver settings, scene overrides, description)
CASES = {
    "sp48-kin-dir": ("square-pedestal", "48x16x4", "relax", dict(KIN_DIR), {}, "kin-dir"),
    "sp48-kin-uni": ("square-pedestal", "48x16x4", "relax", dict(KIN_UNI, max_wall_time=900.0), {}, "kin-uni"),
    "sp48-paper": ("square-pedestal", "48x16x4", "relax", dict(PAPER, max_wall_time=1500.0), {}, "paper"),
    "sp24-kin-dir": ("square-pedestal", "24x8x4", "relax", dict(KIN_DIR), {}, "kin-dir"),
    "sp24-kin-uni": ("square-pedestal", "24x8x4", "relax", dict(KIN_UNI), {}, "kin-uni"),
    "sphere60-green": (
        "sphere",
        "60x60",
        "relax",
        dict(KIN_DIR, t_max=3.0, max_wall_time=480.0),
        dict(MU0),
        "kin-dir, t_max 3 s",
    ),
    "sphere60-quasi": (
        "sphere",
        "60x60",
        "relax",
        dict(KIN_DIR, t_max=3.0, max_wall_time=480.0),
        {"model.thickness_strain": "quasi", **MU0},
        "kin-dir, t_max 3 s",
    ),
    "sphere60-quasi-dir100": (
        "sphere",
        "60x60",
        "relax",
        dict(KIN_DIR, mass_scaling=100, t_max=3.0, max_wall_time=480.0),
        {"model.thickness_strain": "quasi", **MU0},
        "kinetic, director masses x100, t_max 3 s",
    ),
    "sphere60-quasi-noecheck": (
        "sphere",
        "60x60",
        "relax",
        dict(KIN_DIR, t_max=3.0, max_wall_time=480.0, max_energy_error=1e6),
        {"model.thickness_strain": "quasi", **MU0},
        "kin-dir, t_max 3 s, energy check off",
    ),
    "sphere100-green": ("sphere", "100x100", "relax", dict(KIN_DIR, max_wall_time=300.0), dict(MU0), "kin-dir"),
    "sphere30-green": ("sphere", "30x30", "relax", dict(KIN_DIR, max_wall_time=600.0), dict(MU0), "kin-dir"),
    "sphere30-quasi": (
        "sphere",
        "30x30",
        "relax",
        dict(KIN_DIR, max_wall_time=600.0),
        {"model.thickness_strain": "quasi", **MU0},
        "kin-dir",
    ),
    "hang-20": ("hang-20", "40x40", "explicit", dict(max_wall_time=600.0), {}, "paper (alpha 5, no mass scaling)"),
    "hang-20-dir": (
        "hang-20",
        "40x40",
        "explicit",
        dict(mass_scaling=10, mass_scaling_mode="director"),
        {},
        "alpha 5, director masses x10",
    ),
    "hang-100": ("hang-100", "50x50", "explicit", dict(max_wall_time=720.0), {}, "paper (alpha 5, no mass scaling)"),
    "hang-100-dir": (
        "hang-100",
        "50x50",
        "explicit",
        dict(mass_scaling=10, mass_scaling_mode="director"),
        {},
        "alpha 5, director masses x10",
    ),
    "lsp-kin-dir": ("large-square-pedestal", None, "relax", dict(KIN_DIR, max_wall_time=900.0), {}, "kin-dir"),
    "disc-a5-kin-dir": ("square-on-disc", None, "relax", dict(KIN_DIR, max_wall_time=240.0), {}, "kin-dir"),
    "disc-a5-paper": ("square-on-disc", None, "relax", dict(PAPER, max_wall_time=900.0), {}, "paper"),
    "disc-a1-paper": (
        "square-on-disc",
        None,
        "relax",
        dict(PAPER, alpha=1.0, max_wall_time=900.0),
        {},
        "alpha 1, masses x100",
    ),
    # Rayleigh damping as in the paper, but only the director masses x100 (the translational
    # masses real, so the sheet falls at g, not g/100): run by the CLI in this session, see NOTES
    "disc-a5-dir100": (
        "square-on-disc",
        None,
        "relax",
        dict(PAPER, mass_scaling_mode="director", threads=1, max_wall_time=1800.0),
        {},
        "alpha 5, director masses x100",
    ),
    "disc-a1-dir100": (
        "square-on-disc",
        None,
        "relax",
        dict(PAPER, alpha=1.0, mass_scaling_mode="director", threads=1, max_wall_time=1800.0),
        {},
        "alpha 1, director masses x100",
    ),
    # The paper's trajectory at a fraction of its steps.  All masses xs with Rayleigh alpha is, for
    # Eq. (23), exactly the unscaled system with alpha sqrt(s) run in time stretched by sqrt(s)
    # (tests/test_explicit.py::test_uniform_mass_scaling_is_a_time_stretch), so the paper's alpha = 5
    # and 1 with masses x100 follow the unscaled alpha = 50 and 10.  Scaling the director masses
    # instead (x100) keeps that translational damping but lets the thickness mode stop limiting the
    # step.  Checkpointed every 20k steps (a stopped run resumes with --set restart=...).
    "disc-a50-dir100": (
        "square-on-disc",
        None,
        "relax",
        dict(
            PAPER,
            alpha=50.0,
            mass_scaling_mode="director",
            threads=1,
            max_wall_time=3300.0,
            checkpoint=str(RUNS / "disc-a50-dir100.ckpt.npz"),
            checkpoint_every=20000,
        ),
        {},
        "alpha 50, director masses x100 (= paper alpha 5, masses x100)",
    ),
    "disc-a10-dir100": (
        "square-on-disc",
        None,
        "relax",
        dict(
            PAPER,
            alpha=10.0,
            mass_scaling_mode="director",
            threads=1,
            max_wall_time=3300.0,
            checkpoint=str(RUNS / "disc-a10-dir100.ckpt.npz"),
            checkpoint_every=20000,
        ),
        {},
        "alpha 10, director masses x100 (= paper alpha 1, masses x100)",
    ),
}

# Observations that are not in any cached case (runs stopped by hand, etc.), printed with the report.
NOTES = [
    "square-on-disc with the paper's damping path (cases disc-a50-dir100, disc-a10-dir100; 2026-11-22 "
    "06:04 UTC, both at once, 1 thread each, load 0.5-2.5).  All masses x100 with Rayleigh alpha is exactly the "
    "unscaled run with alpha x10 in time stretched by 10 (tested to 4e-12), so the paper's alpha = 5 and 1 are "
    "alpha = 50 and 10 here, with only the director masses x100 (the translational path is the paper's; the "
    "step 3.70e-5 s instead of 7.67e-5 s over a 10x shorter simulated time: ~5x fewer steps).  "
    "'alpha 5' (= 50): STEADY at t = 9.14 s (= 91 s of the paper's scaled time) after 246.8k steps, 1576 s wall, "
    "DC 0.0583 = the static Newton's 0.0583, 8 folds, 0 interpenetrated nodes, energy error 1.4e-6.  "
    "'alpha 1' (= 10): STEADY at t = 2.07 s after 56.0k steps, 377 s wall, DC 0.0653, 8 folds, 0 interpenetrated "
    "nodes, energy error 7.8e-6.  Two different 8-fold states (top.png of the runs): alpha 50 creeps into the static "
    "solution's pattern, folds centred at +-22.5 deg off the warp/weft axes; alpha 10 swings into folds on the axes "
    "and the diagonals, which stand further out (DC 12 % higher; min z -24.5 vs -25.3 cm).  The paper reports 10 folds "
    "(alpha 5) and 8 (alpha 1), 12 statically; we get 8 throughout: the fold count is the paper's for alpha 1 only.  "
    "The previous session's runs with alpha 5 and 1 on the director-scaled masses (cases disc-a5-dir100, "
    "disc-a1-dir100 below) were 10x less damped than the paper's path, which is why alpha 1 did not settle.",
    "sphere 60x60, Green strain, kin-dir, no wall/t_max cap (2026-11-22 02:22-02:41 UTC, load ~6-8): stopped by hand "
    "after 19 min wall without a steady state (at the 48x16x4 pedestal's measured 1.4e6 element-steps/s that is "
    "roughly 25 s of simulated time; the 20x20 mesh reached steady state at t = 5.1 s in 30 s wall).  The 60x60 "
    "sphere cases were then rerun for a fixed simulated window t_max = 3 s (the fall and first contact, where "
    "interpenetration happens) so that Green and Eq. (24) are compared over the same window.",
    "sphere 30x30, Green, kin-dir, t_max 60 s: the cloth SLID OFF the sphere and fell freely (min z = -1.6e6 cm "
    "at t = 60 s, final E_kin = W_ext, contact energy 0; energy balance still 4e-5).  The contact is frictionless "
    "and nothing holds the sheet's in-plane position, so a cloth draped over a sphere is an unstable equilibrium "
    "(like a rope over a frictionless cylinder): round-off asymmetry grows until it slides off.  A 20x20 probe "
    "(not cached) reached the steady-state test at t = 5.1 s before the slide grew (30 s wall, 29 max "
    "interpenetrated nodes, DC 0.200, 4 folds).  This is a property of the scene, not of the integrator: the "
    "'steady state' of the sphere scene is only the plateau before the slide.  A fix for the scene (not made "
    "here: meshing/scenes are not this script's files): hold the in-plane translations of the centre node (it "
    "sits on the sphere's top, so the symmetric drape is unchanged) or add friction.",
    "sphere 60x60 with Eq. (24) (model.thickness_strain = quasi), kin-dir: STOPPED by the solver's energy check at "
    "t = 2.287 s (energy balance error 1.61 > 0.5, 'the run is creating energy'), although the step (5.65e-5 s) "
    "is 0.9 x the critical step, which the re-check at step 40000 (t = 2.26 s) had found unchanged; the blow-up "
    "grew within 500 steps.  The Green run on the same mesh, settings and window did not do this (energy error "
    "2.2e-5 over 3 s).  Its max interpenetration count (11 nodes) is over 0-2.28 s only, the Green one (87) over "
    "0-3 s, so the two are not over the same window.  Looks wrong: either a loss of stability of the Eq. (24) "
    "thickness energy under the large director-mass scaling (x1e4), or a bug in the quasi strain's force; the "
    "sphere60-quasi-dir100 case (director masses x100) would check the first (defined, NOT run for lack of time).  A likelier cause: Eq. (24) as printed "
    "is discontinuous -- when n_p.d_p crosses -mu the nodal strain jumps from |x_n| - 1 ~ 0 to -|x_n| - 1 ~ -2, "
    "so the stored thickness energy jumps by ~2 C_z per node with no work done; the explicit solver's energy "
    "guard (max_energy_error 0.5) reads that jump as energy creation.  The sphere60-quasi-noecheck case reruns it "
    "with the guard off (max_energy_error 1e6) to tell the two apart.  Result: with the guard off the Eq. (24) run "
    "stays finite and bounded to t = 3 s (min z -18.6 cm, like Green's), max 12 interpenetrated nodes over 0-3 s "
    "(Green: 87 over the same window), but the energy books do not balance (error 43): the kinetic damping removed "
    "5750 gf cm of kinetic energy against 133 of external work, and the final strain energy is 111 gf cm -- energy "
    "injected by the strain jumps of flipped nodes.  So the stop is Eq. (24)'s discontinuity, not an unstable step; "
    "with Eq. (24) the energy balance is not a usable health check, and relaxation (kinetic damping) absorbs it.",
    "hang-20 snapshots (png/hang-20_iso_t*.png), looked at: t = 0 flat; t = 0.1 s the free part has dropped ~4 "
    "cm while the edge between the two fixed corners stays straight at z = 0 (the corners keep their 20 cm "
    "spacing, so that edge can only sag by stretching); t = 0.4 s the sheet swings through, rotated about the "
    "held edge; t = 2.1 s it hangs vertically, almost at rest (E_kin 9e-4 vs W_ext 76.5 gf cm), 20 cm below the "
    "held edge, with no visible wrinkles -- consistent with the paper's description of Fig. 9 (settled by ~2 s; "
    "the smaller sheet has fewer wrinkles than the 100 cm one).",
    "hang-100 snapshots (director masses x10; png/hang-100-dir_iso_t*.png), looked at: at t = 0.4 s the 100 cm "
    "sheet is still falling (free edge ~45 cm down) while the 20 cm one had already swung through at 0.4 s -- "
    "the larger sheet drapes slower, as the paper says; by t = 1.4 s it hangs vertically and t = 3.0 s looks "
    "the same (settled).  The held edge sags slightly between the corners.  The paper's 'more wrinkles' on the "
    "larger sheet are not clearly visible in these renders (a smooth vertical sheet); not checked further.",
    "hang-100 plain (no mass scaling) vs director masses x10, final state at t = 3.0 s: largest node-position "
    "difference 0.064 cm for a largest displacement of 142.6 cm (0.05 %); wall 487 s vs 177 s.  hang-20 and "
    "hang-100 both ran without mass scaling (the paper's settings), so director scaling was not needed.",
    "Not run for lack of time (03:45 UTC deadline, shared 2-core machine at load 4-8): square-pedestal 48x16x4 with "
    "the paper's relaxation (alpha 5, masses x100): the 24x8x4 mesh needed 402k steps (31 s simulated) and the "
    "48x16x4 step is the same (7.67e-5 s, limited by the thickness mode), so ~400k+ steps x 3072 quads ~ 15+ min; "
    "square-on-disc with alpha 5 and 1 (paper settings): not attempted beyond the capped kin-dir probe below.",
    "sphere 100x100 (Green, kin-dir, capped at 300 s wall): reached t = 1.30 s (38.5k steps of 3.39e-5 s) at "
    "1.34e6 element-steps/s on the solver's default 2 threads (10000 quads >= SMALL_MESH_ELEMENTS; the benchmark "
    "measured 1 thread faster on this loaded machine).  0 interpenetrated nodes up to 1.3 s.  Extrapolated: ~3 s "
    "of simulated time (the 60x60 comparison window) needs ~11-12 min wall; a steady state is not reachable in "
    "the sphere scene as it stands (the cloth slides off the frictionless sphere; see above), so '100x100 "
    "completes in under 10 minutes' is NOT met / not meaningful here.",
    "square-on-disc 30x240 (kin-dir, capped at 240 s wall): not steady at the cap (t = 2.07 s, 55.9k steps), but "
    "already at DC 0.0582 with 8 folds, vs the static Newton solution's 0.0583 and 8 folds (static_scenes.json; "
    "the paper's 10 folds with alpha = 5 and 8 with alpha = 1 are for its Rayleigh-damped relaxation, which was "
    "not run: with masses x100 the step is the thickness-mode one, ~7.7e-5 s, and the pedestal 24x8x4 needed 31 s "
    "of simulated time, i.e. ~400k steps x 7200 quads ~ 30 min or more here).",
    "square-on-disc 30x240 with the paper's relaxation (Rayleigh alpha 5, ALL masses x100), by `solidshell run square-on-disc "
    "--solver relax --set solver.relax.max_wall_time=2700` (2026-11-22 04:22-05:07 UTC, load 3-5): NOT steady at the 2700 s "
    "cap: t = 14.3 s after 187k steps of 7.67e-5 s, DC still 0.239 (the static equilibrium is 0.058), 8 folds, energy "
    "error 1.3e-7.  With masses x100 and the weight unchanged the sheet falls at g/100 and its overdamped terminal "
    "speed is g / (100 alpha) ~ 2 cm/s: tens of seconds of simulated time, hours of wall time here.",
    "square-on-disc 30x240, Rayleigh damping as the paper but only the DIRECTOR masses x100 (cases disc-a5-dir100 / "
    "disc-a1-dir100, run by the CLI: `solidshell run square-on-disc --solver relax --set solver.relax.alpha=5.0 --set "
    "solver.relax.mass_scaling_mode=director --set solver.relax.threads=1 --set solver.relax.max_wall_time=1800`, "
    "2026-11-22 05:08-05:38 UTC, both at once, load 2-5, 1 thread each, 0.66-0.75 M element-steps/s): alpha 5: STEADY "
    "at t = 4.40 s after 118.9k steps of 3.70e-5 s (critical 4.12e-5), 1309 s wall, DC 0.0527, 8 folds, energy "
    "error 3.0e-5, interpenetrated nodes max 96 (48 at the end); alpha 1: NOT steady at the 1800 s cap (t = 6.89 s, "
    "186k steps, residual 19.7), DC 0.0485, 8 folds, energy error 3.0e-3, interpenetrated nodes max 408.  The paper "
    "reports 10 folds (alpha 5) and 8 (alpha 1); we get 8 in both, like the static solution (8).  The low DC (the "
    "static solution's is 0.058) is the scene's: it has no pedestal body, so the deep folds hang inside the "
    "pedestal's footprint (see top.png of these runs); with a disc pedestal body the static Newton gives DC 0.105, "
    "8 folds (static_scenes, 'newton + pedestal contact body').",
    "large-square-pedestal 45x15x4, kin-dir (case lsp-kin-dir, run by the CLI: `solidshell run large-square-pedestal "
    "--solver relax --set solver.relax.damping=kinetic --set solver.relax.mass_scaling=1e4 --set "
    "solver.relax.mass_scaling_mode=director`, 2026-11-22 05:56 UTC, load 0.5-1.3): STEADY at t = 1.54 s after 25.2k "
    "steps of 6.13e-5 s (critical 6.81e-5), 66 s wall, 1.04 M element-steps/s, DC 0.1547 vs the static Newton's 0.1546 "
    "(+0.01 %), 4 folds (static: 4), energy error 6.0e-6, max 12 interpenetrated nodes.",
]

SUMMARY_KEYS = (
    "converged",
    "message",
    "steps",
    "dt",
    "critical_time_step",
    "t_final",
    "wall_time_s",
    "energy_balance_error",
    "drape_coefficient",
    "fold_count",
    "max_interpenetrated_nodes",
    "max_active_nodes",
    "max_penetration",
    "resets",
    "mass_scaling",
    "mass_scaling_mode",
    "element_steps_per_second",
    "threads",
    "frames",
    "min_z",
    "max_displacement",
    "files",
    "series_parameter",
    "final_relative_residual",
    "final_kinetic_energy",
    "critical_time_step_min",
    "time_step_reductions",
    "time_step_rechecks",
    "kinetic_resets",
    "status",
    "steady_state_reached",
    "max_contact_penetration",
    "max_contact_nodes",
    "damping",
    "alpha",
    "external_work",
    "damping_dissipation",
    "kinetic_energy",
    "strain_energy",
)


def run_case(name: str) -> dict:
    from solidshell.run import run_scene

    scene, mesh, solver, settings, overrides, label = CASES[name]
    out_dir = RUNS / name
    row = dict(
        case=name,
        scene=scene,
        mesh=mesh or "(scene default)",
        solver=solver,
        settings_label=label,
        settings={k: v for k, v in settings.items()},
        overrides=overrides,
        run_dir=str(out_dir),
    )
    s = (
        cases.run_recorded(
            lambda: run_scene(
                scene,
                mesh=mesh,
                solver=solver,
                out_dir=out_dir,
                progress=PROGRESS,
                overrides=overrides or None,
                **settings,
            ),
            row,
        )
        or {}
    )
    for k in SUMMARY_KEYS:
        if k in s:
            row[k] = s[k]
    row["mesh"] = s.get("mesh", row["mesh"])
    row["n_nodes"] = (s.get("counts") or {}).get("nodes")
    row["n_elements"] = (s.get("counts") or {}).get("elements")
    cases.store(CACHE, name, row)
    print(json.dumps({k: v for k, v in row.items() if k != "files"}, default=str), flush=True)
    return row


def _static_reference() -> dict:
    """(scene, mesh) -> (DC, folds) from the static scenes' report (newton), if present."""
    ref = {}
    p = OUT / "static_scenes.json"
    if p.exists():
        try:
            for r in json.load(open(p)):
                if r.get("converged") and r.get("solver") == "newton":
                    ref[(r["scene"], r["mesh"])] = (
                        r.get("drape_coefficient"),
                        r.get("fold_count"),
                        r.get("wall_time_s"),
                    )
        except (OSError, ValueError, KeyError, TypeError):
            pass
    return ref


def report() -> list:
    rows, missing = cases.cached(CACHE, CASES)
    ref = _static_reference()
    lines = [
        "# Dynamic scenes (Section 4)",
        "",
        "Generated by `python -m verification.dynamic_scenes --report` from the per-case cache "
        "`verification/out/dynamic_scenes/`.  Wall times are on a shared 2-core machine; the "
        "1/5/15-min load averages at start and end of each run are given.  Settings: `paper` = "
        "Rayleigh alpha 5 1/s, all masses x100; `kin-uni` = kinetic damping, all masses x100; "
        "`kin-dir` = kinetic damping, director masses x1e4.",
        "",
    ]
    lines += [
        "| case | scene | mesh | settings | steady / done | steps | dt [s] | t_sim [s] | wall [s] | DC | "
        "static DC | DC diff | folds (static) | max interp. nodes | energy err | load start → end | note |",
        "|" + "---|" * 17,
    ]
    for r in rows:
        st = ref.get((r["scene"], r["mesh"]))
        dc = r.get("drape_coefficient")
        diff = f"{100 * (dc - st[0]) / st[0]:+.2f} %" if (st and isinstance(dc, (int, float)) and st[0]) else "–"
        r["static_drape_coefficient"] = st[0] if st else None
        r["static_fold_count"] = st[1] if st else None
        folds = cell(r.get("fold_count")) + (f" ({st[1]})" if st else "")
        note = r.get("error") or ("" if r.get("converged") else (r.get("message") or ""))
        lines.append(
            "| "
            + " | ".join(
                [
                    r["case"],
                    r["scene"],
                    str(r["mesh"]),
                    r["settings_label"],
                    cell(r.get("converged"), no="no"),
                    cell(r.get("steps")),
                    cell(r.get("dt"), ".3e"),
                    cell(r.get("t_final"), ".3f"),
                    cell(r.get("wall_time_s", r.get("total_wall_s")), ".1f"),
                    cell(dc, ".4g"),
                    cell(st[0] if st else None, ".4g"),
                    diff,
                    folds,
                    cell(r.get("max_interpenetrated_nodes")),
                    cell(r.get("energy_balance_error"), ".2e"),
                    f"{r['load_start'].split()[0]} → {r['load_end'].split()[0]}",
                    str(note).replace("|", "/")[:160],
                ]
            )
            + " |"
        )
    if NOTES:
        lines += ["", "Notes:", ""] + [f"* {n}" for n in NOTES]
    if missing:
        lines += ["", "Not run (no result in the cache): " + ", ".join(missing) + "."]
    lines.append("")
    text = "\n".join(lines)
    cases.write_report(OUT, "dynamic_scenes", text, rows, echo=text)
    return rows


def main(argv=None):
    cases.main(argv, __doc__, CASES, run_case, report, lambda n, c: f"{n} {c[0]} {c[1]} {c[2]} {c[5]}")


if __name__ == "__main__":
    main()
