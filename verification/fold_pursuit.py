"""The paper's fold counts pursued (issue 12 item 5): which states exist, which settings reach them,
and whether each is a stable equilibrium.

The paper reports: a 25.4 cm disc on a 12.7 cm pedestal with 4 folds, and 8 "simply by doubling the
multiplier lambda" of its iteration (§3.3, Fig. 6); a 50x50 cm sheet on a 20 cm pedestal with 12
folds statically (§3.4, Fig. 7) and 10 / 8 by dynamic relaxation with alpha = 5 / 1 per s (§4.2,
Fig. 11).  From the flat start our static solvers give other counts (Fig. 6's and Fig. 7's json).
Drape is multi-stable, so a count that differs is a finding only when both states are shown to be
stable equilibria: every static case here reports the solver's verdict on its final state, the
free-dof tangent's positive definiteness (Cholesky) and smallest eigenvalue (ARPACK), in the scene's
units (gf/cm).  The circle's lambda switch (20x80, the paper's scheme at c = 1e-3, 2e-3, 1e-2) is
run by paper_figures/fig06.py (its json has the same verdicts); the sphere's sharp folds (Fig. 12c)
are pursued in verification/dynamic_sphere.py (cases s60-pursuit-*).

Cases (one at a time: a shared 2-core machine), cached as json in verification/out/fold_pursuit/:

    python -m verification.fold_pursuit --list
    python -m verification.fold_pursuit --case sod30-newton-pert12     # one case (cached)
    python -m verification.fold_pursuit --report                       # verification/out/fold_pursuit.{md,json}

Starting states: ``[perturbation] shape = "folds"`` (solidshell.perturbation): an out-of-plane
cos(n (theta - phase)) start of the given amplitude, zero with its slope at the clamped edge; the
equilibrium reached is one of the unperturbed model.
"""

from __future__ import annotations

from pathlib import Path

from verification import cases
from verification.cases import cell

HERE = Path(__file__).resolve().parent
OUT = HERE / "out"
CACHE = OUT / "fold_pursuit"


def _pert(n, amp, phase=0.0):
    return {
        "perturbation.shape": "folds",
        "perturbation.folds": n,
        "perturbation.amplitude": amp,
        "perturbation.phase": phase,
    }


# name -> (scene, mesh, solver, scene overrides, solver settings, label)
CASES = {
    # square-on-disc (Fig. 7: 12 folds statically).  From the flat start newton and the paper's
    # scheme (c = 1e-2) both give 8 (verification/out/static_scenes.md); are there stable 12- and
    # 10-fold states, and does a 12-fold start reach one?
    "sod10-newton-pert12": ("square-on-disc", "10x80", "static", _pert(12, 2.0), {}, "newton, 12-fold start 2 cm"),
    "sod20-newton-pert12": ("square-on-disc", "20x160", "static", _pert(12, 2.0), {}, "newton, 12-fold start 2 cm"),
    "sod30-newton-pert12": ("square-on-disc", "30x240", "static", _pert(12, 2.0), {}, "newton, 12-fold start 2 cm"),
    "sod30-newton-pert10": ("square-on-disc", "30x240", "static", _pert(10, 2.0), {}, "newton, 10-fold start 2 cm"),
    # square-on-disc by dynamic relaxation (Fig. 11a: the paper's 10 folds at alpha = 5 1/s, all masses
    # x100 = alpha 50 with director masses x100, fig11.py): from the flat sheet this path ends on 8
    # folds; does it keep a 10-fold start, i.e. is the static 10-fold equilibrium (sod30-newton-pert10)
    # also a steady state of the paper's damping path?
    "sod30-relax-a50-pert10": (
        "square-on-disc",
        "30x240",
        "relax",
        _pert(10, 2.0),
        dict(damping="rayleigh", alpha=50.0, mass_scaling=100.0, mass_scaling_mode="director", max_wall_time=2700.0),
        "relax, Rayleigh alpha 50 director x100 (Fig. 11a's path), 10-fold start 2 cm",
    ),
    # circle-pedestal 10x40 with lambda doubled (the 20x80 runs are fig06.py's)
    "circ10-paper-c2e-3": (
        "circle-pedestal",
        "10x40",
        "static",
        {"solver.static.method": "paper", "solver.static.c": 2e-3},
        {},
        "paper scheme, c = 2e-3 (lambda doubled)",
    ),
}

KEYS = (
    "converged",
    "message",
    "drape_coefficient",
    "fold_count",
    "fold_angles_deg",
    "interpenetrated_nodes",
    "iterations",
    "positive_definite",
    "min_tangent_eigenvalue",
    "saddles_left",
    "saddle_eigenvalues",
    "min_z",
    "wall_time_s",
    "self_intersections",
    "penetration",
)


def run_case(name: str) -> dict:
    from solidshell.run import run_scene

    scene, mesh, solver, overrides, settings, label = CASES[name]
    row = dict(case=name, scene=scene, mesh=mesh, solver=solver, overrides=overrides, settings=settings, label=label)
    return cases.run_and_store(
        CACHE,
        name,
        row,
        lambda: run_scene(
            scene, mesh=mesh, solver=solver, out_dir=None, progress=False, overrides=overrides, **settings
        ),
        KEYS,
    )


def _beyond(pen) -> str:
    """The contact contract's cell: face points (and nodes) deeper than the tolerance in all bodies,
    and the deepest face point in % of h ('–' for rows run before the summary had the entry)."""
    if not pen or not pen.get("bodies"):
        return "–"
    b = pen["bodies"]
    n = sum(int(x.get("nodes_beyond", 0)) for x in b)
    f = sum(int(x.get("face_points_beyond", 0)) for x in b)
    deep = max(float(x.get("deepest_face_point_cm", 0.0)) for x in b) / float(pen["thickness_cm"])
    return f"{f}{f' (+{n} nodes)' if n else ''} ({100 * deep:.2f} % h)"


def report() -> list:
    rows, missing = cases.cached(CACHE, CASES)
    lines = [
        "# Fold counts pursued (issue 12 item 5)",
        "",
        "Generated by `python -m verification.fold_pursuit --report` from `verification/out/fold_pursuit/`. "
        "Static cases: the final free-dof tangent's positive definiteness (pos. def.: a stable equilibrium) and "
        "smallest eigenvalue [gf/cm]; folds and fold angles from the projected boundary (solidshell.analysis). "
        "Crossing pairs: triangle pairs of the sheet that intersect (solidshell.layers); face points beyond: "
        "points of the 5x5 lattice per element deeper than 2 % of h inside a body (the summary's penetration "
        "entry, verification/penetration_check.py's contract). "
        "Wall times on a shared 2-core machine (load = 1/5/15-min average at start -> end).",
        "",
        "| case | scene | mesh | settings | converged | folds | fold angles [deg] | DC | pos. def. | min eig | "
        "interp. nodes | crossing pairs | face points beyond (deepest) | iterations | wall [s] | load |",
        "|" + "---|" * 16,
    ]
    for r in rows:
        if r.get("error"):
            lines.append(
                f"| {r['case']} | {r['scene']} | {r['mesh']} | {r['label']} | ERROR: {r['error']} |" + " |" * 11
            )
            continue
        ang = ", ".join(f"{a:.0f}" for a in (r.get("fold_angles_deg") or []))
        pd = {True: "yes", False: "NO", None: "?"}[r.get("positive_definite")]
        lines.append(
            f"| {r['case']} | {r['scene']} | {r['mesh']} | {r['label']} | "
            f"{'yes' if r.get('converged') else 'NO'} | {r.get('fold_count')} | {ang} | "
            f"{cell(r.get('drape_coefficient'), '.4f')} | {pd} | {cell(r.get('min_tangent_eigenvalue'), '.3g')} | "
            f"{r.get('interpenetrated_nodes')} | {cell(r.get('self_intersections'))} | {_beyond(r.get('penetration'))} | "
            f"{r.get('iterations')} | {cell(r.get('total_wall_s'), '.0f')} | "
            f"{r['load_start']} -> {r['load_end']} |"
        )
    if missing:
        lines += ["", "Not run (no result in the cache): " + ", ".join(missing) + "."]
    lines += ["", "Messages:", ""] + [f"* {r['case']}: {r.get('error') or r.get('message')}" for r in rows]
    text = "\n".join(lines) + "\n"
    cases.write_report(OUT, "fold_pursuit", text, dict(cases=rows, not_run=missing), echo=text[:-1])
    return rows


def main(argv=None):
    cases.main(
        argv,
        __doc__,
        CASES,
        run_case,
        report,
        lambda n, c: f"{n:26s} {c[0]:16s} {c[1]:8s} {c[5]}",
        echo_keys=(
            "case",
            "error",
            "converged",
            "fold_count",
            "drape_coefficient",
            "positive_definite",
            "min_tangent_eigenvalue",
            "total_wall_s",
        ),
    )


if __name__ == "__main__":
    main()
