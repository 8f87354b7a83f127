"""The explicit loop's throughput with the face contact on, and the contact's share of a step.

The sphere scene (Sec. 4.2: 30 x 30 cm wool on a R = 5 cm sphere, friction 0.3, the scene's FIRE
relaxation) on an n x n mesh is first relaxed to its draped steady state, where the contact carries
the sheet over the whole cap and the folds press on the sphere's sides -- the contact's heaviest
load.  From that state three integrators take the same steps, interleaved in rounds so that all see
the same machine load: the scene's own (the sphere, nodes and face points, contact_faces.py, and
the self-contact, contact_self_penalty.py), the sphere without the self-contact, and neither.
Printed: element-steps per second of each (wall and CPU), the sphere's share of a step
1 - rate_sphere / rate_neither and the self-contact's 1 - rate_scene / rate_sphere (ratios inside
one run: shared machines distort them less than the absolute rates).  The load average is printed
with every pass.

    python benchmarks/contact_share.py [--n 60] [--steps 500] [--rounds 3] [--passes 2] [--threads 2]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np

from solidshell.run import run_scene
from solidshell.scenes import load
from solidshell.scenes.build import build_problem
from solidshell.solvers.explicit import Integrator, threads_for
from solidshell.solvers.explicit.settings import RELAX_PRESETS


def draped(n: int):
    """(the scene's problem, the same without self-contact, the same without bodies either, the
    relaxed steady state (N, 6)).  Without the sphere the sheet falls: the self-contact's candidate
    pairs are then re-selected every few steps, which the draped sheet at rest does not need, so the
    bodies' share is measured with the self-contact off on both sides and the self-contact's share
    against the same sphere."""
    out = run_scene("sphere", mesh=f"{n}x{n}", solver="relax", out_dir=None, progress=False)
    alone = build_problem(load("sphere"), out.mesh)
    alone.self_contact = False
    bare = build_problem(load("sphere"), out.mesh)
    bare.contact = []
    bare.self_contact = False
    return out.problem, alone, bare, np.asarray(out.U, float).reshape(out.mesh.n_nodes, 6), out.summary


def one_pass(prob, alone, bare, U, steps: int, rounds: int, threads: int | None) -> dict:
    s = {**RELAX_PRESETS["fast"], "U0": U, "max_steps": 10 * steps * rounds, "check_every": 10 * steps * rounds}
    with threads_for(prob, threads) as n_threads:  # the solver's own choice when threads is None
        integ = {
            "scene": Integrator(prob, s, relax=True),
            "contact": Integrator(alone, s, relax=True),
            "bare": Integrator(bare, s, relax=True),
        }
        for it in integ.values():
            it.advance(5)  # compile / warm
        wall = {k: [] for k in integ}
        cpu = {k: [] for k in integ}
        for _ in range(rounds):
            for k, it in integ.items():
                t, c = time.perf_counter(), time.process_time()
                it.advance(steps)
                wall[k].append(time.perf_counter() - t)
                cpu[k].append(time.process_time() - c)
    M = prob.model.mesh.n_elements
    rate = {k: M * steps / statistics.median(v) for k, v in wall.items()}
    rate_cpu = {k: M * steps / statistics.median(v) for k, v in cpu.items()}
    f = integ["contact"].forces
    return dict(
        elements=M,
        steps_per_round=steps,
        rounds=rounds,
        threads=int(n_threads),
        face_points=int(len(f.faces)) if f.faces is not None else 0,
        el_steps_per_s_scene=rate["scene"],
        el_steps_per_s_contact=rate["contact"],
        el_steps_per_s_bare=rate["bare"],
        el_steps_per_cpu_s_contact=rate_cpu["contact"],
        contact_share_wall=1.0 - rate["contact"] / rate["bare"],
        contact_share_cpu=1.0 - rate_cpu["contact"] / rate_cpu["bare"],
        self_contact_share_wall=1.0 - rate["scene"] / rate["contact"],
        loadavg=os.getloadavg(),
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=60, help="n x n mesh of the sphere scene (paper: 60, 100)")
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--threads", type=int, default=None, help="numba threads (default: the solver's choice)")
    ap.add_argument("--json", default=None, help="write the results here")
    a = ap.parse_args(argv)
    t = time.perf_counter()
    prob, alone, bare, U, summary = draped(a.n)
    print(
        f"sphere {a.n}x{a.n} relaxed in {time.perf_counter() - t:.1f} s: DC {summary['drape_coefficient']:.4f}, "
        f"{summary.get('max_contact_nodes')} nodes in contact at most",
        flush=True,
    )
    rows = []
    for i in range(a.passes):
        r = one_pass(prob, alone, bare, U, a.steps, a.rounds, a.threads)
        rows.append(r)
        print(
            f"pass {i + 1}: {r['elements']} elements, {r['face_points']} face points, {r['threads']} threads: "
            f"{r['el_steps_per_s_scene'] / 1e6:.2f} M element-steps/s as the scene runs (sphere + self-contact), "
            f"{r['el_steps_per_s_contact'] / 1e6:.2f} M with the sphere alone, {r['el_steps_per_s_bare'] / 1e6:.2f} M "
            f"with neither; the sphere's share {100 * r['contact_share_wall']:.1f} % (CPU "
            f"{100 * r['contact_share_cpu']:.1f} %), the self-contact's {100 * r['self_contact_share_wall']:.1f} %; "
            f"load average {' '.join(f'{x:.2f}' for x in r['loadavg'])}",
            flush=True,
        )
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
