"""What accuracy costs in time: work-precision series and "cost to reach" a target error.

For one case: every ok run becomes a point (stepping wall time per simulated
second, headline error), grouped by engine + integrator (+ options) and
ordered along its dt/tolerance sweep. ``cost_to_reach`` interpolates each line
log-log between its two sweep points that bracket the target error.
"""

from __future__ import annotations

import math

__all__ = ["TARGETS", "ERROR_DISPLAY_FLOOR", "headline_quantity", "line_label", "series", "cost_to_reach"]

# Error levels of the "cost to reach" table (in the unit of the headline error).
TARGETS = (1e-2, 1e-4, 1e-6, 1e-8)
# Errors of exactly 0 are drawn at this level on log axes (below any double-precision roundoff).
ERROR_DISPLAY_FLOOR = 1e-17


def headline_quantity(records):
    """The error quantity that sums up a case: joint angle for jointed cases, else orientation
    (else position); None when no run measured any."""
    for q in ("joint", "orientation", "position"):
        if any(not math.isnan(r.max_error(q)) for r in records):
            return q
    return None


def line_label(r):
    """A work-precision line: ``engine integrator`` and its options."""
    return " ".join(x for x in (r.engine, r.integrator, r.options_label) if x)


def series(records):
    """``({label: [(cost_per_sim_s, error, point_label), ...]}, quantity)`` sorted by cost, ok runs only."""
    quantity = headline_quantity(records)
    out = {}
    if quantity is None:
        return out, None
    for r in records:
        err, wall = r.max_error(quantity), r.cost.wall_s_median
        if not r.ok or not (math.isfinite(err) and math.isfinite(wall)):
            continue
        horizon = r.t_final if math.isfinite(r.t_final) and r.t_final > 0 else 1.0
        out.setdefault(line_label(r), []).append((wall / horizon, max(err, ERROR_DISPLAY_FLOOR), r.sweep_label))
    for pts in out.values():
        pts.sort()
    return out, quantity


def cost_to_reach(points, target):
    """Interpolated cost (s per simulated s) to reach ``target`` along one line, or None.

    ``points``: [(cost, error, label)] sorted by cost. The cheapest point already
    below target is exact; otherwise log-log interpolation between consecutive
    points that bracket the target.
    """
    if not points:
        return None
    if points[0][1] <= target:
        return points[0][0]
    for (c0, e0, _), (c1, e1, _) in zip(points, points[1:]):
        if e1 <= target < e0:
            f = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(c0) + f * (math.log(c1) - math.log(c0)))
    return None
