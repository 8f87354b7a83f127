"""Fig. 6: a 25.4 cm wool disc draped over a 12.7 cm pedestal (paper §3.3), static.
(a) top and isometric views on 20x80 elements (the paper: four folds); (b) projected boundaries of
10x40 and 20x80; (c) another converged state on 20x80 with eight folds, which the paper obtains by
doubling the multiplier lambda of its iteration (Eqs. 16-18).  Here both states come from the
paper's scheme (solver.static.method = "paper"): (a) with c = 1e-3 (four folds) and (c) with
c = 1e-2, lambda x10: with lambda only doubled (c = 2e-3) the 10x40 run stays in the four-fold
state (measured by the quick run of this script, 2026-12-01), so doubling does not reproduce the
paper's switch here; c = 1e-2 reaches eight folds (verification/out/static_scenes.md), as does the
energy Newton from the flat start.  The fold counts reached are printed on the panels.  --quick:
10x40 (and 5x20 for (b)).

    python -m paper_figures.fig06 [--quick] [--out DIR]
"""

from __future__ import annotations

from pathlib import Path

from . import common

NAME = "fig06"
CAPTION = ("A circular fabric sheet draped over a circular pedestal. (a) The top and isometric views predicted "
           "by using a 20x80 mesh; (b) the deformed boundary projected to X-Y plane. (c) the top and isometric "
           "views of another convergent predictions by using the 20x80 mesh.")
C_A, C_C = 1e-3, 1e-2


def make(out_dir: Path, quick: bool = False) -> dict:
    fine, coarse = ("10x40", "5x20") if quick else ("20x80", "10x40")
    recs, bnd = [], {}
    runs = {}
    for key, m, c in (("a", fine, C_A), ("coarse", coarse, C_A), ("c", fine, C_C)):
        out, rec = common.run("circle-pedestal", mesh=m, solver="static",
                              overrides={"solver.static.method": "paper", "solver.static.c": c})
        rec["c"] = c
        recs.append(rec)
        runs[key] = (out, rec)
    for key in ("coarse", "a"):
        out, rec = runs[key]
        bnd[common.describe(rec)] = common.projected_boundary(out)
    rows = [(f"(a) {fine}, c = {C_A:g}: {runs['a'][1].get('fold_count')} folds", runs["a"][0],
             common.positions(runs["a"][0].mesh, runs["a"][0].U)),
            (f"(c) {fine}, c = {C_C:g}: {runs['c'][1].get('fold_count')} folds", runs["c"][0],
             common.positions(runs["c"][0].mesh, runs["c"][0].U))]
    fig, _ = common.views_figure(rows, boundaries=bnd, pedestal=runs["a"][0].scene.pedestal(),
                                 boundary_title="(b) projected boundaries")
    folds = (runs["a"][1].get("fold_count"), runs["c"][1].get("fold_count"))
    info = {"figure": NAME, "caption": CAPTION, "quick": quick, "runs": recs,
            "differs_from_paper": f"fold counts (a) {folds[0]}, (c) {folds[1]} (paper: 4 and 8); (c) uses lambda x10 (c = 1e-2), not x2: "
                                  "c = 2e-3 stays at 4 folds on 10x40; (b) has no experiment "
                                  "and no 30x120 S4R curve" + ("; quick: 10x40 / 5x20 instead of 20x80 / 10x40" if quick else "")}
    common.save(fig, out_dir, NAME, info, suptitle="Fig. 6  25.4 cm disc on a 12.7 cm pedestal (§3.3, static, the paper's scheme)")
    return info


if __name__ == "__main__":
    from .registry import script_main
    script_main(NAME)
