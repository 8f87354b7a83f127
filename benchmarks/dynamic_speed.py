"""Element-steps per second of the explicit loop (Eq. 23) at 2500 and 10000 quads.

A 20 x 20 cm wool sheet hung by two adjacent corners (Section 4.1) on 50x50 and 100x100 quads,
gravity, alpha = 5 1/s, no mass scaling; the loop (``explicit.run``) is timed for ``--steps`` steps
with the critical step given (its estimate is excluded), ``--repeats`` times, median reported; the
whole measurement is run ``--passes`` times (default 2) so that the spread shows the machine's
noise.  Each size is measured with 1 thread and with all numba threads (the machine's cores), and
the solver's default choice is said.  ``uptime`` is recorded before and after each pass: on a shared
machine the absolute figures are only as good as the load lets them be.  Target (issue 5): >= 1.5e6
element-steps/s on 2 cores.

    python benchmarks/dynamic_speed.py [--sizes 50 100] [--steps 200] [--repeats 3] [--passes 2]

Writes benchmarks/out/dynamic_speed.json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import time
from pathlib import Path

import numba

from solidshell import Fabric
from solidshell.boundary import clamp, gravity_loads
from solidshell.meshing import build_mesh
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers import explicit

OUT = Path(__file__).resolve().parent / "out"


def hung_sheet(n: int, size: float = 20.0) -> Problem:
    """The Section 4.1 sheet: size x size cm wool, n x n quads, the two corners at y = +size/2 held
    (all six dofs), self-weight -- built from the library's scene pieces."""
    mesh = build_mesh("square", f"{n}x{n}", size=size)
    model = Model(mesh, Fabric.wool())
    return Problem(model, clamp(mesh, "hung"), gravity_loads(model), name=f"hung {n}x{n}")


def uptime() -> str:
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True, timeout=5).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return " ".join(f"{x:.2f}" for x in os.getloadavg())


def measure(prob: Problem, dtc: float, steps: int, repeats: int, threads: int) -> dict:
    vals, walls = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        r = explicit.run(
            prob,
            {
                "t_end": steps * 0.9 * dtc,
                "critical_time_step": dtc,
                "threads": threads,
                "sample_every": 100,
                "recheck_every": 0,
            },
        )
        walls.append(time.perf_counter() - t0)
        vals.append(r.info["element_steps_per_second"])
    return dict(
        threads=threads,
        steps=r.info["steps"],
        element_steps_per_s=statistics.median(vals),
        all_repeats=vals,
        wall_s=walls,
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[50, 100])
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--json", default=str(OUT / "dynamic_speed.json"))
    a = ap.parse_args(argv)
    nthr = numba.config.NUMBA_NUM_THREADS
    probs, dtcs = {}, {}
    for n in a.sizes:
        probs[n] = hung_sheet(n)
        s0 = explicit.run(probs[n], {"t_end": 1e-6})  # compile, and the critical step
        dtcs[n] = s0.info["critical_time_step"]
    rows, loads = [], []
    for p in range(a.passes):
        loads.append(dict(pass_=p + 1, before=uptime()))
        for n in a.sizes:
            ne = probs[n].model.mesh.n_elements
            default = 1 if ne < explicit.SMALL_MESH_ELEMENTS else nthr
            for thr in sorted({1, nthr}):
                r = measure(probs[n], dtcs[n], a.steps, a.repeats, thr)
                r.update(pass_=p + 1, n=n, elements=ne, solver_default_threads=default, critical_time_step_s=dtcs[n])
                rows.append(r)
                print(
                    f"pass {p + 1}  {n}x{n} ({ne} quads) {thr} thread(s){' [default]' if thr == default else ''}: "
                    f"{r['element_steps_per_s']:.3g} element-steps/s (median of {a.repeats}: "
                    f"{', '.join(f'{v:.3g}' for v in r['all_repeats'])})",
                    flush=True,
                )
        loads[-1]["after"] = uptime()
        print(f"pass {p + 1} load: before [{loads[-1]['before']}]  after [{loads[-1]['after']}]", flush=True)
    res = dict(
        numba_threads=nthr,
        cpu_count=os.cpu_count(),
        target_element_steps_per_s=1.5e6,
        rows=rows,
        uptime=loads,
        date=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
    )
    Path(a.json).parent.mkdir(parents=True, exist_ok=True)
    with open(a.json, "w") as fh:
        json.dump(res, fh, indent=1)


if __name__ == "__main__":
    main()
