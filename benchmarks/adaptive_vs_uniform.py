"""Paper §6 against uniform meshes: each scene relaxed on its uniform fine mesh and adaptively from its
level-0 mesh (§5.5), the two runs back to back in one process so that their wall-time ratio is
measured under the same machine load.

    python benchmarks/adaptive_vs_uniform.py [--cases square-pedestal ...] [--out benchmarks/out]

Both runs use the same relaxation (kinetic damping, director masses x1e4 by default, or the
relaxation of ``--set solver.relax.preset=NAME`` alone; any ``--set solver.relax.KEY=VALUE``
applies to both).  Per case: the uniform mesh's node count, the
adaptive run's maximum active nodes and their ratio (the paper: "only half"), drape coefficient,
fold count, the most interpenetrated nodes at any sample, steps, wall time, the remeshing share and
the energy balance.  Writes ``adaptive_vs_uniform.json`` / ``.md`` (rewritten after every run) and
copies each run's pictures to ``<out>/adaptive_png/``; run folders go to ``runs/bench-adaptive/<tag>/``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import time
from pathlib import Path

from solidshell import run_scene
from solidshell.scenes import parse_overrides

CASES = {  # scene: (uniform mesh of the paper's comparison, level-0 mesh of §6)
    "square-pedestal": ("48x16x4", "6x2x4"),
    "large-square-pedestal": ("45x15x4", "6x2x4"),
    "square-on-disc": ("30x240", "4x32"),
    "sphere": ("100x100", "16x16"),
}
RELAX = {
    "solver.relax.damping": "kinetic",
    "solver.relax.mass_scaling": 1e4,
    "solver.relax.mass_scaling_mode": "director",
}
KEYS = (
    "converged",
    "drape_coefficient",
    "fold_count",
    "max_interpenetrated_nodes",
    "interpenetrated_nodes",
    "steps",
    "t_final",
    "energy_balance_error",
    "max_active_nodes",
    "final_active_nodes",
    "remesh_count",
    "remesh_time_s",
    "remesh_share",
    "remesh_phase_s",
    "remesh_energy_jump",
    "max_level_reached",
    "message",
)


def threads() -> int:
    import numba

    return numba.config.NUMBA_NUM_THREADS


def load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def one(scene, mesh, adaptive, overrides, folder, max_wall):
    t = time.perf_counter()
    out = run_scene(
        scene,
        mesh=mesh,
        solver="relax",
        out_dir=folder,
        progress=False,
        overrides=overrides,
        adaptive=adaptive,
        force=True,
        max_wall_time=max_wall,
    )
    wall = time.perf_counter() - t
    s = out.summary
    row = {k: s.get(k) for k in KEYS}
    row.update(wall_s=wall, nodes=s["counts"]["nodes"], elements=s["counts"]["elements"])
    return row


def table(results) -> str:
    lines = [
        "| scene | uniform mesh (nodes) | adaptive max active nodes (ratio) | DC uniform / adaptive (diff) | "
        "folds u / a | max interp. u / a | steps u / a | wall u / a [s] (ratio) | remesh share | "
        "remeshes | energy err u / a | load before -> after |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        u, a = r["uniform"], r["adaptive"]
        if u is None or a is None:
            continue
        dc_u, dc_a = u["drape_coefficient"], a["drape_coefficient"]
        diff = (dc_a - dc_u) / dc_u if dc_u else float("nan")
        lines.append(
            f"| {r['scene']} | {r['uniform_mesh']} ({u['nodes']}) | {a['max_active_nodes']} "
            f"({a['max_active_nodes'] / u['nodes']:.2f}) | {dc_u:.4f} / {dc_a:.4f} ({diff:+.1%}) | "
            f"{u['fold_count']} / {a['fold_count']} | {u['max_interpenetrated_nodes']} / "
            f"{a['max_interpenetrated_nodes']} | {u['steps']} / {a['steps']} | {u['wall_s']:.0f} / "
            f"{a['wall_s']:.0f} ({a['wall_s'] / u['wall_s']:.2f}) | {a['remesh_share']:.1%} | {a['remesh_count']} | "
            f"{u['energy_balance_error']:.1e} / {a['energy_balance_error']:.1e} | {r['load_before']} -> "
            f"{r['load_after']} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="*", default=list(CASES))
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="scene overrides for both runs (e.g. adapt.const=0.3)",
    )
    ap.add_argument("--out", default="benchmarks/out")
    ap.add_argument("--tag", default="adaptive_vs_uniform")
    ap.add_argument("--max-wall", type=float, default=1800.0, help="wall-time cap of each run [s]")
    ap.add_argument("--skip-uniform", action="store_true", help="adaptive runs only")
    ap.add_argument("--uniform", metavar="MESH", help="the uniform mesh instead of the case's (one case only)")
    args = ap.parse_args(argv)
    if args.uniform and len(args.cases) != 1:
        ap.error("--uniform needs exactly one case")
    out = Path(args.out)
    png = out / "adaptive_png"
    png.mkdir(parents=True, exist_ok=True)
    given = parse_overrides(args.set)
    # keys given alongside a preset win over it: with RELAX beside a preset, "--set
    # solver.relax.preset=paper" would keep kinetic damping and director masses (docs/adaptivity.md)
    over = {**({} if "solver.relax.preset" in given else RELAX), **given}
    jpath = out / f"{args.tag}.json"
    results = json.loads(jpath.read_text()) if jpath.exists() else []
    for scene in args.cases:
        uni, lvl0 = CASES[scene]
        uni = args.uniform or uni
        rec = {
            "scene": scene,
            "uniform_mesh": uni,
            "level0_mesh": lvl0,
            "overrides": over,
            "load_before": load(),
            "uniform": None,
            "adaptive": None,
        }
        for variant, mesh, adaptive in (("uniform", uni, False), ("adaptive", lvl0, True)):
            if variant == "uniform" and args.skip_uniform:
                continue
            folder = Path("runs/bench-adaptive") / args.tag / f"{scene}-{variant}"  # runs side by side apart
            rec[variant] = one(scene, mesh, adaptive, over, folder, args.max_wall)
            for p in folder.glob("*.png"):
                shutil.copy(p, png / f"{scene}-{variant}-{p.name}")
            print(
                scene,
                variant,
                json.dumps(
                    {
                        k: rec[variant][k]
                        for k in ("drape_coefficient", "fold_count", "nodes", "max_active_nodes", "wall_s", "steps")
                    }
                ),
                flush=True,
            )
        rec["load_after"] = load()
        results = [r for r in results if r["scene"] != scene] + [rec]
        jpath.write_text(json.dumps(results, indent=1, default=str))
        (out / f"{args.tag}.md").write_text(
            f"# Paper §6: adaptive against uniform meshes\n\n`python benchmarks/adaptive_vs_uniform.py "
            f"{' '.join('--set ' + s for s in args.set)}` (2 CPUs, shared, {threads()} numba thread(s); 1/5/15-min "
            f"load averages per case).\n\n" + table(results)
        )


if __name__ == "__main__":
    main()
