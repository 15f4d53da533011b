"""The findings: the Pareto fronts of every case, the summary table (also ``summary.csv``) and
each case's sentences (``reports.findings`` finds them; this section lays them out)."""

from __future__ import annotations

import math

from dalembert.reports import figures
from dalembert.reports.findings import ACCURACY_TARGETS, ENERGY_HAZARD
from dalembert.reports.page import Part
from dalembert.reports.sections.common import run_link, section_id
from dalembert.reports.tables import MISSING, Cell, Table, escape_html, escape_md, num

__all__ = ["findings"]

COUNTED = ("diverged", "failed", "energy", "tolerance")  # the hazards the summary counts per engine


def _summary_table(found, titles):
    """The summary as a ``Table`` and as rows of ``summary.csv`` (full precision)."""
    head = ["case", "engine", "best error", "best at"] + [f"cheapest run to error ≤ {t:g} · its cost (s/s)" for t in ACCURACY_TARGETS]
    head += ["diverged", "stopped", f"energy > {100 * ENERGY_HAZARD:g} %", "beyond tol.", "runs"]
    rows, csv_rows = [], []
    for f in found:
        for e in f.engines:
            cells = [Cell(titles[f], html=f'<a href="#{escape_html(section_id(f))}">{escape_html(titles[f])}</a>',
                          wrap=True), Cell(e.engine)]
            if e.best:
                cells += [num(e.best.error, suffix=f" {f.ranked_unit}"), run_link(e.best.run, wrap=True)]
            else:
                cells += [Cell(MISSING, math.nan), Cell("no finished run")]
            for reach in e.reaches:
                p = reach.point
                if p:  # the setting on one line, its cost below it
                    link = run_link(p.run)
                    cells.append(Cell(f"{link.text} · {p.cost:.2g}", p.cost, wrap=True,
                                      html=f'{link.html}<br><span class="cost">{p.cost:.2g}</span>'))
                else:
                    cells.append(Cell("never", math.nan))
            counts = {k: sum(len(h.runs) for h in f.hazards_of(e.engine, k)) for k in COUNTED}
            cells += [Cell(str(counts[k]), float(counts[k])) for k in COUNTED]
            cells.append(Cell(str(len(e.runs)), float(len(e.runs))))
            rows.append(cells)
            csv_rows.append(dict(case=f.case.name, case_version=f.case.version, engine=e.engine,
                                 quantity=f.ranked or "", unit=f.ranked_unit,
                                 best_error=e.best.error if e.best else math.nan,
                                 best_settings=e.best.run.settings_label if e.best else "",
                                 **{f"cheapest_to_{t:g}": (r.point.run.settings_label if r.point else "never")
                                    for t, r in zip(ACCURACY_TARGETS, e.reaches)},
                                 **{f"cost_to_{t:g}": (r.point.cost if r.point else math.nan)
                                    for t, r in zip(ACCURACY_TARGETS, e.reaches)},
                                 **{k: n for k, n in counts.items()}, runs=len(e.runs)))
    return Table(head, rows, cls="summary"), csv_rows


def findings(rep):
    """``(Part, summary rows)``: the findings section and the rows of ``summary.csv``."""
    part, found, titles = Part(), rep.found, rep.titles
    part.heading("Findings", 2, anchor="findings")
    panels = [dict(title=titles[f], ylabel=(f"best {f.ranked} ({f.ranked_unit})" if f.headline is not None else
                                            f"best {f.quantity} error ({f.unit})"),
                   fronts={e.engine: [(p.cost, p.error) for p in e.front] for e in f.engines if e.front},
                   floor=f.case.floor.get(f.ranked), tolerance=f.ranked_tolerance) for f in found if f.ranked]
    panels = [p for p in panels if p["fronts"]]
    if panels:
        part.figure(figures.pareto_summary(panels, rep.colours),
                    "Each engine's best error at each cost (Pareto front: a point is a run no cheaper run of the "
                    "engine beats); lower left is better. Dashed: the case's tolerance; dotted: "
                    f"{figures.ROUNDOFF_NOTE}.", "summary")
    table, csv_rows = _summary_table(found, titles)
    part.para("Per case and engine: the most accurate run, the cheapest run that reaches each accuracy in the "
              "case's headline error (stepping seconds per simulated second; \"never\": no run did), and how many "
              "of its runs are hazards (listed below). Click a header to sort, a setting to see its run.")
    part.table(table)
    for f in found:
        part.raw(f'<p class="case"><a href="#{escape_html(section_id(f))}">{escape_html(titles[f])}</a></p>',
                 [f"**{escape_md(titles[f])}**", ""])
        part.items(f.sentences)
    return part, csv_rows
