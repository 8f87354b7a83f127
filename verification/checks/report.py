"""Write ``verification.json``, ``report.md`` and the figures (matplotlib, Agg) of a verification run."""

from __future__ import annotations

import json
import math
from pathlib import Path

from solidshell.errors import IOFailure


def _write(path: Path, text: str) -> Path:
    try:
        path.write_text(text)
    except OSError as e:
        raise IOFailure.from_oserror(e, path) from None
    return path


def draw(fig: dict, path: Path) -> Path:
    """One figure: "curves" (reference as lines, ours as markers) or "convergence" (log-log, the
    observed rate in the legend)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f, ax = plt.subplots(figsize=(7.5, 5.0))
    if fig["kind"] == "curves":
        for i, s in enumerate(fig["series"]):
            if s.get("role") == "reference":
                ax.plot(s["x"], s["y"], "-", lw=2.2, color="0.25" if i % 2 == 0 else "0.55", label=s["label"])
            else:
                ax.plot(s["x"], s["y"], "o-", ms=4, lw=0.8, mfc="none", label=s["label"])
        if fig.get("logx"):
            ax.set_xscale("log")
        if fig.get("logy"):
            ax.set_yscale("log")
        if fig.get("equal"):
            ax.set_aspect("equal", adjustable="box")
    else:
        for s in fig["series"]:
            pts = [(h, e) for h, e in zip(s["h"], s["error"]) if e and e > 0 and math.isfinite(e)]
            if not pts:
                continue
            rate = s.get("rate")
            lab = s["label"] + (f" (observed rate {rate:.2f})" if rate is not None and math.isfinite(rate) else "")
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=lab)
        ax.invert_xaxis()
    ax.set_xlabel(fig["xlabel"])
    ax.set_ylabel(fig["ylabel"])
    ax.set_title(fig["title"], fontsize=10)
    ax.grid(True, which="both", lw=0.3)
    if fig.get("equal"):  # a tall equal-aspect plot leaves room on the right
        ax.legend(fontsize=8, loc="center left", bbox_to_anchor=(1.02, 0.5))
    else:
        ax.legend(fontsize=8)
    f.tight_layout()
    try:
        f.savefig(path, dpi=110)
    except OSError as e:
        raise IOFailure.from_oserror(e, path) from None
    finally:
        plt.close(f)
    return path


def _num(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def markdown(run: dict, figures: dict) -> str:
    m = run["machine"]
    recs = run["records"]
    n_pass = sum(r.status == "passed" for r in recs)
    L = [
        "# solidshell verification report",
        "",
        f"`solidshell verify{' --quick' if run['quick'] else ''}` at {m['time_utc']}: {len(recs)} records, "
        f"{n_pass} passed, {run['failed']} failed, {run['skipped']} skipped, in {run['wall_time_s']:.1f} s "
        f"(Python {m['python']}, {m['cpus']} CPUs, load average "
        f"{', '.join(f'{x:.2f}' for x in m['load_average']) if m['load_average'] else '?'}).",
        "",
        "Every record compares one measured quantity with an independent reference; `error` is relative "
        "(|value - ref| / |ref|) unless the tolerance column says abs; `why` says where the tolerance comes from.",
        "",
    ]
    L += ["| check | records | failed | skipped | wall [s] |", "|---|---|---|---|---|"]
    for c in run["checks"]:
        L.append(
            f"| [{c['name']}](#{c['name']}) | {c['records']} | {c['failed']} | {c['skipped']} | "
            f"{c['wall_time_s']:.1f} |"
        )
    L.append("")
    for c in run["checks"]:
        L += [f"## {c['name']}", "", c["summary"] + ".", ""]
        rows = [r for r in recs if r.check == c["name"]]
        L += [
            "| record | quantity | value | reference | error | tolerance | result | reference (source) | why |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for r in rows:
            tol = "" if r.tolerance is None else f"{r.tolerance:g}" + (" abs" if r.error_kind == "abs" else "")
            res = r.status + (f" ({r.note})" if r.note else "")
            err = "" if r.error is None else f"{r.error:.2e}"
            L.append(
                f"| {r.name} | {r.quantity} | {_num(r.value)} | {_num(r.reference_value)} | {err} | {tol} | "
                f"{res} | {r.reference} ({r.source}) | {r.why} |"
            )
        L.append("")
        for p in figures.get(c["name"], []):
            L += [f"![{c['name']}]({p})", ""]
    return "\n".join(L) + "\n"


def write_report(run: dict, out: Path) -> list[Path]:
    """verification.json, report.md and figures/<check>-<k>.png under ``out``."""
    out = Path(out)
    figdir = out / "figures"
    try:
        figdir.mkdir(exist_ok=True)
    except OSError as e:
        raise IOFailure.from_oserror(e, figdir) from None
    figures: dict[str, list[str]] = {}
    files = []
    for fig in run["figures"]:
        k = len(figures.setdefault(fig["check"], []))
        p = draw(fig, figdir / f"{fig['check']}-{k}.png")
        figures[fig["check"]].append(f"figures/{p.name}")
        files.append(p)
    data = {
        "quick": run["quick"],
        "wall_time_s": run["wall_time_s"],
        "machine": run["machine"],
        "failed": run["failed"],
        "skipped": run["skipped"],
        "checks": run["checks"],
        "records": [r.to_dict() for r in run["records"]],
        "figures": figures,
    }
    files.insert(0, _write(out / "verification.json", json.dumps(data, indent=1, default=float)))
    files.insert(1, _write(out / "report.md", markdown(run, figures)))
    return files
