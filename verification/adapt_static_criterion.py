"""Which mesh does the split criterion of Eq. (25) ask for at the drape's equilibrium, and how far is
the drape on that mesh from the uniform fine mesh's?

The §6 comparison asks the adaptive relaxation for the uniform mesh's drape coefficient within 1 %
on at most half its nodes.  A relaxation mixes two questions: whether the run has settled, and
whether the mesh it settled on is fine enough.  This study answers the second one alone, with the
static solver: from the level-0 mesh, solve, mark by Eq. (25), split (2:1 balanced, transition
patterns, DK transfer of the state: the driver's own pieces), solve again from the transferred state,
until Eq. (25) asks for no split.  No merges: Eq. (26) only undoes splits a moving sheet no longer
needs.  The end mesh is the one a relaxation settling with these constants keeps, at most.

    PYTHONPATH=. python verification/adapt_static_criterion.py [--scene square-pedestal]
        [--level0 6x2x4] [--uniform 48x16x4] [--const 0.5 0.3 0.2] [--membrane scene coarse-ans]

Writes ``verification/out/adapt_static_criterion.md`` / ``.json``: per const and membrane choice,
the final active nodes (and their share of the uniform mesh's), DC, folds, and the DC difference
to the uniform mesh solved the same way.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from solidshell import analysis
from solidshell.adapt.background import BackgroundMesh
from solidshell.adapt.criteria import DEFAULT_EPS, leaf_bending_strain, level_side_lengths, mark
from solidshell.adapt.forest import AdaptiveMesh
from solidshell.adapt.transfer import to_new_mesh
from solidshell.run.summary import pedestal_area
from solidshell.scenes import load
from solidshell.scenes.build import build_problem, build_scene_mesh
from solidshell.solvers.static import solve_static

OUT = Path(__file__).resolve().parent / "out"
MEMBRANE_LABEL = {"scene": "scene membrane (full)", "coarse-ans": "ans below the finest level"}


def membranes(choice, act, levels, scene_membrane):
    """The quads' membranes: the scene's everywhere ("scene"), or "ans" below the finest level
    ("coarse-ans") or below level K ("ans-below-K")."""
    if choice == "scene":
        return None
    below = levels if choice == "coarse-ans" else int(choice.rsplit("-", 1)[1])
    coarse = act.elem_leaf[: len(act.mesh.quads), 0] < below
    return np.where(coarse, "ans", scene_membrane).tolist()


def solve(sc, mesh, membrane, U0=None):
    pb = build_problem(sc, mesh, membrane=membrane)
    r = solve_static(pb.model, pb.fixed, pb.loads, U0=U0, contact=pb.contact)
    d = analysis.drape_summary(mesh, r.U, pedestal_area=pedestal_area(sc) or 0.0)
    return pb, r, d


def refine_to_equilibrium(sc, level0, levels, const, choice, max_rounds=8):
    """The static solve-mark-split loop; returns the rows of every round."""
    bg = BackgroundMesh.from_level0(level0, levels)
    L = level_side_lengths(bg)
    forest = AdaptiveMesh(bg)
    act, U, rows = forest.active_mesh(), None, []
    for k in range(max_rounds):
        t = time.perf_counter()
        pb, r, d = solve(sc, act.mesh, membranes(choice, act, levels, sc.model["membrane"]), U)
        eb = pb.model.bending_strain(r.U)
        leaves, eb_leaf = leaf_bending_strain(eb, act.elem_leaf)
        marks = mark(eb_leaf, leaves, L, const, min(DEFAULT_EPS, 0.5 * const), max_level=levels)
        rows.append(
            dict(
                round=k,
                nodes=int(act.mesh.n_nodes),
                elements=int(act.mesh.n_elements),
                converged=bool(r.converged),
                dc=float(d["drape_coefficient"]),
                folds=d.get("fold_count"),
                splits=int(marks.split.sum()),
                iterations=r.info.get("iterations"),
                seconds=time.perf_counter() - t,
            )
        )
        print(
            f"  const {const} {choice} round {k}: {act.mesh.n_nodes} nodes, DC {d['drape_coefficient']:.4f}, "
            f"{d.get('fold_count')} folds, {int(marks.split.sum())} splits asked",
            flush=True,
        )
        if not marks.split.any():
            break
        old = act
        forest.split(leaves[marks.split])
        act = forest.active_mesh()
        U = to_new_mesh(bg, r.U, old.nodes, act.nodes, "dk").reshape(-1, 6)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="square-pedestal")
    ap.add_argument("--level0", default="6x2x4")
    ap.add_argument("--uniform", default="48x16x4")
    ap.add_argument("--levels", type=int, default=3)
    ap.add_argument("--const", type=float, nargs="*", default=[0.5, 0.3, 0.2])
    ap.add_argument(
        "--membrane",
        nargs="*",
        default=["scene", "coarse-ans"],
        help="scene | coarse-ans | ans-below-K (quads of levels < K get ans membranes)",
    )
    ap.add_argument("--out", default=str(OUT))
    a = ap.parse_args(argv)
    sc = load(a.scene)
    level0, _ = build_scene_mesh(sc, a.level0)
    uni, _ = build_scene_mesh(sc, a.uniform)
    t = time.perf_counter()
    _, ru, du = solve(sc, uni, None)
    uniform = dict(
        mesh=a.uniform,
        nodes=int(uni.n_nodes),
        dc=float(du["drape_coefficient"]),
        folds=du.get("fold_count"),
        seconds=time.perf_counter() - t,
    )
    print(f"uniform {a.uniform}: {uni.n_nodes} nodes, DC {uniform['dc']:.4f}, {uniform['folds']} folds", flush=True)
    cases = []
    for choice in a.membrane:
        for c in a.const:
            rows = refine_to_equilibrium(sc, level0, a.levels, c, choice)
            cases.append(dict(const=c, membrane=choice, rounds=rows))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    doc = dict(scene=a.scene, level0=a.level0, levels=a.levels, uniform=uniform, cases=cases, load=os.getloadavg())
    (out / "adapt_static_criterion.json").write_text(json.dumps(doc, indent=1))
    lines = [
        f"# Eq. (25) at the static equilibrium: {a.scene}, level 0 {a.level0}, {a.levels} levels",
        "",
        f"`PYTHONPATH=. python verification/adapt_static_criterion.py` (load {os.getloadavg()[0]:.1f}). "
        f"Uniform {a.uniform} (scene membrane, static): {uniform['nodes']} nodes, DC {uniform['dc']:.4f}, "
        f"{uniform['folds']} folds.",
        "",
        "| const | quad membranes | rounds | end nodes (share) | DC (vs uniform) | folds |",
        "|---|---|---|---|---|---|",
    ]
    for case in cases:
        end = case["rounds"][-1]
        lines.append(
            f"| {case['const']} | {MEMBRANE_LABEL.get(case['membrane'], case['membrane'])} | "
            f"{len(case['rounds'])} | {end['nodes']} ({end['nodes'] / uniform['nodes']:.2f}) | "
            f"{end['dc']:.4f} ({(end['dc'] - uniform['dc']) / uniform['dc']:+.1%}) | {end['folds']} |"
        )
    (out / "adapt_static_criterion.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
