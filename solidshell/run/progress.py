"""A run's progress: a callback(fraction, text) -- the caller's, a tqdm bar on a terminal, or none.

with reporting(progress, "square-pedestal") as cb:
    cb(0.5, "solving")
"""

from __future__ import annotations

import sys
import threading
from contextlib import contextmanager


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
    """The run's progress callback: ``progress`` itself when callable, a :class:`_Bar` labelled
    ``label`` when true (closed on leaving), a no-op when false."""
    if callable(progress):
        yield progress
    elif progress:
        bar = _Bar(label)
        try:
            yield bar
        finally:
            bar.close()
    else:
        from ..problem import no_progress

        yield no_progress
