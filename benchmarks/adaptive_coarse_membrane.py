"""Wall time of an adaptive relaxation with the assumed membrane on the coarse quads against the
scene's (compatible) membrane: the cost of ``adapt.coarse_membrane = "ans"`` end to end.

    NUMBA_NUM_THREADS=1 python benchmarks/adaptive_coarse_membrane.py [--scene square-pedestal]
        [--t-max 0.5] [--passes 2] [--set KEY=VALUE ...]

Runs, interleaved in one process (so that the machine's load falls on all alike), per pass:
``scene`` (every quad the scene's membrane), ``ans`` (quads below the finest level "ans", their
forces by the lane kernel elements/lanes_ans.py) and ``ans-core`` (the same run with the ans blocks
through core.energy_force, the explicit solver's path before lanes_ans, by switching
lanes_ans.covers off).  Prints steps, simulated time reached, maximum active nodes, drape
coefficient, wall time, wall time per step and per step and active node, and the ratios to
``scene``, with the load average.  ``ans`` and ``ans-core`` must reach the same state to round-off
(their DC is printed to 6 digits).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

from solidshell import run_scene
from solidshell.elements import lanes_ans
from solidshell.scenes import parse_overrides


def one(scene, variant, t_max, extra, folder):
    over = {"solver.relax.t_max": t_max, "output.pictures": [], "output.snapshots": [], **extra}
    if variant != "scene":
        over["adapt.coarse_membrane"] = "ans"
    covers = lanes_ans.covers
    if variant == "ans-core":
        lanes_ans.covers = lambda c: False
    try:
        t = time.perf_counter()
        out = run_scene(
            scene, solver="relax", out_dir=folder, progress=False, overrides=over, adaptive=True, force=True
        )
        wall = time.perf_counter() - t
    finally:
        lanes_ans.covers = covers
    s = out.summary
    return dict(
        wall=wall,
        steps=s.get("steps"),
        t=s.get("t_final"),
        nodes=s.get("max_active_nodes"),
        dc=s.get("drape_coefficient"),
        status=out.result.info.get("status"),
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="square-pedestal")
    ap.add_argument("--t-max", type=float, default=0.5)
    ap.add_argument("--passes", type=int, default=2)
    ap.add_argument("--variants", default="scene,ans,ans-core")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args(argv)
    extra = parse_overrides(args.set)
    import numba

    with tempfile.TemporaryDirectory() as tmp:
        for p in range(args.passes):
            print(
                f"pass {p + 1}: {args.scene}, relax to t_max = {args.t_max} s, numba threads "
                f"{numba.config.NUMBA_NUM_THREADS}, load average {os.getloadavg()}",
                flush=True,
            )
            rows = {}
            for v in args.variants.split(","):
                rows[v] = r = one(args.scene, v, args.t_max, extra, os.path.join(tmp, v))
                per = r["wall"] / max(r["steps"], 1)
                print(
                    f"  {v:9s} {r['status']:>12s} steps {r['steps']:6d} t {r['t']:.4f} s  max nodes "
                    f"{r['nodes']:5d}  DC {r['dc']:.6f}  wall {r['wall']:6.1f} s  {per * 1e3:6.3f} ms/step  "
                    f"{per / r['nodes'] * 1e6:5.2f} us/step/node",
                    flush=True,
                )
            if "scene" in rows:
                base = rows["scene"]
                for v, r in rows.items():
                    if v != "scene":
                        print(
                            f"  {v} / scene: wall {r['wall'] / base['wall']:.2f}, per step "
                            f"{r['wall'] / r['steps'] / (base['wall'] / base['steps']):.2f}"
                        )
            print(f"  load average after the pass {os.getloadavg()}", flush=True)


if __name__ == "__main__":
    main()
