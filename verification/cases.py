"""Cached verification cases: the piece the long case studies share (fold_pursuit, dynamic_sphere,
dynamic_scenes, static_scenes).

A case is one long run (minutes to an hour on the shared 2-core machine), so each is run on its own
(``--case NAME``), its row cached as ``<cache>/<name>.json``, and the report assembled from whatever
the cache holds (``--report``).  The cache is committed: it is the only source of a report's rows,
so a report regenerated from a clean checkout is the stored one.  This module holds the cache's
file format, the load-average stamp, the table cell format, the report writer and the command line;
each study keeps its cases, its row and its tables.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path


def load_average() -> str:
    """The 1/5/15-min load averages, '4.52 2.47 1.52' (wall times on a shared machine need it)."""
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        try:
            return " ".join(f"{x:.2f}" for x in os.getloadavg())
        except OSError:
            return "?"


def utc_now() -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())


def cache_file(cache: Path, name: str) -> Path:
    return Path(cache) / f"{name}.json"


def store(cache: Path, name: str, row: dict) -> Path:
    """Write one case's row to the cache (indented JSON; numpy and other values by str)."""
    p = cache_file(cache, name)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(json.dumps(row, indent=1, default=str) + "\n")
    return p


def cached(cache: Path, names) -> tuple[list[dict], list[str]]:
    """(rows of the cached cases among ``names``, in that order; the names not in the cache)."""
    rows, missing = [], []
    for n in names:
        p = cache_file(cache, n)
        if p.exists():
            rows.append(json.loads(p.read_text()))
        else:
            missing.append(n)
    return rows, missing


def run_recorded(call, row: dict) -> dict | None:
    """Run ``call()`` (a run_scene call) into ``row``: load average and UTC time at the start
    ('load_start', 'started'), at the end ('load_end'), the wall time ('total_wall_s') and
    'error' (None, or the exception as one line: a failed run is a result too).  Returns the
    run's summary, or None when it raised."""
    row.update(load_start=load_average(), started=utc_now())
    t0 = time.perf_counter()
    summary = None
    try:
        summary = call().summary
        row["error"] = None
    except Exception as exc:  # recorded, not hidden
        row["error"] = f"{type(exc).__name__}: {exc}"
    row["total_wall_s"] = time.perf_counter() - t0
    row["load_end"] = load_average()
    return summary


def run_and_store(cache: Path, name: str, row: dict, call, keys) -> dict:
    """run_recorded, then the summary's ``keys`` into ``row`` (when the run returned), and the row
    into the cache; returns the row."""
    s = run_recorded(call, row)
    if s is not None:
        row.update({k: s.get(k) for k in keys})
    store(cache, name, row)
    return row


def cell(v, spec: str = "", no: str = "NO") -> str:
    """A table cell: '–' for a missing value, yes / ``no`` for a bool, a float by ``spec``
    (format-spec mini-language), anything else by str."""
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else no
    if isinstance(v, float):
        return format(v, spec)
    return str(v)


def write_report(out: Path, stem: str, text: str, data, echo: str | None = None) -> None:
    """``<out>/<stem>.md`` (``text``) and ``<out>/<stem>.json`` (``data``); ``echo`` printed."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{stem}.md").write_text(text)
    (out / f"{stem}.json").write_text(json.dumps(data, indent=1, default=str) + "\n")
    if echo is not None:
        print(echo)


def parser(doc: str) -> argparse.ArgumentParser:
    """The command line of a study script: its docstring as help; the script adds its options."""
    return argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)


def main(argv, doc: str, cases: dict, run_case, report, listing, echo_keys=None) -> None:
    """``--case NAME`` (repeatable: run and cache each), ``--report`` (write the report from the
    cache; also what no option does), ``--list`` (one line per case, ``listing(name, case)``).
    ``echo_keys``: the row's keys printed as one JSON line after each case."""
    ap = parser(doc)
    ap.add_argument(
        "--case",
        action="append",
        default=[],
        choices=list(cases),
        metavar="NAME",
        help="run this case and cache its row (repeatable; --list shows the names)",
    )
    ap.add_argument("--report", action="store_true", help="write the report from the cache")
    ap.add_argument("--list", action="store_true", help="list the cases")
    a = ap.parse_args(argv)
    if a.list:
        for n, c in cases.items():
            print(listing(n, c))
        return
    for n in a.case:
        r = run_case(n)
        if echo_keys:
            print(json.dumps({k: r.get(k) for k in echo_keys}, default=str), flush=True)
    if a.report or not a.case:
        report()
