"""A matplotlib figure as SVG text, cropped to what it draws, measured without drawing it an extra time.

``savefig(bbox_inches="tight")`` draws the whole figure once, unseen, before it measures the box to crop to, then
draws it again into the file. For a figure laid out already (``tight_layout``, or axes placed by hand) that first
draw changes nothing the measurement reads: ``tight_box`` measures the same box without it (the same numbers to
the SVG's last digit), and the figure is drawn once. A constrained layout is computed in that first draw, so a
figure with one is saved as before.

The text is a function of the figure alone, so that two reports of one store are byte-identical: no date in its
metadata, and none of the random ids matplotlib salts with ``uuid4()`` (``svg.hashsalt`` unset). Its ids are salted
by the figure's own drawing (``own_ids``): unique to it among a page's inlined figures, as the random ones were.
"""

from __future__ import annotations

import hashlib
import io
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.backends.backend_svg import FigureCanvasSVG, RendererSVG  # noqa: E402

from dalembert.reports import tick_labels  # noqa: E402

__all__ = ["svg", "tight_box", "own_ids", "SVG_DPI", "SAVE_SALT"]

SVG_DPI = 72  # matplotlib's SVG backend draws a figure at 72 dpi: its units are points
SAVE_SALT = "dalembert"  # ``svg.hashsalt`` while a figure is saved: any fixed text (``own_ids`` salts again)
# An id matplotlib's SVG backend makes from a hash (``RendererSVG._make_id``: a type, then 10 hex digits of the
# salted SHA-256 of what it names): clip paths p, markers m, hatches h, images, a path collection's paths
# C<collection>_<path>_. Matched where it is defined (id="...") and referred to ("#..." in an href, url(#...)).
_HASHED_ID = re.compile(r'(?<=["#])((?:[pmh]|image|C[0-9a-f]+_[0-9a-f]+_)[0-9a-f]{10})(?=[")])')


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
    # the salt for this save only, not the user's process's; "Date": None writes no date (not even SOURCE_DATE_EPOCH's)
    with matplotlib.rc_context({"svg.hashsalt": SAVE_SALT}):
        fig.savefig(buf, format="svg", bbox_inches=box, metadata={"Date": None})
    plt.close(fig)
    text = buf.getvalue()
    return own_ids(text[text.index("<svg"):])


def own_ids(text):
    """``text`` (an SVG matplotlib wrote with a fixed ``svg.hashsalt``) with each of its hashed ids salted again by
    the SHA-256 of ``text`` itself: the same ids for the same drawing in any process, and ids that no other figure
    inlined in the same page has (a fixed salt alone gives two figures' equal clip boxes, markers, one id), unless it
    is the same drawing.

    Parameters
    ----------
    text : str — an SVG document

    Returns
    -------
    str — ``text`` with each id ``_HASHED_ID`` matches, and every reference to it, renamed (its type kept)
    """
    salt = hashlib.sha256(text.encode("utf-8")).digest()
    new = {}

    def renamed(match):
        old = match.group(1)
        if old not in new:
            new[old] = old[:-10] + hashlib.sha256(salt + old.encode("utf-8")).hexdigest()[:10]
        return new[old]

    return _HASHED_ID.sub(renamed, text)


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
