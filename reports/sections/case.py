"""A case's head: its version, parameters, horizon, effects and truth, its tolerances with their
reasons, the conserved quantities it declares and the metrics it measures, with their descriptions and units."""

from __future__ import annotations

from dalembert.reports.formatting import params_text, value_text
from dalembert.reports.page import Part
from dalembert.reports.sections.common import section_id
from dalembert.reports.tables import Cell, Table, num

__all__ = ["case_header"]


def case_header(rep, f):
    """The head of case version ``f``'s section (a ``Part``)."""
    part, case = Part(), f.case
    part.heading(rep.titles[f], 2, anchor=section_id(f))
    part.para(f"Version {case.version}; parameters {params_text(f.runs[0].params) or 'defaults'}; horizon "
              f"{value_text(case.t_final, 's')}; effects {', '.join(sorted(case.scene.effects))}; truth: {case.truth}; "
              f"{len(f.runs)} runs.")
    conserved = [inv for inv in case.invariants if inv.kind != "metric"]
    metrics = [inv for inv in case.invariants if inv.kind == "metric"]
    if conserved:  # a declared quantity is shown with what it is wherever its drift is shown
        part.para("Conserved quantities the case declares (each drift is max |x(t) - x(0)| / scale):")
        part.table(Table(["quantity", "description", "unit", "scale", "bound on the drift"],
                         [[Cell(inv.name), Cell(inv.description, wrap=True), Cell(inv.unit),
                           Cell(value_text(inv.scale, inv.unit), inv.scale),
                           num(case.tolerances[inv.name].value, "{:g}") if inv.name in case.tolerances
                           else Cell("none")] for inv in conserved]), note_constant=False)
    if metrics:  # a metric is a figure in its unit, not a drift: its bound is shown in that unit too
        part.para("Metrics the case measures on every run (each the largest |figure| over the run, in its unit):")
        part.table(Table(["metric", "what is measured", "unit", "bound"],
                         [[Cell(m.name), Cell(m.description, wrap=True), Cell(m.unit),
                           Cell(value_text(case.tolerances[m.name].value * m.scale, m.unit),
                                case.tolerances[m.name].value * m.scale) if m.name in case.tolerances
                           else Cell("none")] for m in metrics]), note_constant=False)
    part.table(Table(["tolerance", "value", "reason"],
                     [[k, num(t.value, "{:g}"), Cell(t.reason, wrap=True)] for k, t in sorted(case.tolerances.items())]),
               note_constant=False, collapsed=f"the case's {len(case.tolerances)} tolerances and their reasons")
    return part
