"""The contact cases' figures: each engine's motion against the closed form, and the creep of every engine
setting on a log scale (the panels come from ``reports.sections.contact``). Drawn with the helpers of
``reports.figures``, in its style.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.ticker import MaxNLocator

from dalembert.reports.figures import PANEL_H, ROW_W, TOLERANCE_STYLE, grid, plt, svg, thin

__all__ = ["contact_panels", "creep_bars", "TRUTH_STYLE"]

TRUTH_STYLE = dict(color="k", ls="--", lw=1.6)  # the closed form, over the engines' lines
LABEL_ROOM = 4.0  # factor of room right of the longest bar on a log axis, for the value written after it


def contact_panels(panels):
    """A contact case's figures against the truth: one panel per figure, a line per run and the truth dashed.

    Parameters
    ----------
    panels : list of dict — ``title``, ``xlabel``, ``ylabel``, ``lines`` [(label, colour, linestyle, x, y), ...]
        (x, y ndarrays of one length, in the axes' units), ``truth`` (x, y) or None, ``markers`` (bool: points
        joined, for per-event figures such as the apex of each bounce)
    """
    fig, axes = grid(len(panels), ncols=2, sharex=False, sharey=False, height=PANEL_H + 0.4)
    for ax, p in zip(axes, panels):
        marker = dict(marker="o", ms=4) if p.get("markers") else {}
        for label, colour, style, x, y in p["lines"]:
            xx, yy = (x, y) if p.get("markers") else thin(np.asarray(x), np.asarray(y))
            ax.plot(xx, yy, color=colour, ls=style, lw=1.1, label=label, **marker)
        if p.get("truth") is not None:
            x, y = p["truth"]
            ax.plot(x, y, **TRUTH_STYLE, label="closed form", **marker)
        if p.get("markers"):  # events are counted: whole numbers on the axis
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_title(p["title"])
        ax.set_xlabel(p["xlabel"])
        ax.set_ylabel(p["ylabel"])
        if ax.lines:
            ax.legend(fontsize=6, framealpha=0.85)
    fig.tight_layout()
    return svg(fig)


def creep_bars(bars, colours, bound, xlabel):
    """Creep speed per engine and setting, a bar each on a log axis, the case's bound dashed.

    Parameters
    ----------
    bars : list of (engine, label, value) — value in the axis' unit; a zero is written beside the axis, not drawn
    colours : dict engine -> colour
    bound : float or None — the case's bound, in the axis' unit
    xlabel : str
    """
    fig, ax = plt.subplots(figsize=(ROW_W * 0.6, 0.9 + 0.32 * len(bars)))
    positive = [v for _, _, v in bars if v > 0 and math.isfinite(v)]
    low = min(positive + ([bound] if bound else [])) / 10.0 if positive or bound else 1e-12
    for i, (engine, label, value) in enumerate(bars):
        if value > 0 and math.isfinite(value):
            ax.barh(i, value - low, left=low, color=colours[engine], height=0.6)
            ax.text(value, i, f" {value:.3g}", va="center", fontsize=7)
        else:
            ax.text(low, i, f" {value:g}", va="center", fontsize=7)
    if bound:  # named above the axis, where no bar's value is written
        ax.axvline(bound, **TOLERANCE_STYLE)
        ax.annotate("the case's bound", (bound, 1.0), xycoords=("data", "axes fraction"), ha="center", va="bottom",
                    fontsize=7, color=TOLERANCE_STYLE["color"])
    ax.set_xscale("log")
    ax.set_xlim(low, max(positive + ([bound] if bound else []), default=low * 10.0) * LABEL_ROOM)
    ax.set_yticks(range(len(bars)), [f"{e} {label}".strip() for e, label, _ in bars])
    ax.invert_yaxis()
    ax.set_xlabel(xlabel)
    fig.tight_layout()
    return svg(fig)
