"""Wall time to steady state of dynamic relaxation: mass scalings and dampers side by side.

Issue 13's targets (issue 5's in brackets): ``square-pedestal`` 48x16x4 to steady state in under
15 s (2 min) and ``sphere`` 100x100 in under 60 s (10 min); the scenes' default relaxation within 3x
of the static solver on the same mesh.  Each case runs ``run_scene(scene, mesh, solver="relax",
...)`` (no files written, the solver's default threads) with each variant:

* ``uniform``  kinetic (Cundall) damping, all masses x100 (the paper's scaling, Section 4.2);
* ``director`` kinetic damping, only the director (U_n) masses x1e4: the thickness mode stops
               limiting the step;
* ``paper``    (not run by default: tens of minutes to hours) Rayleigh alpha = 5 1/s, all masses x100;
* ``paper-dir`` (not run by default) Rayleigh alpha = 50 1/s with the director masses x100: for the
               translations the same damped path as ``paper`` (masses x s with alpha is alpha sqrt(s)
               in time stretched by sqrt(s); tests/test_explicit.py), in fewer steps;
* ``kin100``   kinetic damping, director masses x100 (past x100 the thickness mode no longer limits
               the step, and more director inertia only slows the slowest drape mode);
* ``fire100``  FIRE (damping/fire.py), director masses x100;
* ``modal100`` Rayleigh alpha = 2 omega_min re-estimated every 2000 steps (damping/modal.py), x100;
* ``default``  the scene's own [solver.relax] settings (its preset);
* ``static``   the static solver (``solver="static"``) on the same mesh: the reference time and state.

and prints, per run: steady or not, steps, step, simulated and wall time (the solver's own, after a
warm-up that compiles the kernels), element-steps per second, drape coefficient, fold count, max
interpenetrated nodes, energy balance error, and the largest node-position difference from the
first variant's steady state.  ``--passes`` (default 2) repeats the whole set so that the machine's
noise shows; the table quotes each pass and the median, and the ratio of the variants' wall times
inside each pass.  ``uptime`` is recorded before and after each run.  Last, a cProfile of
``--profile-steps`` steps of the first case and variant lists the top items by own time.

    python benchmarks/explicit_relaxation.py [--cases square-pedestal:48x16x4 sphere:100x100]
        [--variants uniform director] [--passes 2] [--max-wall 1800]

Writes benchmarks/out/explicit_relaxation.{md,json}.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
OUT = ROOT / "benchmarks" / "out"

from solidshell.run import run_scene  # noqa: E402

VARIANTS = {
    "uniform": dict(damping="kinetic", mass_scaling=100, mass_scaling_mode="uniform"),
    "director": dict(damping="kinetic", mass_scaling=1e4, mass_scaling_mode="director"),
    "paper": dict(damping="rayleigh", alpha=5.0, mass_scaling=100, mass_scaling_mode="uniform"),
    "paper-dir": dict(damping="rayleigh", alpha=50.0, mass_scaling=100, mass_scaling_mode="director"),
    "kin100": dict(damping="kinetic", mass_scaling=100, mass_scaling_mode="director"),
    "fire100": dict(damping="fire", mass_scaling=100, mass_scaling_mode="director"),
    "modal100": dict(damping="modal", mass_scaling=100, mass_scaling_mode="director"),
    "default": dict(),
    "static": dict(),
}
TARGETS = {"square-pedestal:48x16x4": 15.0, "sphere:100x100": 60.0}  # [s], issue 13


def uptime() -> str:
    try:
        out = subprocess.run(["uptime"], capture_output=True, text=True, timeout=5).stdout
        return out.split("load average:")[-1].strip()
    except (OSError, subprocess.SubprocessError):
        return " ".join(f"{x:.2f}" for x in os.getloadavg())


def run_one(case: str, variant: str, max_wall: float) -> tuple[dict, np.ndarray]:
    scene, mesh = case.split(":")
    load0 = uptime()
    t0 = time.perf_counter()
    if variant == "static":
        out = run_scene(scene, mesh=mesh, solver="static", out_dir=None, progress=False)
    else:
        out = run_scene(
            scene, mesh=mesh, solver="relax", out_dir=None, progress=False, max_wall_time=max_wall, **VARIANTS[variant]
        )
    total = time.perf_counter() - t0
    s = out.summary
    row = dict(
        case=case,
        variant=variant,
        settings=VARIANTS[variant],
        converged=s.get("converged"),
        steps=s.get("steps") or s.get("iterations"),
        dt=s.get("dt"),
        critical_dt=s.get("critical_time_step"),
        t_sim=s.get("t_final"),
        wall_s=(s.get("wall_time_s") or s.get("timings", {}).get("solve") or total),
        total_s=total,
        element_steps_per_s=s.get("element_steps_per_second"),
        drape_coefficient=s.get("drape_coefficient"),
        fold_count=s.get("fold_count"),
        max_interpenetrated_nodes=s.get("max_interpenetrated_nodes"),
        energy_balance_error=s.get("energy_balance_error"),
        message=s.get("message"),
        load_before=load0,
        load_after=uptime(),
    )
    return row, np.asarray(out.U)[:, :3]


def profile(case: str, variant: str, steps: int, top: int = 12) -> list[dict]:
    """cProfile of ``steps`` relaxation steps: the functions with the most own time."""
    scene, mesh = case.split(":")
    pr = cProfile.Profile()
    pr.enable()
    run_scene(scene, mesh=mesh, solver="relax", out_dir=None, progress=False, max_steps=steps, **VARIANTS[variant])
    pr.disable()
    st = pstats.Stats(pr, stream=io.StringIO())
    total = sum(v[2] for v in st.stats.values())
    items = sorted(st.stats.items(), key=lambda kv: -kv[1][2])[:top]
    return [
        dict(
            function=f"{Path(f).name}:{line}({name})",
            calls=v[1],
            own_s=v[2],
            cumulative_s=v[3],
            own_fraction=v[2] / total,
        )
        for (f, line, name), v in items
    ]


def _fmt(x, f="{:.4g}"):
    return "–" if x is None else (("yes" if x else "no") if isinstance(x, bool) else f.format(x))


def write_md(res: dict, path: Path) -> str:
    rows = res["rows"]
    lines = [
        "# Dynamic relaxation: wall time to steady state (issues 5 and 13)",
        "",
        "`python benchmarks/explicit_relaxation.py " + "`, then `".join(res["argv"]) + f"` (last on {res['date']}), "
        f"{res['cpu_count']} CPUs (shared; the 1/5/15-min load averages before and after each run are "
        "given).  wall = the solver's own time (after a warm-up that compiled the kernels); "
        "|Δx| = largest node-position difference from the first variant's steady state in the same pass; "
        "runs taken from the log of an interrupted invocation (`--import-log`) lack the fields it did not print (–).",
        "",
        "| case | variant | pass | steady | steps | dt [s] | t_sim [s] | wall [s] | element-steps/s | DC | folds "
        "| max interp. | energy err | abs Δx [cm] | load before → after |",
        "|" + "---|" * 15,
    ]
    for r in rows:
        lines.append(
            "| "
            + " | ".join(
                [
                    r["case"],
                    r["variant"],
                    str(r["pass_"]),
                    _fmt(r.get("converged")),
                    _fmt(r.get("steps"), "{}"),
                    _fmt(r.get("dt"), "{:.3e}"),
                    _fmt(r.get("t_sim"), "{:.3f}"),
                    _fmt(r.get("wall_s"), "{:.1f}"),
                    _fmt(r.get("element_steps_per_s"), "{:.3g}"),
                    _fmt(r.get("drape_coefficient")),
                    _fmt(r.get("fold_count"), "{}"),
                    _fmt(r.get("max_interpenetrated_nodes"), "{}"),
                    _fmt(r.get("energy_balance_error"), "{:.1e}"),
                    _fmt(r.get("max_position_difference_cm"), "{:.2e}"),
                    f"{r['load_before']} → {r['load_after']}",
                ]
            )
            + " |"
        )
    lines += [
        "",
        "Medians over the passes (target from issue 5):",
        "",
        "| case | variant | median wall [s] | target [s] | meets | wall / first variant (per pass) |",
        "|---|---|---|---|---|---|",
    ]
    for m in res["medians"]:
        lines.append(
            f"| {m['case']} | {m['variant']} | {m['median_wall_s']:.1f} | {_fmt(m['target_s'], '{:.0f}')} | "
            f"{_fmt(m['meets_target'])} | {', '.join(f'{x:.2f}' for x in m['ratios'])} |"
        )
    if res.get("profile"):
        pf = res["profile"]
        lines += [
            "",
            f"Profile (cProfile) of {pf['steps']} steps of {pf['case']} / {pf['variant']}, top items "
            "by own time (numba kernels count as their Python caller's own time):",
            "",
            "| function | calls | own [s] | own share | cumulative [s] |",
            "|---|---|---|---|---|",
        ]
        for it in pf["top"]:
            lines.append(
                f"| `{it['function']}` | {it['calls']} | {it['own_s']:.2f} | {100 * it['own_fraction']:.1f} % "
                f"| {it['cumulative_s']:.2f} |"
            )
    text = "\n".join(lines) + "\n"
    path.write_text(text)
    return text


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=list(TARGETS), help="scene:mesh ...")
    ap.add_argument("--variants", nargs="+", default=["uniform", "director"], choices=list(VARIANTS))
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--max-wall", type=float, default=1800.0, help="wall-time limit per run [s]")
    ap.add_argument(
        "--profile-steps",
        type=int,
        default=5000,
        help="profile this many steps of the first case and variant (0: no profile)",
    )
    ap.add_argument("--append", action="store_true", help="add to OUT.json's runs (passes numbered on)")
    ap.add_argument(
        "--import-log", default=None, help="also take the runs printed in this log of an earlier invocation"
    )
    ap.add_argument("--out", default=str(OUT / "explicit_relaxation"), help="writes OUT.md and OUT.json")
    a = ap.parse_args(argv)
    for c in a.cases:
        if ":" not in c:
            ap.error(f"--cases: {c!r} is not scene:mesh")
    # warm-up: compile (or load) the kernels so the first timed run does not pay for it
    for v in a.variants:
        if v == "static":
            run_scene("square-pedestal", mesh="6x2x4", solver="static", out_dir=None, progress=False)
        elif v != "modal100":
            run_scene(
                "square-pedestal",
                mesh="6x2x4",
                solver="relax",
                out_dir=None,
                progress=False,
                max_steps=50,
                **VARIANTS[v],
            )
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    res = dict(profile=None, argv=[], rows=[])
    if a.append and out.with_suffix(".json").exists():
        res = json.loads(out.with_suffix(".json").read_text())
    res["argv"] = res.get("argv", []) + [" ".join(argv if argv is not None else sys.argv[1:])]
    rows = res["rows"]
    if a.import_log:
        rows += import_log(a.import_log)
    p0 = max((r["pass_"] for r in rows), default=0)
    for p in range(p0 + 1, p0 + a.passes + 1):
        for case in a.cases:
            first = None
            for v in a.variants:
                row, x = run_one(case, v, a.max_wall)
                row["pass_"] = p
                if first is None:
                    first = x
                row["max_position_difference_cm"] = float(np.max(np.linalg.norm(x - first, axis=1)))
                rows.append(row)
                print(
                    f"pass {p} {case:<24} {v:<9} {'steady' if row['converged'] else 'NOT steady'} "
                    f"{row['steps'] or 0:>7} steps of {row['dt'] or 0:.3e} s  t_sim {row['t_sim'] or 0:.3f} s  "
                    f"wall {row['wall_s']:7.1f} s  {row['element_steps_per_s'] or 0:.3g} el-steps/s  "
                    f"DC {row['drape_coefficient']:.4f}  folds {row['fold_count']}  "
                    f"|dx| {row['max_position_difference_cm']:.2e} cm  load [{row['load_before']}] -> "
                    f"[{row['load_after']}]",
                    flush=True,
                )
                save(res, out)  # after every run: a long benchmark stopped half-way keeps what it measured
    if a.profile_steps:
        res["profile"] = dict(
            case=a.cases[0],
            variant=a.variants[0],
            steps=a.profile_steps,
            top=profile(a.cases[0], a.variants[0], a.profile_steps),
        )
    print(save(res, out))


LOG_LINE = re.compile(
    r"pass (?P<pass_>\d+) (?P<case>\S+)\s+(?P<variant>\S+)\s+(?P<steady>steady|NOT steady)\s+(?P<steps>\d+) steps of "
    r"(?P<dt>\S+) s\s+t_sim (?P<t_sim>\S+) s\s+wall\s+(?P<wall_s>\S+) s\s+(?P<eps>\S+) el-steps/s\s+DC (?P<dc>\S+)\s+"
    r"folds (?P<folds>\d+)\s+\|dx\| (?P<dx>\S+) cm\s+load \[(?P<lb>[^]]*)\] -> \[(?P<la>[^]]*)\]"
)


def import_log(path: str) -> list[dict]:
    """Rows from the printed lines of an earlier invocation (one that was stopped before it wrote
    its JSON); the fields a line does not print are left out."""
    rows = []
    for line in Path(path).read_text().splitlines():
        m = LOG_LINE.match(line.strip())
        if m:
            g = m.groupdict()
            rows.append(
                dict(
                    case=g["case"],
                    variant=g["variant"],
                    pass_=int(g["pass_"]),
                    converged=g["steady"] == "steady",
                    steps=int(g["steps"]),
                    dt=float(g["dt"]),
                    t_sim=float(g["t_sim"]),
                    wall_s=float(g["wall_s"]),
                    element_steps_per_s=float(g["eps"]),
                    drape_coefficient=float(g["dc"]),
                    fold_count=int(g["folds"]),
                    max_position_difference_cm=float(g["dx"]),
                    load_before=g["lb"],
                    load_after=g["la"],
                    from_log=str(path),
                )
            )
    return rows


def save(res: dict, out: Path) -> str:
    """Medians over the passes, then OUT.json and OUT.md; returns the markdown."""
    rows = res["rows"]
    medians = []
    for case in dict.fromkeys(r["case"] for r in rows):
        first_v = next(r["variant"] for r in rows if r["case"] == case)
        for v in dict.fromkeys(r["variant"] for r in rows if r["case"] == case):
            rs = [r for r in rows if r["case"] == case and r["variant"] == v]
            ratios = []
            for r in rs:
                ref = [
                    q["wall_s"]
                    for q in rows
                    if q["case"] == case and q["pass_"] == r["pass_"] and q["variant"] == first_v
                ]
                if ref:
                    ratios.append(r["wall_s"] / ref[0])
            med = statistics.median(r["wall_s"] for r in rs)
            tgt = TARGETS.get(case)
            medians.append(
                dict(
                    case=case,
                    variant=v,
                    runs=len(rs),
                    median_wall_s=med,
                    target_s=tgt,
                    ratios=ratios,
                    meets_target=(None if tgt is None else bool(med < tgt and all(r["converged"] for r in rs))),
                )
            )
    res.update(medians=medians, cpu_count=os.cpu_count(), date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()))
    with open(out.with_suffix(".json"), "w") as fh:
        json.dump(res, fh, indent=1, default=str)
    return write_md(res, out.with_suffix(".md"))


if __name__ == "__main__":
    main()
