"""Run the KratosMultiphysics worker (``kratos_shell.py``) from solidshell's Python.

Kratos lives in its own virtual environment so that it never touches the project's main one:

    python3.11 -m venv .venv-kratos && .venv-kratos/bin/pip install KratosMultiphysics KratosStructuralMechanicsApplication

The Python that runs Kratos is, in order: ``$SOLIDSHELL_KRATOS_PYTHON``; ``.venv-kratos/bin/python``
at the repository root; the current interpreter if it imports KratosMultiphysics.  When none has
Kratos, ``require_kratos`` prints one line saying so and exits with status 3.

The worker runs with OMP_NUM_THREADS=1: on a shared, overloaded 2-core machine Kratos' OpenMP
threads spin-wait and a 10-element strip took 38 s on 2 threads against 0.9 s on 1 (measured
here); solidshell's static solver is timed on its defaults in the same process for comparison.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
WORKER = os.path.join(HERE, "kratos_shell.py")
INSTALL = (
    "python3.11 -m venv .venv-kratos && .venv-kratos/bin/pip install KratosMultiphysics "
    "KratosStructuralMechanicsApplication"
)
MISSING_STATUS = 3


def _has_kratos(python: str) -> bool:
    try:
        r = subprocess.run(
            [python, "-c", "import KratosMultiphysics.StructuralMechanicsApplication"], capture_output=True, timeout=120
        )
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0


def find_kratos_python() -> str | None:
    """The first interpreter (see module docstring) that imports Kratos' structural application."""
    cands = [
        os.environ.get("SOLIDSHELL_KRATOS_PYTHON"),
        os.path.join(ROOT, ".venv-kratos", "bin", "python"),
        sys.executable,
    ]
    for c in cands:
        if c and os.path.exists(c) and _has_kratos(c):
            return c
    return None


def require_kratos() -> str:
    """The Kratos interpreter, or one line on stderr and exit status 3."""
    py = find_kratos_python()
    if py is None:
        print(f"KratosMultiphysics not found (set SOLIDSHELL_KRATOS_PYTHON or install it: {INSTALL})", file=sys.stderr)
        sys.exit(MISSING_STATUS)
    return py


def run_once(python: str, problem: dict, timeout: float = 3600.0) -> dict:
    """One worker run; the answer dict plus ``wall_process_s`` (start-up, import and solve)."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    t0 = time.perf_counter()
    r = subprocess.run(
        [python, WORKER], input=json.dumps(problem), capture_output=True, text=True, env=env, timeout=timeout
    )
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        tail = " | ".join(line for line in r.stderr.strip().splitlines()[-3:])
        raise RuntimeError(f"Kratos worker failed (status {r.returncode}): {tail}")
    out = json.loads(r.stdout)
    out["wall_process_s"] = wall
    return out


def run_kratos(python: str, problem: dict, steps=(1, 2, 4, 8, 16, 32, 64), verbose: bool = False) -> dict:
    """Solve with the fewest uniform load steps that converge, trying ``steps`` in turn (a failed
    Kratos Newton step cannot be rolled back from Python, so each try starts afresh).

    Returns the converged answer with ``attempts`` (steps tried, converged?, solve time) and
    ``wall_solve_total_s``, the solve time summed over all tries: what a user pays to find the
    working step count; ``wall_solve_s`` is the successful try alone."""
    attempts, total = [], 0.0
    out = None
    for s in steps:
        out = run_once(python, dict(problem, steps=s))
        total += out["wall_solve_s"]
        attempts.append(
            {
                "steps": s,
                "converged": out["converged"],
                "wall_solve_s": out["wall_solve_s"],
                "iterations": out["iterations"],
            }
        )
        if verbose:
            print(
                f"  Kratos {s} load step(s): {'converged' if out['converged'] else 'failed at step '}"
                f"{'' if out['converged'] else len(out['iterations'])}, {sum(out['iterations'])} Newton "
                f"iterations, {out['wall_solve_s']:.2f} s",
                file=sys.stderr,
                flush=True,
            )
        if out["converged"]:
            break
    out["attempts"] = attempts
    out["wall_solve_total_s"] = total
    return out
