"""Ctrl-C and SIGTERM deferred to the end of a step: the explicit and relaxation loops' steps and
a run's writing of its results (solidshell.run.driver) complete before the signal acts.  A module
of its own so that a static run's writing need not import the explicit solver."""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager


@contextmanager
def deferred_interrupt():
    """During the loop a Ctrl-C (SIGINT) sets ``flag[0]`` instead of raising, so the step in progress
    completes and the run returns its last completed state; a second Ctrl-C raises as usual.  SIGTERM
    (what SLURM, Kubernetes and ``timeout`` send) is deferred the same way when the process has a
    Python handler for it (the CLI installs one; a bare library process keeps the default, which
    ends it).  A handler with a ``note(signum)`` method hears of the signal it was spared."""
    flag = [False]
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return
    old = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    ours = [sig for sig, h in old.items() if sig == signal.SIGINT or callable(h)]

    def handler(signum, frame):
        flag[0] = True
        for sig in ours:
            signal.signal(sig, old[sig])
        note = getattr(old.get(signum), "note", None)
        if callable(note):
            note(signum)

    for sig in ours:
        signal.signal(sig, handler)
    try:
        yield flag
    finally:
        for sig in ours:
            signal.signal(sig, old[sig])
