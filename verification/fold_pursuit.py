"""The paper's fold counts pursued (issue 12 item 5): which states exist, which settings reach them,
and whether each is a stable equilibrium.

The paper reports: a 25.4 cm disc on a 12.7 cm pedestal with 4 folds, and 8 "simply by doubling the
multiplier lambda" of its iteration (§3.3, Fig. 6); a 50x50 cm sheet on a 20 cm pedestal with 12
folds statically (§3.4, Fig. 7) and 10 / 8 by dynamic relaxation with alpha = 5 / 1 per s (§4.2,
Fig. 11).  From the flat start our static solvers give other counts (Fig. 6's and Fig. 7's json).
Drape is multi-stable, so a count that differs is a finding only when both states are shown to be
stable equilibria: every static case here reports the solver's verdict on its final state, the
free-dof tangent's positive definiteness (Cholesky) and smallest eigenvalue (ARPACK), in the scene's
units (gf/cm).  The sphere's sharp folds (Fig. 12c) are pursued in verification/dynamic_sphere.py
(cases s60-*-pursuit).

Cases (one at a time: a shared 2-core machine), cached as json in verification/out/fold_pursuit/:

    python -m verification.fold_pursuit --list
    python -m verification.fold_pursuit --case sod30-newton-pert12     # one case (cached)
    python -m verification.fold_pursuit --report                       # verification/out/fold_pursuit.{md,json}

Starting states: ``[perturbation] shape = "folds"`` (solidshell.perturbation): an out-of-plane
cos(n (theta - phase)) start of the given amplitude, zero with its slope at the clamped edge; the
equilibrium reached is one of the unperturbed model.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "out"
CACHE = OUT / "fold_pursuit"


def _pert(n, amp, phase=0.0):
    return {"perturbation.shape": "folds", "perturbation.folds": n, "perturbation.amplitude": amp,
            "perturbation.phase": phase}


PAPER = {"solver.static.method": "paper"}

# name -> (scene, mesh, solver, scene overrides, solver settings, label)
CASES = {
    # square-on-disc (Fig. 7: 12 folds statically).  From the flat start newton and the paper's
    # scheme (c = 1e-2) both give 8 (verification/out/static_scenes.md); are there stable 12- and
    # 10-fold states, and does a 12-fold start reach one?
    "sod10-newton-pert12": ("square-on-disc", "10x80", "static", _pert(12, 2.0), {}, "newton, 12-fold start 2 cm"),
    "sod20-newton-pert12": ("square-on-disc", "20x160", "static", _pert(12, 2.0), {}, "newton, 12-fold start 2 cm"),
    "sod30-newton-pert12": ("square-on-disc", "30x240", "static", _pert(12, 2.0), {}, "newton, 12-fold start 2 cm"),
    "sod30-newton-pert10": ("square-on-disc", "30x240", "static", _pert(10, 2.0), {}, "newton, 10-fold start 2 cm"),
    "sod30-newton-pert12-a5": ("square-on-disc", "30x240", "static", _pert(12, 5.0), {}, "newton, 12-fold start 5 cm"),
    # circle-pedestal 20x80 (Fig. 6): the paper's scheme at both ends of Eq. (18) and doubled;
    # fig06.py runs c = 1e-3, 2e-3 and 1e-2; these add the steps between
    "circ20-paper-c1e-3": ("circle-pedestal", "20x80", "static", dict(PAPER, **{"solver.static.c": 1e-3}), {},
                           "paper scheme, c = 1e-3"),
    "circ20-paper-c2e-3": ("circle-pedestal", "20x80", "static", dict(PAPER, **{"solver.static.c": 2e-3}), {},
                           "paper scheme, c = 2e-3 (lambda doubled)"),
    "circ20-paper-c4e-3": ("circle-pedestal", "20x80", "static", dict(PAPER, **{"solver.static.c": 4e-3}), {},
                           "paper scheme, c = 4e-3"),
    "circ20-paper-c5e-3": ("circle-pedestal", "20x80", "static", dict(PAPER, **{"solver.static.c": 5e-3}), {},
                           "paper scheme, c = 5e-3"),
    "circ10-paper-c2e-3": ("circle-pedestal", "10x40", "static", dict(PAPER, **{"solver.static.c": 2e-3}), {},
                           "paper scheme, c = 2e-3 (lambda doubled)"),
}

KEYS = ("converged", "message", "drape_coefficient", "fold_count", "fold_angles_deg", "interpenetrated_nodes",
        "iterations", "positive_definite", "min_tangent_eigenvalue", "saddles_left", "saddle_eigenvalues",
        "min_z", "wall_time_s")


def _load() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "?"


def run_case(name: str) -> dict:
    from solidshell.runner import run_scene

    scene, mesh, solver, overrides, settings, label = CASES[name]
    row = dict(case=name, scene=scene, mesh=mesh, solver=solver, overrides=overrides, settings=settings, label=label,
               load_start=_load(), started=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()))
    t0 = time.perf_counter()
    try:
        o = run_scene(scene, mesh=mesh, solver=solver, out_dir=None, progress=False, overrides=overrides, **settings)
        row.update({k: o.summary.get(k) for k in KEYS})
        row["error"] = None
    except Exception as exc:  # recorded, not hidden
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["total_wall_s"] = round(time.perf_counter() - t0, 1)
    row["load_end"] = _load()
    CACHE.mkdir(parents=True, exist_ok=True)
    (CACHE / f"{name}.json").write_text(json.dumps(row, indent=1, default=str) + "\n")
    return row


def _f(v, fmt):
    return "–" if v is None else format(v, fmt)


def report() -> list:
    rows = [json.loads((CACHE / f"{n}.json").read_text()) for n in CASES if (CACHE / f"{n}.json").exists()]
    lines = ["# Fold counts pursued (issue 12 item 5)", "",
             "Generated by `python -m verification.fold_pursuit --report` from `verification/out/fold_pursuit/`. "
             "Static cases: the final free-dof tangent's positive definiteness (pos. def.: a stable equilibrium) and "
             "smallest eigenvalue [gf/cm]; folds and fold angles from the projected boundary (solidshell.analysis). "
             "Wall times on a shared 2-core machine (load = 1/5/15-min average at start -> end).", "",
             "| case | scene | mesh | settings | converged | folds | fold angles [deg] | DC | pos. def. | min eig | "
             "interp. nodes | iterations | wall [s] | load |",
             "|" + "---|" * 14]
    for r in rows:
        if r.get("error"):
            lines.append(f"| {r['case']} | {r['scene']} | {r['mesh']} | {r['label']} | ERROR: {r['error']} |"
                         + " |" * 9)
            continue
        ang = ", ".join(f"{a:.0f}" for a in (r.get("fold_angles_deg") or []))
        pd = {True: "yes", False: "NO", None: "?"}[r.get("positive_definite")]
        lines.append(f"| {r['case']} | {r['scene']} | {r['mesh']} | {r['label']} | "
                     f"{'yes' if r.get('converged') else 'NO'} | {r.get('fold_count')} | {ang} | "
                     f"{_f(r.get('drape_coefficient'), '.4f')} | {pd} | {_f(r.get('min_tangent_eigenvalue'), '.3g')} | "
                     f"{r.get('interpenetrated_nodes')} | {r.get('iterations')} | {_f(r.get('total_wall_s'), '.0f')} | "
                     f"{r['load_start']} -> {r['load_end']} |")
    missing = [n for n in CASES if not (CACHE / f"{n}.json").exists()]
    if missing:
        lines += ["", "Not run (no result in the cache): " + ", ".join(missing) + "."]
    lines += ["", "Messages:", ""] + [f"* {r['case']}: {r.get('error') or r.get('message')}" for r in rows]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "fold_pursuit.md").write_text("\n".join(lines) + "\n")
    (OUT / "fold_pursuit.json").write_text(json.dumps(dict(cases=rows, not_run=missing), indent=1, default=str) + "\n")
    print("\n".join(lines))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", action="append", default=[])
    ap.add_argument("--report", action="store_true")
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args(argv)
    if a.list:
        for n, c in CASES.items():
            print(f"{n:26s} {c[0]:16s} {c[1]:8s} {c[5]}")
    for c in a.case:
        if c not in CASES:
            sys.exit(f"unknown case {c!r}; --list shows them")
        r = run_case(c)
        print(json.dumps({k: r.get(k) for k in ("case", "error", "converged", "fold_count", "drape_coefficient",
                                                "positive_definite", "min_tangent_eigenvalue", "total_wall_s")},
                         default=str), flush=True)
    if a.report:
        report()


if __name__ == "__main__":
    main()
