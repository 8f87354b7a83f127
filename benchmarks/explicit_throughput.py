"""Throughput of the explicit loop (Eq. 23): element-steps per second.

A wool sheet hung by two adjacent corners (Section 4.1) on n x n quads, gravity, alpha = 5 1/s; the
loop is timed for a fixed number of steps (the critical-step estimate is excluded: it is given).
Each size is timed ``--repeats`` times and the median is reported, and the whole measurement is run
twice (``--passes``) so that the spread between passes shows the machine's noise.  The element pass
alone (``FusedForces.element_pass``: the lane kernels and their scatter, what each step of the loop
runs) is timed the same way, so that the loop's own overhead is the ratio of
the two -- a ratio inside one run, which shared machines do not distort as much as absolute times.

    python benchmarks/explicit_throughput.py [--sizes 10 20 40] [--steps 300] [--threads 1]
    python benchmarks/explicit_throughput.py --compare --sizes 100 --steps 200 [--threads 2]

``--compare`` times, inside one process and interleaved in rounds (so both see the same machine
load), the loop with the fused lane-kernel path (solvers/explicit/fused.py) against the previous
path (Model.internal_force + scatter + kernels.central_step, still used for models without element
blocks), and prints the ratio and the largest relative difference of the states after the steps.
Run it from the repository root with ``PYTHONPATH=.`` when another checkout is installed in the
environment (the path of the imported package is printed first).
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np

from solidshell import Fabric
from solidshell.boundary import clamp, gravity_loads
from solidshell.meshing import build_mesh
from solidshell.model import Model
from solidshell.problem import Problem
from solidshell.solvers import explicit
from solidshell.solvers.explicit.fused import FusedForces


def hung_sheet(n: int, size: float = 20.0) -> Problem:
    """The Section 4.1 sheet: size x size cm wool, n x n quads, the two corners at y = +size/2 held
    (all six dofs), self-weight -- built from the library's scene pieces."""
    mesh = build_mesh("square", f"{n}x{n}", size=size)
    model = Model(mesh, Fabric.wool())
    return Problem(model, clamp(mesh, "hung"), gravity_loads(model), name=f"hung {n}x{n}")


def measure(n: int, steps: int, repeats: int, threads):
    prob = hung_sheet(n)
    m = prob.model
    U = np.zeros((m.n_nodes, 6))
    passes = FusedForces(m)
    passes.element_pass(U)  # compile / warm
    s0 = explicit.run(prob, {"t_end": 1e-5, "threads": threads})
    dtc = s0.info["critical_time_step"]
    loop, kern = [], []
    import numba

    old = numba.get_num_threads()
    for _ in range(repeats):
        r = explicit.run(
            prob, {"t_end": steps * 0.9 * dtc, "critical_time_step": dtc, "threads": threads, "sample_every": 100}
        )
        loop.append(r.info["element_steps_per_second"])
        numba.set_num_threads(r.info["threads"])
        t = time.perf_counter()
        for _ in range(steps):
            passes.element_pass(U)
        kern.append(m.mesh.n_elements * steps / (time.perf_counter() - t))
        numba.set_num_threads(old)
    return dict(
        elements=m.mesh.n_elements,
        steps=steps,
        threads=r.info["threads"],
        loop_element_steps_per_s=statistics.median(loop),
        kernel_element_evals_per_s=statistics.median(kern),
        loop_over_kernel=statistics.median(loop) / statistics.median(kern),
        critical_time_step_s=dtc,
        time_step_force_evals=s0.info["time_step_force_evals"],
    )


def compare(n: int, steps: int, rounds: int, threads):
    """Old vs fused loop on the n x n hung sheet, interleaved: (dict of medians, ratio, state diff)."""
    import os

    import numba

    from solidshell.solvers.explicit import Integrator

    prob = hung_sheet(n)
    dtc = explicit.run(prob, {"t_end": 1e-5, "threads": threads}).info["critical_time_step"]
    s = {"t_end": 10 * steps * rounds * dtc, "critical_time_step": dtc, "sample_every": 100}
    old = numba.get_num_threads()
    if threads:
        numba.set_num_threads(threads)
    integ = {"old": Integrator(prob, s), "fused": Integrator(prob, s)}
    integ["old"].forces.fused = None  # the previous path: model.internal_force + central_step
    for it in integ.values():
        it.advance(2)  # compile / warm
    wall = {k: [] for k in integ}
    cpu = {k: [] for k in integ}
    for _ in range(rounds):
        for k, it in integ.items():
            t, c = time.perf_counter(), time.process_time()
            it.advance(steps)
            wall[k].append(time.perf_counter() - t)
            cpu[k].append(time.process_time() - c)
    numba.set_num_threads(old)
    D = {k: it.state.D for k, it in integ.items()}
    diff = float(np.max(np.abs(D["fused"] - D["old"])) / np.max(np.abs(D["old"])))
    M = prob.model.mesh.n_elements
    rate = {k: M * steps / statistics.median(wall[k]) for k in integ}
    rate_cpu = {k: M * steps / statistics.median(cpu[k]) for k in integ}
    return dict(
        elements=M,
        steps_per_round=steps,
        rounds=rounds,
        threads=numba.get_num_threads() if not threads else threads,
        old_el_steps_per_s=rate["old"],
        fused_el_steps_per_s=rate["fused"],
        old_el_steps_per_cpu_s=rate_cpu["old"],
        fused_el_steps_per_cpu_s=rate_cpu["fused"],
        ratio_wall=rate["fused"] / rate["old"],
        ratio_cpu=rate_cpu["fused"] / rate_cpu["old"],
        state_rel_diff=diff,
        total_steps=integ["old"].state.step,
        loadavg=os.getloadavg(),
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 20, 40])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--threads", type=int, default=None, help="numba threads (default: solver's choice)")
    ap.add_argument("--json", default=None, help="write the results here")
    ap.add_argument("--compare", action="store_true", help="old vs fused loop, interleaved in one run")
    ap.add_argument("--rounds", type=int, default=5, help="--compare: interleaved rounds per pass")
    a = ap.parse_args(argv)
    import solidshell

    print(f"solidshell from {solidshell.__file__}", flush=True)
    out = []
    if a.compare:
        import os

        for p in range(a.passes):
            for n in a.sizes:
                print(f"load average before: {os.getloadavg()}", flush=True)
                r = compare(n, a.steps, a.rounds, a.threads)
                r["pass"] = p + 1
                out.append(r)
                print(
                    f"pass {p + 1}  {n}x{n} ({r['elements']} quads, {r['threads']} thr, {r['total_steps']} steps each): "
                    f"old {r['old_el_steps_per_s']:.3g} / fused {r['fused_el_steps_per_s']:.3g} el-steps/s "
                    f"(ratio {r['ratio_wall']:.2f}); per CPU-second old {r['old_el_steps_per_cpu_s']:.3g} / fused "
                    f"{r['fused_el_steps_per_cpu_s']:.3g} (ratio {r['ratio_cpu']:.2f}); max |D_fused - D_old| / "
                    f"max |D_old| = {r['state_rel_diff']:.2e}; load {r['loadavg'][0]:.1f}",
                    flush=True,
                )
        if a.json:
            with open(a.json, "w") as fh:
                json.dump(out, fh, indent=1)
        return
    for p in range(a.passes):
        for n in a.sizes:
            r = measure(n, a.steps, a.repeats, a.threads)
            r["pass"] = p + 1
            out.append(r)
            print(
                f"pass {p + 1}  {n:>3}x{n:<3} ({r['elements']:>5} quads, {r['threads']} thr): loop "
                f"{r['loop_element_steps_per_s']:.3g} el-steps/s, kernel {r['kernel_element_evals_per_s']:.3g} "
                f"el/s, loop/kernel {r['loop_over_kernel']:.2f}, dt_crit {r['critical_time_step_s']:.3g} s",
                flush=True,
            )
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(out, fh, indent=1)


if __name__ == "__main__":
    main()
