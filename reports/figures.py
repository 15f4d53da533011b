"""Figures as SVG text (matplotlib, Agg): embedded in the HTML, written beside the Markdown.

Each function takes data already chosen from the store (points, cells, series)
and draws it; none reads a store. Colours mean one thing per figure: engines
in the summary (``engine_colours``, the same in every figure of a report),
integrators within a work-precision panel, sweep values in time plots.
"""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from dalembert.reports import tick_labels  # noqa: E402
from dalembert.reports.formatting import value_text  # noqa: E402
from dalembert.reports.svg_text import svg  # noqa: E402

plt.rcParams.update({"svg.fonttype": "none", "font.size": 9, "axes.grid": True, "grid.alpha": 0.3,
                     "legend.fontsize": 7, "axes.titlesize": 10})
tick_labels.register()  # log axes labelled "10⁻³", not mathtext (its parsing was a third of a report's build)

__all__ = ["engine_colours", "pareto_summary", "work_precision", "stability", "time_grid", "diverged_runs",
           "diverged_figure", "stability_map", "map_costs", "scaling", "MAX_POINTS", "svg", "grid", "thin"]

MAX_POINTS = 400  # per time-series line: figures stay small; the data stay in the store
PANEL_W, PANEL_H = 3.3, 2.8  # inches per small-multiple panel: four fit across the page
ROW_W, MAX_PANEL_W = 4 * PANEL_W, 4.4  # a row of fewer panels shares the same width, up to this per panel
# Okabe & Ito's colour-blind-safe qualitative palette (engines: at most this many per report).
ENGINE_PALETTE = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442")
# Integrators within one panel: matplotlib's tab10 plus two darks, so Exudyn's twelve stay distinct.
INTEGRATOR_PALETTE = tuple(plt.get_cmap("tab10").colors) + ("#000000", "#8c6d31")
OPTION_STYLES = ("-", "--", ":", "-.")
LEGEND_W = 2.2  # inches beside a panel for its own legend (stability maps)
FLOOR_STYLE = dict(color="k", ls=":", lw=1.2)
# What the dotted line is (``reference.roundoff``: RK4 in double against its extended-precision twin), said wherever
# it is drawn: an estimate, so a run below it is no contradiction.
ROUNDOFF_NOTE = ("the roundoff floor, an estimate of the roundoff a double-precision integrator accumulates over the "
                 "horizon, not a bound (a run may sit below it)")
# Markers beside the colours of a panel's integrators: a colour comes back after INTEGRATOR_PALETTE's twelve, with
# another marker (Drake's fifteen integrators stay distinct).
INTEGRATOR_MARKERS = ("o", "s", "^", "D", "v")
TOLERANCE_STYLE = dict(color="#c0392b", ls="--", lw=1.0)
DIVERGED_MARGIN = 2.0  # factor of room below the lowest and above the largest error on the diverged runs' axis
# Per diverged run, the share of its samples (%) that may lie below the axis: its start at roundoff (1e-16 at
# the first samples) before the error grows, which would otherwise squeeze every run into the top decades.
DIVERGED_LOW_PERCENTILE = 5.0


def thin(t, y):
    step = max(1, len(t) // MAX_POINTS)
    return t[::step], y[::step]


def engine_colours(engines):
    """One colour per engine name, in sorted order (the same engine, the same colour, in every figure)."""
    return {e: ENGINE_PALETTE[i % len(ENGINE_PALETTE)] for i, e in enumerate(sorted(engines))}


def _columns(n, most=4):
    """Panels per row: four, or three when that leaves fewer empty slots (six panels: 3 x 2)."""
    if n <= most:
        return max(1, n)
    return min((most, most - 1), key=lambda c: (-(-n // c) * c - n, -c))


def _panel_width(ncols):
    return min(MAX_PANEL_W, ROW_W / ncols)


def grid(n, ncols=4, sharex=True, sharey=True, height=PANEL_H):
    ncols = _columns(n, ncols)
    nrows = math.ceil(n / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(_panel_width(ncols) * ncols, height * nrows), sharex=sharex,
                             sharey=sharey, squeeze=False)
    flat = axes.ravel()
    for ax in flat[n:]:
        ax.set_visible(False)
    return fig, flat[:n]


def _levels(ax, floor, tolerance):
    """The case's roundoff floor and tolerance as horizontal lines (labelled in the legend)."""
    if floor:
        ax.axhline(floor, **FLOOR_STYLE, label="roundoff floor (estimate)")
    if tolerance:
        ax.axhline(tolerance, **TOLERANCE_STYLE, label="tolerance")


# ---------------------------------------------------------------------------------------------- summary
def pareto_summary(panels, colours, xlabel="stepping time per simulated second (s/s)"):
    """Per case, each engine's Pareto front: the best error it reaches at each cost.

    Parameters
    ----------
    panels : list of dict — ``title``, ``ylabel``, ``fronts`` {engine: [(cost, error), ...] by cost},
        ``floor``, ``tolerance`` (None when absent)
    colours : dict engine -> colour
    """
    fig, axes = grid(len(panels), sharey=False)
    for ax, p in zip(axes, panels):
        for engine, front in sorted(p["fronts"].items()):
            c, e = zip(*front)
            # a step down at each point: at a cost between two points, the cheaper one's error is the best
            ax.step(list(c) + [c[-1] * 3], list(e) + [e[-1]], where="post", color=colours[engine], lw=1.6,
                    label=engine)
            ax.plot(c, e, "o", color=colours[engine], ms=3.5)
        _levels(ax, p.get("floor"), p.get("tolerance"))
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(p["title"])
        ax.set_ylabel(p["ylabel"])
        ax.set_xlabel(xlabel)
    handles = [Line2D([], [], color=colours[e], lw=2, marker="o", ms=4) for e in sorted(colours)]
    labels = sorted(colours)
    handles += [Line2D([], [], **TOLERANCE_STYLE), Line2D([], [], **FLOOR_STYLE)]
    labels += ["case tolerance", "roundoff floor (estimate)"]
    fig.legend(handles, labels, loc="upper center", ncol=len(labels), bbox_to_anchor=(0.5, 1.0), frameon=False,
               fontsize=9)
    fig.tight_layout(rect=(0, 0, 1, 0.93 if len(axes) <= 4 else 0.96))
    return svg(fig)


# ---------------------------------------------------------------------------------------------- work-precision
def work_precision(panels, ylabel, floor=None, tolerance=None, xlabel="stepping time per simulated second (s/s)"):
    """Small multiples on shared axes, a panel per engine (and per option variant of it): a line per
    integrator along its sweep, the sweep value written at each end only.

    Parameters
    ----------
    panels : list of dict — ``title``, ``engine``, ``lines`` [dict ``integrator``,
        ``points`` [(cost, error, sweep label), ...] from coarse to fine]
    """
    ncols = _columns(len(panels))
    nrows = math.ceil(len(panels) / ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(_panel_width(ncols) * ncols, 3.9 * nrows), sharex=True, sharey=True,
                             squeeze=False, layout="constrained")
    flat = axes.ravel()
    for ax in flat[len(panels):]:
        ax.set_visible(False)
    # an integrator keeps its colour in every panel of its engine
    colour = {}
    for p in panels:
        names = sorted({ln["integrator"] for q in panels if q["engine"] == p["engine"] for ln in q["lines"]})
        colour.update({(p["engine"], i): (INTEGRATOR_PALETTE[k % len(INTEGRATOR_PALETTE)],
                                          INTEGRATOR_MARKERS[(k // len(INTEGRATOR_PALETTE)) % len(INTEGRATOR_MARKERS)])
                       for k, i in enumerate(names)})
    for ax, p in zip(flat, panels):
        placed = []
        for ln in sorted(p["lines"], key=lambda ln: ln["integrator"]):
            c, e, names = zip(*ln["points"])
            col, mark = colour[(p["engine"], ln["integrator"])]
            ax.plot(c, e, "-", color=col, lw=1.3)
            ax.plot(c[:1], e[:1], mark, mfc="white", mec=col, ms=4.5)  # open: the coarse end
            ax.plot(c[-1:], e[-1:], mark, color=col, ms=4.5)  # filled: the fine end
            for k in sorted({0, len(c) - 1}):
                _end_label(ax, placed, c[k], e[k], names[k], col)
        _levels(ax, floor, tolerance)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(p["title"])
        ax.set_xlabel(xlabel)
        # the legend's keys carry each integrator's colour and marker (a colour alone repeats past twelve)
        handles = [Line2D([], [], color=colour[(p["engine"], i)][0], marker=colour[(p["engine"], i)][1], lw=1.3, ms=4,
                          label=i) for i in sorted({ln["integrator"] for ln in p["lines"]})]
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, fontsize=7,
                  frameon=False, handlelength=1.4, columnspacing=0.9)
    for row in axes:
        row[0].set_ylabel(ylabel)
    return svg(fig)


def _end_label(ax, placed, x, y, text, colour):
    """Write a sweep value beside a line's end, unless the same text is already written close by
    (lines that end together share one label instead of a smudge of overlapping ones)."""
    lx, ly = math.log10(x), math.log10(y)
    if any(t == text and abs(lx - px) < 0.25 and abs(ly - py) < 0.6 for t, px, py in placed):
        return
    placed.append((text, lx, ly))
    ax.annotate(text, (x, y), xytext=(3, 2), textcoords="offset points", fontsize=6, color=colour)


# ---------------------------------------------------------------------------------------------- stability
def stability(blocks, label, bound=None, cmap="YlOrRd"):
    """Magnitude per run on a log colour scale, with its stored verdict written in the cell;
    a block per kind of sweep (fixed-step, adaptive) side by side, a row per engine, integrator and
    options.

    Parameters
    ----------
    blocks : list of dict — ``title``, ``rows`` [label], ``columns`` [sweep label], ``cells``
        {(row, column): (value or None, verdict, note)}
    label : str — what the colour measures (colour-bar label)
    bound : float or None — the case's bound on it, marked on the colour bar
    """
    values = [v for b in blocks for v, _, _ in b["cells"].values() if v is not None and v > 0 and math.isfinite(v)]
    norm = LogNorm(vmin=min(values), vmax=max(values)) if values else None
    if norm is not None and norm.vmin == norm.vmax:
        norm = LogNorm(vmin=norm.vmin / 10, vmax=norm.vmax * 10)
    colormap = plt.get_cmap(cmap)
    # sizes in inches: every cell the same size whatever its block's row count
    cell_w, cell_h, label_w, top, bottom = 1.25, 0.24, 2.5, 0.55, 0.15
    rows = max(len(b["rows"]) for b in blocks)
    widths = [label_w + cell_w * len(b["columns"]) for b in blocks]
    fig_w, fig_h = sum(widths) + 1.4, top + bottom + cell_h * rows
    fig = plt.figure(figsize=(fig_w, fig_h))
    x = 0.0
    axes = []
    for b, w in zip(blocks, widths):
        h = cell_h * len(b["rows"])
        ax = fig.add_axes(((x + label_w) / fig_w, (fig_h - top - h) / fig_h, (w - label_w) / fig_w, h / fig_h))
        axes.append(ax)
        x += w
        for i, r in enumerate(b["rows"]):
            for j, c in enumerate(b["columns"]):
                if (r, c) not in b["cells"]:
                    continue
                value, verdict, note = b["cells"][(r, c)]
                if value is not None and value > 0 and math.isfinite(value) and norm is not None:
                    face = colormap(norm(value))
                    text = f"{value:.1e} {verdict}"
                    dark = sum(face[:3]) < 1.3
                elif verdict == "diverged":
                    face, text, dark = "#222222", f"diverged {note}".strip(), True
                else:
                    face, text, dark = "#e8e8e8", f"{verdict} {note}".strip(), False
                ax.add_patch(plt.Rectangle((j, i), 1, 1, facecolor=face, edgecolor="white", lw=1,
                                           hatch="//" if verdict in ("failed", "timeout") else None))
                ax.text(j + 0.5, i + 0.5, text, ha="center", va="center", fontsize=6.5,
                        weight="normal" if verdict == "stable" else "bold", color="white" if dark else "black")
        ax.set_xlim(0, len(b["columns"]))
        ax.set_ylim(len(b["rows"]), 0)
        ax.set_xticks(np.arange(len(b["columns"])) + 0.5, b["columns"], fontsize=8)
        ax.xaxis.tick_top()
        ax.set_yticks(np.arange(len(b["rows"])) + 0.5, b["rows"], fontsize=7)
        ax.tick_params(length=0)
        ax.grid(False)
        ax.set_title(b["title"], loc="left", fontsize=9, pad=16)
    if norm is not None:
        cax = fig.add_axes(((fig_w - 1.1) / fig_w, bottom / fig_h, 0.15 / fig_w, (fig_h - top - bottom) / fig_h))
        bar = fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=colormap), cax=cax, label=label)
        if bound and norm.vmin <= bound <= norm.vmax:
            bar.ax.axhline(bound, color="k", lw=2)
            bar.ax.text(-0.3, bound, "bound", ha="right", va="center", fontsize=7, transform=bar.ax.get_yaxis_transform())
    return svg(fig)


# ---------------------------------------------------------------------------------------------- time plots
SWEEP_COLOURS = ("#1b4f9c", "#6baed6", "#b2182b", "#f4a582", "#4d4d4d", "#a6a6a6")


def time_grid(rows, engines, sweep_colours):
    """Quantities against time: a row per quantity (shared y), a column per engine (shared x), a
    line per run (coloured by its sweep value).

    Parameters
    ----------
    rows : list of dict — ``ylabel``, ``log`` (bool), ``series`` {engine: [(label, sweep, t, y), ...]},
        ``bound`` (the case's tolerance on the quantity, drawn dashed; None for none)
    engines : list of str — the columns
    sweep_colours : dict sweep label -> colour
    """
    n_rows, n_cols = len(rows), len(engines)
    fig, axes = plt.subplots(n_rows, n_cols, figsize=(_panel_width(n_cols) * n_cols, 2.0 * n_rows + 0.5), sharex=True,
                             sharey="row", squeeze=False)
    for i, row in enumerate(rows):
        for j, engine in enumerate(engines):
            ax = axes[i, j]
            for label, sweep, t, y in row["series"].get(engine, []):
                tt, yy = thin(t, y)
                if row["log"]:
                    ax.semilogy(tt, np.where(np.isfinite(yy), np.maximum(np.abs(yy), 1e-17), np.nan), lw=1,
                                color=sweep_colours[sweep], label=label)
                else:
                    ax.plot(tt, yy, lw=1, color=sweep_colours[sweep], label=label)
            if row.get("bound"):
                ax.axhline(row["bound"], **TOLERANCE_STYLE)
            if i == 0:
                ax.set_title(engine)
                if ax.lines:
                    ax.legend(fontsize=6, loc="lower right", framealpha=0.85)
            if j == 0:
                ax.set_ylabel(row["ylabel"])
            if i == n_rows - 1:
                ax.set_xlabel("t (s)")
    fig.tight_layout()
    return svg(fig)


def diverged_figure(panels, ylabel):
    """Runs that diverged: their error until it stopped being finite, the divergence time marked;
    a panel per engine, one above the other, the runs named beside it. Returns the matplotlib figure
    (``diverged_runs`` gives its SVG).

    The y axis is logarithmic and spans every run: from the lowest of the runs' low ends (each run's
    ``DIVERGED_LOW_PERCENTILE`` percentile: below it only its roundoff start, which its line enters
    from) to the largest error of any run. A run that blew up to 1e30 and one that diverged from 1e-3
    both show; the axis is never set from one run's size alone (it was: the largest error over 1e12,
    which hid every smaller run). Not symlog: the errors are positive and span decades, and a linear
    band near zero would hold nothing; not clipped with markers: a marker hides the run's shape. An
    error of exactly zero (the exact start) has no place on a log axis and is left out.

    Parameters
    ----------
    panels : dict engine -> list of (label, t, y, t_diverged or None) — ``t`` (n,) s, ``y`` (n,) the
        error in the unit of ``ylabel``, NaN or inf once the run stopped being finite
    ylabel : str — the error and its unit
    """
    fig, axes = plt.subplots(len(panels), 1, figsize=(9.5, 2.9 * len(panels)), squeeze=False, layout="constrained")
    for ax, (engine, runs) in zip(axes[:, 0], sorted(panels.items())):
        drawn = []
        for k, (label, t, y, t_div) in enumerate(runs):
            colour = INTEGRATOR_PALETTE[k % len(INTEGRATOR_PALETTE)]
            tt, yy = thin(np.asarray(t), np.abs(np.asarray(y, dtype=float)))
            yy = np.where(np.isfinite(yy) & (yy > 0), yy, np.nan)
            drawn.append(yy[np.isfinite(yy)])
            ax.semilogy(tt, yy, lw=1, color=colour,
                        label=label + (f" (t = {value_text(t_div, 's')})" if t_div is not None else ""))
            if t_div is not None:
                ax.axvline(t_div, color=colour, ls=":", lw=1)
                ax.plot([t_div], [1], "x", color=colour, ms=7, mew=2, transform=ax.get_xaxis_transform(),
                        clip_on=False)
        drawn = [v for v in drawn if v.size]
        if drawn:  # from the lowest run's growth (not its roundoff start) to the largest error, with room
            ax.set_ylim(min(np.percentile(v, DIVERGED_LOW_PERCENTILE) for v in drawn) / DIVERGED_MARGIN,
                        max(v.max() for v in drawn) * DIVERGED_MARGIN)
        ax.set_title(f"{engine}: runs that diverged (x: when)", loc="left")
        ax.set_xlabel("t (s)")
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return fig


def diverged_runs(panels, ylabel):
    """``diverged_figure`` as SVG text."""
    return svg(diverged_figure(panels, ylabel))


# ---------------------------------------------------------------------------------------------- stability maps
def _bracket_point(ax, x, bracket, scale, colour, filled, offset):
    """One boundary at ``x``: a marker at the largest passing step, a bar up to the smallest failing
    one; a triangle where the boundary lies beyond the probes (up: passes at every probe)."""
    face = colour if filled else "white"
    if bracket.passed is not None and bracket.failed is not None:
        ax.plot([x * offset] * 2, [bracket.passed * scale, bracket.failed * scale], color=colour, lw=1, alpha=0.6)
        ax.plot(x * offset, bracket.passed * scale, "o", color=colour, mfc=face, ms=4.5)
        return bracket.passed * scale
    if bracket.passed is not None:
        ax.plot(x * offset, bracket.passed * scale, "^", color=colour, mfc=face, ms=6)
        return bracket.passed * scale
    if bracket.failed is not None:
        ax.plot(x * offset, bracket.failed * scale, "v", color=colour, mfc=face, ms=6)
    return None


def stability_map(panels, xlabel, ylabel, rate):
    """A panel per engine: for each integrator (colour) the stable boundary (filled markers, solid
    line) and the finite boundary (hollow markers, dashed) against the swept parameter, log-log.
    Two panels a row, each with its own legend at its right: an engine's integrators get distinct
    colours within its panel (a legend shared by five engines' 40 integrators repeats colours).

    Parameters
    ----------
    panels : list of dict — ``title`` and ``lines`` {integrator label: [(value, Boundary), ...]}
    xlabel, ylabel : str
    rate : bool — plot parameter x step (dimensionless) instead of the step
    """
    most = max((len(p["lines"]) for p in panels), default=1)
    nrows = max(1, math.ceil(len(panels) / 2))
    fig, grid = plt.subplots(nrows, 2, figsize=(2 * (PANEL_W + LEGEND_W), max(PANEL_H, 0.75 + 0.14 * most) * nrows),
                             sharex=True, sharey=True, squeeze=False)
    axes = grid.ravel()
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    for ax, p in zip(axes, panels):
        colour = {label: INTEGRATOR_PALETTE[i % len(INTEGRATOR_PALETTE)] for i, label in enumerate(sorted(p["lines"]))}
        style = {label: OPTION_STYLES[0] if i < len(INTEGRATOR_PALETTE) else OPTION_STYLES[2]
                 for i, label in enumerate(sorted(p["lines"]))}
        for label, points in sorted(p["lines"].items()):
            for filled, side, ls, offset in ((True, "stable", style[label], 0.97), (False, "finite", "--", 1.03)):
                xs, ys = [], []
                for value, b in points:
                    y = _bracket_point(ax, value, getattr(b, side), value if rate else 1.0, colour[label], filled,
                                       offset)
                    if y is not None:
                        xs.append(value * offset)
                        ys.append(y)
                if len(xs) > 1:
                    ax.plot(xs, ys, ls, color=colour[label], lw=1.2)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(p["title"])
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.legend([Line2D([], [], color=colour[label], ls=style[label], lw=2) for label in sorted(p["lines"])],
                  sorted(p["lines"]), loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False, fontsize=6.5)
    handles = [Line2D([], [], color="k", ls="-", marker="o", ms=4.5),
               Line2D([], [], color="k", ls="--", marker="o", mfc="white", ms=4.5),
               Line2D([], [], color="k", ls="", marker="^", ms=6), Line2D([], [], color="k", ls="", marker="v", ms=6)]
    names = ["stable up to", "finite up to", "beyond the largest step probed", "below the smallest"]
    fig.legend(handles, names, loc="upper center", ncol=4, bbox_to_anchor=(0.5, 1.0), frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.subplots_adjust(wspace=LEGEND_W / PANEL_W + 0.25)
    for ax in axes[:len(panels)]:
        ax.xaxis.set_tick_params(labelbottom=True)
    return svg(fig)


def map_costs(panels, xlabel, ylabel):
    """A panel per engine: the cost of reaching the target accuracy against the swept parameter,
    a line per integrator (values that never reach it are left out)."""
    labels = sorted({label for p in panels for label in p["lines"]})
    colour = {label: INTEGRATOR_PALETTE[i % len(INTEGRATOR_PALETTE)] for i, label in enumerate(labels)}
    fig, axes = grid(len(panels))
    for ax, p in zip(axes, panels):
        for label, points in sorted(p["lines"].items()):
            reached = [(x, c) for x, c in points if c is not None]
            if reached:
                ax.plot(*zip(*reached), "o-", color=colour[label], ms=4, lw=1.2, label=label)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(p["title"])
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
    fig.legend([Line2D([], [], color=colour[label], lw=2) for label in labels], labels, loc="upper center",
               ncol=min(len(labels), 6), bbox_to_anchor=(0.5, 1.0), frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    return svg(fig)


def scaling(lines, colours, sizes, xlabel="bodies N"):
    """One log-log panel: cost against the number of bodies (or ``xlabel``'s count), a line per (engine, label)
    coloured by engine (``colours``), a line style per label within an engine; ``lines`` maps (engine, label) to
    [(N, cost s/s)], the label carrying its fitted exponent. ``sizes`` (the N run) are the x ticks."""
    fig, ax = plt.subplots(figsize=(2 * PANEL_W, 1.3 * PANEL_H))
    styles = {}
    for (engine, label), points in sorted(lines.items()):
        style = OPTION_STYLES[styles.setdefault(engine, 0) % len(OPTION_STYLES)]
        styles[engine] += 1
        ax.plot(*zip(*points), marker="o", ls=style, color=colours[engine], ms=4, lw=1.4, label=f"{engine} {label}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xticks(list(sizes))
    ax.set_xticklabels([str(n) for n in sizes])
    ax.minorticks_off()
    ax.set_xlabel(xlabel)
    ax.set_ylabel("stepping time per simulated second (s/s)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)
    return svg(fig)


# ---------------------------------------------------------------------------------------------- contact
