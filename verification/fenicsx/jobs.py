"""Venv side: solidshell meshes and sections -> DOLFINx job files; running the DOLFINx model.

The DOLFINx model (``model.py``) runs under the system python3 in a subprocess; the two sides share
nothing but the JSON files written here (job) and by the model (result).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
MODEL = HERE / "model.py"
SYSTEM_PYTHON = os.environ.get("SOLIDSHELL_FENICSX_PYTHON", "/usr/bin/python3")


class DolfinxMissing(RuntimeError):
    """DOLFINx cannot be imported by the system python (one-line message)."""


def check_dolfinx(python: str = SYSTEM_PYTHON) -> str:
    """The DOLFINx version under ``python``; raises DolfinxMissing with a one-line reason."""
    if not (os.path.isfile(python) and os.access(python, os.X_OK)):
        raise DolfinxMissing(f"DOLFINx not available: no system python at {python}")
    try:
        p = subprocess.run(
            [python, "-c", "import dolfinx, sys; sys.stdout.write(dolfinx.__version__)"],
            capture_output=True,
            text=True,
            timeout=120,
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise DolfinxMissing(f"DOLFINx not available: {python} could not run ({exc.__class__.__name__})") from None
    if p.returncode != 0:
        raise DolfinxMissing(
            f"DOLFINx not available under {python} (import dolfinx failed); "
            f"install it with verification/fenicsx/install_and_run.sh"
        )
    return p.stdout.strip()


def mesh_dict(mesh) -> dict:
    """A solidshell ShellMesh as plain lists (nodes, quads, tris, node sets)."""
    return {
        "nodes": np.asarray(mesh.nodes, dtype=float).tolist(),
        "quads": np.asarray(mesh.quads, dtype=int).tolist() if mesh.quads is not None else [],
        "tris": np.asarray(mesh.tris, dtype=int).tolist() if mesh.tris is not None and len(mesh.tris) else [],
        "node_sets": {k: np.asarray(mesh.node_set(k), dtype=int).tolist() for k in mesh.node_sets},
    }


def section_dict(mat) -> dict:
    """The rigidities of a solidshell section (one source of truth: solidshell.material)."""
    return {
        "C_m": np.asarray(mat.C_m).tolist(),
        "C_b": np.asarray(mat.C_b).tolist(),
        "C_t": np.asarray(mat.C_t).tolist(),
        "warp_angle_rad": float(mat.warp_angle_rad),
        "weight_per_area": float(mat.weight_per_area),
    }


def make_job(name, mesh, mat, clamped="clamped", gravity=True, line_load=None, **extra) -> dict:
    job = {
        "name": name,
        "mesh": mesh_dict(mesh),
        "section": section_dict(mat),
        "clamped": clamped,
        "gravity": bool(gravity),
    }
    if line_load is not None:
        job["line_load"] = line_load
    job.update(extra)
    return job


def run_model(
    job: dict, work_dir, ranks: int = 1, timeout: float = 3600.0, python: str = SYSTEM_PYTHON, reuse: bool = False
) -> dict:
    """Write the job, run model.py (under mpirun for ranks > 1), read the result.

    ``reuse``: return the stored converged result of an identical job in ``work_dir`` instead.

    Returns the result dict plus ``process_wall_time_s`` (including JIT compilation and MPI start)
    and ``log`` (the model's stdout/stderr tail).  A failed process gives converged=False with its
    last stderr line in ``status``.
    """
    work = Path(work_dir)
    work.mkdir(parents=True, exist_ok=True)
    tag = f"{job['name']}-np{ranks}"
    jp, rp = work / f"{tag}.job.json", work / f"{tag}.result.json"
    if reuse and jp.exists() and rp.exists() and json.loads(jp.read_text()) == json.loads(json.dumps(job)):
        # the same job already solved in this work directory (crosscheck --reuse): its result
        res = json.loads(rp.read_text())
        if res.get("converged"):
            res.update(reused=True, process_wall_time_s=float("nan"), log=[])
            return res
    jp.write_text(json.dumps(job))
    if rp.exists():
        rp.unlink()
    cmd = [python, str(MODEL), str(jp), str(rp)]
    if ranks > 1:
        mpirun = shutil.which("mpirun") or "/usr/bin/mpirun"
        cmd = [mpirun, "--allow-run-as-root", "--oversubscribe", "-n", str(ranks)] + cmd
    env = dict(os.environ, OMP_NUM_THREADS="1")
    # the model's output goes to the log files as it runs, so an hour-long drape can be watched
    lp, ep = work / f"{tag}.log", work / f"{tag}.stderr.log"
    t0 = time.perf_counter()
    with open(lp, "w") as fo, open(ep, "w") as fe:
        try:
            rc = subprocess.run(cmd, stdout=fo, stderr=fe, text=True, timeout=timeout, env=env).returncode
            err = ""
        except subprocess.TimeoutExpired:
            rc, err = -1, f"timed out after {timeout:.0f} s"
    wall = time.perf_counter() - t0
    out = lp.read_text()
    err = (ep.read_text() + "\n" + err).strip()
    log = (out + "\n" + err).strip().splitlines()[-8:]
    if rp.exists():
        res = json.loads(rp.read_text())
    else:
        last = next((ln for ln in reversed(err.strip().splitlines()) if ln.strip()), f"exit {rc}")
        res = {"converged": False, "status": f"model process failed (exit {rc}): {last}"}
    res["process_wall_time_s"] = wall
    res["log"] = log
    return res


if __name__ == "__main__":  # a quick manual check: python -m verification.fenicsx.jobs
    try:
        print(check_dolfinx())
    except DolfinxMissing as exc:
        print(exc, file=sys.stderr)
        sys.exit(3)
