"""Figures as SVG text (matplotlib, Agg): embedded in the HTML, written beside the Markdown."""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

plt.rcParams.update({"svg.fonttype": "none", "font.size": 9, "axes.grid": True, "grid.alpha": 0.3})

MAX_POINTS = 400  # per line: figures stay small; the data stay in the store


def _svg(fig):
    buf = io.StringIO()
    fig.savefig(buf, format="svg", bbox_inches="tight")
    plt.close(fig)
    text = buf.getvalue()
    return text[text.index("<svg"):]


def _thin(t, *ys):
    step = max(1, len(t) // MAX_POINTS)
    return (t[::step],) + tuple(y[::step] for y in ys)


def work_precision(lines, ylabel, floor=None, title=""):
    """Log-log error against stepping time per simulated second, one line per engine + integrator."""
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    for label, pts in sorted(lines.items()):
        c, e, names = zip(*pts)
        (h,) = ax.loglog(c, e, "o-", label=label, ms=4)
        for ci, ei, name in zip(c, e, names):
            ax.annotate(name, (ci, ei), fontsize=6, color=h.get_color(), xytext=(3, 3), textcoords="offset points")
    if floor:
        ax.axhline(floor, color="k", ls=":", lw=1, label="roundoff floor (double RK4 at dt = 1e-3 vs extended precision)")
    ax.set_xlabel("stepping wall time per simulated second (s/s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    return _svg(fig)


def time_series(t, curves, ylabel, log=False, title="", truth=None):
    """Curves ``{label: y (n,) or (n, k)}`` against time; ``truth`` drawn dashed."""
    fig, ax = plt.subplots(figsize=(7.5, 3.2))
    if truth is not None:
        tt, *yy = _thin(t, np.atleast_2d(truth.T).T)
        ax.plot(tt, yy[0], "k--", lw=1.2, label="truth")
    for label, y in sorted(curves.items()):
        tt, yy = _thin(t, y)
        if log:
            ax.semilogy(tt, np.maximum(np.abs(yy), 1e-17), lw=1, label=label)
        else:
            ax.plot(tt, yy, lw=1, label=label)
    ax.set_xlabel("t (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    return _svg(fig)


VERDICT_COLOURS = {"stable": "#3c9a4b", "drifts": "#e0a526", "diverged": "#c0392b", "failed": "#7f3c8d",
                   "timeout": "#555555", "unsupported": "#cfcfcf"}


def stability_grid(rows, columns, cells, title=""):
    """Colour-coded grid: ``cells[(row, column)] = verdict``."""
    fig, ax = plt.subplots(figsize=(max(4, 0.9 * len(columns) + 2.5), 0.32 * len(rows) + 1.2))
    for i, r in enumerate(rows):
        for j, c in enumerate(columns):
            v = cells.get((r, c))
            if v is None:
                continue
            ax.add_patch(plt.Rectangle((j, i), 1, 1, color=VERDICT_COLOURS.get(v, "#ffffff")))
            ax.text(j + 0.5, i + 0.5, v, ha="center", va="center", fontsize=6)
    ax.set_xlim(0, len(columns))
    ax.set_ylim(len(rows), 0)
    ax.set_xticks(np.arange(len(columns)) + 0.5, columns, rotation=30, ha="right", fontsize=7)
    ax.set_yticks(np.arange(len(rows)) + 0.5, rows, fontsize=7)
    ax.grid(False)
    ax.set_title(title)
    return _svg(fig)
