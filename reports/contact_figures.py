"""The contact cases' figures: each engine's motion against the closed form, the creep of every engine
setting on a log scale (the panels come from ``reports.sections.contact``), and a contact map: a contact metric
over an engine option against the step (``reports.sections.contact_maps``). Drawn with the helpers of
``reports.figures``, in its style.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.patches import Rectangle
from matplotlib.ticker import MaxNLocator

from dalembert.reports.figures import PANEL_H, ROW_W, TOLERANCE_STYLE, grid, plt, svg, thin

__all__ = ["contact_panels", "creep_bars", "contact_map", "TRUTH_STYLE", "MAP_CMAP", "BEYOND_HATCH"]

TRUTH_STYLE = dict(color="k", ls="--", lw=1.6)  # the closed form, over the engines' lines
LABEL_ROOM = 4.0  # factor of room right of the longest bar on a log axis, for the value written after it
MAP_CMAP = "viridis"  # perceptually uniform and colour-blind safe: a contact map's log colour scale
BEYOND_HATCH = "///"  # a contact map's cell beyond the case's bound: hatched and outlined in the tolerance's colour


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


def contact_map(panels, xs, ys, xlabel, ylabel):
    """A contact metric over an engine option (rows) against the step (columns): a cell per run on a log colour
    scale, its value written in it, a cell beyond the case's bound hatched and outlined.

    Parameters
    ----------
    panels : list of dict — ``title``, ``values`` ndarray (len(ys), len(xs)) in the colour bar's unit (NaN: no run,
        or one that stored no value; 0 is written, not coloured: a log scale has no 0), ``beyond`` bool ndarray of
        the same shape (the cells past the case's bound), ``unit`` (the colour bar's label)
    xs, ys : sequence of float — the columns' steps (s) and the rows' option values, ascending
    xlabel, ylabel : str
    """
    fig, axes = grid(len(panels), ncols=2, sharex=False, sharey=False, height=PANEL_H + 0.6)
    for ax, p in zip(axes, panels):
        values = np.asarray(p["values"], dtype=float)
        positive = values[np.isfinite(values) & (values > 0)]
        lo, hi = (positive.min(), positive.max()) if positive.size else (1.0, 10.0)
        norm = LogNorm(lo, hi if hi > lo else lo * 10.0)
        shown = np.ma.masked_where(~(np.isfinite(values) & (values > 0)), values)
        mesh = ax.pcolormesh(np.arange(len(xs) + 1) - 0.5, np.arange(len(ys) + 1) - 0.5, shown, cmap=MAP_CMAP,
                             norm=norm, shading="flat")
        for (i, j), value in np.ndenumerate(values):
            if p["beyond"][i, j]:
                ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1.0, 1.0, fill=False, hatch=BEYOND_HATCH,
                                       edgecolor=TOLERANCE_STYLE["color"], lw=1.2))
            if math.isfinite(value):  # dark text on the scale's bright top half, white on its dark bottom
                bright = value > 0 and norm(value) > 0.5
                ax.text(j, i, f"{value:.2g}", ha="center", va="center", fontsize=7,
                        color="k" if bright else "w" if value > 0 else "k")
        ax.set_xticks(range(len(xs)), [f"{x:.3g}" for x in xs], rotation=30)
        ax.set_yticks(range(len(ys)), [f"{y:.3g}" for y in ys])
        ax.grid(False)
        ax.set_title(p["title"])
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        fig.colorbar(mesh, ax=ax, label=p["unit"])
    fig.tight_layout()
    return svg(fig)
