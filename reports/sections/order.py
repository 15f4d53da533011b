"""Observed order: per engine and fixed-step integrator (and options), the order of convergence its step pairs show
(``reports.order``: the rule for which pairs count), beside the order the integrator declares."""

from __future__ import annotations

from dalembert.reports.order import (FLOOR_MARGIN, ORDER_MARGIN, SATURATED_ANGLE, left_out, observed_orders,
                                     step_pairs)
from dalembert.reports.page import Part
from dalembert.reports.tables import MISSING, Cell, Table

__all__ = ["observed_order"]


def observed_order(rep):
    """The observed-order section (a ``Part``; empty when no two fixed-step runs of one line pair); the declared
    order is the one the runs stored (``RunRecord.integrator_order``)."""
    part = Part()
    excluded = {}
    pairs = step_pairs(((f.case, f.runs, f.quantity) for f in rep.found), excluded)
    if not pairs:
        return part
    found = observed_orders(pairs)
    part.heading("Observed order of convergence", 2, anchor="observed-order")
    flagged = [o for o in found if o.flagged or o.below]
    skipped = left_out(excluded)
    named = ", ".join(_line(o) for o in flagged)
    part.para("Per engine, fixed-step integrator and options, the order p = log(e1/e2) / log(dt1/dt2) of each pair "
              "of runs at successive steps of the matrix (one case, options and parameters; e the case's headline "
              "error, the max over the horizon), beside the order the integrator declares. Only pairs in the "
              f"asymptotic range count: both runs finished without diverging, both errors at least {FLOOR_MARGIN:g} "
              f"times the run's roundoff floor (the case's; a float32 run's own), an angle error below "
              f"{SATURATED_ANGLE:g} rad (larger ones saturate), no contact (an event's timing error is first order "
              "whatever the integrator)" + (f"; left out: {skipped}" if skipped else "") + ". Flagged: a median more "
              f"than {ORDER_MARGIN:g} below the declared order (and the cases whose own median is)."
              + (f" {len(flagged)} flagged: {named}." if flagged else ""))
    head = ["engine", "integrator", "declared", "observed median (range)", "pairs", "cases", "flag"]
    rows = []
    for o in found:
        on = ", ".join(o.below)
        flag = ((f"below declared (on {on})" if o.below != o.cases else "below declared") if o.flagged
                else f"below on {on}" if o.below else "")
        each = "; ".join(" ".join(x for x in (p.case, p.options, f"dt {p.dts[0]:g} -> {p.dts[1]:g}: {p.order:.2f}") if x)
                         for p in o.pairs)  # every pair, on hover
        rows.append([Cell(o.engine), Cell(" ".join(x for x in (o.integrator, o.options) if x), wrap=True),
                     Cell(str(o.declared) if o.declared is not None else MISSING, o.declared if o.declared else -1.0,
                          title="" if o.declared is not None else "its runs stored no declared order (or several)"),
                     Cell(f"{o.median:.2f} ({o.low:.2f} to {o.high:.2f})", o.median, title=each),
                     Cell(str(len(o.pairs)), len(o.pairs)), Cell(", ".join(o.cases), wrap=True),
                     Cell(flag, wrap=True)])
    marked = [o.flagged or bool(o.below) for o in found]
    if any(marked):  # the flagged lines in view, every line one click away
        part.table(Table(head, [r for r, m in zip(rows, marked) if m], row_classes=["diverged"] * sum(marked)),
                   note_constant=False)
    part.table(Table(head, rows, row_classes=["diverged" if m else "" for m in marked]), note_constant=False,
               collapsed=f"every line's observed order ({len(found)} lines)")
    return part


def _line(o):
    """``engine integrator options`` of an ``ObservedOrder``."""
    return " ".join(x for x in (o.engine, o.integrator, o.options) if x)
