"""Work-precision of the static solvers on the Section 3.1 wool strip (warp-cut).

For each mesh n x 1 and each solver setting: tip-deflection error against the heavy elastica
(reference/elastica_strip.json), iterations, linear solves and wall time, and the wall time as a
ratio to the default solver on the same mesh measured in the same run (absolute times on a shared
machine are noisy; ratios inside one run are what to compare).

Run:  python benchmarks/static_strip.py [--meshes 10 20 40 80] [--json out.json]
Not part of the test run.
"""

from __future__ import annotations

import argparse
import json
import time

SETTINGS = [
    ("newton (default: trust region + shift)", dict(method="newton")),
    ("newton, Armijo line search", dict(method="newton", line_search="armijo")),
    ("paper Eq. 18, c = 1e-2", dict(method="paper", c=1e-2)),
    ("paper Eq. 18, c = 2e-2", dict(method="paper", c=2e-2)),
    ("arc-length (Crisfield)", dict(method="arclength")),
]


def main(argv=None):
    from verification.checks import references
    from verification.checks.strips import solve_strip

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=int, nargs="+", default=[10, 20, 40, 80])
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    ref = references.elastica_strip()["strip"]["warp"]["tip_z"]
    solve_strip(a.meshes[0], "warp")  # warm-up: numba compilation / cache load, not timed
    rows = []
    print(f"{'solver':42} {'mesh':>6} {'tip err':>9} {'iters':>6} {'solves':>6} {'time [s]':>8} {'x default':>9}")
    for n in a.meshes:
        t_default = None
        for name, kw in SETTINGS:
            t0 = time.perf_counter()
            sol = solve_strip(n, "warp", **kw)
            wall = time.perf_counter() - t0
            r = sol["result"]
            err = (sol["tip_z"] - ref) / ref
            t_default = wall if t_default is None else t_default
            rows.append(
                dict(
                    solver=name,
                    mesh=f"{n}x1",
                    rel_error=err,
                    converged=r.converged,
                    iterations=r.info["iterations"],
                    linear_solves=r.info["linear_solves"],
                    wall_time_s=wall,
                    time_ratio_to_default=wall / t_default,
                )
            )
            print(
                f"{name:42} {n:>4}x1 {err:9.2e} {r.info['iterations']:6d} "
                f"{r.info['linear_solves']:6d} {wall:8.2f} {wall / t_default:9.2f}"
                + ("" if r.converged else "  NOT CONVERGED"),
                flush=True,
            )
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return rows


if __name__ == "__main__":
    main()
