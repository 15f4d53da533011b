"""Log-axis tick labels of the report's figures are plain text (``reports/tick_labels.py``), the same labels
matplotlib writes as mathtext."""

import pytest
from matplotlib.cm import ScalarMappable

from dalembert.reports import figures
from dalembert.reports.tick_labels import plain

plt = figures.plt


@pytest.mark.parametrize("mathtext,text", [
    (r"$\mathdefault{10^{-3}}$", "10⁻³"),
    (r"$\mathdefault{10^{12}}$", "10¹²"),
    (r"$\mathdefault{2\times10^{-3}}$", "2×10⁻³"),
    (r"$\mathdefault{1}$", "1"),
    (r"$\mathdefault{10^{-1.5}}$", "10^-1.5"),  # no superscript for a fractional decade's point
    ("", ""),
    ("0.5", "0.5"),
])
def test_a_mathtext_label_is_written_as_plain_text(mathtext, text):
    assert plain(mathtext) == text


def test_a_log_figure_s_svg_has_the_decades_in_plain_text_and_no_mathtext():
    """Both axes, a minor tick's label (a range under one decade labels 2×10⁻³...) and a LogNorm colour bar (which
    sets its own formatter) are labelled as matplotlib's mathtext formatter would, in plain text."""
    fig, (ax, narrow) = plt.subplots(1, 2)
    ax.plot([1e-4, 10.0], [1.0, 2.0])
    ax.set_xscale("log")
    fig.colorbar(ScalarMappable(norm=figures.LogNorm(1e-3, 1.0)), ax=ax)
    narrow.plot([1.0, 2.0], [2e-3, 9e-3])
    narrow.set_yscale("log")
    text = figures.svg(fig)
    assert "mathdefault" not in text and "$" not in text
    for label in ("10⁻⁴", "10⁻²", "10⁻³", "10⁻¹", "2×10⁻³", "6×10⁻³"):
        assert f">{label}<" in text, label
