"""Run checks, print one line per record, and hand the results to the report writer."""

from __future__ import annotations

import os
import platform
import time
import traceback
from pathlib import Path

from solidshell.errors import InputError, IOFailure

from .record import CHECKS, Context, Record

DEFAULT_OUT = "verification-out"


def select(names=None, quick: bool = False) -> list:
    """The checks to run: the named ones (in registry order), else the quick or the default set.
    An unknown name is an InputError listing the valid names."""
    from . import load_checks

    load_checks()
    if names:
        bad = [n for n in names if n not in CHECKS]
        if bad:
            raise InputError(f"unknown check {bad[0]!r}; valid: {', '.join(CHECKS)}")
        return [c for c in CHECKS.values() if c.name in set(names)]
    return [c for c in CHECKS.values() if (c.quick if quick else c.default)]


def prepare_out(out_dir) -> Path:
    """Create the output folder and prove it writable before anything runs (IOFailure otherwise)."""
    p = Path(out_dir)
    try:
        p.mkdir(parents=True, exist_ok=True)
        probe = p / ".write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as e:
        raise IOFailure.from_oserror(e, p) from None
    return p


def fmt_value(v, digits: int = 6, missing: str = "-") -> str:
    """A table cell: floats to ``digits`` significant digits, None as ``missing``."""
    if v is None:
        return missing
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return str(v)


HEADER = f"{'name':<58} {'value':>13} {'reference':>13} {'error':>10} {'tol':>8}  result"


def line(r: Record) -> str:
    res = {"passed": "pass", "failed": "FAIL", "skipped": "skipped", "error": "ERROR"}[r.status]
    err = "-" if r.error is None else f"{r.error:.2e}"
    tol = "-" if r.tolerance is None else f"{r.tolerance:.2g}"
    extra = f"  ({r.note})" if r.note else ""
    return f"{r.name:<58} {fmt_value(r.value):>13} {fmt_value(r.reference_value):>13} {err:>10} {tol:>8}  {res}{extra}"


def _error_record(name: str, note: str, why: str) -> Record:
    return Record(
        name=f"{name}/error",
        reference="-",
        source="-",
        quantity="-",
        value=None,
        reference_value=None,
        error=None,
        tolerance=None,
        passed=False,
        wall_time_s=0.0,
        status="error",
        note=note,
        why=why,
    )


def failed(r: Record) -> bool:
    """A record that fails the run: status failed or error, or a False verdict whatever its status."""
    return r.status in ("failed", "error") or r.passed is False


def run_checks(checks, quick: bool = False, log=print) -> dict:
    """Run the checks; a check that raises, or returns no record, becomes one "error" record (the
    run goes on, and the run's ``failed`` count, hence ``solidshell verify``'s exit status, says so)."""
    ctx = Context(quick=quick, log=log)
    records, per_check = [], []
    t_all = time.perf_counter()
    log(HEADER)
    for c in checks:
        t0 = time.perf_counter()
        n_fig = len(ctx.figures)
        try:
            recs = list(c.fn(ctx))
        except Exception as exc:  # noqa: BLE001 - a broken check is a failed check, not a crash
            fr = traceback.extract_tb(exc.__traceback__)[-1]
            recs = [
                _error_record(
                    c.name,
                    " ".join(f"{type(exc).__name__}: {exc}".split()),
                    f"{type(exc).__name__} raised at {Path(fr.filename).name}:{fr.lineno} in {fr.name}",
                )
            ]
        else:
            if not recs:  # a check that measured nothing has verified nothing
                recs = [_error_record(c.name, "the check returned no records", "a check returns >= 1 record")]
        wall = time.perf_counter() - t0
        for r in recs:
            r.check, r.topic = c.name, c.topic
            log(line(r))
        for f in ctx.figures[n_fig:]:
            f["check"] = c.name
        records += recs
        per_check.append(
            {
                "name": c.name,
                "topic": c.topic,
                "summary": c.summary,
                "wall_time_s": wall,
                "records": len(recs),
                "failed": sum(failed(r) for r in recs),
                "skipped": sum(r.status == "skipped" for r in recs),
            }
        )
    total = time.perf_counter() - t_all
    n_fail = sum(failed(r) for r in records)
    n_skip = sum(r.status == "skipped" for r in records)
    log(
        f"{len(records)} records from {len(checks)} checks: {len(records) - n_fail - n_skip} passed, "
        f"{n_fail} failed, {n_skip} skipped; {total:.1f} s"
    )
    return {
        "quick": quick,
        "records": records,
        "checks": per_check,
        "figures": ctx.figures,
        "wall_time_s": total,
        "failed": n_fail,
        "skipped": n_skip,
        "machine": machine(),
    }


def machine() -> dict:
    try:
        load = os.getloadavg()
    except OSError:  # pragma: no cover - not on this platform
        load = None
    return {
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "load_average": load,
        "time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }


def verify(names=None, quick: bool = False, out_dir=DEFAULT_OUT, log=print, write: bool = True) -> dict:
    """Select, run, and (``write``) write ``verification.json``, ``report.md`` and the figures to
    ``out_dir``.  Returns the run dict (``records`` are Record objects; ``failed`` counts failures
    and errors)."""
    from .report import write_report

    checks = select(names, quick)
    out = prepare_out(out_dir) if write else None
    run = run_checks(checks, quick, log)
    if write:
        files = write_report(run, out)
        log(f"wrote {', '.join(str(f) for f in files)}")
        run["files"] = [str(f) for f in files]
    return run


def fenicsx(out_dir, reuse: bool = False, log=print) -> dict:
    """``solidshell verify --fenicsx``: verification.fenicsx.crosscheck.main(out) -> record dicts (the
    Record format), printed like the other checks and written to <out>/fenicsx.json.  DOLFINx runs
    under the system python (verification/fenicsx/jobs.py); without it an InputError (one line) is
    raised before anything is written.  Returns {"records", "failed", "files"}."""
    import dataclasses
    import json

    from ..fenicsx import crosscheck, jobs

    try:
        jobs.check_dolfinx()  # before anything is written
        out = prepare_out(out_dir)
        rows = crosscheck.main(out, reuse=reuse)
    except jobs.DolfinxMissing as e:
        raise InputError(str(e)) from None
    fields = set(Record.__dataclass_fields__)
    required = {k for k, f in Record.__dataclass_fields__.items() if f.default is dataclasses.MISSING}
    recs = []
    for i, r in enumerate(rows):
        missing = sorted(required - set(r))
        if missing:
            raise InputError(f"verification.fenicsx.crosscheck record {i} lacks {', '.join(missing)}")
        r = {k: v for k, v in r.items() if k in fields}
        if "status" not in r:
            r["status"] = "skipped" if r["passed"] is None else "passed" if r["passed"] else "failed"
        recs.append(Record(**r))
    log(HEADER)
    for r in recs:
        log(line(r))
    p = out / "fenicsx.json"
    try:
        p.write_text(json.dumps([r.to_dict() for r in recs], indent=1, default=float))
    except OSError as e:
        raise IOFailure.from_oserror(e, p) from None
    log(f"wrote {p}")
    return {"records": recs, "failed": sum(failed(r) for r in recs), "files": [str(p)]}
