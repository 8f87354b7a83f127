"""Adaptive-mesh bookkeeping speed and quality (paper Sections 5.1-5.3): background construction,
split/merge and active_mesh() times on the paper's level-0 meshes, the transition patterns'
minimum angle and aspect ratio, and the curved-boundary area with averaged vs projected nodes.

    PYTHONPATH=. python benchmarks/adapt_mesh.py          (about half a minute)
"""

import time

import numpy as np

from solidshell.adapt import AdaptiveMesh, BackgroundMesh, boundary_area_report, circle_projector
from solidshell.adapt.transition import PATTERN_NAMES, TRANSITION_POLICIES, pattern_quality
from solidshell.meshing import build_mesh


def best_of(f, n=5):
    t = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        t.append(time.perf_counter() - t0)
    return min(t)


def random_half_refined(bg, seed=0):
    """Split a random half of the leaves, level after level (2:1 balance adds more)."""
    am = AdaptiveMesh(bg)
    rng = np.random.default_rng(seed)
    for _ in range(bg.levels):
        lv = am.leaves()
        am.split(lv[rng.random(len(lv)) < 0.5])
    return am


def timings():
    print("## active_mesh() timings (best of 5)\n")
    print(
        "| level-0 mesh | levels | state | leaves | elements (quads+tris) | nodes | build bg [s] | split+merge [s] | first active_mesh [s] | active_mesh [s] |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    cases = [
        ("square_on_square 6x2x4", build_mesh("square_on_square", "6x2x4", sheet=20, pedestal=10)),
        ("square 16x16", build_mesh("square", "16x16", size=30)),
    ]
    for name, m in cases:
        t_bg = best_of(lambda: BackgroundMesh.from_level0(m, 3), 3)
        bg = BackgroundMesh.from_level0(m, 3)
        for state in ("all level 3", "random half"):
            if state == "all level 3":
                am = AdaptiveMesh(bg)
                t_sm = best_of(lambda: (am.refine_all(), am.coarsen_all()), 3)
                am.refine_all()
            else:
                t_sm = best_of(lambda: random_half_refined(bg), 3)
                am = random_half_refined(bg)
            bg.__dict__.pop("_variants", None)
            t0 = time.perf_counter()
            am.active_mesh()  # first call also chooses the variants of the levels
            t_first = time.perf_counter() - t0
            t = best_of(am.active_mesh)
            a = am.active_mesh()
            print(
                f"| {name} | 3 | {state} | {am.n_leaves()} | {a.mesh.n_quads}+{a.mesh.n_tris} | "
                f"{a.mesh.n_nodes} | {t_bg:.4f} | {t_sm:.4f} | {t_first:.4f} | {t:.4f} |"
            )


def quality():
    print("\n## transition patterns: minimum angle [deg] / maximum aspect ratio (longest/shortest edge)\n")
    sq = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    m = build_mesh("square_on_square", "6x2x4", sheet=20, pedestal=10)
    trap = m.nodes[m.quads][:, :, :2]
    for policy in TRANSITION_POLICIES:
        qs, qt = pattern_quality(sq, policy), pattern_quality(trap, policy)
        per = [pattern_quality(trap[e : e + 1], policy) for e in range(len(trap))]
        worst = {pid: min(range(len(trap)), key=lambda e: per[e][pid][0]) for pid in qt}
        typical = {pid: float(np.median([q[pid][0] for q in per])) for pid in qt}
        print(f"\nadapt.transitions = {policy!r}\n")
        print(
            "| id | pattern | unit square | 6x2x4: worst parent and rotation | worst parent | 6x2x4: median over parents of the min angle |"
        )
        print("|---|---|---|---|---|---|")
        for pid in sorted(qs):
            print(
                f"| {pid} | {PATTERN_NAMES[pid]} | {qs[pid][0]:.1f} / {qs[pid][1]:.2f} | "
                f"{qt[pid][0]:.1f} / {qt[pid][1]:.2f} | {worst[pid]} | {typical[pid]:.1f} |"
            )


def areas():
    print("\n## curved boundaries: sheet area with averaged vs projected boundary mid-edge nodes\n")
    print("| mesh | levels | level 0 | averaged | projected | difference | exact | error averaged | error projected |")
    print("|---|---|---|---|---|---|---|---|---|")
    cases = [
        ("square_on_disc 4x32", build_mesh("square_on_disc", "4x32"), 10.0, 50.0**2 - np.pi * 10.0**2),
        ("disc_on_disc 10x40", build_mesh("disc_on_disc", "10x40"), (6.35, 12.7), np.pi * (12.7**2 - 6.35**2)),
    ]
    for name, m, r, exact in cases:
        proj = circle_projector((0, 0), r)
        for lv in (1, 3):
            a = boundary_area_report(m, lv, proj, exact)
            print(
                f"| {name} | {lv} | {a['level0']:.4f} | {a['averaged']:.4f} | {a['projected']:.4f} | "
                f"{a['difference']:+.4f} | {exact:.4f} | {a['error_averaged']:+.2e} | {a['error_projected']:+.2e} |"
            )


if __name__ == "__main__":
    timings()
    quality()
    areas()
