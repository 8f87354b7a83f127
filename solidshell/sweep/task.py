"""One sweep run, as a Dask task: ``run_task(task) -> row`` (a dict of ledger columns).

The task runs ``solidshell.runner.run_scene`` in the worker's process, writes the run's folder
(``OUT/runs/<key>``: summary.json, result.vtu, top.png, ...) and returns the row the client records.
It limits the process to ``threads`` threads (numba's kernels and BLAS) so that N single-threaded
workers use N cores, which is what the speed-up of a sweep rests on.

A run refused by its own checks (InputError) or stopped by its solver (SolverError) is recorded
but counted as failed: its row says ``status = "error"`` with the one-line reason, a resumed sweep
does not repeat it, and ``solidshell sweep`` names it and exits 1.
Anything else (a bug, a lost worker) propagates, and Dask retries the task.
"""

from __future__ import annotations

import json
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from .ledger import PROFILE_POINTS

__all__ = ["run_task", "make_task", "row_from_output"]


def make_task(spec, run, out, threads: int = 1, group: str = "C1", pictures=("top",)) -> dict:
    """The plain-data task of a run (pickled to the worker)."""
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

    t0, c0 = time.perf_counter(), time.process_time()
    over = {"output.pictures": task["pictures"], **task["overrides"]}
    with _limit_threads(task["threads"]):
        try:
            out = run_scene(
                task["scene"],
                mesh=task["mesh"],
                solver=task["solver"],
                out_dir=task["run_dir"],
                progress=False,
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
    row = row_from_output(task, out, time.perf_counter() - t0)
    row["cpu_time_s"] = time.process_time() - c0  # all threads of the worker process
    row["finished_at"] = _now()
    return row


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")
