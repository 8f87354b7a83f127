"""Run a sweep on ``dask.distributed``: a LocalCluster by default, or any scheduler by address.

One run per task; each worker runs one task at a time with ``threads`` threads (1 by default), so
a cluster of N workers keeps N cores busy.  Tasks are retried (``retries``) when they raise, and
Dask reschedules the task of a worker that dies (a killed process, a lost machine) on another one.
The client records each result in the ledger (solidshell.sweep.ledger) as it arrives; an
interrupted sweep, started again with the same ``--out``, skips the runs recorded and never records
a run twice.

Run folders are written by the workers under ``OUT/runs/<key>`` (an absolute path): workers on
other machines need that folder on a shared filesystem.  The ledger is written by the client only.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

from ..errors import InputError
from .ledger import Ledger
from .spec import SweepSpec
from .task import make_task, run_label, run_task

__all__ = ["run_sweep", "Cluster", "SweepResult", "require_dask", "describe", "INSTALL_HINT"]

INSTALL_HINT = "pip install 'solidshell[sweep]'  (or: pip install 'dask[distributed]' pyarrow)"


def require_dask() -> None:
    """InputError (one line, with the install command) when dask.distributed or pyarrow is missing."""
    missing = []
    for mod in ("distributed", "pyarrow"):
        try:
            __import__(mod)
        except ImportError:
            missing.append("dask.distributed" if mod == "distributed" else mod)
    if missing:
        raise InputError(f"solidshell sweep needs {' and '.join(missing)}: {INSTALL_HINT}")


@dataclass
class SweepResult:
    """What :func:`run_sweep` returns."""

    out: Path
    total: int  # runs in the sweep
    skipped: int  # already in the ledger when it started (with a result or failed)
    recorded: int  # results (status "done") recorded by this invocation
    failed: list = field(default_factory=list)  # (key, one-line reason) of this invocation's runs
    #                                without a result: refused/stopped (an "error" row, recorded so a
    #                                resumed sweep does not repeat it) or lost (a task that kept raising)
    failed_before: list = field(default_factory=list)  # (key, reason) of skipped runs whose row is an error
    interrupted: bool = False
    wall_time_s: float = 0.0
    workers: int = 0
    dashboard: str | None = None


def _dashboard(client) -> str | None:
    try:
        services = client.scheduler_info().get("services", {})
    except Exception:  # noqa: BLE001 - a display detail must never stop a sweep
        return None
    return client.dashboard_link if "dashboard" in services else None


WORKER_MB = 300
"""Memory [MB] a local worker process takes before its run (Python, numpy, numba, distributed; ~250
MB measured on this machine): with the run's own, what bounds --workers by the available memory."""

_SCHEMES = ("tcp", "tls", "inproc", "ucx", "ws", "wss")


def check_workers(workers: int, threads: int = 1) -> None:
    """The local cluster's guard (InputError, one line, before anything is written): at most four
    worker processes per CPU (more only queue for the cores) and no more than the available memory
    holds at WORKER_MB each (--workers 1000 grew to 4 GB and swapped)."""
    cpus = os.cpu_count() or 1
    if workers > 4 * cpus:
        raise InputError(
            f"--workers {workers} exceeds the guard of 4 worker processes per CPU ({4 * cpus} on this machine's "
            f"{cpus}); more only queue for the cores"
        )
    from ..sizing import available_memory

    avail = available_memory()
    need = workers * WORKER_MB * 2**20
    if avail is not None and need > avail:
        raise InputError(
            f"--workers {workers}: {workers} worker processes need about {need / 2**30:.1f} GiB before their runs, "
            f"more than the {avail / 2**30:.1f} GiB available; use fewer workers"
        )


def check_scheduler(address: str) -> str:
    """``address`` when it reads as a Dask scheduler address (SCHEME://HOST:PORT, the scheme one of
    Dask's); else InputError, one line.  Whether it answers is found by connecting."""
    from urllib.parse import urlsplit

    bad = InputError(f"--scheduler {address!r} is not a scheduler address: give tcp://HOST:PORT")
    try:
        u = urlsplit(address)
        port = u.port
    except ValueError:
        raise bad from None
    if u.scheme not in _SCHEMES or (u.scheme != "inproc" and (not u.hostname or port is None)):
        raise bad
    return address


def _client(scheduler, workers, threads):
    """(client, cluster or None): a LocalCluster on the loopback interface, or a scheduler."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            return Client(scheduler, timeout="20s"), None
        except (OSError, TimeoutError, ValueError) as e:
            raise InputError(f"--scheduler {scheduler}: cannot connect ({' '.join(str(e).split())})") from None
    n = workers or max(1, (os.cpu_count() or 1) // max(1, threads))
    cluster = LocalCluster(
        n_workers=n,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",
        silence_logs=40,
    )
    return Client(cluster), cluster


@dataclass(frozen=True)
class Cluster:
    """Where the runs go and what each gets.

    scheduler : "tcp://HOST:PORT" of a running scheduler; None starts a LocalCluster of ``workers``
                processes (default: the CPU count / threads) on 127.0.0.1
    threads   : threads per run (numba kernels, BLAS)
    retries   : extra attempts of a task that raised
    """

    scheduler: str | None = None
    workers: int | None = None
    threads: int = 1
    retries: int = 2


class _Progress:
    """A tqdm bar on a terminal, else one line per finished run (on ``stream``)."""

    def __init__(self, total, done, enabled, stream: TextIO):
        self.stream = stream
        self.total, self.n = total, done
        self.bar = None
        if enabled and stream.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=total, initial=done, desc="sweep", unit="run", file=stream, smoothing=0.0)
        self.enabled = enabled

    def update(self, text: str):
        self.n += 1
        if self.bar is not None:
            self.bar.set_postfix_str(text[:50], refresh=False)
            self.bar.update(1)
        elif self.enabled:
            print(f"sweep: {self.n}/{self.total} {text}", file=self.stream, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def describe(spec: SweepSpec, key: str) -> str:
    """``run <index> (<its varied settings>) [key <key>]``: which entry of the sweep a key is."""
    run = next((r for r in spec.runs if r.key == key), None)
    return f"run [key {key}]" if run is None else run_label(spec, run)


def _label(row) -> str:
    if row.get("status") != "done":
        return f"{row['key']}: error"
    dc = row.get("drape_coefficient")
    dc_s = f"DC {dc:.3f}" if isinstance(dc, float) else "no DC"
    conv = "" if row.get("converged") else " NOT converged"
    return f"{row['key']}: {dc_s}, {row.get('fold_count')} folds, {row.get('wall_time_s', 0):.0f} s{conv}"


def run_sweep(
    spec: SweepSpec,
    out,
    cluster: Cluster = Cluster(),
    *,
    progress: bool = True,
    group: str = "C1",
    pictures=("top",),
    stream: TextIO | None = None,
    limit: int | None = None,
) -> SweepResult:
    """Run the sweep's runs missing from ``out``'s ledger on a Dask cluster (module docstring).

    cluster   : the scheduler or local workers, threads per run, retries (:class:`Cluster`)
    group     : the symmetry group of the fingerprints (solidshell.sweep.states.symmetry_group)
    limit     : submit at most this many of the missing runs (a partial sweep; resumable)
    progress  : the client's bar (a terminal) or one line per run, and each run's progress lines in
                its worker's log (solidshell.sweep.task); False: neither
    """
    require_dask()
    from distributed import as_completed

    scheduler, workers, threads, retries = cluster.scheduler, cluster.workers, cluster.threads, cluster.retries
    stream = stream or sys.stderr
    if threads < 1:
        raise InputError(f"--threads must be >= 1, got {threads}")
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be >= 1, got {workers}")
    if scheduler and workers is not None:
        raise InputError("--workers starts a local cluster; a --scheduler has its own workers")
    if workers is not None:
        check_workers(workers, threads)
    ledger = Ledger(out, spec)
    ledger.check()
    # a scheduler is reached before anything is written: a wrong or unreachable address leaves
    # --out as it was
    early = _client(check_scheduler(scheduler), None, threads) if scheduler else None
    try:
        ledger.open()
    except BaseException:
        if early is not None:
            early[0].close()
        raise
    done = ledger.done_keys()
    todo = [r for r in spec.runs if r.key not in done]
    if limit is not None:
        todo = todo[:limit]
    keys = {r.key for r in spec.runs}
    res = SweepResult(
        out=Path(out),
        total=spec.n_runs,
        skipped=len(done & keys),
        recorded=0,
        failed_before=[(k, why) for k, why in ledger.errors() if k in keys],
    )
    if not todo:
        if early is not None:
            early[0].close()
        return res
    t0 = time.perf_counter()
    client, cluster = early if early is not None else _client(scheduler, workers, threads)
    bar = None
    futures = []
    try:
        res.workers = len(client.scheduler_info().get("workers", {}))
        res.dashboard = _dashboard(client)
        where = scheduler or f"local cluster of {res.workers} worker process(es) on 127.0.0.1"
        print(
            f"sweep {spec.name}: {len(todo)} run(s) to do, {res.skipped} already recorded; {where}; "
            f"dashboard: {res.dashboard or 'not served (pip install bokeh)'}",
            file=stream,
            flush=True,
        )
        # progress: the client's bar or lines, and each run's own lines in its worker's log
        tasks = [make_task(spec, r, out, threads, group, pictures, progress) for r in todo]
        futures = [
            client.submit(run_task, t, key=f"solidshell-{spec.name}-{t['key']}", retries=retries, pure=False)
            for t in tasks
        ]
        bar = _Progress(spec.n_runs, res.skipped, progress, stream)
        for fut in as_completed(futures):
            try:
                row = fut.result()
            except Exception as e:  # noqa: BLE001 - a lost run is reported, the sweep goes on
                key = fut.key.rsplit("-", 1)[-1]
                res.failed.append((key, " ".join(f"{type(e).__name__}: {e}".split())[:300]))
                bar.update(f"{key}: FAILED")
                continue
            if row.get("status") != "done":  # refused or stopped: recorded, but not a result
                res.failed.append((row["key"], row.get("error") or f"status {row.get('status')!r}"))
                ledger.append(row)
            elif ledger.append(row):
                res.recorded += 1
            bar.update(_label(row))
    except KeyboardInterrupt:
        res.interrupted = True
        for f in futures:
            f.cancel()
    finally:
        if bar is not None:
            bar.close()
        client.close()
        if cluster is not None:
            cluster.close()
        res.wall_time_s = time.perf_counter() - t0
    return res
