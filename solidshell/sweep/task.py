"""One sweep run, as a Dask task: ``run_task(task) -> row`` (a dict of ledger columns).

The task runs ``solidshell.runner.run_scene`` in the worker's process, writes the run's folder
(``OUT/runs/<key>``: summary.json, result.vtu, top.png, ...) and returns the row the client records.
It limits the process to ``threads`` threads (numba's kernels and BLAS) so that N single-threaded
workers use N cores, which is what the speed-up of a sweep rests on.

Its progress goes to the worker's log: a ``logging`` line every SOLIDSHELL_PROGRESS_INTERVAL
seconds (10 by default; solidshell.run.progress) with the run's index, varied settings and key, the
fraction done, elapsed time, ETA and the solver's figures (step, t, E_kin, residual).  On a Dask
worker the lines are handed to the worker's own logger ("distributed.worker"), so they print where
the worker logs (a ``dask worker``'s stderr; a LocalCluster's, the console of the sweep) and come
back with ``Client.get_worker_logs()``; elsewhere they print on stderr unless a handler takes them.
A run shorter than the interval logs nothing.  ``solidshell sweep --no-progress`` turns them off.

A run refused by its own checks (InputError) or stopped by its solver (SolverError) is recorded
but counted as failed: its row says ``status = "error"`` with the one-line reason, a resumed sweep
does not repeat it, and ``solidshell sweep`` names it and exits 1.
Anything else (a bug, a lost worker) propagates, and Dask retries the task.
"""

from __future__ import annotations

import json
import logging
import time
from contextlib import nullcontext
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from .ledger import PROFILE_POINTS

__all__ = ["run_task", "make_task", "row_from_output"]


def run_label(spec, run) -> str:
    """``run <index> (<its varied settings>) [key <key>]``: which entry of the sweep a run is."""
    varied = {k: v for k, v in run.inputs().items() if k in spec.axes}
    what = ", ".join(f"{k}={v}" for k, v in varied.items())[:120]
    return f"run {run.index}" + (f" ({what})" if what else "") + f" [key {run.key}]"


def make_task(spec, run, out, threads: int = 1, group: str = "C1", pictures=("top",), progress: bool = True) -> dict:
    """The plain-data task of a run (pickled to the worker); ``progress``: log its progress lines."""
    return {
        "key": run.key,
        "index": run.index,
        "case": run.case,
        "sweep": spec.name,
        "scene": spec.scene,
        "mesh": run.mesh,
        "solver": run.solver,
        "overrides": dict(run.overrides),
        "run_dir": str((Path(out) / "runs" / run.key).resolve()),
        "threads": int(threads),
        "group": group,
        "pictures": list(pictures),
        "label": f"sweep {spec.name} {run_label(spec, run)}",
        "progress": bool(progress),
    }


def _limit_threads(n: int):
    """Numba's kernel threads and BLAS/OpenMP pools of this process to n (returns a context)."""
    try:
        import numba

        numba.set_num_threads(max(1, min(n, numba.config.NUMBA_NUM_THREADS)))
    except (ImportError, ValueError):
        pass
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=n)


def _worker_address() -> str:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return "local"


class _WorkerLog(logging.Handler):
    """Records handed to the Dask worker's own logger, "distributed.worker": its handlers print
    them where the worker logs and keep them for Client.get_worker_logs() (its deque)."""

    def emit(self, record):
        logging.getLogger("distributed.worker").handle(record)


def _worker_handlers() -> tuple:
    """(_WorkerLog(),) inside a Dask worker, else ()."""
    try:
        from distributed import get_worker

        get_worker()
    except (ImportError, ValueError):
        return ()
    return (_WorkerLog(),)


def _shown(task: dict):
    """The context in which the run's progress lines reach the worker's log (module docstring)."""
    from ..run import progress

    return progress.visible(_worker_handlers()) if task.get("progress") else nullcontext()


def row_from_output(task: dict, out, wall: float) -> dict:
    """The ledger row of a finished run_scene output."""
    from .. import analysis
    from .states import fingerprint

    s = out.summary
    kind = s.get("solver")
    row = _base_row(task, s.get("scene"), s.get("mesh"), kind)
    stable = s.get("positive_definite") if kind == "static" else s.get("steady_state_reached")
    if kind == "explicit":
        stable = None
    row.update(
        {
            "status": "done",
            "converged": bool(s.get("converged")),
            "solver_status": s.get("status"),
            "stable": None if stable is None else bool(stable),
            "min_tangent_eigenvalue": s.get("min_tangent_eigenvalue"),
            "residual": s.get("final_relative_residual"),
            "drape_coefficient": s.get("drape_coefficient"),
            "fold_count": s.get("fold_count"),
            "fold_angles_deg": s.get("fold_angles_deg"),
            "mean_radius": s.get("mean_radius"),
            "interpenetrated_nodes": s.get("interpenetrated_nodes"),
            "nodes": s["counts"]["nodes"],
            "elements": s["counts"]["elements"],
            "wall_time_s": wall,
        }
    )
    if s.get("center") is not None and s.get("finite"):
        poly = analysis.projected_boundary(out.mesh, out.U)
        _, r = analysis.radius_profile(poly, s["center"], PROFILE_POINTS)
        row["radius_profile"] = [float(x) for x in r.astype(np.float32)]
    row["fingerprint"] = fingerprint(row["fold_count"], row["fold_angles_deg"], row["drape_coefficient"], task["group"])
    return row


def _base_row(task, scene, mesh, solver) -> dict:
    row = {
        "key": task["key"],
        "index": task["index"],
        "case": task["case"],
        "sweep": task["sweep"],
        "scene": scene,
        "mesh": mesh,
        "solver": solver,
        "symmetry": task["group"],
        "inputs": json.dumps({"mesh": task["mesh"], "solver": task["solver"], **task["overrides"]}, sort_keys=True),
        "run_dir": task["run_dir"],
        "worker": _worker_address(),
    }
    row.update(task["overrides"])
    return row


def run_task(task: dict) -> dict:
    """Run one sweep run (see the module docstring); returns its ledger row."""
    from ..errors import InputError, SolverError
    from ..run import run_scene
    from ..run.progress import _Lines

    t0, c0 = time.perf_counter(), time.process_time()
    over = {"output.pictures": task["pictures"], **task["overrides"]}
    with _limit_threads(task["threads"]), _shown(task):
        lines = _Lines(task.get("label") or f"run [key {task['key']}]") if task.get("progress") else None
        try:
            out = run_scene(
                task["scene"],
                mesh=task["mesh"],
                solver=task["solver"],
                out_dir=task["run_dir"],
                progress=lines or False,
                overrides=over,
                force=True,
            )
        except (InputError, SolverError) as e:
            row = _base_row(task, None, task["mesh"], task["solver"])
            row.update(
                status="error",
                error=" ".join(f"{type(e).__name__}: {e}".split())[:500],
                wall_time_s=time.perf_counter() - t0,
            )
            row["finished_at"] = _now()
            return row
        finally:
            if lines is not None:
                lines.close()  # its "done" line, while the lines are still shown
    row = row_from_output(task, out, time.perf_counter() - t0)
    row["cpu_time_s"] = time.process_time() - c0  # all threads of the worker process
    row["finished_at"] = _now()
    return row


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")
