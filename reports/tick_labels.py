"""Log-axis tick labels as plain text: "10⁻³" and "2×10⁻³", not mathtext.

matplotlib labels a log axis with mathtext (``$\\mathdefault{10^{-3}}$``); parsing it (pyparsing) was a third of
a report's build time, each label parsed again for each figure and each layout pass. The same label written
with Unicode superscripts is plain text: measured once, drawn as text in the SVG (``svg.fonttype: none``).
:func:`register` makes the ``"log"`` scale label this way in this process (``set_xscale("log")``, ``semilogy``);
:func:`plain_figure` relabels what set its own formatter (a ``LogNorm`` colour bar) before the figure is saved.
"""

from __future__ import annotations

import re

import matplotlib.scale
from matplotlib.ticker import LogFormatterSciNotation

__all__ = ["PlainLogFormatter", "PlainLogScale", "plain", "plain_figure", "register"]

_SUPERSCRIPT = str.maketrans("0123456789-+", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻⁺")
_POWER = re.compile(r"\^\{([^{}]*)\}")


def plain(label):
    """``label`` (str: a mathtext tick label of ``LogFormatterSciNotation``, or plain text) as plain text.

    ``$\\mathdefault{2\\times10^{-3}}$`` -> ``2×10⁻³``; an exponent with a character that has no superscript
    (a fractional decade, ``10^{-1.5}``) keeps its caret: ``10^-1.5``.
    """
    if not (label.startswith("$") and label.endswith("$")):
        return label
    text = label[1:-1].replace(r"\mathdefault", "").replace(r"\times", "×").replace(r"\cdot", "·")

    def power(m):
        exponent = m.group(1)
        return exponent.translate(_SUPERSCRIPT) if re.fullmatch(r"[-+]?\d+", exponent) else "^" + exponent

    return _POWER.sub(power, text).replace("{", "").replace("}", "")


class PlainLogFormatter(LogFormatterSciNotation):
    """``LogFormatterSciNotation`` (the same ticks labelled, the same numbers) writing :func:`plain` text."""

    def __call__(self, x, pos=None):
        return plain(super().__call__(x, pos))


class PlainLogScale(matplotlib.scale.LogScale):
    """matplotlib's log scale, its tick labels by :class:`PlainLogFormatter` (its locators unchanged)."""

    def __init__(self, *args, **kwargs):
        # no parameter named ``axis``: matplotlib >= 3.11 then constructs it without one (the parameter is
        # pending deprecation there); an older one passes it first, to ``LogScale`` through ``args``
        super().__init__(*args, **kwargs)

    def set_default_locators_and_formatters(self, axis):
        super().set_default_locators_and_formatters(axis)
        major, minor = axis.get_major_formatter(), axis.get_minor_formatter()
        axis.set_major_formatter(PlainLogFormatter(self.base, labelOnlyBase=major.labelOnlyBase))
        axis.set_minor_formatter(PlainLogFormatter(self.base, labelOnlyBase=minor.labelOnlyBase))


def register():
    """The ``"log"`` scale of this process labelled by :class:`PlainLogFormatter` (idempotent)."""
    matplotlib.scale.register_scale(PlainLogScale)


def plain_figure(fig):
    """Every axis of ``fig`` (colour bars too) that a ``LogFormatterSciNotation`` labels, labelled by a
    :class:`PlainLogFormatter` of the same base and choice of labelled ticks instead."""
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            for get, put in ((axis.get_major_formatter, axis.set_major_formatter),
                             (axis.get_minor_formatter, axis.set_minor_formatter)):
                old = get()
                if isinstance(old, LogFormatterSciNotation) and not isinstance(old, PlainLogFormatter):
                    put(PlainLogFormatter(old._base, labelOnlyBase=old.labelOnlyBase,
                                          minor_thresholds=old.minor_thresholds, linthresh=old._linthresh))
