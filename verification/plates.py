"""Square plate under uniform pressure: solid-shell centre deflection vs the Kirchhoff series.

The table printer over verification.checks.plates, where the computation and its description live.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from verification.checks.plates import (  # noqa: F401  (the computations live in the package)
    NU,
    A,
    centre_deflection,
    mitc3_plate,
    plate_bc,
    plate_buckling,
    square_plate_mesh,
    triangle_vs_mitc3,
)

from . import OUT, plate_reference, rate, write_json


def run(
    ns=(4, 8, 16, 32),
    kinds=("quad", "quad~", "tri", "trix"),
    supports=("clamped", "ss_hard", "ss_soft"),
    ratios=(100.0, 1000.0),
    verbose=True,
):
    refs = plate_reference()
    ref = refs["alpha"]
    exact = {"clamped": ref["clamped"], "ss_hard": ref["simply_supported"], "ss_soft": ref["simply_supported"]}
    c_mindlin = refs.get("mindlin_ss_shear_coefficient")
    rows = []
    if verbose:
        print(f"{'support':8s} {'mesh':5s} {'a/h':>6s} {'N':>3s} {'w_c D/(q a^4)':>14s} {'rel.err':>10s} {'rate':>6s}")
    for support in supports:
        for kind in kinds:
            for ah in ratios:
                prev = None
                for n in ns:
                    t0 = time.perf_counter()
                    w = centre_deflection(n, kind, support, ah)
                    err = (w - exact[support]) / exact[support]
                    r = rate(prev, err) if prev is not None else None
                    row = dict(
                        support=support,
                        mesh=kind,
                        a_over_h=ah,
                        n=n,
                        alpha=w,
                        exact=exact[support],
                        rel_error=err,
                        rate=r,
                        seconds=time.perf_counter() - t0,
                    )
                    if support == "ss_hard" and c_mindlin is not None:
                        wm = exact[support] + c_mindlin / ah**2  # hard SS Reissner-Mindlin plate
                        row.update(mindlin=wm, rel_error_vs_mindlin=(w - wm) / wm)
                    rows.append(row)
                    if verbose:
                        rs = "" if r is None else f"{r:6.2f}"
                        rm = row.get("rel_error_vs_mindlin")
                        ms = "" if rm is None else f"   vs Mindlin {rm:+.3e}"
                        print(f"{support:8s} {kind:5s} {ah:6.0f} {n:3d} {w:14.8f} {err:+10.3e} {rs:>6s}{ms}")
                    prev = err
    return rows


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
    for ax, support in zip(axes, ("clamped", "ss_hard", "ss_soft")):
        for kind, mk in (("quad", "o"), ("quad~", "D"), ("tri", "^"), ("trix", "s")):
            for ah, ls in ((100.0, "-"), (1000.0, "--")):
                sel = [r for r in rows if r["support"] == support and r["mesh"] == kind and r["a_over_h"] == ah]
                if not sel:
                    continue
                ax.loglog(
                    [A / r["n"] for r in sel],
                    [max(abs(r["rel_error"]), 1e-16) for r in sel],
                    ls,
                    marker=mk,
                    label=f"{kind}, a/h={ah:.0f}",
                )
        hh = np.array([A / 4, A / 32])
        ax.loglog(hh, 0.3 * (hh / hh[0]) ** 2, "k:", label="O(h^2)")
        ax.axhline(0.01, color="grey", lw=0.5)
        ax.set_title(support)
        ax.set_xticks([1 / 32, 1 / 16, 1 / 8, 1 / 4])
        ax.set_xticklabels(["1/32", "1/16", "1/8", "1/4"])
        ax.minorticks_off()
        ax.set_xlabel("element size / a")
        ax.grid(True, which="both", lw=0.3)
    axes[0].set_ylabel("|relative error of w_c| vs Kirchhoff series")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description="square plate vs Kirchhoff series")
    ap.add_argument("--quick", action="store_true", help="N = 4, 8, 16 only")
    args = ap.parse_args(argv)
    ns = (4, 8, 16) if args.quick else (4, 8, 16, 32)
    rows = run(ns=ns)
    mitc3 = triangle_vs_mitc3(ns=ns)
    buck = []
    print("Buckling of the SS square plate under uniaxial compression, k = N_cr a^2/(pi^2 D), a/h = 100:")
    for kind in ("quad", "tri"):
        for n in (4, 8, 16):
            b = plate_buckling(n, kind)
            buck.append(b)
            print(
                f"  {kind:5s} N={n:3d}  k = "
                + ", ".join(f"{v:.4f}" for v in b["k"])
                + "  rel.err "
                + ", ".join(f"{e:+.2e}" for e in b["rel_error"])
                + "  (ref 4, 6.25, 11.11)"
            )
    p = write_json(
        "plates",
        {
            "description": __doc__.splitlines()[0],
            "nu": NU,
            "a": A,
            "rows": rows,
            "triangle_vs_independent_mitc3": mitc3,
            "buckling": buck,
        },
    )
    OUT.mkdir(exist_ok=True)
    plot(rows, OUT / "plates.png")
    print("wrote", p, "and", OUT / "plates.png")
    bad = [
        r
        for r in rows
        if r["n"] == 32 and r["mesh"] in ("quad", "quad~") and r["support"] != "ss_soft" and abs(r["rel_error"]) > 0.01
    ]
    print("32x32 quads within 1%:", "yes" if not bad else f"NO ({len(bad)} cases)")
    return rows


if __name__ == "__main__":
    main()
