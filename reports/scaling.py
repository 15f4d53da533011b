"""Scaling: how the cost of a run grows with the number of bodies, for a case swept over its size.

A *size sweep* is a case run in several versions whose scenes hold different numbers of bodies
(``dalembert run --case chain --param n=2,4,8,16``). Per engine, integrator, options and step
(or tolerance), its stepping time per simulated second against the body count N is a line; the
line's fitted exponent ``p`` in ``cost ~ N^p`` (least squares on log cost against log N) says
how the engine's cost grows: ~1 for a recursive O(N) algorithm, up to 3 for a dense mass matrix
factorised every step. ``python -m benchmarks.scaling`` prints the same figures for a fixed
sweep; this reads them from whatever a store holds.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from dalembert.reports.work_precision import cost_per_sim_s

__all__ = ["SizeSweep", "size_sweeps", "fitted_exponent", "line_key", "robot_costs"]


@dataclass(frozen=True)
class SizeSweep:
    """One case swept over its size.

    Attributes
    ----------
    case : str
    sizes : tuple of int — the body counts run
    lines : dict (engine, line label) -> list of (N bodies, cost s/s), by N
    exponents : dict (engine, line label) -> float — the fitted exponent p of cost ~ N^p
    """

    case: str
    sizes: tuple
    lines: dict
    exponents: dict


def fitted_exponent(points):
    """The least-squares slope of log cost against log N over ``points`` [(N, cost s/s)], or None
    with fewer than two distinct N."""
    n = np.array([p[0] for p in points], dtype=float)
    c = np.array([p[1] for p in points], dtype=float)
    if len(set(n)) < 2:
        return None
    return float(np.polyfit(np.log(n), np.log(c), 1)[0])


def line_key(r):
    """The line a run belongs to within its engine: integrator, options, step or tolerance."""
    step = f"dt={r.settings.dt:g}" if r.settings.dt is not None else f"rtol={r.settings.rtol:g}"
    return " ".join(x for x in (r.settings.integrator, r.options_text, step) if x)


def robot_costs(records, case_of):
    """Real robots' stepping costs against their degrees of freedom: ``{(engine, line label): [(dof, cost s/s,
    robot)]}``, by dof, from the finished, timed runs of cases tagged ``robot``. ``case_of(name, version)`` is the
    stored ``CaseRecord``; a robot is named by its case's ``model`` parameter (a file by its name)."""
    out = {}
    for r in records:
        cost = cost_per_sim_s(r)
        if r.status != "ok" or not math.isfinite(cost) or cost <= 0.0:
            continue
        case = case_of(r.case, r.case_version)
        if "robot" not in case.tags:
            continue
        dof = sum(len(j.v0) for j in case.scene.joints)
        robot = os.path.splitext(os.path.basename(str(case.params.get("model", r.case))))[0]
        out.setdefault((r.engine, line_key(r)), []).append((dof, cost, robot))
    return {k: sorted(v) for k, v in out.items()}


def size_sweeps(records, bodies_of):
    """The ``SizeSweep`` of every case whose stored versions have scenes of at least two sizes.
    ``bodies_of(case name, version) -> int``, the number of bodies of that version's scene.
    Only finished, timed runs count (a diverged run's cost is that of a shorter motion)."""
    out = []
    for name in sorted({r.case for r in records}):
        runs = [r for r in records if r.case == name]
        size = {v: bodies_of(name, v) for v in {r.case_version for r in runs}}
        if len(set(size.values())) < 2:
            continue
        lines = {}
        for r in runs:
            cost = cost_per_sim_s(r)
            if r.status != "ok" or not math.isfinite(cost) or cost <= 0.0:
                continue
            lines.setdefault((r.engine, line_key(r)), []).append((size[r.case_version], cost))
        lines = {k: sorted(v) for k, v in lines.items() if len({n for n, _ in v}) >= 2}
        if lines:
            out.append(SizeSweep(name, tuple(sorted(set(size.values()))), lines,
                                 {k: fitted_exponent(v) for k, v in lines.items()}))
    return out
