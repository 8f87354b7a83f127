"""A run's progress: a callback(fraction, text) -- the caller's, a tqdm bar on a terminal, a
``logging`` line every :data:`INTERVAL` seconds elsewhere (a pipe, a log file, CI, a notebook, a
Dask worker), or none.

with reporting(progress, "square-pedestal") as cb:
    cb(0.5, "solving")

A process nobody configured logging in (a Dask worker: the root logger has no handler and passes
WARNING and up only) would drop the INFO lines; :func:`visible` makes them reach a handler for
the length of a run (solidshell.sweep.task: the worker's own log).
"""

from __future__ import annotations

import logging
import math
import os
import sys
import threading
import time
from contextlib import contextmanager

#: seconds of wall time between two progress lines off a terminal (environment variable
#: SOLIDSHELL_PROGRESS_INTERVAL; read when a run starts, so tests may patch it)
INTERVAL = float(os.environ.get("SOLIDSHELL_PROGRESS_INTERVAL", "10") or 10)

#: the logger of the progress lines (INFO); the CLI prints them on stderr, a library user sees them
#: with e.g. ``logging.basicConfig(level=logging.INFO)``
plog = logging.getLogger("solidshell.progress")


class _Bar:
    """progress(fraction, text) drawn as a tqdm bar on stderr, only when stderr is a terminal (logs
    and pipes stay clean).  A ticker thread redraws it every quarter second, so the bar appears
    half a second after the start and its elapsed time and ETA keep moving even while a solver is
    busy between two progress calls (a numba compile, a factorisation)."""

    SHOW_AFTER = 0.5  # s: short runs finish without a bar flashing by
    TICK = 0.25  # s between redraws

    def __init__(self, label: str):
        self.bar = None
        if not _is_terminal(sys.stderr):
            return
        from tqdm import tqdm

        # ETA from the average rate since the start (smoothing 0): solver fractions are uneven
        self.bar = tqdm(
            total=1000,
            desc=label,
            file=sys.stderr,
            delay=self.SHOW_AFTER,
            leave=False,
            smoothing=0.0,
            mininterval=self.TICK,
            bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}<{remaining}{postfix}",
        )
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._tick, name="solidshell-progress", daemon=True)
        self._thread.start()

    def _tick(self):
        if self._stop.wait(self.SHOW_AFTER):
            return
        while not self._stop.is_set():
            self.bar.refresh()
            self._stop.wait(self.TICK)

    def __call__(self, fraction: float, text: str = "") -> None:
        if self.bar is None:
            return
        try:
            n = int(round(1000 * min(max(float(fraction), 0.0), 1.0)))
        except (TypeError, ValueError):
            return
        if text:
            self.bar.set_postfix_str(" ".join(str(text).split())[:60], refresh=False)
        if n > self.bar.n:
            self.bar.update(n - self.bar.n)

    def close(self):
        if self.bar is not None:
            self._stop.set()
            self._thread.join(1.0)
            self.bar.close()


def duration(seconds: float) -> str:
    """``4.2 s``, ``42 s``, ``3 min 05 s``, ``1 h 02 min``."""
    if seconds < 9.95:
        return f"{max(0.0, seconds):.1f} s"
    s = int(round(seconds))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


class _Lines:
    """progress(fraction, text) as a ``logging`` line on :data:`plog` every ``interval`` seconds of
    wall time, with the figures the bar shows: the label, the fraction done, the time elapsed, the
    ETA (from the average rate since the start, as the bar's) and the solver's own text (t, E_kin,
    residual for the dynamics; load factor and residual for the static solvers).  A ticker thread
    writes them, so a line comes even while the solver is busy between two calls; a run shorter
    than ``interval`` logs nothing, a longer one ends with a ``done`` line."""

    def __init__(self, label: str, interval: float | None = None):
        self.label = label
        self.interval = max(0.01, float(INTERVAL if interval is None else interval))
        self.t0 = time.perf_counter()
        self.frac, self.text, self.lines = 0.0, "", 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._tick, name="solidshell-progress-lines", daemon=True)
        self._thread.start()

    def __call__(self, fraction: float, text: str = "") -> None:
        try:
            f = min(max(float(fraction), 0.0), 1.0)
        except (TypeError, ValueError):
            return
        if math.isfinite(f):
            self.frac = max(self.frac, f)
        if text:
            self.text = " ".join(str(text).split())[:200]

    def line(self) -> str:
        """The line as it would be logged now."""
        elapsed = time.perf_counter() - self.t0
        f = self.frac
        eta = f", ETA {duration(elapsed * (1.0 - f) / f)}" if 0.01 <= f < 1.0 and elapsed >= 1.0 else ""
        return f"{self.label}: {100.0 * f:3.0f}% after {duration(elapsed)}{eta}" + (
            f" -- {self.text}" if self.text else ""
        )

    def _tick(self) -> None:
        while not self._stop.wait(self.interval):
            if plog.isEnabledFor(logging.INFO):
                plog.info(self.line())
                self.lines += 1

    def close(self) -> None:
        self._stop.set()
        self._thread.join(1.0)
        if self.lines and plog.isEnabledFor(logging.INFO):
            plog.info(f"{self.label}: done after {duration(time.perf_counter() - self.t0)}")


LOG_FORMAT = "%(asctime)s - %(name)s - %(levelname)s - %(message)s"
"""The format of the progress lines :func:`visible` prints itself (Dask's own, so that a worker's
log reads as one)."""

_VISIBLE = threading.Lock()
_SETUP: dict = {"users": 0, "added": [], "level": logging.NOTSET}  # visible()'s shared set-up


@contextmanager
def visible(handlers=()):
    """:data:`plog`'s INFO lines reach a handler while inside: its level INFO (when it would pass
    less), ``handlers`` added, and -- when neither these nor any other handler on its way up would
    take them -- a stream handler on stderr in :data:`LOG_FORMAT`.  Nested or concurrent uses (the
    threads of one worker) share the first one's set-up, undone when the last leaves."""
    with _VISIBLE:
        if not _SETUP["users"]:
            _SETUP["level"] = plog.level
            if plog.getEffectiveLevel() > logging.INFO:
                plog.setLevel(logging.INFO)
            added = [h for h in handlers if h not in plog.handlers]
            for h in added:
                plog.addHandler(h)
            if not plog.hasHandlers():
                h = logging.StreamHandler(sys.stderr)
                h.setFormatter(logging.Formatter(LOG_FORMAT))
                plog.addHandler(h)
                added.append(h)
            _SETUP["added"] = added
        _SETUP["users"] += 1
    try:
        yield plog
    finally:
        with _VISIBLE:
            _SETUP["users"] -= 1
            if not _SETUP["users"]:
                for h in _SETUP["added"]:
                    plog.removeHandler(h)
                plog.setLevel(_SETUP["level"])
                _SETUP["added"] = []


def _is_terminal(stream) -> bool:
    """Whether ``stream`` is an open terminal (a replaced sys.stderr may have no isatty)."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed file
        return False


def _phase(cb, lo, hi):
    """A progress callback mapping [0,1] onto [lo,hi] of the outer one."""
    return lambda f, text="": cb(lo + (hi - lo) * float(f), text)


@contextmanager
def reporting(progress, label: str):
    """The run's progress callback: ``progress`` itself when callable; when true, a :class:`_Bar`
    labelled ``label`` if stderr is a terminal, else :class:`_Lines` (closed on leaving); a no-op
    when false."""
    if callable(progress):
        yield progress
    elif progress:
        bar: _Bar | _Lines = _Bar(label) if _is_terminal(sys.stderr) else _Lines(label)
        try:
            yield bar
        finally:
            bar.close()
    else:
        from ..problem import no_progress

        yield no_progress
