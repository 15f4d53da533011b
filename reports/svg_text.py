"""A matplotlib figure as SVG text, cropped to what it draws, measured without drawing it an extra time.

``savefig(bbox_inches="tight")`` draws the whole figure once, unseen, before it measures the box to crop to, then
draws it again into the file. For a figure laid out already (``tight_layout``, or axes placed by hand) that first
draw changes nothing the measurement reads: ``tight_box`` measures the same box without it (the same numbers to
the SVG's last digit), and the figure is drawn once. A constrained layout is computed in that first draw, so a
figure with one is saved as before.
"""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.backends.backend_svg import FigureCanvasSVG, RendererSVG  # noqa: E402

from dalembert.reports import tick_labels  # noqa: E402

__all__ = ["svg", "tight_box", "SVG_DPI"]

SVG_DPI = 72  # matplotlib's SVG backend draws a figure at 72 dpi: its units are points


def svg(fig):
    """``fig`` as SVG text (from ``<svg``), cropped as ``bbox_inches="tight"`` crops it; ``fig`` is closed.

    Parameters
    ----------
    fig : matplotlib.figure.Figure — laid out (``tight_layout``, constrained, or axes placed by hand)

    Returns
    -------
    str — the SVG document from its ``<svg`` tag (no XML declaration: it is inlined in the HTML)
    """
    tick_labels.plain_figure(fig)  # a colour bar's own log formatter too
    box = tight_box(fig)
    buf = io.StringIO()
    fig.savefig(buf, format="svg", bbox_inches=box)
    plt.close(fig)
    text = buf.getvalue()
    return text[text.index("<svg"):]


def tight_box(fig):
    """The box ``savefig(bbox_inches="tight")`` would crop an SVG of ``fig`` to, measured without drawing; ``fig``'s
    layout engine (if any) is run here, as that save runs it, and then taken off (saving runs none).

    Measured as matplotlib's SVG backend measures it: on its canvas, in points (the figure at 72 dpi), by its
    renderer's text metrics, padded by ``savefig.pad_inches``.

    Returns
    -------
    matplotlib.transforms.Bbox — in inches, in the figure's frame (origin bottom left)
    """
    canvas, dpi = fig.canvas, fig.dpi
    FigureCanvasSVG(fig)  # fig.canvas for now: a constrained layout measures with its canvas's renderer
    fig.dpi = SVG_DPI
    try:
        engine = fig.get_layout_engine()  # tight_layout leaves a placeholder: nothing to run
        if engine is not None:
            engine.execute(fig)
        width, height = fig.get_size_inches() * SVG_DPI
        box = fig.get_tightbbox(RendererSVG(width, height, io.StringIO(), image_dpi=dpi))
    finally:
        fig.set_canvas(canvas)
        fig.dpi = dpi
    fig.set_layout_engine(None)  # laid out: savefig would otherwise draw it unseen once more to run the engine
    return box.padded(plt.rcParams["savefig.pad_inches"])
