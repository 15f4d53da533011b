"""Stability in one case: the drift (or error) of every run against its settings with the stored
verdicts, the reasons of the runs that are not stable, and the energy drift rates."""

from __future__ import annotations

import math

from dalembert.reports import figures
from dalembert.reports.findings import ENERGY_LIKE, run_name
from dalembert.reports.formatting import counted, value_text
from dalembert.reports.page import Part
from dalembert.reports.sections.common import grid_row
from dalembert.reports.tables import Cell, Table, num
from dalembert.reports.trend import reason_text, verdict_word
from dalembert.reports.work_precision import sweep_key

__all__ = ["stability"]


def stability(rep, f, name):
    """Case version ``f``'s stability grid, verdict reasons and drift rates (a ``Part``; empty when
    the case has neither an energy nor a headline error); ``name`` prefixes its figure."""
    part = Part()
    energy = next((n for n in ENERGY_LIKE if n in f.case.conserved), None)
    measure = energy or f.quantity
    if measure is None:
        return part
    label = (f"{measure} drift (relative)" if energy else f"max {measure} error ({f.unit})")
    shown = [r for r in f.runs if r.status != "unsupported"]
    blocks = []
    for title, fixed in (("fixed step", True), ("adaptive", False)):
        runs = sorted((r for r in shown if (r.settings.dt is not None) == fixed),
                      key=lambda r: (grid_row(r), sweep_key(r)))
        if not runs:
            continue
        cells = {}
        for r in runs:
            value = r.drifts.get(measure) if energy else r.max_error(measure)
            note = f"t={value_text(r.t_diverged, 's')}" if r.t_diverged is not None else ""
            cells[(grid_row(r), r.sweep_label)] = (value if r.ok and value is not None and math.isfinite(value)
                                                   else None, verdict_word(rep.store, r, f.case), note)
        blocks.append(dict(title=title, cells=cells,
                           rows=sorted({k[0] for k in cells}),
                           columns=[c for c in dict.fromkeys(r.sweep_label for r in sorted(runs, key=sweep_key))]))
    if not blocks:
        return part
    part.heading("Stability", 3)
    bound = f.case.tolerances.get(measure)
    part.figure(figures.stability(blocks, label, bound.value if bound else None),
                f"{name}: {label} per run (colour, log scale; the bar marks the case's bound) and its stored verdict "
                "(word: it weighs every conserved quantity the case bounds, the colour this one; \"varies\": beyond the "
                "bound but within bounds, no trend, \"drifts\": a trend); fixed-step and "
                "adaptive runs apart. Black: diverged (at the time shown); grey, hatched: stopped early.",
                f"{name}-stability")
    n_unsupported = len(f.runs) - len(shown)
    if n_unsupported:
        part.para(f"{counted(n_unsupported, 'unsupported run')} not drawn; the hazards above list them with the reason.")
    reasons = [f"{run_name(r)}: {verdict_word(rep.store, r, f.case)} — {reason_text(rep.store, r, f.case)}"
               for r in shown if r.judgement.reason and r.judgement.verdict != "stable"]
    if reasons:
        part.details(f"why {len(reasons)} run(s) are not stable (stored verdict reasons)", "\n".join(reasons))
    _drift_rates(part, f)
    return part


def _drift_rates(part, f):
    """Energy drift per simulated second: a steady slope is secular drift (most integrators), a
    slope near zero bounded oscillation (symplectic, geometric ones)."""
    name = next((n for n in ENERGY_LIKE if any(n in r.drift_rates for r in f.runs)), None)
    ok = [r for r in f.runs if r.ok and name and not math.isnan(r.drift_rates.get(name, math.nan))]
    if not ok:
        return
    rates = {(grid_row(r), r.sweep_label): r.drift_rates[name] for r in ok}
    cols = list(dict.fromkeys(r.sweep_label for r in sorted(ok, key=sweep_key)))
    rows = [[Cell(row)] + [num(rates.get((row, c)), "{:+.2e}", " /s") for c in cols]
            for row in sorted({k[0] for k in rates})]
    what = "energy" if name == "energy" else "energy balance (E less the work of the loads)"
    part.heading("Energy drift rate", 3)
    part.para(f"Least-squares slope of the relative change of the {what} per simulated second (negative: lost); "
              "bounded oscillation shows as a slope near zero, secular drift as a steady one. Finished runs only.")
    part.table(Table(["engine integrator options"] + [f"{c} (1/s)" for c in cols], rows), note_constant=False,
               collapsed=f"{len(rows)} rows")
