"""What a relaxation's reported residual is made of (issue 36: Fig. 22's unexplained "last residual 988").

    NUMBA_NUM_THREADS=1 python -m verification.residual_probe SCENE OUT [--levels L] [--t-max T] [--every K]

runs SCENE adaptively on the paper's relaxation path (Rayleigh alpha = 5 1/s, all masses x100: what
paper_figures/_adaptive.py runs for Figs. 19-22; ``--levels`` as the figures' ``adapt.levels``, 0 =
the scene's) with its files written to OUT/run (so that verification/penetration_check.py and
self_check.py can read them), and at every K-th steady-state check (and every check of the last 300
steps) records in OUT/residual.json the quantities behind the steady test (solvers/explicit/
observers.steady): the relative residual |P - F + C|_free / |P|_free (dimensionless; R and P in the
scene's force unit, gf), E_kin / W_ext, |P|_free, the norm of R over the free translational dofs
(columns 0-2 of a node's six) and over the free director dofs (3-5), and the three nodes with the
largest |R| (their position, weight P and R split the same way).  The integrator is wrapped, not
changed: the run is the one the figure makes.

Measured with it (2026-12-05, sphere, 2 levels, t_max 15 s): R is the hanging corners' translational
out-of-balance force (the sheet still moving), the director dofs carry < 1e-3 of it after the passes
stop; a check at the first step after a remesh reads the transferred state (1.5-3x the check
before).  docs/verification.md, the Fig. 22 row.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

PAPER_PATH = dict(damping="rayleigh", alpha=5.0, mass_scaling=100.0, mass_scaling_mode="uniform")
"""The paper's relaxation path as paper_figures/_adaptive.py sets it."""


def breakdown(integ, n: int, vMv: float) -> dict:
    """The steady test's quantities at check step n of ``integ`` (an explicit Integrator whose
    residual buffer holds R = P - F + C of this step)."""
    st = integ.state
    R = np.zeros_like(integ._R)
    R[integ.free_idx] = integ._R[integ.free_idx]
    Rn = R.reshape(-1, 6)
    node = np.sqrt(np.einsum("ij,ij->i", Rn, Rn))
    X = np.asarray(integ.model.mesh.nodes, float) + st.D.reshape(-1, 6)[:, :3]
    P = np.asarray(integ.P).reshape(-1, 6)
    return dict(
        step=int(n),
        t=float(integ.time_of(n)),
        nodes=int(integ.N),
        rel_res=float(st.last_rel_res),
        rel_ke=float(st.last_rel_ke),
        P_free_norm=float(integ.Pn),
        R_translation=float(np.linalg.norm(Rn[:, :3])),
        R_director=float(np.linalg.norm(Rn[:, 3:])),
        kinetic=0.5 * float(vMv),
        top=[
            dict(node=int(i), x=X[i].tolist(), P=P[i, :3].tolist(), R_t=Rn[i, :3].tolist(), R_d=Rn[i, 3:].tolist())
            for i in np.argsort(node)[::-1][:3]
        ],
    )


def main(argv=None) -> int:
    from solidshell.run import run_scene
    from solidshell.solvers.explicit import integrator

    ap = argparse.ArgumentParser(prog="python -m verification.residual_probe", description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("out", type=Path)
    ap.add_argument("--levels", type=int, default=0, help="adapt.levels (0: the scene's)")
    ap.add_argument("--t-max", type=float, default=40.0, help="simulated end [s] (the figures': 40, --quick 15)")
    ap.add_argument("--every", type=int, default=1000, help="record every K-th step's check (default 1000)")
    a = ap.parse_args(argv)
    rows: list[dict] = []
    steady = integrator.Integrator._steady

    def recorded(self, n, vMv):
        r = steady(self, n, vMv)
        if n % a.every == 0 or self.end_step - n <= 300:
            rows.append(breakdown(self, n, vMv))
        return r

    integrator.Integrator._steady = recorded
    t0 = time.perf_counter()
    try:
        out = run_scene(
            a.scene,
            solver="relax",
            adaptive=True,
            out_dir=a.out / "run",
            progress=False,
            force=True,
            overrides={"adapt.levels": a.levels} if a.levels else None,
            t_max=a.t_max,
            **PAPER_PATH,
        )
    finally:
        integrator.Integrator._steady = steady
    s = out.summary
    head = {k: s.get(k) for k in ("message", "final_relative_residual", "drape_coefficient", "fold_count")}
    head["wall_s"] = round(time.perf_counter() - t0, 1)
    (a.out / "residual.json").write_text(json.dumps(dict(run=head, checks=rows), indent=1) + "\n")
    print(json.dumps(head))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
