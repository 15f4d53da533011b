"""The figure of one engine's versions side by side: per case, integrator and quantity, the value against the
engine version (log scale), one line per setting (step, tolerance, options).

Draws data already chosen from the store (``dalembert.reports.sections.versions``); reads none.
"""

from __future__ import annotations

import math

from dalembert.reports.figures import INTEGRATOR_MARKERS, INTEGRATOR_PALETTE, grid, svg

__all__ = ["versions_figure", "PANEL_H"]

# A panel's height, inches: its x axis carries the version names turned upright under it.
PANEL_H = 3.2


def versions_figure(versions, panels):
    """One panel per case, integrator and quantity: the value at each version, one line per setting.

    Parameters
    ----------
    versions : list of str — the x axis, in version order (``3.2.7``, ..., ``4.0.0``): one tick each
    panels : list of dict — ``title`` (case and integrator), ``ylabel`` (the quantity, with its unit),
        ``lines`` {setting label: [value or NaN per entry of ``versions``]} (NaN: that version has no finished
        run, or its value is zero, which a log axis cannot place)

    Returns
    -------
    str — the SVG text
    """
    fig, axes = grid(len(panels), sharex=False, sharey=False, height=PANEL_H)
    x = list(range(len(versions)))
    for ax, panel in zip(axes, panels):
        for i, (label, values) in enumerate(sorted(panel["lines"].items())):
            shown = [v if (v is not None and math.isfinite(v) and v > 0) else math.nan for v in values]
            ax.plot(x, shown, color=INTEGRATOR_PALETTE[i % len(INTEGRATOR_PALETTE)],
                    marker=INTEGRATOR_MARKERS[(i // len(INTEGRATOR_PALETTE)) % len(INTEGRATOR_MARKERS)], ms=3.5,
                    lw=1.2, label=label)
        if any(v > 0 for values in panel["lines"].values() for v in values if v is not None and math.isfinite(v)):
            ax.set_yscale("log")
        ax.set_xticks(x)
        ax.set_xticklabels(versions, rotation=90, fontsize=7)
        ax.set_title(panel["title"])
        ax.set_ylabel(panel["ylabel"])
        ax.legend(loc="best")
    fig.supxlabel("engine version")
    fig.tight_layout()
    return svg(fig)
