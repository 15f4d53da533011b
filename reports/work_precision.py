"""What accuracy costs in time: work-precision series and "cost to reach" a target error.

For one case: every ok run becomes a point (stepping wall time per simulated
second, headline error), grouped by engine + integrator (+ options) and
ordered along its dt/tolerance sweep. ``cost_to_reach`` interpolates each line
log-log between its two sweep points that bracket the target error.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["TARGETS", "headline_error", "series", "cost_to_reach"]

# Error levels of the "cost to reach" table (in the unit of the headline error).
TARGETS = (1e-2, 1e-4, 1e-6, 1e-8)


def headline_error(df):
    """The error column that sums up a case: joint angle for jointed cases, else orientation."""
    for col in ("err_joint_max", "err_orientation_max", "err_position_max"):
        if col in df and df[col].notna().any():
            return col
    return None


def _line_label(row):
    opts = row.get("options") or "{}"
    return f"{row['engine']} {row['integrator']}" + ("" if opts in ("{}", "") else f" {opts}")


def series(df):
    """``{label: [(cost_per_sim_s, error, point_label), ...]}`` sorted by cost, ok runs only."""
    col = headline_error(df)
    out = {}
    if col is None:
        return out, None
    for _, r in df[df["status"] == "ok"].iterrows():
        err, wall = r.get(col), r.get("wall_s_median")
        if err is None or wall is None or not (np.isfinite(err) and np.isfinite(wall)):
            continue
        horizon = r.get("t_final") or 1.0
        point = f"dt={r['dt']:g}" if r.get("dt") == r.get("dt") and r.get("dt") is not None else f"tol={r['rtol']:g}"
        out.setdefault(_line_label(r), []).append((wall / horizon, max(float(err), 1e-17), point))
    for pts in out.values():
        pts.sort()
    return out, col


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
