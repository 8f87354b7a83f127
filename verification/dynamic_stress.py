"""Stability stress tests of the explicit solver (Eq. 23) on small meshes.

1. ``steps``:   square-pedestal 24x8x4 (explicit, alpha = 5 1/s, no mass scaling, gravity), dt =
   f x the estimated critical step for f = 0.5 ... 1.2.  Each f is tried twice: as a user would
   (``dt`` only: above dt_crit the solver must refuse with the numbers), and with
   ``allow_unstable=True`` for ``--steps`` steps (default 3000): below 1 the run must stay finite and
   energy-balanced; above 1 the instability must be *detected* (non-finite state or energy creation
   -> converged = False with a message), never returned as a good result.
2. ``long``:    a run under gravity held for 10^5 steps (strip-warp 20x1 cantilever, alpha = 5, and,
   if asked, square-pedestal 24x8x4): must stay finite, energy-balanced and bounded (the largest
   displacement over 20 snapshots compared with the static solution's).
3. ``fabrics``: extreme but valid fabrics on square-pedestal 24x8x4 by dynamic relaxation (kinetic
   damping, director masses x1e4): bending (warp, weft and torsion) rigidities x0.01 and x100, weight
   x10.  Each must either reach a steady state or be refused/stopped with the reason.

    python -m verification.dynamic_stress [--parts steps long fabrics] [--steps 3000]

Writes ``verification/out/dynamic_stress.json`` and ``.md`` (parts already measured are kept when
only some parts are rerun).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from solidshell.run import run_scene

OUT = Path(__file__).resolve().parent / "out"
WOOL = dict(bending_warp=0.083, bending_weft=0.063, torsion=0.027, weight=0.019)
FACTORS = (0.5, 0.7, 0.9, 0.95, 0.99, 1.01, 1.05, 1.1, 1.2)


def _load():
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def _run(scene, mesh, solver, overrides=None, **settings):
    t0 = time.perf_counter()
    try:
        out = run_scene(
            scene, mesh=mesh, solver=solver, out_dir=None, progress=False, overrides=overrides or None, **settings
        )
        return out, None, time.perf_counter() - t0
    except Exception as e:  # noqa: BLE001 - a refusal is a result
        return None, f"{type(e).__name__}: {e}", time.perf_counter() - t0


def part_steps(n_steps: int) -> dict:
    scene, mesh = "square-pedestal", "24x8x4"
    base = dict(alpha=5.0, mass_scaling=1)
    out, err, _ = _run(scene, mesh, "explicit", t_end=1e-6, **base)
    if err:
        return dict(error=err)
    dtc = out.summary["critical_time_step"]
    rows = []
    for f in FACTORS:
        dt = f * dtc
        t_end = n_steps * dt
        # as a user would: no allow_unstable
        o1, e1, w1 = _run(scene, mesh, "explicit", t_end=t_end, dt=dt, critical_time_step=dtc, **base)
        plain = dict(
            refused=e1 is not None,
            reason=e1,
            converged=None if o1 is None else o1.summary.get("converged"),
            steps=None if o1 is None else o1.summary.get("steps"),
            energy_balance_error=None if o1 is None else o1.summary.get("energy_balance_error"),
            wall_s=w1,
        )
        # forced: allow_unstable
        o2, e2, w2 = _run(
            scene, mesh, "explicit", t_end=t_end, dt=dt, critical_time_step=dtc, allow_unstable=True, **base
        )
        s2 = {} if o2 is None else o2.summary
        forced = dict(
            error=e2,
            converged=s2.get("converged"),
            status=s2.get("status"),
            steps=s2.get("steps"),
            finite=s2.get("finite"),
            energy_balance_error=s2.get("energy_balance_error"),
            max_displacement=s2.get("max_displacement"),
            message=s2.get("message"),
            wall_s=w2,
        )
        rows.append(dict(factor=f, dt=dt, plain=plain, forced=forced))
        print(
            f"dt = {f:.2f} dt_crit: plain {'REFUSED' if e1 else 'ran'}"
            f"{'' if not e1 else ' (' + e1[:90] + ')'}; forced: {forced['status']} "
            f"steps {forced['steps']} E-err {forced['energy_balance_error']} max|U| {forced['max_displacement']}",
            flush=True,
        )
    ok = all(
        (r["factor"] < 1 and not r["plain"]["refused"] and r["forced"]["converged"])
        or (r["factor"] > 1 and r["plain"]["refused"] and not r["forced"]["converged"])
        for r in rows
    )
    return dict(
        scene=scene,
        mesh=mesh,
        settings=base,
        critical_time_step=dtc,
        steps_per_run=n_steps,
        rows=rows,
        passed=ok,
        load=_load(),
    )


def part_long(n_steps: int, pedestal: bool) -> dict:
    cases = [("strip-warp", "20x1")] + ([("square-pedestal", "24x8x4")] if pedestal else [])
    rows = []
    for scene, mesh in cases:
        base = dict(alpha=5.0, mass_scaling=1)
        o, e, _ = _run(scene, mesh, "explicit", t_end=1e-6, **base)
        if e:
            rows.append(dict(scene=scene, mesh=mesh, error=e))
            continue
        dt = 0.9 * o.summary["critical_time_step"]
        t_end = n_steps * dt
        snaps = list(np.linspace(0.0, t_end, 21)[1:])
        time.perf_counter()
        o, e, w = _run(scene, mesh, "explicit", t_end=t_end, snapshots=snaps, recheck_every=0, **base)
        if e:
            rows.append(dict(scene=scene, mesh=mesh, error=e, wall_s=w))
            continue
        s = o.summary
        frames = o.result.frames or []
        umax = [float(np.max(np.linalg.norm(U[:, :3], axis=1))) for _, U in frames]
        st, es, _ = _run(scene, mesh, "static")
        u_static = None if st is None else float(np.max(np.linalg.norm(st.U[:, :3], axis=1)))
        rows.append(
            dict(
                scene=scene,
                mesh=mesh,
                steps=s.get("steps"),
                dt=s.get("dt"),
                t_end=s.get("t_final"),
                converged=s.get("converged"),
                finite=s.get("finite"),
                energy_balance_error=s.get("energy_balance_error"),
                max_displacement_over_snapshots=max(umax) if umax else None,
                max_displacement_by_snapshot=umax,
                static_max_displacement=u_static,
                static_error=es,
                wall_s=w,
                element_steps_per_second=s.get("element_steps_per_second"),
                message=s.get("message"),
            )
        )
        print(
            f"long {scene} {mesh}: {s.get('steps')} steps, finite {s.get('finite')}, E-err "
            f"{s.get('energy_balance_error')}, max|U| over snapshots {max(umax) if umax else None} "
            f"(static {u_static}), wall {w:.1f} s",
            flush=True,
        )
    ok = all(
        r.get("converged")
        and r.get("finite")
        and r.get("max_displacement_over_snapshots") is not None
        and (
            r.get("static_max_displacement") is None
            or r["max_displacement_over_snapshots"] < 3 * r["static_max_displacement"]
        )
        for r in rows
    )
    return dict(rows=rows, steps=n_steps, passed=ok, load=_load())


def part_fabrics(max_wall: float) -> dict:
    scene, mesh = "square-pedestal", "24x8x4"
    relax = dict(damping="kinetic", mass_scaling=1e4, mass_scaling_mode="director", max_wall_time=max_wall)
    variants = {
        "wool": {},
        "bending x0.01": {f"material.{k}": 0.01 * WOOL[k] for k in ("bending_warp", "bending_weft", "torsion")},
        "bending x100": {f"material.{k}": 100 * WOOL[k] for k in ("bending_warp", "bending_weft", "torsion")},
        "weight x10": {"material.weight": 10 * WOOL["weight"]},
    }
    rows = []
    for name, ov in variants.items():
        o, e, w = _run(scene, mesh, "relax", overrides=ov, **relax)
        s = {} if o is None else o.summary
        rows.append(
            dict(
                variant=name,
                overrides=ov,
                refused=e is not None,
                reason=e,
                converged=s.get("converged"),
                status=s.get("status"),
                steps=s.get("steps"),
                dt=s.get("dt"),
                critical_time_step=s.get("critical_time_step"),
                t_final=s.get("t_final"),
                drape_coefficient=s.get("drape_coefficient"),
                fold_count=s.get("fold_count"),
                energy_balance_error=s.get("energy_balance_error"),
                finite=s.get("finite"),
                message=s.get("message"),
                wall_s=w,
            )
        )
        print(
            f"fabric {name}: {'REFUSED ' + e if e else s.get('status')} steps {s.get('steps')} dt {s.get('dt')} "
            f"DC {s.get('drape_coefficient')} folds {s.get('fold_count')} wall {w:.1f} s",
            flush=True,
        )
    ok = all(r["refused"] or r["converged"] or (r["finite"] and r["message"]) for r in rows)
    return dict(scene=scene, mesh=mesh, settings=relax, rows=rows, passed=ok, load=_load())


def _fmt(x, f="{:.3g}"):
    if x is None:
        return "–"
    if isinstance(x, bool):
        return "yes" if x else "no"
    return f.format(x) if isinstance(x, (int, float)) else str(x)


def write_report(res: dict):
    OUT.mkdir(parents=True, exist_ok=True)
    with open(OUT / "dynamic_stress.json", "w") as fh:
        json.dump(res, fh, indent=1, default=str)
    L = ["# Explicit solver stability stress tests", "", "Generated by `python -m verification.dynamic_stress`.", ""]
    p = res.get("steps")
    if p and "rows" in p:
        L += [
            f"## Step size vs the estimated critical step ({p['scene']} {p['mesh']}, alpha 5, no mass scaling, "
            f"dt_crit = {p['critical_time_step']:.4e} s, {p['steps_per_run']} steps per run)",
            "",
            "| dt / dt_crit | plain run | forced (allow_unstable) status | steps | energy err | max abs(U) [cm] | message |",
            "|---|---|---|---|---|---|---|",
        ]
        for r in p["rows"]:
            pl, fo = r["plain"], r["forced"]
            plain = (
                ("refused: " + pl["reason"].split(":", 1)[-1].strip()[:120])
                if pl["refused"]
                else f"ran, converged {_fmt(pl['converged'])}, E-err {_fmt(pl['energy_balance_error'])}"
            )
            L.append(
                f"| {r['factor']:.2f} | {plain.replace('|', '/')} | {fo['status'] or fo['error']} | {_fmt(fo['steps'], '{}')} | "
                f"{_fmt(fo['energy_balance_error'])} | {_fmt(fo['max_displacement'])} | "
                f"{str(fo['message'] or '').replace('|', '/')[:120]} |"
            )
        L += ["", f"Passed (stable and accepted below 1, refused and detected above): {_fmt(p['passed'])}", ""]
    p = res.get("long")
    if p and "rows" in p:
        L += [
            f"## Long run under gravity ({p['steps']} steps, alpha 5, dt = 0.9 dt_crit)",
            "",
            "| scene | mesh | steps | dt [s] | t [s] | finite | energy err | max abs(U) over 20 snapshots [cm] | static max abs(U) | wall [s] |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in p["rows"]:
            if r.get("error"):
                L.append(f"| {r['scene']} | {r['mesh']} | error: {r['error']} |||||||| ")
                continue
            L.append(
                f"| {r['scene']} | {r['mesh']} | {r['steps']} | {_fmt(r['dt'], '{:.3e}')} | {_fmt(r['t_end'])} | "
                f"{_fmt(r['finite'])} | {_fmt(r['energy_balance_error'])} | {_fmt(r['max_displacement_over_snapshots'], '{:.4f}')} | "
                f"{_fmt(r['static_max_displacement'], '{:.4f}')} | {_fmt(r['wall_s'], '{:.1f}')} |"
            )
        L += ["", f"Passed: {_fmt(p['passed'])}", ""]
    p = res.get("fabrics")
    if p and "rows" in p:
        L += [
            f"## Extreme fabrics ({p['scene']} {p['mesh']}, relax, kinetic damping, director masses x1e4, "
            f"wall limit {p['settings']['max_wall_time']:g} s)",
            "",
            "| fabric | outcome | steps | dt [s] | t_sim [s] | DC | folds | energy err | wall [s] | message |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        for r in p["rows"]:
            outc = "refused" if r["refused"] else ("steady" if r["converged"] else (r["status"] or "not steady"))
            L.append(
                f"| {r['variant']} | {outc} | {_fmt(r['steps'], '{}')} | {_fmt(r['dt'], '{:.3e}')} | {_fmt(r['t_final'])} | "
                f"{_fmt(r['drape_coefficient'], '{:.4f}')} | {_fmt(r['fold_count'], '{}')} | {_fmt(r['energy_balance_error'])} | "
                f"{_fmt(r['wall_s'], '{:.1f}')} | {str(r['reason'] or r['message'] or '').replace('|', '/')[:160]} |"
            )
        L += ["", f"Passed (steady, or refused/stopped with a reason): {_fmt(p['passed'])}", ""]
    text = "\n".join(L)
    (OUT / "dynamic_stress.md").write_text(text)
    print(text)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parts", nargs="+", default=["steps", "long", "fabrics"], choices=["steps", "long", "fabrics"])
    ap.add_argument("--steps", type=int, default=3000, help="steps per run of the step-size sweep")
    ap.add_argument("--long-steps", type=int, default=100000)
    ap.add_argument("--long-pedestal", action="store_true", help="also hold square-pedestal 24x8x4 for --long-steps")
    ap.add_argument("--max-wall", type=float, default=300.0, help="wall-time limit per extreme-fabric run [s]")
    a = ap.parse_args(argv)
    res = {}
    p = OUT / "dynamic_stress.json"
    if p.exists():
        try:
            res = json.load(open(p))
        except ValueError:
            res = {}
    for part in a.parts:
        t0 = time.perf_counter()
        if part == "steps":
            res["steps"] = part_steps(a.steps)
        elif part == "long":
            res["long"] = part_long(a.long_steps, a.long_pedestal)
        else:
            res["fabrics"] = part_fabrics(a.max_wall)
        res[part]["wall_s"] = time.perf_counter() - t0
        write_report(res)


if __name__ == "__main__":
    main()
