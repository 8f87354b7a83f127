"""Command line: ``solidshell scenes | fabrics | mesh | run | sweep | verify | figures | bench`` (also ``python -m solidshell ...``).

    solidshell scenes
    solidshell fabrics                          (the fabric library: solidshell/fabrics.toml)
    solidshell mesh SCENE [--mesh 48x16x4] [--out DIR] [--force] [--allow-large] [-q | -v]
    solidshell run  SCENE [--mesh M] [--solver static|explicit|relax] [--set key=value ...] [--out DIR]
                          [--checkpoint FILE] [--restart FILE] [--no-pictures] [--force] [--allow-large]
                          [--no-progress] [-q | -v]
    solidshell sweep SWEEP [--scheduler tcp://HOST:PORT] [--workers N] [--threads N] [--out DIR]
                           [--retries N] [--limit N] [--list]     (solidshell.sweep; needs dask)
    solidshell verify [NAME ...] [--quick] [--out DIR] [--list] [--references] [--fenicsx]
    solidshell figures [FIG ...] [--quick] [--out DIR]     (the paper's figures, paper_figures/)
    solidshell bench [NAME ...] [--quick] [--out DIR] [--list]   (work-precision, solidshell/bench/)

SCENE is a packaged scene name (``solidshell scenes`` lists them) or the path of a .toml scene
file.  ``--set`` overrides any scene key by its dotted name (``--set solver.static.c=2e-3``,
``--set material.warp_angle=90``, ``--set solver.explicit.t_end=0.4``); the value is read as a TOML
value when it is one (numbers, true/false, [arrays], "strings"), else as a bare string.

Everything is checked before a file is written: a bad setting, scene key, mesh size (estimated
memory against the available memory; ``--allow-large`` to try anyway) or a sheet starting inside a
contact body stops the command with one line on stderr and nothing written.  An output folder
holding files solidshell did not write is refused unless ``--force``; an earlier run's files there
are replaced once the new run has a result (every file carries the run's ``run_id``).  Warnings
go to stderr, one line each (logger ``solidshell``), and to summary.json ``warnings``.  Progress: a
bar when stderr is a terminal, else a ``solidshell: progress: ...`` line every 10 s (environment
variable SOLIDSHELL_PROGRESS_INTERVAL) with the fraction done, time elapsed, ETA and the solver's
figures; ``--quiet`` prints only errors and one final line, ``-v`` adds the solver's figures and
timings.  ``run`` ends with the scene's own figures: a strip's tip deflection against the heavy
elastica (reference/elastica_strip.json), a drape's DC with its definition and areas, a hung
sheet's corners.

Exit status: 0 done (``run``: converged), 1 the solver did not converge or stopped (the last state
is written), 2 bad input (one line on stderr, no traceback, nothing written), 3 an I/O failure
(the path named), 130 interrupted (Ctrl-C: the last state is written with a summary marked
``"interrupted": true`` when the solver returned one), 143 terminated (SIGTERM, what SLURM,
Kubernetes and ``timeout`` send: handled as Ctrl-C, the state written the same way).
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
import tomllib

from .errors import InputError, IOFailure, SolverError
from .solvers import KINDS

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_INPUT, EXIT_IO, EXIT_INTERRUPTED = 0, 1, 2, 3, 130
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143, the status a shell gives a process SIGTERM ended


class _Terminate:
    """The CLI's SIGTERM handler: SIGTERM is handled as Ctrl-C (KeyboardInterrupt; an explicit or
    relaxation loop defers it to the end of its step and returns its state, solidshell.interrupts.
    deferred_interrupt), and remembered, for exit status 143 instead of 130."""

    def __init__(self):
        self.received = False

    def note(self, signum) -> None:
        """A loop that deferred the signal tells us it came."""
        self.received = True

    def __call__(self, signum, frame):
        self.received = True
        raise KeyboardInterrupt


_TERM = _Terminate()


def _interrupted_status() -> int:
    return EXIT_TERMINATED if _TERM.received else EXIT_INTERRUPTED


class _StderrLines(logging.Handler):
    """Log records of the "solidshell" logger as ``solidshell: warning: ...`` lines on the stderr of
    the moment (sys.stderr looked up at each record, so a redirected stderr is honoured); the
    progress lines (logger "solidshell.progress", off a terminal) as ``solidshell: progress: ...``."""

    def emit(self, record):
        try:
            kind = "progress" if record.name == PROGRESS_LOGGER else record.levelname.lower()
            _say(f"solidshell: {kind}: {record.getMessage()}")
        except Exception:  # pragma: no cover - logging must never break a run
            self.handleError(record)


class _Verbosity(logging.Filter):
    """Which records reach stderr: -1 (--quiet) errors only; 0 (default) warnings and errors and
    the progress lines; 1 (-v) also the library's info lines; 2 (-vv) also its debug lines."""

    level = 0

    def filter(self, record):
        if record.levelno >= logging.ERROR:
            return True
        if self.level < 0:
            return False
        if record.levelno >= logging.WARNING or record.name == PROGRESS_LOGGER:
            return True
        return record.levelno >= (logging.INFO if self.level == 1 else logging.DEBUG) and self.level >= 1


PROGRESS_LOGGER = "solidshell.progress"  # solidshell.run.progress.plog
_HANDLER = _StderrLines()
_FILTER = _Verbosity()
_HANDLER.addFilter(_FILTER)


def _install_log_handler(verbosity: int = 0) -> None:
    """The "solidshell" logger's records on stderr, as many as ``verbosity`` asks (_Verbosity)."""
    log = logging.getLogger("solidshell")
    if _HANDLER not in log.handlers:
        log.addHandler(_HANDLER)
    log.propagate = False  # one line per warning (not a second one from a root handler)
    _FILTER.level = verbosity
    log.setLevel(logging.ERROR if verbosity < 0 else logging.INFO if verbosity < 2 else logging.DEBUG)


class _Parser(argparse.ArgumentParser):
    """argparse with usage errors as one line and exit status 2.  The line names the subcommand
    (``solidshell: error: run: argument --solver: ...``); main() prints the one ``solidshell:`` prefix."""

    def error(self, message):
        sub = self.prog.removeprefix("solidshell").strip()
        raise InputError(f"{sub}: {message}" if sub else message)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="solidshell",
        description="Fabric drape with ANS solid-shell elements "
        "(Xie, Sze & Zhou, FEAD 106 (2015) 85-102).  Units: cm, gf, s.",
    )
    from . import __version__

    p.add_argument("--version", action="version", version=f"solidshell {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    sub.add_parser("scenes", help="list the packaged scenes (name, paper section, default mesh, title)")
    sub.add_parser("fabrics", help="list the fabric library (B, G, W, T, tensile rigidity, measured DC; sources)")

    m = sub.add_parser("mesh", help="build a scene's mesh and write it with pictures and a summary")
    m.add_argument("scene", help="scene name or path of a .toml scene file")
    m.add_argument("--mesh", metavar="DENSITY", help="mesh density, e.g. 48x16x4 (default: the scene's)")
    m.add_argument("--set", metavar="KEY=VALUE", action="append", default=[], help="override a scene key")
    m.add_argument("--out", metavar="DIR", help="output directory (default: runs/<scene>-mesh)")
    _common(m)

    r = sub.add_parser("run", help="run a scene and write the results")
    r.add_argument("scene", help="scene name or path of a .toml scene file")
    r.add_argument("--mesh", metavar="DENSITY", help="mesh density, e.g. 24x8x4 (default: the scene's)")
    r.add_argument("--solver", choices=list(KINDS), help="solver (default: the scene's [solver] kind)")
    r.add_argument(
        "--set",
        metavar="KEY=VALUE",
        action="append",
        default=[],
        help="override a scene key, e.g. solver.static.c=2e-3 (repeatable)",
    )
    r.add_argument("--out", metavar="DIR", help="output directory (default: runs/<scene>)")
    r.add_argument(
        "--checkpoint",
        metavar="FILE",
        help="explicit/relax: save the state to FILE while running (solver.<kind>.checkpoint)",
    )
    r.add_argument(
        "--restart", metavar="FILE", help="explicit/relax: continue from the checkpoint FILE (solver.<kind>.restart)"
    )
    r.add_argument(
        "--adaptive",
        action="store_true",
        help="reversible adaptive 1-to-4 subdivision (paper §5; explicit/relax only), from the "
        "scene's mesh.adaptive_level0 or --mesh; settings: --set adapt.KEY=VALUE",
    )
    r.add_argument("--no-progress", action="store_true", help="no progress bar or progress lines")
    r.add_argument(
        "--no-pictures",
        action="store_true",
        help="write no PNG pictures (the same as --set output.pictures=[] --set "
        "output.snapshots=[]): a small run then never loads matplotlib",
    )
    _common(r)

    w = sub.add_parser(
        "sweep",
        help="an ensemble of runs on dask.distributed (solidshell.sweep); "
        "results in a Parquet ledger, states and a figure",
    )
    w.add_argument("sweep", nargs="?", help="sweep .toml file or packaged study name (--list)")
    w.add_argument(
        "--scheduler",
        metavar="tcp://HOST:PORT",
        help="a running Dask scheduler (default: a local cluster on 127.0.0.1)",
    )
    w.add_argument(
        "--workers", type=int, metavar="N", help="local cluster: worker processes (default: CPU count / threads)"
    )
    w.add_argument("--threads", type=int, default=1, metavar="N", help="threads per run (default 1)")
    w.add_argument("--retries", type=int, default=2, metavar="N", help="extra attempts of a failed task")
    w.add_argument(
        "--out",
        metavar="DIR",
        help="output folder (default: runs/sweep-<name>); run again with the same folder to resume",
    )
    w.add_argument("--limit", type=int, metavar="N", help="run at most N of the missing runs")
    w.add_argument("--list", action="store_true", help="list the packaged studies")
    w.add_argument("--no-progress", action="store_true", help="no progress bar or lines")
    from .verify_cli import add_parser as _add_verify

    _add_verify(sub)
    from .bench.cli import add_parser as _add_bench

    _add_bench(sub)
    f = sub.add_parser("figures", help="render the paper's figures (paper_figures/): Figs. 4-13, 19-22")
    f.add_argument("figs", nargs="*", metavar="FIG", help="figure numbers, e.g. 5 12 (default: all)")
    f.add_argument("--quick", action="store_true", help="coarser meshes and faster relaxation (minutes)")
    f.add_argument("--out", metavar="DIR", default="figures", help="output folder (default: figures)")
    return p


def _common(p):
    p.add_argument(
        "--force", action="store_true", help="write into an output folder that holds files solidshell did not write"
    )
    p.add_argument(
        "--allow-large", action="store_true", help="skip the size guard (estimated memory against the available memory)"
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="print nothing but errors and one final line (no progress; warnings only in summary.json)",
    )
    g.add_argument(
        "-v",
        "--verbose",
        action="count",
        default=0,
        help="more detail: the solver's figures and the timings at the end, the library's info log lines "
        "(-vv: and its debug lines)",
    )


def _cmd_scenes(args) -> int:
    from . import scenes

    rows = []
    for name in scenes.available():
        s = scenes.load(name)
        rows.append((name, f"§{s.paper_section}" if s.paper_section else "-", s.density or "file", s.title))
    w = [max(len(r[i]) for r in rows) for i in range(3)]
    for r in rows:
        print(f"{r[0]:<{w[0]}}  {r[1]:<{w[1]}}  {r[2]:<{w[2]}}  {r[3]}")
    return EXIT_OK


def _default_out(scene: str, suffix: str = "") -> str:
    from pathlib import Path

    stem = Path(scene).stem if scene.endswith(".toml") else scene
    return str(Path("runs") / f"{stem}{suffix}")


def _cmd_mesh(args) -> int:
    from .run import run_scene
    from .scenes import parse_overrides

    out_dir = args.out or _default_out(args.scene, "-mesh")
    res = run_scene(
        args.scene,
        mesh=args.mesh,
        solver="none",
        out_dir=out_dir,
        progress=not args.quiet,
        overrides=parse_overrides(args.set),
        force=args.force,
        allow_large=args.allow_large,
    )
    c = res.summary["counts"]
    size = f"{c['nodes']} nodes, {c['quads']} quads, {c['triangles']} triangles"
    if args.quiet:
        print(f"{res.summary['scene']}: mesh {res.summary['mesh']}: {size}; wrote {res.out_dir}/")
        return EXIT_OK
    print(
        f"{res.summary['scene']}: mesh {res.summary['mesh']}: {size}; node sets: "
        + ", ".join(f"{k} ({v})" for k, v in c["node_sets"].items())
    )
    print(f"wrote {res.out_dir}/: " + file_list(res.summary["files"]))
    return EXIT_OK


def _cmd_run(args) -> int:
    if not args.no_pictures:  # the pictures' process starts before our own imports (render.server)
        from .render import server

        server.start()
    try:
        res = _run_scene_of(args)
    except BaseException:
        if not args.no_pictures:  # the child started above draws nothing now
            server.discard()
        raise
    s = res.summary
    c = s["counts"]
    status = "INTERRUPTED" if s.get("interrupted") else "converged" if s.get("converged") else "NOT converged"
    line = f"{s['scene']}: {s['solver']} on mesh {s['mesh']} ({c['nodes']} nodes, {c['elements']} elements): {status}"
    total = s["timings"].get("total", 0.0)
    head = _headline(res)
    if args.quiet:  # one line
        brief = "".join(f"; {b}" for b, _ in head if b)
        print(f"{line}{brief}; {total:.1f} s; wrote {res.out_dir}/")
        return _run_status(s)
    if s.get("message"):
        line += f" -- {s['message']}"
    print(line)
    for _, full in head:
        print("  " + full)
    extras = [
        f"{k} = {s[k]:.4g}" if isinstance(s[k], float) else f"{k} = {s[k]}"
        for k in (
            "drape_coefficient",
            "fold_count",
            "interpenetrated_nodes",
            "max_displacement",
            "max_active_nodes",
            "remesh_count",
            "max_interpenetrated_nodes",
        )
        if s.get(k) is not None
    ]
    if extras:
        print("  " + ", ".join(extras))
    if args.verbose:
        for ln in _details(s):
            print("  " + ln)
    print(f"  {total:.1f} s; wrote {res.out_dir}/: " + file_list(s["files"]))
    return _run_status(s)


def _run_scene_of(args):
    """run_scene with the ``run`` command's arguments."""
    from .run import run_scene
    from .scenes import parse_overrides

    out_dir = args.out or _default_out(args.scene)
    extra = {k: v for k, v in (("checkpoint", args.checkpoint), ("restart", args.restart)) if v}
    overrides = parse_overrides(args.set)
    if args.no_pictures:
        clash = [k for k in ("output.pictures", "output.snapshots") if k in overrides]
        if clash:
            raise InputError(f"run: --no-pictures and --set {clash[0]}=... ask for opposite things; give one of them")
        overrides.update({"output.pictures": [], "output.snapshots": []})
    return run_scene(
        args.scene,
        mesh=args.mesh,
        solver=args.solver,
        out_dir=out_dir,
        progress=not (args.no_progress or args.quiet),
        overrides=overrides,
        force=args.force,
        allow_large=args.allow_large,
        adaptive=True if args.adaptive else None,
        **extra,
    )


def file_list(names) -> str:
    """The written files' names for one line: a numbered series of more than three files (a static
    run writes one frame per load step, hundreds on a long path) shown as its first and last name
    and its count, e.g. ``series_00000.vtu ... series_00763.vtu (764 files)``."""
    import re

    groups: dict = {}
    order = []
    for name in names:
        m = re.fullmatch(r"(.*?)(\d+)(\.[^.]+)", name)
        key = (m.group(1), len(m.group(2)), m.group(3)) if m else name
        if key not in groups:
            groups[key] = []
            order.append(key)
        groups[key].append(name)
    out = []
    for key in order:
        g = groups[key]
        out.append(", ".join(g) if len(g) <= 3 else f"{g[0]} ... {g[-1]} ({len(g)} files)")
    return ", ".join(out)


# ----------------------------------------------------------------------------- each scene's figures
def _headline(res) -> list[tuple[str, str]]:
    """What the scene's user wants at the end, as (brief for --quiet, full line) pairs: a strip's tip
    against the heavy elastica, a drape's DC with its definition and areas, a hung sheet's corners."""
    s = res.summary
    if s.get("finite") is False or res.U is None:
        return []
    out = []
    try:
        if s.get("tip_position") is not None:
            out.append(_tip_line(res))
        if s.get("drape_coefficient") is not None:
            out.append(_dc_line(s))
        elif not out and s.get("solver") != "none":
            corners = _corners_line(res)
            if corners:
                out.append(corners)
    except Exception as e:  # the figures must never lose a written run
        out.append(("", f"(closing figures unavailable: {type(e).__name__}: {e})"))
    return out


def _dc_line(s: dict) -> tuple[str, str]:
    dc, folds = s["drape_coefficient"], s.get("fold_count")
    A, As, Ap = s.get("projected_area"), s.get("sheet_area"), s.get("pedestal_area")
    f = f", {folds} folds" if folds is not None else ""
    brief = f"DC {dc:.4g}{f}"
    if not isinstance(A, (int, float)) or not isinstance(As, (int, float)):
        return brief, f"drape coefficient DC = {dc:.4g}{f}"
    if isinstance(Ap, (int, float)) and Ap > 0:
        how = f"(A_projected - A_pedestal)/(A_sheet - A_pedestal) = ({A:.4g} - {Ap:.4g})/({As:.4g} - {Ap:.4g}) cm^2"
    else:
        how = f"A_projected/A_sheet = {A:.4g}/{As:.4g} cm^2 (no pedestal)"
    return brief, f"drape coefficient DC = {dc:.4g} = {how}{f}"


def _strip_reference(s: dict) -> tuple[str, dict] | None:
    """The stored heavy elastica this strip is, if any (solidshell.references.strip_elastica)."""
    from .references import strip_elastica

    return strip_elastica(s)


def _tip_line(res) -> tuple[str, str]:
    """The strip's tip deflection (downwards, from its clamped end) [cm], against the heavy elastica
    when the strip is one of the stored ones."""
    import numpy as np

    s, mesh = res.summary, res.mesh
    tip = np.asarray(s["tip_position"], float)
    clamp = mesh.node_sets.get("clamped") if mesh is not None else None
    origin = np.asarray(mesh.nodes, float)[clamp].mean(0) if clamp is not None and len(clamp) else np.zeros(3)
    x, d = tip[0] - origin[0], origin[2] - tip[2]
    where = f"tip deflection {d:.4g} cm (tip {x:.4g} cm along x from the clamp, {-d:.4g} cm in z)"
    ref = _strip_reference(s)
    if ref is None:
        return f"tip deflection {d:.4g} cm", where + "; no stored reference for this strip"
    cut, r = ref
    dr = -float(r["tip_z"])
    rel = (d - dr) / dr
    return (
        f"tip deflection {d:.4g} cm (elastica {dr:.4g}, {rel:+.2%})",
        f"{where}; heavy elastica ({cut}-cut, reference/elastica_strip.json): {dr:.4g} cm "
        f"({float(r['tip_x']):.4g} cm along x): {rel:+.2%}",
    )


def _corners_line(res) -> tuple[str, str] | None:
    """A sheet's corners (node sets corner_sw/se/ne/nw of the square recipe) at the end [cm], the
    held ones marked."""
    import numpy as np

    mesh = res.mesh
    sets = getattr(mesh, "node_sets", None) or {}
    names = [n for n in ("corner_sw", "corner_se", "corner_ne", "corner_nw") if len(sets.get(n, ())) == 1]
    if not names:
        return None
    fixed = None if res.problem is None else np.asarray(res.problem.fixed, bool).reshape(-1, 6)
    parts, lowest = [], None
    for n in names:
        i = int(sets[n][0])
        p = np.asarray(mesh.nodes[i], float) + np.asarray(res.U[i, :3], float)
        held = fixed is not None and i < len(fixed) and bool(fixed[i, :3].all())
        parts.append(f"{n[7:]} ({', '.join(f'{round(v, 3) + 0.0:.4g}' for v in p)})" + (" held" if held else ""))
        if not held and (lowest is None or p[2] < lowest):
            lowest = float(p[2])
    brief = f"lowest free corner z {lowest:.4g} cm" if lowest is not None else ""
    return brief, "corners at the end [cm]: " + ", ".join(parts)


def _run_status(s: dict) -> int:
    if s.get("interrupted"):
        return _interrupted_status()
    return EXIT_OK if s.get("converged") else EXIT_NOT_CONVERGED


# the solver's figures -v prints, when the summary has them
_DETAIL_KEYS = (
    "method",
    "load_steps",
    "iterations",
    "linear_solves",
    "factorizations",
    "final_relative_residual",
    "positive_definite",
    "min_tangent_eigenvalue",
    "steps",
    "t_final",
    "dt",
    "critical_time_step",
    "damping",
    "mass_scaling",
    "final_kinetic_energy",
    "energy_balance_error",
    "element_steps_per_second",
    "self_intersections",
    "min_layer_gap",
    "peak_memory_mb",
)


def _details(s: dict) -> list[str]:
    """-v: the solver's figures, the timings by phase and the warnings' count."""
    figs = [
        f"{k} = {s[k]:.4g}" if isinstance(s[k], float) else f"{k} = {s[k]}"
        for k in _DETAIL_KEYS
        if s.get(k) is not None and not isinstance(s[k], (dict, list))
    ]
    out = ["solver: " + ", ".join(figs)] if figs else []
    t = s.get("timings") or {}
    if t:
        out.append("timings: " + ", ".join(f"{k} {v:.2f} s" for k, v in t.items()))
    out.append(f"warnings: {len(s.get('warnings') or [])} (summary.json)")
    return out


def _cmd_sweep(args) -> int:
    from pathlib import Path

    from .sweep import load_spec, studies

    if args.list:
        for name in studies():
            spec = load_spec(name)
            print(f"{name}  ({spec.n_runs} runs, scene {spec.scene})  {spec.description}")
        return EXIT_OK
    if not args.sweep:
        raise InputError("sweep: give a sweep file or a packaged study name (--list)")
    from .sweep.engine import require_dask

    require_dask()  # before the sweep is parsed: the one thing to install first
    from .sweep.engine import Cluster, describe, run_sweep
    from .sweep.report import sweep_group, write_report

    spec = load_spec(args.sweep)
    out = args.out or f"runs/sweep-{spec.name}"
    group = sweep_group(spec)
    for k, v in (("retries", args.retries), ("limit", args.limit)):
        if v is not None and v < 0:
            raise InputError(f"--{k} must be >= 0, got {v}")
    cluster = Cluster(scheduler=args.scheduler, workers=args.workers, threads=args.threads, retries=args.retries)
    res = run_sweep(spec, out, cluster, progress=not args.no_progress, group=group, limit=args.limit)
    rep = write_report(spec, out, group)
    print(
        f"sweep {spec.name}: {res.recorded} run(s) recorded now, {res.skipped} before, "
        f"{len(res.failed)} failed now, {len(res.failed_before)} before, {res.total} in all; "
        f"{res.wall_time_s:.1f} s"
    )
    for key, why in res.failed:
        _say(f"solidshell: {describe(spec, key)} failed: {why}")
    for key, why in res.failed_before:
        _say(f"solidshell: {describe(spec, key)} failed in an earlier invocation: {why}")
    freq = ", ".join(f"{k} folds {v:.0%}" for k, v in rep["fold_frequencies"].items())
    print(
        f"  {len(rep['states'])} state(s) under {rep['group']}"
        + (f"; {freq}" if freq else "")
        + (f"; {rep['unsettled']} unsettled" if rep["unsettled"] else "")
    )
    print(f"  wrote {out}/: ledger/ (Parquet), " + ", ".join(Path(f).name for f in rep["files"]))
    if res.interrupted:
        return _interrupted_status()
    # 1: a run failed (now or before: its error row stays in the ledger), or runs are missing (--limit)
    incomplete = res.recorded + len(res.failed) + res.skipped < res.total
    return EXIT_NOT_CONVERGED if res.failed or res.failed_before or incomplete else EXIT_OK


def _cmd_figures(args) -> int:
    try:
        from paper_figures.registry import make_figures, module_name
    except ImportError:
        raise InputError(
            "the paper_figures package is not importable here: run from the source tree "
            "(or install it with pip install -e .)"
        ) from None
    for f in args.figs:  # every name checked before any figure runs
        module_name(f)
    make_figures(args.figs, quick=args.quick, out_dir=args.out)
    return EXIT_OK


def main(argv=None) -> int:
    """Entry point; returns the exit status (the console script exits with it)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    # let "--mesh -3x4" reach the density check (argparse would take -3x4 for an option)
    for i in range(len(argv) - 2, -1, -1):
        if argv[i] == "--mesh" and argv[i + 1].startswith("-") and argv[i + 1][1:2].isdigit():
            argv[i : i + 2] = [f"--mesh={argv[i + 1]}"]
    _install_log_handler()
    main_thread = threading.current_thread() is threading.main_thread()
    old_term = signal.signal(signal.SIGTERM, _TERM) if main_thread else None
    _TERM.received = False
    try:
        return _main(argv)
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, old_term)


def console() -> None:
    """The process's entry point (``python -m solidshell``): :func:`main`'s exit status, and a quick
    end.  Once main() has returned, Python's exit handlers run (atexit: logging, temporary folders,
    multiprocessing's children) and the standard streams are flushed; then the process ends without
    the interpreter's teardown, whose largest part is the C libraries' static destructors -- LLVM's,
    loaded with numba: 0.15-0.3 s of every ``solidshell run``, measured (issue 41; docs/benchmarks.md
    section 5c).  With other threads still running (none in a run) it exits the ordinary way,
    which waits for them."""
    code = main()
    others = [t for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon and t.is_alive()]
    if others:
        sys.exit(code)
    import atexit
    import os

    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (``| head``): nothing more to say
            pass
    os._exit(code)


def _main(argv) -> int:
    try:
        args = _parser().parse_args(argv)
        _install_log_handler(-1 if getattr(args, "quiet", False) else getattr(args, "verbose", 0) or 0)
        if args.command == "scenes":
            return _cmd_scenes(args)
        if args.command == "fabrics":
            from .fabrics import listing

            print("\n".join(listing()))
            return EXIT_OK
        if args.command == "mesh":
            return _cmd_mesh(args)
        if args.command == "sweep":
            return _cmd_sweep(args)
        if args.command == "verify":
            from .verify_cli import run as _cmd_verify

            return _cmd_verify(args)
        if args.command == "figures":
            return _cmd_figures(args)
        if args.command == "bench":
            from .bench.cli import run as _cmd_bench

            return _cmd_bench(args)
        return _cmd_run(args)
    except InputError as e:
        _say(f"solidshell: error: {_unprefixed(e)}")
        return EXIT_INPUT
    except tomllib.TOMLDecodeError as e:
        _say(f"solidshell: error: not valid TOML: {e}")
        return EXIT_INPUT
    except IOFailure as e:
        _say(f"solidshell: I/O error: {e}")
        return EXIT_IO
    except OSError as e:
        where = f" {e.filename}:" if e.filename else ""
        _say(f"solidshell: I/O error:{where} {e.strerror or e}")
        return EXIT_IO
    except SolverError as e:
        _say(f"solidshell: solver stopped: {e}")
        return EXIT_NOT_CONVERGED
    except KeyboardInterrupt:
        what = "terminated (SIGTERM)" if _TERM.received else "interrupted"
        _say(f"solidshell: {what}; this run's summary.json was not written")
        return _interrupted_status()


def _unprefixed(e: Exception) -> str:
    """The error's text without a leading ``solidshell:`` of its own (the line has one already)."""
    text = str(e).strip()
    while text.lower().startswith("solidshell:"):
        text = text[len("solidshell:") :].strip()
    return text


def _say(msg: str) -> None:
    print(" ".join(str(msg).split()), file=sys.stderr)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
