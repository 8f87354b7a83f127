"""What a sweep writes after its runs: the state table, a short report and the figure.

``OUT/states.csv``  one line per distinct equilibrium: fold count, frequency, DC (min/mean/max),
                    the representative run's fold angles, key and picture
``OUT/report.md``   the same table, the fold-count frequencies, the runs without a state, and a
                    table of state per case (for studies that vary solver settings by case)
``OUT/<name>.png``  the figure of the sweep's [plot] (solidshell.sweep.plots)

All of it is recomputed from the ledger, so ``solidshell sweep`` on a finished sweep rewrites it.
"""

from __future__ import annotations

import csv
from pathlib import Path

from .ledger import Ledger
from .plots import curve_figure, states_figure
from .spec import SweepSpec
from .states import classify, symmetry_group

__all__ = ["sweep_group", "write_report"]


def sweep_group(spec: SweepSpec) -> str:
    """The symmetry group the sweep's states are taken under ([classify] symmetry, or the scene's)."""
    if spec.classify.symmetry != "auto":
        return spec.classify.symmetry
    from ..scenes import load

    sc = load(spec.scene)
    if spec.runs:
        sc = sc.with_overrides(spec.runs[0].overrides)
    return symmetry_group(sc)


_STATE_COLUMNS = [
    "state",
    "fold_count",
    "runs",
    "frequency",
    "dc_min",
    "dc_mean",
    "dc_max",
    "fold_angles_deg",
    "stable_runs",
    "interpenetrated_runs",
    "representative_key",
    "picture",
]


def write_report(spec: SweepSpec, out, group: str | None = None) -> dict:
    """Classify the ledger's runs and write states.csv, report.md and the figure; returns
    {"states": [...], "unsettled": n, "files": [...], "fold_frequencies": {n: fraction}}."""
    out = Path(out)
    group = group or sweep_group(spec)
    rows = Ledger(out, spec).read().to_pylist()
    c = spec.classify
    states, unsettled = classify(rows, c.dc_tol, c.boundary_tol, group)
    total = len(rows)
    files = [_write_states_csv(out / "states.csv", states, total)]
    freq = {}
    for st in states:
        freq[st.fold_count] = freq.get(st.fold_count, 0) + st.count
    lines = _summary_lines(spec, rows, states, unsettled, group)
    lines += _state_table_lines(states, total)
    lines += [
        "",
        "Fold-count frequencies: " + (", ".join(f"{k} folds: {v}/{total}" for k, v in sorted(freq.items())) or "none"),
        "",
    ]
    if unsettled:
        lines.append(
            "Unsettled runs: "
            + ", ".join(
                f"{r['key']} ({r.get('error') or r.get('solver_status') or 'not converged'})" for r in unsettled
            )
        )
        lines.append("")
    if len({r["case"] for r in rows}) > 1:
        lines += _per_case_lines(spec, rows, states)
    if total:
        fig = _write_figure(spec, out, rows, states, unsettled)
        files.append(fig)
        lines.append(f"Figure: {fig.name}")
    md = out / "report.md"
    md.write_text("\n".join(lines) + "\n")
    files.append(md)
    return {
        "states": states,
        "unsettled": len(unsettled),
        "files": files,
        "group": group,
        "fold_frequencies": {k: v / total for k, v in sorted(freq.items())} if total else {},
    }


def _write_states_csv(path: Path, states, total: int) -> Path:
    """states.csv: one line per state (the module docstring); returns its path."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(_STATE_COLUMNS)
        for st in states:
            lo, mean, hi = st.dc_range()
            rep = st.representative
            w.writerow(
                [
                    st.number,
                    st.fold_count,
                    st.count,
                    f"{st.count / total:.4f}",
                    f"{lo:.4f}",
                    f"{mean:.4f}",
                    f"{hi:.4f}",
                    " ".join(f"{a:.1f}" for a in rep.get("fold_angles_deg") or []),
                    sum(1 for m in st.members if m.get("stable")),
                    sum(1 for m in st.members if m.get("interpenetrated_nodes")),
                    rep["key"],
                    str(Path(rep["run_dir"]) / "top.png"),
                ]
            )
    return path


def _summary_lines(spec: SweepSpec, rows, states, unsettled, group: str) -> list[str]:
    """report.md's title, description and one-paragraph count of runs and states."""
    c = spec.classify
    n_failed = sum(1 for r in rows if r.get("status") != "done")
    return [
        f"# Sweep {spec.name}",
        "",
        spec.description,
        "",
        f"{len(rows)} of {spec.n_runs} runs recorded, {n_failed} of them failed (no result); "
        f"{len(states)} distinct state(s) under symmetry {group} "
        f"(dc_tol {c.dc_tol}, boundary_tol {c.boundary_tol}); {len(unsettled)} run(s) unsettled "
        f"(not converged or failed).",
        "",
    ]


def _state_table_lines(states, total: int) -> list[str]:
    """report.md's table of states: folds, runs, frequency, DC, stable and self-penetrating runs."""
    lines = [
        "| state | folds | runs | frequency | DC mean (min-max) | stable | self-penetrating | representative |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for st in states:
        lo, mean, hi = st.dc_range()
        stable = sum(1 for m in st.members if m.get("stable"))
        pen = [m.get("interpenetrated_nodes") for m in st.members]
        pen_s = "?" if all(p is None for p in pen) else f"{sum(1 for p in pen if p)}/{st.count}"
        lines.append(
            f"| S{st.number} | {st.fold_count} | {st.count} | {st.count / total:.2f} | "
            f"{mean:.4f} ({lo:.4f}-{hi:.4f}) | {stable}/{st.count} | {pen_s} | {st.representative['key']} |"
        )
    return lines


def _per_case_lines(spec: SweepSpec, rows, states) -> list[str]:
    """report.md's tally of the states each case's runs reached (for studies that vary settings by case)."""
    lines = ["State per case (runs):", ""]
    member = {m["key"]: f"S{st.number}" for st in states for m in st.members}
    cases: dict = {}
    for r in rows:
        cases.setdefault(r["case"], []).append(member.get(r["key"], "unsettled"))
    case_desc = spec.raw.get("case", [{}])
    for ci in sorted(cases):
        desc = ", ".join(f"{k}={v}" for k, v in case_desc[ci].items()) if ci < len(case_desc) else ""
        tally: dict = {}
        for s in cases[ci]:
            tally[s] = tally.get(s, 0) + 1
        lines.append(f"- case {ci} ({desc}): " + ", ".join(f"{s} x{n}" for s, n in sorted(tally.items())))
    lines.append("")
    return lines


def _write_figure(spec: SweepSpec, out: Path, rows, states, unsettled) -> Path:
    """The sweep's [plot] figure, OUT/<name>.png: the states' frequencies or a curve of the runs."""
    p = spec.plot
    fig = out / f"{spec.name}.png"
    if p.kind == "states":
        states_figure(states, unsettled, len(rows), fig, title=spec.name)
    else:
        curve_figure(rows, p.x, p.y, fig, p.x_ref, p.x_label, p.by, p.log_x, title=spec.name)
    return fig
