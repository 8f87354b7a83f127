"""Nightly check of the paper's figures (issue 34): ``solidshell figures --quick`` into a folder,
every figure's PNG and JSON present, and each figure's numbers compared with the stored ones in
``reference/figures_quick.json``, so that a figure can neither go missing nor change state silently.

    NUMBA_NUM_THREADS=1 python -m verification.figures_quick              # ~5 min on one thread
    python -m verification.figures_quick --keep figures-quick             # keep the PNGs/JSONs there
    python -m verification.figures_quick --from figures-quick             # check a folder already made
    python -m verification.figures_quick 5 6 19                           # some figures only
    NUMBA_NUM_THREADS=1 python -m verification.figures_quick --regenerate # store today's numbers

Exit status 0: every figure made and equal to the stored values within the tolerances; 1: a PNG or
JSON missing, ``solidshell figures`` failed, a run stopped on its wall-time cap (its state depends
on the machine's load, so it cannot be compared), or a number differs; 2: bad input.  Prints one
row per compared number (stored, now, tolerance) and the differences at the end.

What is compared (:data:`TOLERANCES`, also written into the reference file with the reasons): per
run of each figure, the numbers that say which state it is in -- fold count, interpenetrated and
active node counts, remesh count, converged, the final tangent's verdict, the nodes of the adaptive
frames drawn, Fig. 12's interpenetrated node ids -- exactly; the continuous numbers (drape
coefficient, tip position, smallest tangent eigenvalue, end time, frame times) to a tolerance that
covers round-off between thread counts but not a change of state.  Iteration and step counts are
printed, never a failure: they are the solver's path, not the state.  1 and 2 numba threads give
every number bit for bit (the file's ``threads_check``).

Figs. 19-22 stop at t = 15 s, before the steady state: their state is a point on a trajectory, and
a change of the path moves it.  Between 7d59487 and 8f55fba (kernels without value-changing
fast-math, ARPACK's start vector fixed, the static package's split) the static states' DCs moved
by at most 8e-12 relative, Figs. 11-13's not at all, Figs. 19-21's by at most 9e-10, and Fig. 22's,
caught between an 8- and a 4-fold pattern at t = 15 s, by 1.8e-2 (0.2662 -> 0.2710, 1538 -> 1552
nodes, same 4 folds; its step's estimate moved by 7e-4).  A failure there with the same fold count
is a changed path: look at the PNG, then ``--regenerate`` and say so in the commit.

Why here and not in benchmarks/: this checks results, not speed (the per-figure wall times are
printed and stored for information only).  The stored numbers are this code's own, a regression
baseline, not an independent reference; ``--regenerate`` after an intended change, with the commit
message saying what changed.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from solidshell.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "reference" / "figures_quick.json"
COMMAND = "NUMBA_NUM_THREADS=1 python -m verification.figures_quick --regenerate"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

# quantity -> how it is compared; "exact" or (rel, abs): |now - stored| <= abs + rel |stored|
TOLERANCES = {
    # which run it is: the scripts' own labels
    "scene": ("exact", "the run's identity"),
    "mesh": ("exact", "the run's identity (the adaptive runs name their level-0 mesh and levels)"),
    "solver": ("exact", "the run's identity"),
    "start": ("exact", "the run's identity (Fig. 7)"),
    "panel": ("exact", "the run's identity (Fig. 6)"),
    "c": ("exact", "the run's identity (Fig. 6, the paper's Eq. 18 constant)"),
    "paper_alpha": ("exact", "the run's identity (Fig. 11)"),
    # which state it reached: counts, exact
    "converged": ("exact", "steady/converged or not is a state: a relaxation that no longer settles is a change"),
    "fold_count": ("exact", "the state (a multi-stable drape's states differ in their folds)"),
    "interpenetrated_nodes": ("exact", "a count of the final state (n_p . d_p < 0, §4.3)"),
    "max_interpenetrated_nodes": ("exact", "a count over the run"),
    "max_active_nodes": ("exact", "the adaptive mesh's largest size: which elements were split"),
    "remesh_count": ("exact", "the adaptive path's passes that changed the mesh"),
    "frame_nodes": ("exact", "the node counts of the adaptive frames drawn (the figure's titles)"),
    "positive_definite": ("exact", "the final tangent's verdict: a stable equilibrium or not"),
    "interpenetrated_node_ids": ("exact", "Fig. 12: which nodes are interpenetrated (the zoom is centred on them)"),
    # the solver's path, not the state: printed (marked when changed), never a failure
    "iterations": (
        "info",
        "the static solver's path: the same bit for bit on 1 and 2 threads (threads_check), but "
        "between 7d59487 and 8f55fba Fig. 7's flat start went from 215 to 205 Newton iterations "
        "to the same state (DC equal to 1e-6): a path, not a state",
    ),
    "steps": (
        "info",
        "the explicit/relaxation step count: bit for bit on 1 and 2 threads (threads_check); it moves "
        "with the step's estimate without the state moving (t_final, frame_times and the state's "
        "numbers say when it matters)",
    ),
    # continuous
    "drape_coefficient": (
        (1e-6, 1e-9),
        (
            "1 and 2 threads give it bit for bit (threads_check); round-off-level code changes moved the "
            "static states by <= 8e-12 and Figs. 19-21 by <= 9e-10 (7d59487 -> 8f55fba), so 1e-6 relative "
            "covers round-off, while the quick set's states differ by >= 0.05 in DC (Fig. 6, 10x40: 4 folds "
            "0.485, 8 folds 0.645): it flags any change of state and any change of the model above 1 ppm "
            "(Fig. 22, unsteady at t = 15 s, moved 1.8e-2 on that path change: see the module's docstring)"
        ),
    ),
    "tip_position": ((1e-6, 1e-9), "[cm] Fig. 4 strips: as the DC (a 10x1 vs 20x1 mesh moves the tip by 3e-2 cm)"),
    "tip_z_error_vs_elastica": ((1e-5, 1e-9), "[cm] a difference of two numbers of ~4 cm each: 1e-6 of those"),
    "min_tangent_eigenvalue": (
        (1e-4, 1e-12),
        (
            "[gf/cm] an iterative eigensolver's value (ARPACK; a random start vector per process before a177596): "
            "1.4e-15 relative between two runs (threads_check), ~6e-12 for the same state reached on another "
            "path (Fig. 6 (a) and (c)), 1.4e-7 after round-off-level code changes (Fig. 7, 7d59487 -> 8f55fba); states "
            "differ by factors (10x40: 4 folds 6.0e-3, 8 folds 1.4e-3)"
        ),
    ),
    "t_final": (
        (1e-3, 1e-12),
        "[s] the end: a steady state is tested every 100 steps (0.3 % of t on Fig. 11 (a)), "
        "so 1e-3 flags settling at another test; a run to t_max ends within one step (<1e-4 s) "
        "past it whatever the step's estimate",
    ),
    "frame_times": (
        (1e-3, 1e-12),
        "[s] the kept frames' times (every 0.05 s of simulated time, the nearest to the figure's instants): as t_final",
    ),
    "zoom_cm": ((1e-6, 1e-6), "[cm] Fig. 12's zoom window, from the interpenetrated nodes' positions"),
    "times": ("exact", "Figs. 9-10: the scene's snapshot times (input)"),
}
RUN_KEYS = (
    "scene",
    "mesh",
    "solver",
    "start",
    "panel",
    "c",
    "paper_alpha",
    "converged",
    "fold_count",
    "drape_coefficient",
    "interpenetrated_nodes",
    "max_interpenetrated_nodes",
    "max_active_nodes",
    "remesh_count",
    "frame_nodes",
    "positive_definite",
    "min_tangent_eigenvalue",
    "iterations",
    "steps",
    "t_final",
    "frame_times",
    "tip_position",
    "tip_z_error_vs_elastica",
)
FIGURE_KEYS = ("times", "frame_times", "zoom_cm", "interpenetrated_node_ids")
WALL_CAP = "wall-time limit"


def tolerance_table() -> dict:
    """TOLERANCES as the reference file stores them: quantity -> {compare, why}."""
    return {
        k: {"compare": v[0] if v[0] == "exact" else {"rel": v[0][0], "abs": v[0][1]}, "why": v[1]}
        for k, v in TOLERANCES.items()
    }


def figure_names(figs) -> list[str]:
    """'5', 'fig05', ... -> ['fig05', ...] (all when empty); InputError on an unknown name."""
    from paper_figures.registry import FIGURES, module_name

    return list(dict.fromkeys(module_name(f) for f in (figs or FIGURES)))


def key_numbers(info: dict) -> dict:
    """The numbers of one figure's JSON that say which state it shows (the stored subset)."""
    out = {k: info[k] for k in FIGURE_KEYS if k in info}
    out["runs"] = [{k: r[k] for k in RUN_KEYS if k in r} for r in info.get("runs", [])]
    return out


def check_files(folder: Path, name: str) -> tuple[dict | None, list[str]]:
    """(the figure's JSON or None, problems) for figNN.png and figNN.json in folder."""
    problems, info = [], None
    png, js = folder / f"{name}.png", folder / f"{name}.json"
    if not png.is_file():
        problems.append(f"{name}: {png.name} missing")
    elif png.read_bytes()[:8] != PNG_MAGIC or png.stat().st_size < 10_000:
        problems.append(f"{name}: {png.name} is not a rendered PNG ({png.stat().st_size} bytes)")
    if not js.is_file():
        problems.append(f"{name}: {js.name} missing")
        return None, problems
    try:
        info = json.loads(js.read_text())
    except ValueError as e:
        return None, problems + [f"{name}: {js.name} is not JSON ({e})"]
    if info.get("figure") != name or info.get("quick") is not True:
        problems.append(
            f"{name}: {js.name} is figure {info.get('figure')!r}, quick={info.get('quick')!r} "
            f"(expected {name!r}, quick=True)"
        )
    if not info.get("runs"):
        problems.append(f"{name}: {js.name} records no runs")
    for i, r in enumerate(info.get("runs", [])):
        if WALL_CAP in str(r.get("message", "")):
            problems.append(
                f"{name} run {i}: stopped by its wall-time cap ({r['message']}): the state reached "
                "depends on the machine's load and cannot be compared"
            )
    return info, problems


def _close(key, old, new) -> tuple[bool, str]:
    """(equal within key's tolerance, the tolerance as text); "info" quantities always pass."""
    tol = TOLERANCES[key][0]
    if tol == "info":
        return True, "info" if old == new else "info: changed"
    if tol == "exact":
        return old == new, "exact"
    rel, ab = tol
    olds, news = (old, new) if isinstance(old, list) else ([old], [new])
    if not isinstance(news, list) or len(olds) != len(news):
        return False, f"rel {rel:g}"
    ok = all(
        isinstance(a, (int, float))
        and isinstance(b, (int, float))
        and not isinstance(b, bool)
        and math.isfinite(b)
        and abs(b - a) <= ab + rel * abs(a)
        for a, b in zip(olds, news)
    )
    return ok, f"rel {rel:g}"


def _fmt(v, digits: int = 10) -> str:
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    if isinstance(v, list):
        s = "[" + ", ".join(_fmt(x, 5) for x in v[:4]) + (", ..." if len(v) > 4 else "") + "]"
        return s if len(v) <= 4 else f"{s} ({len(v)})"
    return str(v)


def compare(stored: dict, now: dict, name: str) -> tuple[list[tuple], list[str]]:
    """Rows (figure, where, quantity, stored, now, tolerance, ok) and the differences found, for one
    figure's stored key numbers against its current ones (both from :func:`key_numbers`)."""
    rows, diffs = [], []

    def one(where, key, a, b):
        if key not in TOLERANCES:
            return
        if b is None:
            ok, tol = False, "missing now"
        elif a is None:
            ok, tol = False, "not stored"
        else:
            ok, tol = _close(key, a, b)
        rows.append((name, where, key, a, b, tol, ok))
        if not ok:
            diffs.append(f"{name} {where} {key}: stored {_fmt(a)}, now {_fmt(b)} ({tol})")

    for key in sorted(set(stored) | set(now)):
        if key != "runs":
            one("figure", key, stored.get(key), now.get(key))
    sr, nr = stored.get("runs", []), now.get("runs", [])
    if len(sr) != len(nr):
        diffs.append(f"{name}: {len(nr)} runs now, {len(sr)} stored")
    for i, (a, b) in enumerate(zip(sr, nr)):
        for key in [k for k in RUN_KEYS if k in a or k in b]:
            one(f"run {i}", key, a.get(key), b.get(key))
    return rows, diffs


def run_figures(names: list[str], folder: Path, log=print) -> tuple[int, float]:
    """``solidshell figures NAMES --quick --out folder`` as a user runs it; (exit status, wall [s])."""
    cmd = [sys.executable, "-m", "solidshell", "figures", *names, "--quick", "--out", str(folder)]
    log("$ " + " ".join(cmd[2:]) + f"   (NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')})")
    t = time.perf_counter()
    r = subprocess.run(cmd, cwd=ROOT, text=True, capture_output=True, check=False)
    for line in r.stdout.splitlines():
        log("  " + line)
    if r.returncode:
        log(r.stderr[-2000:])
    return r.returncode, time.perf_counter() - t


def _git_commit() -> str:
    try:
        r = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True, capture_output=True, check=False
        )
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=ROOT,
            text=True,
            capture_output=True,
            check=False,
        ).stdout.strip()
        return r.stdout.strip() + (" (with uncommitted changes)" if dirty else "")
    except OSError:
        return "unknown"


def regenerate(folder: Path, names: list[str], reference: Path, log=print) -> int:
    """Store the key numbers of the figures in folder into the reference file (figures not made
    keep their stored values).  Refuses (1) when a figure is missing or stopped on its wall cap."""
    old = json.loads(reference.read_text()) if reference.is_file() else {}
    figs = dict(old.get("figures", {}))
    walls = dict(old.get("wall_s", {}))
    bad = []
    for name in names:
        info, problems = check_files(folder, name)
        bad += problems
        if info is not None and not problems:
            figs[name] = key_numbers(info)
            walls[name] = info.get("wall_s")
    if bad:
        log("not stored:\n  " + "\n  ".join(bad))
        return 1
    data = {
        "about": "Key numbers of `solidshell figures --quick` (paper_figures/), a regression baseline made by this "
        "code itself, not an independent reference: verification/figures_quick.py compares each "
        "figure's JSON with them.",
        "command": COMMAND,
        "made": {
            "commit": _git_commit(),
            "date": time.strftime("%Y-%m-%d"),
            "numba_threads": os.environ.get("NUMBA_NUM_THREADS", "default"),
            "python": platform.python_version(),
            "machine": platform.machine(),
        },
        "threads_check": old.get("threads_check", ""),
        "tolerances": tolerance_table(),
        "wall_s": {k: walls[k] for k in sorted(walls)},
        "figures": {k: figs[k] for k in sorted(figs)},
    }
    reference.write_text(json.dumps(data, indent=1) + "\n")
    log(f"stored {len(names)} figure(s) into {reference}")
    return 0


def check(folder: Path, names: list[str], reference: Path, log=print) -> int:
    """Compare the figures in folder with the reference file; print the table; 0 or 1."""
    ref = json.loads(reference.read_text())
    stored_figs, walls = ref.get("figures", {}), ref.get("wall_s", {})
    problems, rows = [], []
    for name in names:
        info, p = check_files(folder, name)
        problems += p
        if name not in stored_figs:
            problems.append(f"{name}: no stored values in {reference.name} (run {COMMAND})")
            continue
        if info is None:
            continue
        r, d = compare(stored_figs[name], key_numbers(info), name)
        rows += r
        problems += d
    w = (7, 7, 26, 31, 31, 10)
    log(
        f"{'figure':<{w[0]}}{'where':<{w[1]}}{'quantity':<{w[2]}}{'stored':>{w[3]}}{'now':>{w[4]}}  {'tolerance':<{w[5]}}"
    )
    for fig, where, key, a, b, tol, ok in rows:
        log(
            f"{fig:<{w[0]}}{where:<{w[1]}}{key:<{w[2]}}{_fmt(a):>{w[3]}}{_fmt(b):>{w[4]}}  {tol:<{w[5]}}"
            + ("" if ok else "  DIFFERS")
        )
    log(
        "\nwall time per figure [s] (information, not compared): "
        + ", ".join(f"{n} {walls.get(n, '?')} -> {_wall(folder, n)}" for n in names)
    )
    if problems:
        log(f"\nFAILED: {len(problems)} problem(s)\n  " + "\n  ".join(problems))
        return 1
    log(f"\npassed: {len(names)} figure(s), {len(rows)} numbers as stored ({reference.name})")
    return 0


def _wall(folder: Path, name: str):
    try:
        return json.loads((folder / f"{name}.json").read_text()).get("wall_s", "?")
    except (OSError, ValueError):
        return "?"


def main(argv=None, log=print) -> int:
    p = argparse.ArgumentParser(prog="python -m verification.figures_quick", description=__doc__.split("\n\n")[0])
    p.add_argument("figs", nargs="*", metavar="FIG", help="figures to check (default: all)")
    p.add_argument("--from", dest="source", metavar="DIR", help="check the figures already in DIR (no run)")
    p.add_argument("--keep", metavar="DIR", help="render into DIR and keep it (default: a temporary folder)")
    p.add_argument("--regenerate", action="store_true", help=f"store the numbers made into {REFERENCE.name}")
    p.add_argument("--reference", default=str(REFERENCE), help="the reference file (default: %(default)s)")
    a = p.parse_args(argv)
    try:
        names = figure_names(a.figs)
        reference = Path(a.reference)
        if a.source and a.keep:
            raise InputError("--from DIR checks a folder already made; --keep DIR renders into one: give one")
        if not a.regenerate and not reference.is_file():
            raise InputError(f"reference file {reference} not found (make it with {COMMAND})")
        if a.source and not Path(a.source).is_dir():
            raise InputError(f"--from {a.source}: no such folder")
    except InputError as e:
        print(f"figures_quick: {e}", file=sys.stderr)
        return 2
    act = regenerate if a.regenerate else check
    if a.source:
        return act(Path(a.source), names, reference, log)
    with tempfile.TemporaryDirectory(prefix="figures-quick-") as tmp:
        folder = Path(a.keep) if a.keep else Path(tmp)
        rc, wall = run_figures(names, folder, log)
        log(f"solidshell figures --quick: exit {rc}, {wall:.0f} s\n")
        status = act(folder, names, reference, log)
        return status or (1 if rc else 0)


if __name__ == "__main__":
    sys.exit(main())
