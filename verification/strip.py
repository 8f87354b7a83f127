"""Section 3.1: the 5x1 cm wool strip clamped at one end, drooping under its own weight.

Compares the solid-shell strip (warp- and weft-cut; the weft-cut strip is ``Fabric.wool(warp_angle=90)``)
with the heavy elastica of ``reference/elastica_strip.json`` (an ODE solved to 1e-10, independent of
the shell code) on meshes 10x1 ... 160x1; prints the tip deflection error, the observed convergence
rate, the side-view (x, z) shape error, the solver's iterations and time, and writes
``verification/out/strip_side_view.png`` (side view against the elastica, as Fig. 4b).

Run:  python verification/strip.py [--meshes 10 20 40 80 160] [--method newton|paper|arclength]
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from verification.checks.references import reference_dir
from verification.checks.strips import shape_error, solve_strip, strip_problem  # noqa: F401

HERE = os.path.dirname(os.path.abspath(__file__))
REF = str(reference_dir() / "elastica_strip.json")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=int, nargs="+", default=[10, 20, 40, 80, 160])
    ap.add_argument("--method", default="newton")
    ap.add_argument("--out", default=os.path.join(HERE, "out"))
    ap.add_argument("--no-plot", action="store_true")
    a = ap.parse_args(argv)
    with open(REF) as fh:
        ref = json.load(fh)["strip"]
    rows = []
    sols = {}
    print(
        f"strip 5x1 cm, wool, self-weight; reference: heavy elastica (tip z warp "
        f"{ref['warp']['tip_z']:.6f}, weft {ref['weft']['tip_z']:.6f} cm); solver {a.method}"
    )
    print(
        f"{'cut':5} {'mesh':>6} {'tip z [cm]':>12} {'rel err':>10} {'rate':>6} {'shape err':>10} "
        f"{'iters':>6} {'solves':>6} {'time [s]':>8}"
    )
    for cut in ("warp", "weft"):
        prev = None
        for n in a.meshes:
            sol = solve_strip(n, cut, a.method)
            sols[(cut, n)] = sol
            r = sol["result"]
            err = (sol["tip_z"] - ref[cut]["tip_z"]) / ref[cut]["tip_z"]
            rate = (
                np.log(abs(prev[1] / err)) / np.log(n / prev[0])
                if prev is not None and err != 0 and prev[1] != 0
                else float("nan")
            )
            se = shape_error(sol, ref[cut])
            rows.append(
                dict(
                    cut=cut,
                    mesh=f"{n}x1",
                    tip_z=sol["tip_z"],
                    rel_error=err,
                    rate=rate,
                    shape_error_cm=se,
                    converged=r.converged,
                    iterations=r.info["iterations"],
                    linear_solves=r.info["linear_solves"],
                    wall_time_s=sol["wall"],
                )
            )
            print(
                f"{cut:5} {n:>4}x1 {sol['tip_z']:12.6f} {err:10.2e} {rate:6.2f} {se:10.2e} "
                f"{r.info['iterations']:6d} {r.info['linear_solves']:6d} {sol['wall']:8.2f}"
                + ("" if r.converged else "  NOT CONVERGED: " + r.message),
                flush=True,
            )
            prev = (n, err)
    # Richardson: e(h) = e_inf + C h^p from the three finest meshes (doubling).  e_inf is what the
    # shell converges to minus the elastica: the model difference (the shell stretches -- tensile
    # rigidity 1118 gf/cm --, its director stretches -- E_z --, and it has a thickness), not a
    # discretisation error.
    for cut in ("warp", "weft"):
        e = [r_["rel_error"] for r_ in rows if r_["cut"] == cut]
        if len(e) >= 3 and a.meshes[-1] == 2 * a.meshes[-2] == 4 * a.meshes[-3]:
            d1, d2 = e[-3] - e[-2], e[-2] - e[-1]
            if d1 * d2 > 0:
                p_ = np.log2(d1 / d2)
                e_inf = e[-1] - d2 / (2**p_ - 1)
                print(
                    f"{cut}: Richardson from the three finest meshes: order p = {p_:.2f}, "
                    f"limit error e_inf = {e_inf:.2e} (shell model vs inextensible elastica)"
                )
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "strip_refinement.json"), "w") as fh:
        json.dump(rows, fh, indent=1)
    if not a.no_plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7.5, 5.5))
        for cut, col in (("warp", "C0"), ("weft", "C3")):
            ax.plot(ref[cut]["curve"]["x"], ref[cut]["curve"]["z"], "-", color=col, lw=2, label=f"{cut}: elastica")
            for n, mk in zip(a.meshes[:2], ("o", "s")):
                sol = sols[(cut, n)]
                ax.plot(sol["cx"], sol["cz"], mk, color=col, mfc="none", ms=5, label=f"{cut}: {n}x1 solid-shell")
        ax.set_aspect("equal")
        ax.set_xlabel("x [cm]")
        ax.set_ylabel("z [cm]")
        ax.set_title("5x1 cm wool strip under self-weight (side view)")
        ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.02, 0.5))
        ax.grid(alpha=0.3)
        fig.tight_layout()
        png = os.path.join(a.out, "strip_side_view.png")
        fig.savefig(png, dpi=120)
        print(f"wrote {png}")
    return rows


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
