"""Every run of one case in a sortable table: settings, status, cost and its spread, each error,
each conserved quantity's drift (the case's declared ones too, relative to their scale in their
unit), each metric in its unit, what is beyond the tolerance (and what the run did not measure), and the stored
verdict ("varies" for a ``drifts`` verdict whose quantities oscillate within bounds: ``reports.trend``).
Where a run shared an engine call with other worlds (``--batch``: ``Cost.batch_size`` > 1) its costs are per
world, its share of the batch's wall time; ``BATCH_COLUMNS`` then show the batch's size and its throughput."""

from __future__ import annotations

import math

from dalembert.errors import QUANTITIES
from dalembert.reports.findings import settings_text
from dalembert.reports.formatting import value_text
from dalembert.reports.page import Part
from dalembert.reports.sections.common import drifts_of, shown_value, stored_label
from dalembert.reports.tables import MISSING, Cell, Table, num
from dalembert.reports.trend import reason_text, verdict_word
from dalembert.reports.work_precision import cost_per_sim_s, sweep_key

__all__ = ["every_run", "BATCH_COLUMNS"]

# The columns a table with batched runs adds, spelled once: the worlds of the engine call a run shared (1: alone)
# and that call's throughput in world-steps per second (the batch's, not the world's; ``Cost.world_steps_per_s``).
BATCH_COLUMNS = ("batch (worlds)", "world-steps/s (per batch)")


def _beyond_text(j):
    """The tolerances a finished run exceeds, then those it did not measure (never within: ``dalembert.judge``)."""
    return "; ".join(x for x in (", ".join(j.beyond), "not measured: " + ", ".join(j.not_measured)
                                  if j.not_measured else "") if x)


def every_run(rep, f):
    """Case version ``f``'s table of runs, folded (a ``Part``); each row's id is ``run-<key>``."""
    part = Part()
    runs = sorted(f.runs, key=lambda r: (r.engine, r.settings.integrator, r.options_label, sweep_key(r)))
    errs = [q for q in QUANTITIES if any(not math.isnan(r.max_error(q)) for r in runs)]
    errs.sort(key=lambda q: q != f.quantity)  # the headline error first
    drifts = [n for n in drifts_of(f.case) if any(not math.isnan(r.drifts.get(n, math.nan)) for r in runs)]
    batched = any(r.cost.batch_size > 1 for r in runs)
    head = (["engine", "settings", "status", "cost (s/s)", "cost min–max (s/s)"] + list(BATCH_COLUMNS if batched else ())
            + [f"{q} ({QUANTITIES[q]})" for q in errs] + [stored_label(n, f.case) for n in drifts]
            + ["beyond tolerance", "verdict"])
    rows = []
    for r in runs:
        status = Cell(r.status, title=r.message) if r.ok or not r.message else Cell(
            f"{r.status}" + (f" t={value_text(r.t_diverged, 's')}" if r.t_diverged is not None else ""),
            title=r.message)
        horizon = r.t_final if math.isfinite(r.t_final) and r.t_final > 0 else math.nan
        spread = (Cell(f"{r.cost.wall_s_min / horizon:.2g}–{r.cost.wall_s_max / horizon:.2g}",
                       r.cost.wall_s_max / horizon - r.cost.wall_s_min / horizon,
                       title=f"{r.cost.repeats} timed repeats; {r.cost.concurrent} runs in flight")
                  if math.isfinite(r.cost.wall_s_min) else Cell(MISSING, math.nan))
        cost = num(cost_per_sim_s(r), "{:.2g}")
        if r.cost.batch_size > 1 and cost.text != MISSING:  # the batch's share, not one world's latency
            cost = Cell(cost.text + " per world", cost.sort, title=f"1/{r.cost.batch_size} of its batch's wall time "
                        f"({value_text(r.cost.batch_wall_s, 's')} for {r.cost.batch_size} worlds)")
        rows.append([Cell(r.engine), Cell(settings_text(r), wrap=True), status, cost, spread]
                    + (_batch_cells(r) if batched else []) + [num(r.max_error(q)) for q in errs] + [num(shown_value(r, n, f.case)) for n in drifts]
                    + [Cell(_beyond_text(r.judgement) if r.ok else MISSING, wrap=True),
                       Cell(verdict_word(rep.store, r, f.case), title=reason_text(rep.store, r, f.case))])
    part.heading("Every run", 3)
    part.table(Table(head, rows, row_ids=[f"run-{r.key}" for r in runs],
                     row_classes=[r.judgement.verdict for r in runs], cls="runs"),
               collapsed=f"all {len(runs)} runs of {f.case.name}: click to open; click a header to sort"
               + ("; a batched run's costs are per world, its batch's size and world-steps/s per batch" if batched
                  else ""))
    return part


def _batch_cells(r):
    """``BATCH_COLUMNS``' cells of run ``r``: its batch's size, and the batch's world-steps per second (missing for a
    run stepped alone)."""
    if r.cost.batch_size <= 1:
        return [Cell("1", 1.0, title="stepped alone"), Cell(MISSING, math.nan)]
    return [Cell(str(r.cost.batch_size), float(r.cost.batch_size), title=f"on {r.cost.device}" if r.cost.device
                 else ""), num(r.cost.world_steps_per_s, "{:.3g}")]
