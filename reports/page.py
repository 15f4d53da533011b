"""The report's page writer: the same content as self-contained HTML and as Markdown.

A section writes into a ``Part`` (headings, paragraphs, lists, tables, figures, folded
text), each element once, rendered to both formats at once. ``write_page`` joins the
parts in order, numbers the figures across the whole page (``report_files/NN-name.svg``
beside the Markdown; the same SVG inline in the HTML) and writes ``report.html`` and
``report.md``. The page's CSS and JavaScript are package data (``report.css``,
``report.js``) inlined into the HTML: nothing is loaded from the network.

``report.md`` has the HTML's economy: a part folded with ``details=True`` (a case's evidence: its figures and
tables) is written to ``report_details.md`` instead, under its case's heading and an anchor, and ``report.md``
keeps one link to it in its place. Every number of the page is in one of the two files.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from importlib import resources

from dalembert.reports.tables import escape_html, escape_md
from dalembert.store import atomic_write, file_name

__all__ = ["Part", "write_page", "static_text", "DETAILS"]

DETAILS = "report_details.md"  # beside report.md: the folded evidence report.md links to


@dataclass(frozen=True)
class _Figure:
    """A figure placed in a part: numbered, written and linked when the page is assembled."""

    svg: str
    caption: str
    name: str


@dataclass(frozen=True)
class _Detail:
    """Markdown lines folded out of ``report.md`` into ``DETAILS``, under ``summary``."""

    summary: str
    lines: tuple


class Part:
    """One section's content, collected as HTML strings and Markdown lines (``html``, ``md``);
    a figure is kept as a ``_Figure`` in both until ``write_page`` numbers it."""

    def __init__(self):
        self.html, self.md = [], []

    def __bool__(self):
        return bool(self.html or self.md)

    def heading(self, text, level, anchor=None):
        a = f' id="{escape_html(anchor)}"' if anchor else ""
        self.html.append(f"<h{level}{a}>{escape_html(text)}</h{level}>")
        self.md += ["#" * level + " " + escape_md(text), ""]

    def para(self, text, cls=None):
        """A paragraph of plain text (escaped here); ``cls="warning"`` is bold in Markdown."""
        c = f' class="{cls}"' if cls else ""
        self.html.append(f"<p{c}>{escape_html(text)}</p>")
        self.md += [("> **" + escape_md(text) + "**") if cls == "warning" else escape_md(text), ""]

    def items(self, texts):
        self.html.append("<ul>" + "".join(f"<li>{escape_html(t)}</li>" for t in texts) + "</ul>")
        self.md += [f"- {escape_md(t)}" for t in texts] + [""]

    def table(self, table, note_constant=True, caption="", collapsed=None):
        """A ``Table``; its constant columns become one sentence; ``collapsed``: inside a closed <details>."""
        shown, constant = table.split_constant() if note_constant else (table, [])
        inner = shown.html(caption)
        md = shown.markdown()
        if constant:
            note = "In every row: " + "; ".join(f"{h} {v}" for h, v in constant) + "."
            inner = f'<p class="note">{escape_html(note)}</p>' + inner
            md = [escape_md(note), ""] + md
        if collapsed:
            self.html.append(f"<details><summary>{escape_html(collapsed)}</summary>{inner}</details>")
            self.md += [f"<details><summary>{escape_html(collapsed)}</summary>", ""] + md + ["</details>", ""]
        else:
            self.html.append(inner)
            self.md += md

    def figure(self, svg, caption, name):
        """An SVG figure (text) with its caption; ``name`` makes its file name and HTML id."""
        fig = _Figure(svg, caption, name)
        self.html.append(fig)
        self.md.append(fig)

    def details(self, summary, text):
        """Preformatted ``text`` folded under ``summary``."""
        self.html.append(f"<details><summary>{escape_html(summary)}</summary><pre>{escape_html(text)}</pre></details>")
        self.md += [f"<details><summary>{escape_html(summary)}</summary>", "", "```",
                    text.rstrip().replace("```", "'''"), "```", "", "</details>", ""]

    def folded(self, summary, keep=0, details=False):
        """This part with everything after its first ``keep`` HTML elements (a heading) inside a closed
        ``<details>`` under ``summary``. The Markdown is left as it is, or with ``details`` (and ``keep`` 0) moved
        whole to ``DETAILS``, a link to it in its place (``write_page``)."""
        if details and keep:
            raise ValueError(f"Part.folded.keep: {keep} with details — a part moved to {DETAILS} moves whole: "
                             "give keep=0")
        out = Part()
        if self:
            out.html = (self.html[:keep] + [f'<details class="fold"><summary>{escape_html(summary)}</summary>']
                        + self.html[keep:] + ["</details>"])
            out.md = [_Detail(summary, tuple(self.md))] if details else list(self.md)
        return out

    def raw(self, html, md=()):
        """Markup built by the caller from escaped parts, and its Markdown lines."""
        self.html.append(html)
        self.md += list(md)


def static_text(name):
    """The text of one of the page's package data files (``<name>`` beside this module), without its final newline."""
    return resources.files("dalembert.reports").joinpath(name).read_text(encoding="utf-8").rstrip("\n")


def write_page(parts, out_dir, title="dalembert report", files="report_files"):
    """Write ``report.html`` and ``report.md`` (its figures in ``out_dir/files``) from ``parts``
    (a list of ``Part``, in page order); returns the two paths."""
    files_dir = os.path.join(out_dir, files)
    os.makedirs(files_dir, exist_ok=True)
    names = {}  # figure -> its file, numbered in page order
    for part in parts:
        for x in part.html:
            if isinstance(x, _Figure):
                # a case's name is part of the figure's: checked before it becomes a path
                names[id(x)] = file_name(f"{len(names) + 1:02d}-{x.name}.svg", "figure name", files_dir)
                atomic_write(os.path.join(files_dir, names[id(x)]), x.svg)

    def html(x):
        if isinstance(x, _Figure):
            return (f'<figure class="plot" id="fig-{escape_html(x.name)}">{x.svg}'
                    f"<figcaption>{escape_html(x.caption)}</figcaption></figure>")
        return x

    def md(x):
        return [f"![{escape_md(x.caption)}]({files}/{names[id(x)]})", ""] if isinstance(x, _Figure) else [x]

    main, details = _split_details([x for part in parts for x in part.md], md)
    body = "".join(html(x) for part in parts for x in part.html)
    page = (f'<!DOCTYPE html><html lang="en"><head><meta charset="utf-8"><title>{escape_html(title)}</title>'
            f"<style>{static_text('report.css')}</style></head><body>{body}"
            f"<script>\n{static_text('report.js')}\n</script></body></html>")
    html_path, md_path = os.path.join(out_dir, "report.html"), os.path.join(out_dir, "report.md")
    atomic_write(html_path, page)
    atomic_write(md_path, "\n".join(main) + "\n")
    details_path = os.path.join(out_dir, DETAILS)
    if details:
        atomic_write(details_path, "\n".join(details) + "\n")
    elif os.path.exists(details_path):  # (a report written before into this directory had some)
        os.remove(details_path)
    return html_path, md_path


def _split_details(elements, md):
    """``report.md``'s lines and ``DETAILS``' ([] when nothing is folded out) from the page's Markdown elements
    (lines, figures through ``md``, ``_Detail``s): a detail's lines go under the heading it was folded beneath,
    behind an anchor ``detail-N``, and a link to it takes its place."""
    main, details, context, placed, n = [], [], "", "", 0
    for x in elements:
        if not isinstance(x, _Detail):
            if main and main[-1].startswith(f"- [") and f"]({DETAILS}#" in main[-1]:
                main.append("")  # (the links of one case are one list: a blank line ends it)
            main += md(x)
            if isinstance(x, str) and x.startswith("## "):
                context = x[3:]
            continue
        n += 1
        if not details:
            details = ["# dalembert report: details", "",
                       "The evidence report.md folds: each case's figures and tables, under its heading, in page "
                       "order. Each block is linked from its place in report.md.", ""]
        if context != placed:
            details += [f"## {context}", ""]
            placed = context
        details += [f'<a id="detail-{n}"></a>', "", f"**{escape_md(x.summary)}**", ""]
        details += [line for y in x.lines for line in md(y)]
        main.append(f"- [{escape_md(x.summary)}]({DETAILS}#detail-{n})")
    if main and f"]({DETAILS}#" in main[-1]:
        main.append("")
    return main, details
