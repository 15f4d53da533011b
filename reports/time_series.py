"""The runs worth drawing against time, and their series, from the store's trajectories.

Which runs: for each engine, its most accurate run at each step size or
tolerance of the matrix (what the engine does at that setting at best), and
every run that diverged (drawn until it stopped being finite, its divergence
time marked). What: the headline error against the stored truth, the drift
of each conserved quantity the case declares and, where the scene closes loops,
the loop-closure residuals, computed by the core's ``error_series``,
``drift_series`` and ``loop_residual`` from stored samples only.
"""

from __future__ import annotations

import math

import numpy as np

from dalembert import invariants
from dalembert.errors import error_series
from dalembert.reports.work_precision import sweep_key

__all__ = ["representatives", "diverged", "headline_series", "drift_series", "loop_residual_series"]


def representatives(runs, quantity):
    """``{engine: [run, ...]}``: each engine's most accurate finished run per sweep value, coarse to fine."""
    best = {}
    for r in runs:
        err = r.max_error(quantity)
        if not (r.ok and r.trajectory and math.isfinite(err)):
            continue
        key = (r.engine, r.sweep_label)
        if key not in best or err < best[key].max_error(quantity):
            best[key] = r
    out = {}
    for (engine, _), r in best.items():
        out.setdefault(engine, []).append(r)
    return {e: sorted(rs, key=sweep_key) for e, rs in sorted(out.items())}


def diverged(runs):
    """``{engine: [run, ...]}``: every run judged diverged that left a trajectory, by setting."""
    out = {}
    for r in runs:
        if r.judgement.verdict == "diverged" and r.trajectory:
            out.setdefault(r.engine, []).append(r)
    return {e: sorted(rs, key=lambda r: (r.settings.integrator, r.options_label, sweep_key(r)))
            for e, rs in sorted(out.items())}


def headline_series(store, run, truth, quantity):
    """``(t, error)`` of ``run``'s headline error against the truth at every sample (NaN once not finite),
    or None when its trajectory does not share the truth's samples (a run that stopped early)."""
    traj = store.trajectory(run.key)
    try:
        with np.errstate(invalid="ignore", over="ignore"):
            return truth.t, error_series(traj, truth)[quantity]
    except (ValueError, KeyError):
        return None


def drift_series(store, run, case, name):
    """``(t, drift)`` of the conserved quantity ``name`` (scaled as in ``invariants.CONSERVED``)."""
    traj = store.trajectory(run.key)
    with np.errstate(invalid="ignore", over="ignore"):
        return traj.t, invariants.drift_series(name, case.scene, traj)


def loop_residual_series(store, run, case, level):
    """``(t, residual)``: the largest loop-closure residual of ``run`` at each sample, at ``level``
    ("position": m, or the sine of an axis' tilt; "velocity": their rates), from its stored states."""
    traj = store.trajectory(run.key)
    with np.errstate(invalid="ignore", over="ignore"):
        return traj.t, invariants.loop_residual(case.scene, traj, level)
