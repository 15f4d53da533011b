"""What each engine simulated: one table comparing what the engines' audits say beyond the scene
(``reports.simulated``), and per case each engine's effects audit and generated model, folded."""

from __future__ import annotations

import json

from dalembert.reports.findings import settings_text
from dalembert.reports.page import Part
from dalembert.reports.simulated import ASPECTS, simulated
from dalembert.reports.tables import Cell, Table, escape_html

__all__ = ["engines_simulated", "beyond_the_scene", "audit_id"]


def audit_id(r):
    """The HTML id of run ``r``'s raw audit in its case's section."""
    return f"audit-{r.key}"


def beyond_the_scene(rep):
    """The comparison table (a ``Part``; empty when no run stored an audit): per engine, each aspect of
    ``reports.simulated.ASPECTS``, and a link to a raw audit."""
    part = Part()
    rows = simulated(rep.records, lambda r: rep.case_of(r).scene.gravity)
    if not rows:
        return part
    part.heading("What each engine simulated beyond the scene", 2, anchor="beyond-the-scene")
    part.para("Read back from each engine by its adapter (its effects audit): what it computes that the scene does "
              "not say. A value that differs between options is given with them; \"—\": its audits do not say. "
              "The raw audit is one click away (the last column; each case's section has every engine's).")
    head = ["engine"] + [a.name for a in ASPECTS] + ["raw audit"]
    table_rows = []
    for s in rows:
        cells = [Cell(s.engine)]
        for a in ASPECTS:
            short, full = s.values[a.name]
            cells.append(Cell(short or "—", title=full if full != short else "", wrap=True))
        link = f"{s.run.case} {settings_text(s.run)}"
        cells.append(Cell(link, html=f'<a href="#{escape_html(audit_id(s.run))}">{escape_html(link)}</a>', wrap=True))
        table_rows.append(cells)
    part.table(Table(head, table_rows, cls="summary"), note_constant=False)
    return part


def engines_simulated(rep, f):
    """Per engine of case version ``f``, its most accurate run's (else its first run's) effects audit
    and generated model, folded (a ``Part``); every run ``beyond_the_scene`` links to is among them."""
    part = Part()
    part.heading("What each engine simulated", 3)
    linked = {s.run.key for s in simulated(rep.records, lambda r: rep.case_of(r).scene.gravity)}
    for e in f.engines:
        shown = [e.best.run if e.best else e.runs[0]]
        shown += [r for r in e.runs if r.key in linked and r is not shown[0]]
        for r in shown:
            if r.audit:
                summary = f"{e.engine}: effects audit ({settings_text(r)})"
                text = json.dumps(r.audit, indent=2)
                part.raw(f'<details id="{escape_html(audit_id(r))}"><summary>{escape_html(summary)}</summary>'
                         f"<pre>{escape_html(text)}</pre></details>",
                         [f"<details><summary>{escape_html(summary)}</summary>", "", "```",
                          text.replace("```", "'''"), "```", "", "</details>", ""])
        if shown[0].model:
            part.details(f"{e.engine}: generated model", shown[0].model)
    return part
