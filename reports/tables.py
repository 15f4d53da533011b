"""Tables of the report, written once and rendered twice: as sortable HTML and as Markdown.

A ``Table`` holds ``Cell``s: the text a reader sees, the value its column sorts
by, and (for HTML) a hover title or a link. Every stored string passes through
``escape_html`` or ``escape_md`` on its way out; a cell's ``html`` is for markup
built here from escaped parts (links to a run's row).

Columns whose value is the same in every row say nothing about the rows:
``Table.split_constant`` moves them into a sentence ("in every row: ...").
Clicking a header sorts the HTML table (``report.js``, inlined by the page writer,
nothing loaded from the network); numbers sort by value, not by their text.
"""

from __future__ import annotations

import html
import math
import re
from dataclasses import dataclass

__all__ = ["MISSING", "Cell", "Table", "num", "escape_html", "escape_md"]


def escape_html(text):
    return html.escape(str(text), quote=True)


_MD_SPECIAL = re.compile(r"([\\`*\[\]<>|])")
_MD_UNDERSCORE = re.compile(r"(?<![A-Za-z0-9])_|_(?![A-Za-z0-9])")  # intraword _ is literal in CommonMark


def escape_md(text):
    """``text`` as literal Markdown (a stored name or message cannot start a link, emphasis or cell)."""
    text = _MD_SPECIAL.sub(r"\\\1", str(text))
    return _MD_UNDERSCORE.sub(r"\\_", text).replace("\n", " ")


@dataclass(frozen=True)
class Cell:
    """One table cell.

    Attributes
    ----------
    text : str — what a reader sees (plain text; escaped when rendered)
    sort : float or str or None — what its column sorts by (default: ``text``)
    title : str — hover text in HTML (e.g. a full message)
    html : str or None — ready markup for HTML (built from escaped parts), else the escaped text
    wrap : bool — may break across lines (long text); other cells keep to one line, so numbers stay whole
    """

    text: str
    sort: object = None
    title: str = ""
    html: str | None = None
    wrap: bool = False


MISSING = "—"  # a value not measured


def num(x, fmt="{:.2e}", suffix=""):
    """A number as a cell: shown with ``fmt`` (+ ``suffix``), sorted by its value; ``MISSING`` when missing."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return Cell(MISSING, math.nan)
    return Cell(fmt.format(x) + suffix, float(x))


def _cell(c):
    return c if isinstance(c, Cell) else Cell(str(c))


class Table:
    """Rows of cells under a header.

    Parameters
    ----------
    head : list of str — column headers, units in them ("orientation (rad)")
    rows : list of list of Cell or str
    row_ids : list of str or None — HTML ids of the rows (links to a run land on its row)
    row_classes : list of str or None — CSS classes of the rows (e.g. the verdict)
    cls : str — CSS class of the table (beside ``sortable``)
    """

    def __init__(self, head, rows, row_ids=None, row_classes=None, cls=""):
        self.head = list(head)
        self.rows = [[_cell(c) for c in r] for r in rows]
        self.row_ids = row_ids
        self.row_classes = row_classes
        self.cls = cls

    def split_constant(self, keep=()):
        """``(table without its constant columns, [(header, text)] of those columns)``; columns in
        ``keep`` stay. A table of one row keeps everything (nothing is constant across one thing);
        a column whose measured values are all one is constant "where measured"."""
        if len(self.rows) < 2:
            return self, []

        def values(j):  # a missing value ("—": not measured, e.g. a run that did not finish) does not count
            return {r[j].text for r in self.rows} - {MISSING}

        constant = [j for j, h in enumerate(self.head) if h not in keep and len(values(j)) == 1]
        keep_idx = [j for j in range(len(self.head)) if j not in constant]
        table = Table([self.head[j] for j in keep_idx], [[r[j] for j in keep_idx] for r in self.rows],
                      self.row_ids, self.row_classes, self.cls)
        return table, [(self.head[j], (values(j).pop() or "none") + (
            "" if all(r[j].text != MISSING for r in self.rows) else " (where measured)")) for j in constant]

    def html(self, caption=""):
        head = "".join(f'<th title="click to sort">{escape_html(h)}</th>' for h in self.head)
        body = []
        for i, r in enumerate(self.rows):
            attrs = ""
            if self.row_ids and self.row_ids[i]:
                attrs += f' id="{escape_html(self.row_ids[i])}"'
            if self.row_classes and self.row_classes[i]:
                attrs += f' class="{escape_html(self.row_classes[i])}"'
            body.append(f"<tr{attrs}>" + "".join(_td(c) for c in r) + "</tr>")
        cap = f"<caption>{escape_html(caption)}</caption>" if caption else ""
        return (f'<table class="sortable{" " + self.cls if self.cls else ""}">{cap}<thead><tr>{head}</tr></thead>'
                f"<tbody>{''.join(body)}</tbody></table>")

    def markdown(self):
        """The table as Markdown lines (cells escaped)."""
        lines = ["| " + " | ".join(escape_md(h) for h in self.head) + " |", "|" + "---|" * len(self.head)]
        lines += ["| " + " | ".join(escape_md(c.text) for c in r) + " |" for r in self.rows]
        return lines + [""]


def _td(c):
    sort, attrs = c.sort, ""
    if isinstance(sort, float):
        attrs += f' data-v="{"" if math.isnan(sort) else repr(sort)}"'
    elif sort is not None:
        attrs += f' data-v="{escape_html(sort)}"'
    if c.title:
        attrs += f' title="{escape_html(c.title)}"'
    if c.wrap:
        attrs += ' class="w"'
    return f"<td{attrs}>{c.html if c.html is not None else escape_html(c.text)}</td>"

