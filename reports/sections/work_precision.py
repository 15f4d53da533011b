"""What accuracy costs in one case: work-precision small multiples and, per integrator, the best
error and the cheapest run to each accuracy target; in the case's headline figure where it declares one
(``CaseFindings.ranked``: a contact case's creep, roll onset, ...), else its headline error."""

from __future__ import annotations

import math

from dalembert.reports import figures
from dalembert.reports.figures import ROUNDOFF_NOTE
from dalembert.reports.findings import ACCURACY_TARGETS
from dalembert.reports.page import Part
from dalembert.reports.tables import Cell, Table, num
from dalembert.reports.work_precision import cheapest_reaching, series

__all__ = ["work_precision"]


def work_precision(rep, f, name):
    """Case version ``f``'s work-precision figure and table (a ``Part``, empty without a headline
    error); ``name`` prefixes its figure's file and caption."""
    part = Part()
    lines = series(f.runs, f.ranked, f.case) if f.ranked else {}
    what = f"{f.ranked} ({f.ranked_unit})" if f.headline is not None else f"max {f.quantity} error ({f.unit})"
    if not lines:
        return part
    part.heading("What accuracy costs", 3)
    panels = {}  # a panel per engine and option variant, the engine's defaults first
    for pts in lines.values():
        r = pts[0].run
        panel = panels.setdefault((r.engine, bool(r.settings.options), r.options_label), dict(
            title=" ".join(x for x in (r.engine, r.options_text) if x), engine=r.engine, lines=[]))
        panel["lines"].append(dict(integrator=r.settings.integrator,
                                   points=[(p.cost, p.error, p.run.sweep_label) for p in pts]))
    panels = [panels[k] for k in sorted(panels)]
    part.figure(figures.work_precision(panels, what, floor=f.case.floor.get(f.ranked), tolerance=f.ranked_tolerance),
                f"{name}: {what.rsplit(' (', 1)[0]} against stepping time per simulated second, a panel per engine and "
                "option variant on shared axes (lower left is better); colour and marker: integrator; open marker: "
                "the coarsest step or tolerance, filled: the finest. Dashed: the case's tolerance; dotted: "
                f"{ROUNDOFF_NOTE}.", f"{name}-wp")
    rows = []
    for label, pts in sorted(lines.items()):
        r = pts[0].run
        best = min(pts, key=lambda p: p.error)
        cells = [Cell(r.engine), Cell(r.settings.integrator), Cell(r.options_text or "defaults"),
                 num(best.error), Cell(best.run.sweep_label)]
        for t in ACCURACY_TARGETS:
            p = cheapest_reaching(pts, t)
            cells.append(Cell(f"{p.run.sweep_label} · {p.cost:.2g}", p.cost) if p else Cell("never", math.nan))
        rows.append(cells)
    part.table(Table(["engine", "integrator", "options", f"best ({f.ranked_unit})", "at"]
                     + [f"cheapest to {t:g} (s/s)" for t in ACCURACY_TARGETS], rows),
               collapsed=f"per integrator: best error and the cheapest run to each accuracy ({len(rows)} lines)")
    return part
