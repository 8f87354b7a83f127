"""Running a work-precision study and writing its table, JSON and log-log picture."""

from __future__ import annotations

import json
import os
import platform
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

TARGET = 0.01
"""The error the tables name the cheapest configuration for (1 %, issue 12)."""


@dataclass
class Config:
    """One configuration of a study: ``family`` groups the points of one line in the picture
    (e.g. "static, quads"), ``label`` names the point (e.g. the mesh), ``run`` returns a dict of
    measured quantities (at least ``wall_s``) and ``reference`` marks the run the others are
    compared with."""

    family: str
    label: str
    run: Callable[[], dict]
    reference: bool = False


@dataclass
class Study:
    name: str
    title: str
    error_keys: tuple  # (key, description) of the errors each row gets
    configs: Callable[[bool], list]  # quick -> [Config]
    errors: Callable[[dict, dict], dict]  # (row, reference row) -> {error key: value}
    reference_note: str = ""
    notes: list = field(default_factory=list)


def machine() -> dict:
    """The machine's facts for the record (CPU, cores, numba threads, Python, load)."""
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numba

    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "numba_threads": numba.get_num_threads(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "utc": time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime()),
    }


def load() -> list:
    return [round(x, 2) for x in os.getloadavg()]


def run_study(study: Study, quick: bool, say=print) -> dict:
    """Every configuration once, then the errors against the reference row."""
    rows = []
    for c in study.configs(quick):
        say(f"  {study.name}: {c.family}, {c.label} ...")
        before = load()
        t = time.perf_counter()
        row = dict(c.run())
        row.setdefault("wall_s", time.perf_counter() - t)
        row.update(family=c.family, label=c.label, reference=c.reference, load_before=before, load_after=load())
        rows.append(row)
        say(
            f"    {row['wall_s']:.2f} s  "
            + ", ".join(
                f"{k} {v:.6g}" for k, v in row.items() if k in ("dc", "tip_z", "steps", "rate") and v is not None
            )
        )
    ref = next((r for r in rows if r["reference"]), None)
    for r in rows:
        r["errors"] = study.errors(r, ref)  # ref None: the study's reference is not a run
    return {
        "study": study.name,
        "title": study.title,
        "quick": quick,
        "machine": machine(),
        "reference": study.reference_note,
        "error_keys": [list(k) for k in study.error_keys],
        "notes": list(study.notes),
        "rows": rows,
    }


def cheapest(result: dict, key: str, target: float = TARGET):
    """The row of least wall time whose error ``key`` is at most ``target`` (not the reference
    itself), or None."""
    ok = [
        r
        for r in result["rows"]
        if not r["reference"] and r["errors"].get(key) is not None and r["errors"][key] <= target
    ]
    return min(ok, key=lambda r: r["wall_s"]) if ok else None


def _fmt(v) -> str:
    from verification.checks.runner import fmt_value  # the verification tables' cell format

    return fmt_value(v, 3, "–")


def table(result: dict) -> str:
    keys = [k for k, _ in result["error_keys"]]
    extra = sorted({k for r in result["rows"] for k in r.get("show", {})})
    head = [
        "family",
        "configuration",
        "wall [s]",
        *[f"error: {d}" for _, d in result["error_keys"]],
        *extra,
        "load before → after",
    ]
    head = [h.replace("|", "\\|") for h in head]  # a |x| in a header would end its cell
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in result["rows"]:
        cells = [
            r["family"],
            r["label"] + (" (reference)" if r["reference"] else ""),
            f"{r['wall_s']:.2f}",
            *[_fmt(r["errors"].get(k)) for k in keys],
            *[_fmt(r.get("show", {}).get(k)) for k in extra],
            f"{r['load_before'][0]} → {r['load_after'][0]}",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def markdown(result: dict, command: str) -> str:
    m = result["machine"]
    out = [
        f"# Work-precision: {result['title']}",
        "",
        f"`{command}` on {m['utc']} UTC: {m['cpu']}, {m['cores']} cores (shared), {m['numba_threads']} numba "
        f"thread(s), Python {m['python']}.  Reference: {result['reference']}",
        "",
        table(result),
        "",
    ]
    for k, d in result["error_keys"]:
        c = cheapest(result, k)
        out.append(
            f"- Cheapest configuration within {TARGET:.0%} ({d}): "
            + (f"**{c['family']}, {c['label']}**, {c['wall_s']:.2f} s" if c else "none of these")
        )
    out += [f"- {n}" for n in result["notes"]]
    return "\n".join(out) + "\n"


def picture(result: dict, path: Path) -> None:
    """Error against wall time, log-log, one line per family and one panel per error measure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = result["error_keys"]
    fig, axes = plt.subplots(1, len(keys), figsize=(6.2 * len(keys), 4.6), squeeze=False)
    fams = list(dict.fromkeys(r["family"] for r in result["rows"]))
    # fold counts on the labels only where they differ between runs (then they are different states)
    vary = len({r.get("folds") for r in result["rows"] if r.get("folds") is not None}) > 1
    for ax, (k, desc) in zip(axes[0], keys):
        for i, fam in enumerate(fams):
            # in the study's order (coarse to fine), not by time: sorted by wall time, a family whose
            # finer mesh ran faster drew a zig-zag; each point names its mesh and, where they differ, its
            # folds (different fold counts are different equilibria, not a discretisation error)
            pts = [
                (
                    r["wall_s"],
                    r["errors"][k],
                    r["label"] + (f", {r['folds']} folds" if vary and r.get("folds") is not None else ""),
                )
                for r in result["rows"]
                if r["family"] == fam and r["errors"].get(k) is not None and r["errors"][k] > 0
            ]
            if not pts:
                continue
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", color=f"C{i}", label=fam)
            for x, y, lab in pts:
                ax.annotate(lab, (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7, color=f"C{i}")
        ref = next((r for r in result["rows"] if r["reference"]), None)
        if ref is not None:  # its error is 0: not on a log axis; its cost is
            folds = f", {ref['folds']} folds" if vary and ref.get("folds") is not None else ""
            ax.axvline(
                ref["wall_s"], color="k", lw=0.8, ls=":", label=f"reference: {ref['family']}, {ref['label']}{folds}"
            )
        ax.axhline(TARGET, color="0.5", lw=0.8, ls="--")
        ax.text(ax.get_xlim()[0], TARGET, f" {TARGET:.0%}", va="bottom", fontsize=8, color="0.4")
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel(desc)
        ax.grid(True, which="both", lw=0.3, alpha=0.5)
        ax.legend(fontsize=8)
    m = result["machine"]
    sub = textwrap.fill(
        f"{m['cpu']}, {m['numba_threads']} thread(s); reference: {result['reference']}", 50 + 60 * len(keys)
    )
    fig.suptitle(f"{result['title']}\n{sub}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def write(result: dict, out_dir: Path, command: str) -> list:
    out_dir.mkdir(parents=True, exist_ok=True)
    name = result["study"]
    paths = [out_dir / f"{name}.json", out_dir / f"{name}.md"]
    paths[0].write_text(json.dumps(result, indent=1, default=float) + "\n")
    paths[1].write_text(markdown(result, command))
    if any(r["errors"] for r in result["rows"]):
        paths.append(out_dir / f"{name}.png")
        picture(result, paths[-1])
    return paths
