"""Dynamic relaxation (Section 4.2) of the paper's wool strip (Section 3.1) against the elastica.

The 5 x 1 cm wool strip clamped at one end, warp- and weft-cut, on the paper's 10x1 and 20x1 meshes,
relaxed to its steady state under its own weight by ``solvers.explicit.run_relax`` in three ways:

* ``paper``     Rayleigh damping alpha = 5 1/s, all masses x100 (the paper's settings);
* ``kinetic``   Cundall's kinetic damping, all masses x100;
* ``kin+dir``   kinetic damping with only the director masses scaled, x10^4 (the thickness mode no
                longer limits dt; a steady state does not depend on the masses).

The reference is the inextensible elastica of ``reference/elastica_strip.json`` (an ODE solved to
1e-10, independent of the shell code).  Printed: tip position error, steps, simulated time, wall
time -- so that the three ways are compared inside one run (ratios, not absolute times).

    python -m verification.dynamic_relaxation_strip      (about a minute and a half)
"""

from __future__ import annotations

import time

import numpy as np

from solidshell.solvers import explicit
from verification.checks.dynamics import TOL, VARIANTS  # noqa: F401
from verification.checks.dynamics import relax_strip_problem as strip

from . import REFERENCE, write_json


def main():
    import json

    ref = json.loads((REFERENCE / "elastica_strip.json").read_text())["strip"]
    rows = []
    print(
        f"{'cut':<5}{'mesh':>6} {'variant':<9}{'tip x':>10}{'tip z':>10}{'err x':>10}{'err z':>10}"
        f"{'steps':>8}{'t_sim':>8}{'wall s':>8}  status"
    )
    for cut in ("warp", "weft"):
        rx, rz = ref[cut]["tip_x"], ref[cut]["tip_z"]
        for nx in (10, 20):
            prob = strip(cut, nx)
            tip = np.isclose(prob.model.mesh.nodes[:, 0], 5.0)
            for name, s in VARIANTS.items():
                t0 = time.perf_counter()
                r = explicit.run_relax(prob, {**s, **TOL})
                wall = time.perf_counter() - t0
                x = (prob.model.mesh.nodes[tip, 0] + r.U[tip, 0]).mean()
                z = (prob.model.mesh.nodes[tip, 2] + r.U[tip, 2]).mean()
                i = r.info
                row = dict(
                    cut=cut,
                    mesh=f"{nx}x1",
                    variant=name,
                    settings=s,
                    tip_x=x,
                    tip_z=z,
                    error_x=x - rx,
                    error_z=z - rz,
                    steps=i["steps"],
                    t_sim=i["t_final"],
                    dt=i["dt"],
                    wall_s=wall,
                    steady=i["steady_state_reached"],
                    energy_balance_error=i["energy_balance_error"],
                    final_relative_residual=i["final_relative_residual"],
                    kinetic_resets=i["kinetic_resets"],
                )
                rows.append(row)
                print(
                    f"{cut:<5}{nx:>4}x1 {name:<9}{x:10.5f}{z:10.5f}{x - rx:+10.2e}{z - rz:+10.2e}{i['steps']:>8}"
                    f"{i['t_final']:8.3f}{wall:8.1f}  {'steady' if i['steady_state_reached'] else r.message}",
                    flush=True,
                )
    p = write_json(
        "dynamic_relaxation_strip", dict(reference="reference/elastica_strip.json", tolerances=TOL, rows=rows)
    )
    print(f"wrote {p}")


if __name__ == "__main__":
    main()
