"""Figures of a sweep (matplotlib, Agg): the state gallery and fold-count frequencies of a
multi-stability study, and a response curve (e.g. DC against bending rigidity)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["states_figure", "curve_figure"]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def states_figure(states, unsettled, total, path, title="") -> Path:
    """Left: how often each fold count occurs; right: each state's projected boundary (the
    representative run's r(theta)), titled with its fold count, DC and frequency."""
    plt = _plt()
    n = max(1, len(states))
    cols = min(4, n)
    rows = int(np.ceil(n / cols))
    fig = plt.figure(figsize=(3.2 * (cols + 1.3), 3.2 * rows + 0.6))
    gs = fig.add_gridspec(rows, cols + 1, width_ratios=[1.3] + [1] * cols)
    ax = fig.add_subplot(gs[:, 0])
    counts = {}
    for st in states:
        counts[st.fold_count] = counts.get(st.fold_count, 0) + st.count
    ks = sorted(counts)
    ax.bar([str(k) for k in ks], [counts[k] / total for k in ks], color="tab:blue")
    if unsettled:
        ax.bar(["unsettled"], [len(unsettled) / total], color="tab:gray")
    ax.set_xlabel("fold count")
    ax.set_ylabel(f"fraction of {total} runs")
    ax.set_title("fold-count frequency")
    th = np.linspace(0.0, 2 * np.pi, 361)
    for i, st in enumerate(states):
        a = fig.add_subplot(gs[i // cols, 1 + i % cols], projection="polar")
        r = np.asarray(st.representative["radius_profile"], float)
        a.plot(th, np.append(r, r[0]), color="tab:red", lw=1.2)
        a.fill(th, np.append(r, r[0]), color="tab:red", alpha=0.15)
        a.set_yticklabels([])
        a.set_xticklabels([])
        lo, mean, hi = st.dc_range()
        a.set_title(
            f"S{st.number}: {st.fold_count} folds, DC {mean:.3f}\n{st.count}/{total} runs "
            f"({100 * st.count / total:.0f} %)",
            fontsize=9,
        )
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def curve_figure(rows, x, y, path, x_ref=1.0, x_label=None, by=None, log_x=False, title="") -> Path:
    """y against x / x_ref, one line per value of ``by`` (a column), converged runs only; the
    fold count is written beside each point."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    groups = {}
    for r in rows:
        if r.get("status") != "done" or r.get(y) is None or r.get(x) is None:
            continue
        groups.setdefault(r.get(by) if by else None, []).append(r)
    for g, rs in sorted(groups.items(), key=lambda kv: str(kv[0])):
        rs = sorted(rs, key=lambda r: r[x])
        xs = np.array([float(r[x]) / x_ref for r in rs])
        ys = np.array([float(r[y]) for r in rs])
        ok = np.array([bool(r.get("converged")) for r in rs])
        lab = f"{by} = {g}" if by else None
        (line,) = ax.plot(xs, ys, "-", lw=1, label=lab)
        ax.plot(xs[ok], ys[ok], "o", color=line.get_color())
        ax.plot(xs[~ok], ys[~ok], "x", color=line.get_color())
        for xi, yi, r in zip(xs, ys, rs):
            if r.get("fold_count") is not None:
                ax.annotate(str(r["fold_count"]), (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=7)
    if log_x:
        ax.set_xscale("log", base=2)
    ax.set_xlabel(x_label or (f"{x} / {x_ref:g}" if x_ref != 1.0 else x))
    ax.set_ylabel(y.replace("_", " "))
    ax.grid(True, alpha=0.3)
    if by:
        ax.legend(fontsize=8)
    ax.set_title(
        f"{title + ': ' if title else ''}{y.replace('_', ' ')}  (numbers: fold count; x: not converged)", fontsize=10
    )
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
