"""The verification record, the check registry and the context a check runs in.

A *check* is a function ``fn(ctx) -> list[Record]`` registered under a name with :func:`check`;
it measures one or more quantities against an independent reference and returns one
:class:`Record` per quantity (see the package docstring for the record's fields).  Plots go
through ``ctx.curves`` / ``ctx.convergence`` as plain data; the report writer draws them.
"""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from typing import Callable

STATUSES = ("passed", "failed", "skipped", "error")


@dataclass
class Record:
    """One measured quantity against its reference (the JSON record of ``verification.json``).

    ``error`` is ``|value - reference_value|`` (error_kind "abs") or that divided by
    ``|reference_value|`` ("rel"); ``passed`` is ``error <= tolerance`` (None when skipped)."""

    name: str
    reference: str
    source: str
    quantity: str
    value: float | None
    reference_value: float | None
    error: float | None
    tolerance: float | None
    passed: bool | None
    wall_time_s: float
    why: str = ""
    error_kind: str = "rel"
    status: str = "passed"
    check: str = ""
    topic: str = ""
    note: str = ""

    def to_dict(self) -> dict:
        d = asdict(self)
        for k in ("value", "reference_value", "error", "tolerance"):
            v = d[k]
            if isinstance(v, float) and not math.isfinite(v):
                d[k] = None if math.isnan(v) else ("inf" if v > 0 else "-inf")
        return d


def measure(
    name: str,
    quantity: str,
    value,
    reference_value,
    tolerance: float,
    *,
    reference: str,
    source: str,
    why: str,
    error_kind: str = "rel",
    wall_time_s: float = 0.0,
    note: str = "",
) -> Record:
    """A record with its error and verdict computed: rel = |v - r| / |r|, abs = |v - r|.
    A non-finite value fails (NaN compares false)."""
    v = float(value)
    r = float(reference_value)
    if error_kind == "rel":
        err = abs(v - r) / abs(r) if r != 0 else math.inf
    elif error_kind == "abs":
        err = abs(v - r)
    else:
        raise ValueError(f"error_kind {error_kind!r}")
    ok = bool(err <= tolerance) if math.isfinite(err) else False
    return Record(
        name=name,
        reference=reference,
        source=source,
        quantity=quantity,
        value=v,
        reference_value=r,
        error=err,
        tolerance=float(tolerance),
        passed=ok,
        wall_time_s=float(wall_time_s),
        why=why,
        error_kind=error_kind,
        status="passed" if ok else "failed",
        note=note,
    )


def skipped(name: str, quantity: str, *, reference: str, source: str, why: str, note: str) -> Record:
    """A record that could not be measured for a stated reason (neither passed nor failed)."""
    return Record(
        name=name,
        reference=reference,
        source=source,
        quantity=quantity,
        value=None,
        reference_value=None,
        error=None,
        tolerance=None,
        passed=None,
        wall_time_s=0.0,
        why=why,
        status="skipped",
        note=note,
    )


@dataclass
class Check:
    name: str
    topic: str
    fn: Callable
    summary: str
    quick: bool  # part of --quick
    default: bool  # part of the default set (a check that is neither runs only by name)


CHECKS: dict[str, Check] = {}


def check(name: str, topic: str, summary: str, *, quick: bool = True, default: bool = True):
    """Register ``fn(ctx) -> list[Record]`` as the check ``name``."""

    def deco(fn):
        if name in CHECKS:
            raise ValueError(f"check {name!r} registered twice")
        CHECKS[name] = Check(name, topic, fn, summary, quick, default)
        return fn

    return deco


@dataclass
class Context:
    """What a check gets: ``quick`` (the reduced set), a ``log`` callback for progress lines and
    the figures it declares (plain data, drawn by verification.checks.report)."""

    quick: bool = False
    log: Callable[[str], None] = print
    figures: list = field(default_factory=list)
    cache: dict = field(default_factory=dict)  # results shared by checks of one run

    def curves(
        self,
        title: str,
        series: list[dict],
        xlabel: str,
        ylabel: str,
        equal: bool = False,
        logx: bool = False,
        logy: bool = False,
    ):
        """Our curve(s) over the reference curve(s): series items {label, x, y, role} with role
        "reference" (a line) or "ours" (markers and a thin line)."""
        self.figures.append(
            {
                "kind": "curves",
                "title": title,
                "series": series,
                "xlabel": xlabel,
                "ylabel": ylabel,
                "equal": equal,
                "logx": logx,
                "logy": logy,
            }
        )

    def convergence(self, title: str, series: list[dict], xlabel: str, ylabel: str):
        """Error against mesh size, log-log: series items {label, h, error, rate} (rate: the
        observed order printed in the legend)."""
        self.figures.append(
            {"kind": "convergence", "title": title, "series": series, "xlabel": xlabel, "ylabel": ylabel}
        )


@contextmanager
def timed():
    """``with timed() as t: ...`` then ``t()`` is the elapsed wall time [s]."""
    t0 = time.perf_counter()
    box = [None]
    yield lambda: box[0] if box[0] is not None else time.perf_counter() - t0
    box[0] = time.perf_counter() - t0


def observed_order(h, e) -> list[float | None]:
    """log(e_{i-1}/e_i) / log(h_{i-1}/h_i) for successive meshes (None where undefined)."""
    out = [None]
    for i in range(1, len(h)):
        a, b = abs(e[i - 1]), abs(e[i])
        out.append(math.log(a / b) / math.log(h[i - 1] / h[i]) if a > 0 and b > 0 else None)
    return out
