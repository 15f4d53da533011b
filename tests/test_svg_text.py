"""A figure's SVG text (``reports/svg_text.py``): drawn once, and the same document ``savefig(bbox_inches="tight")``
writes — the same crop box, text and paths — for each kind of layout the report's figures use."""

import io
import pickle
import re

import numpy as np
import pytest
from matplotlib.figure import Figure

from dalembert.reports import figures, svg_text

plt = figures.plt

# The SVG writes coordinates with 6 decimals (points); the box measured without the unseen draw may round the other
# way in that last digit (seen: 1e-6 pt on figures with a colour bar).
LAST_DIGIT_PT = 2e-6
_NUMBER = re.compile(r"-?\d+\.?\d*(?:e[-+]?\d+)?")


def _tight_layout():
    fig, axes = figures.grid(3, sharey=False)
    for k, ax in enumerate(axes):
        ax.loglog([1e-3, 1.0, 10.0], [1e-9, 1e-4 * (k + 1), 1.0], "o-", label=f"line {k}")
        ax.set_title(f"panel {k}")
        ax.set_xlabel("stepping time per simulated second (s/s)")
    fig.legend(loc="upper center", ncol=3, bbox_to_anchor=(0.5, 1.0))
    fig.tight_layout(rect=(0, 0, 1, 0.9))
    return fig


def _constrained():
    """A constrained layout whose legends hang below the axes and whose suptitle is above them: outside the
    axes, inside the crop."""
    fig, axes = plt.subplots(1, 2, figsize=(6, 3), sharey=True, layout="constrained")
    for ax in axes:
        ax.semilogy(np.linspace(0, 1, 50), np.exp(-20 * np.linspace(0, 1, 50)), label="decay")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2))
    fig.suptitle("two panels")
    return fig


def _placed_by_hand():
    """Axes placed by hand, a log colour bar and a label that sticks out of the figure (the crop grows for it)."""
    fig = plt.figure(figsize=(4, 2))
    ax = fig.add_axes((0.3, 0.2, 0.5, 0.6))
    mesh = ax.pcolormesh(np.arange(4), np.arange(3), np.array([[1e-3, 1e-1, 1.0], [10.0, 1e2, 1e-2]]),
                         norm=figures.LogNorm(1e-3, 1e2))
    ax.text(-1.0, 1.0, "a label beyond the left edge", ha="right")
    fig.colorbar(mesh, cax=fig.add_axes((0.85, 0.2, 0.03, 0.6)))
    return fig


LAYOUTS = {"tight_layout": _tight_layout, "constrained": _constrained, "placed by hand": _placed_by_hand}


def _normalised(text):
    """``text`` without what differs between any two saves: the date and the hashed ids."""
    text = re.sub(r"\n *<dc:date>[^<]*</dc:date>", "", text)  # (svg writes none: its line too)
    ids = {}
    return re.sub(r"\b(?:[pmch]|image)[0-9a-f]{10}\b", lambda m: ids.setdefault(m.group(0), f"id{len(ids)}"), text)


def _saved_tight(fig):
    """``fig`` as matplotlib writes it with ``bbox_inches="tight"`` (the labels made plain as ``svg`` makes them)."""
    figures.tick_labels.plain_figure(fig)
    buf = io.StringIO()
    fig.savefig(buf, format="svg", bbox_inches="tight")
    plt.close(fig)
    text = buf.getvalue()
    return text[text.index("<svg"):]


def _assert_same_document(ours, theirs):
    ours, theirs = _normalised(ours), _normalised(theirs)
    assert _NUMBER.split(ours) == _NUMBER.split(theirs)  # the same text, elements and attributes
    a, b = (np.array([float(v) for v in _NUMBER.findall(t)]) for t in (ours, theirs))
    assert a.shape == b.shape and np.max(np.abs(a - b)) <= LAST_DIGIT_PT


@pytest.mark.parametrize("layout", sorted(LAYOUTS))
def test_the_svg_is_the_one_a_tight_save_writes(layout):
    fig = LAYOUTS[layout]()
    twin = pickle.loads(pickle.dumps(fig))  # the same figure, saved the way svg() replaces
    _assert_same_document(figures.svg(fig), _saved_tight(twin))


def test_a_figure_with_its_legend_outside_and_no_layout_is_cropped_as_before():
    """``figures.scaling``: one axes, its legend right of it, beyond the figure's own width."""
    captured = []
    original = svg_text.tight_box

    def keep(fig):
        captured.append(pickle.loads(pickle.dumps(fig)))
        return original(fig)

    svg_text.tight_box = keep
    try:
        text = figures.scaling({("mujoco", "slope 1.0"): [(1, 1e-4), (10, 1e-3)],
                                ("reference", "slope 2.1"): [(1, 1e-3), (10, 1.3e-1)]},
                               {"mujoco": "#0072B2", "reference": "#D55E00"}, [1, 10])
    finally:
        svg_text.tight_box = original
    _assert_same_document(text, _saved_tight(captured[0]))
    width = float(re.search(r'width="([\d.]+)pt"', text).group(1))
    assert width > 2 * figures.PANEL_W * svg_text.SVG_DPI  # the legend beyond the figure is in the crop


@pytest.mark.parametrize("layout", sorted(LAYOUTS))
def test_a_figure_is_drawn_once(layout, monkeypatch):
    """``savefig(bbox_inches="tight")`` draws a figure twice (once unseen, to measure); ``svg`` once."""
    draws = []
    original = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(renderer) or original(self, renderer))
    figures.svg(LAYOUTS[layout]())
    assert len(draws) == 1
