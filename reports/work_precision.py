"""What accuracy costs in time: work-precision points and lines, Pareto fronts, "cost to reach".

For one case every finished run is a point: its stepping wall time per simulated
second (the median of its timed repeats over the case's horizon) against its
headline error (the max over the horizon), or the case's headline figure where it declares one
(a contact case's ``dalembert.metrics.Metric`` with ``headline``: the creep of a box that must stick,
the roll onset of a ball; ``headline_metric``), in its unit. Points group into lines by engine,
integrator and options (and batch size: a batched run's cost is its share of a batch of worlds, per world,
never mixed with runs stepped alone), ordered along their sweep from the coarsest step or
tolerance to the finest. An engine's Pareto front is the best error it reaches
at each cost: its points that no cheaper point beats. What a target accuracy costs is
the cost of the cheapest run that reached it (a run that was made, never an
interpolation between two).
"""

from __future__ import annotations

import math
from typing import NamedTuple

__all__ = ["ERROR_DISPLAY_FLOOR", "Point", "headline_quantity", "headline_metric", "metric_label", "figure_of",
           "figure_reader", "cost_per_sim_s",
           "line_label", "batch_text", "lines_of",
           "sweep_key", "points", "series", "series_of", "pareto_front", "cheapest_reaching"]

# Errors of exactly 0 are drawn at this level on log axes (below any double-precision roundoff).
ERROR_DISPLAY_FLOOR = 1e-17


class Point(NamedTuple):
    """One finished run on the work-precision plane."""

    cost: float  # stepping wall time per simulated second, s/s
    error: float  # max headline error over the horizon (ERROR_DISPLAY_FLOOR where it is 0)
    run: object  # the RunRecord


def headline_quantity(records):
    """The error quantity that sums up a case: joint angle for jointed cases, else orientation
    (else position); None when no run measured any."""
    for q in ("joint", "orientation", "position"):
        if any(not math.isnan(r.max_error(q)) for r in records):
            return q
    return None


def headline_metric(case, records):
    """The headline figure ``case`` (a ``CaseRecord``) declares, an ``InvariantLabel`` (the first declared with
    ``headline``), when a finished run among ``records`` stores it; else None."""
    label = next((i for i in getattr(case, "invariants", ()) if getattr(i, "headline", False)), None)
    if label is None or not any(r.ok and label.name in r.drifts for r in records):
        return None
    return label


def figure_of(r, quantity, case=None):
    """Run ``r``'s ``quantity``: its max error (``errors``) for an error quantity, or a declared metric of
    ``case`` in the metric's unit (the stored value times its scale); NaN when not stored."""
    return figure_reader(quantity, case)(r)


def metric_label(quantity, case):
    """The metric of ``case`` (a ``CaseRecord``, or None) named ``quantity`` (an ``InvariantLabel``), or None: then
    ``quantity`` is read as an error quantity."""
    if case is None:
        return None
    return next((i for i in case.invariants if i.name == quantity and i.kind == "metric"), None)


def figure_reader(quantity, case=None):
    """``figure_of(·, quantity, case)`` as a function of the run alone: the case's metric looked up once, not per
    run (a section reads the figure of every run of a case: 1e5 of them in a map)."""
    label = metric_label(quantity, case)
    if label is not None:
        scale = label.scale
        return lambda r: r.drifts.get(quantity, math.nan) * scale
    missing = (math.nan, math.nan)
    return lambda r: r.errors.get(quantity, missing)[0]  # (``RunRecord.max_error``, inlined)


def cost_per_sim_s(r):
    """Median stepping wall time per simulated second (s/s), NaN when not timed (``RunRecord.cost_per_sim_s``,
    computed once per record)."""
    return r.cost_per_sim_s


def line_label(r):
    """A work-precision line: ``engine integrator`` and its options (as a reader reads them, ``options_text``); a
    batched run's (``Cost.batch_size`` > 1) says its cost is per world of its batch."""
    return " ".join(x for x in (r.engine, r.settings.integrator, r.options_text, batch_text(r)) if x)


def batch_text(r):
    """``(per world of a batch)`` for a run stepped in a batch of more than one world (its cost its share of the
    batch's), else "". One text for every size: a sweep's batches differ in size from step to step, and each run's
    cost is per world either way."""
    return "(per world of a batch)" if getattr(r.cost, "batch_size", 1) > 1 else ""


def lines_of(pts):
    """``{label: [Point, ...]}``: the points grouped by line, a line being one engine, integrator, exact options and
    batch size (``batch_text``).

    The label is ``line_label``; where two lines' options differ only beyond the digits a reader is shown, each
    keeps its options exactly as given (``options_label``), so that no two lines merge.
    """
    exact = {}
    for p in pts:
        exact.setdefault((p.run.engine, p.run.settings.integrator, p.run.options_label, batch_text(p.run)),
                         []).append(p)
    labels = {}
    for key, group in exact.items():
        labels.setdefault(line_label(group[0].run), []).append(key)
    out = {}
    for label, keys in labels.items():
        for key in keys:
            out[label if len(keys) == 1 else " ".join(x for x in key if x)] = exact[key]
    return out


def sweep_key(r):
    """Order along a sweep and across a grid: fixed steps before tolerances, each coarse to fine."""
    return (r.settings.dt is None, -(r.settings.dt if r.settings.dt is not None else (r.settings.rtol or 0.0)))


def points(records, quantity, case=None):
    """The ``Point`` of every finished run with a finite error and cost, in the records' order (``quantity``: an
    error quantity, or a metric of ``case``: ``figure_of``)."""
    out = []
    figure = figure_reader(quantity, case)
    for r in records:
        err, cost = figure(r), r.cost_per_sim_s
        if r.ok and math.isfinite(err) and math.isfinite(cost):
            out.append(Point(cost, max(err, ERROR_DISPLAY_FLOOR), r))
    return out


def series(records, quantity, case=None):
    """``{line_label: [Point, ...]}``, each line ordered along its sweep (coarse to fine)."""
    return series_of(points(records, quantity, case))


def series_of(pts):
    """``series`` of points made already (``points``' list)."""
    out = lines_of(pts)
    for pts in out.values():
        pts.sort(key=lambda p: sweep_key(p.run))
    return out


def pareto_front(pts):
    """The points no cheaper (or equally cheap) point beats in error, by increasing cost."""
    front = []
    for p in sorted(pts, key=lambda p: (p.cost, p.error)):
        if not front or p.error < front[-1].error:
            front.append(p)
    return front


def cheapest_reaching(pts, target):
    """The cheapest point whose error is at most ``target``, or None: a run that was made, not an
    interpolation."""
    reached = [p for p in pts if p.error <= target]
    return min(reached, key=lambda p: p.cost) if reached else None
