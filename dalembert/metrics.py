"""Case metrics: figures a case measures on every run that are not a conserved quantity's change — an error at the
case's events against its closed form (a stop time, a roll onset, an apex height, a velocity after an impact), a
creep speed while the truth sticks, a penetration depth.

A ``Metric`` is declared like an ``Invariant`` (``dalembert.tolerance``), in the case's ``invariants=``, and is
computed by the harness from each run's trajectory (never taken from an engine), stored as the run's
``drifts[name]`` (column ``drift_<name>``), labelled in the store and judged against its tolerance, exactly as a
declared invariant's drift is. The one difference: its ``series`` is the figure itself at each sample, so the
stored value is ``max_t |series(t)| / scale``, with nothing subtracted (an invariant's is its change from
``t = 0``). An event's error is one number: its series holds it at every sample (``constant``).

Helpers to locate events in sampled motion: ``first_crossing`` (a level crossed, interpolated linearly between
samples) and ``apexes`` (local maxima, interpolated by the parabola through three samples: exact for free flight).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert.tolerance import Invariant, InvariantLabel, Tolerance

__all__ = ["Metric", "MetricTolerance", "constant", "first_crossing", "apexes"]


@dataclass(frozen=True)
class MetricTolerance(Tolerance):
    """A ``Metric``'s bound as its case holds it: the ``Tolerance`` (value dimensionless, over ``scale``) with the
    metric's ``unit`` and ``scale``, so a verdict can say the figure and its bound in the metric's unit ("creep
    1.80e-03 m/s > bound 0.0001 m/s"). Made by ``Metric`` from the ``Tolerance`` it is given; the case's version
    and the store keep the value and the reason alone, as for every tolerance."""

    unit: str = ""
    scale: float = 1.0

    def in_unit(self, value):
        """``value`` (dimensionless, over ``scale``) in the metric's unit."""
        return value * self.scale


@dataclass(frozen=True, eq=False)
class Metric(Invariant):
    """A figure measured on each run, stored and judged like a declared invariant's drift.

    Attributes
    ----------
    name, description, unit, scale, tolerance : as ``Invariant``'s; ``description`` says what is measured and
        against what truth
    headline : bool — the case's headline figure, which a report ranks runs by (``InvariantLabel.headline``);
        at most one per case, the first declared one counts
    series : callable ``(scene, traj) -> ndarray (n,)`` — the figure at each sample of ``traj``, in ``unit``;
        the stored value is ``max |series| / scale`` (dimensionless); or None where the run does not measure it
        (made from what the engine reports, e.g. a contact force, and this engine reports none)
    """

    headline: bool = False

    def __post_init__(self):
        if isinstance(self.tolerance, Tolerance) and not isinstance(self.tolerance, MetricTolerance):
            object.__setattr__(self, "tolerance", MetricTolerance(self.tolerance.value, self.tolerance.reason,
                                                                  str(self.unit), self.scale))

    @property
    def label(self):
        """The ``InvariantLabel`` a store keeps, of kind "metric"."""
        return InvariantLabel(self.name, self.description, self.unit, float(self.scale), "metric", bool(self.headline))

    def drift_series(self, scene, traj):
        """``|series(t)| / scale`` at each sample, ndarray (n,), dimensionless; None when the run does not measure
        it (its series returned None: a quantity the engine does not report, such as a contact force)."""
        x = self.series(scene, traj)
        if x is None:
            return None
        x = np.asarray(x, dtype=float)
        if x.shape != traj.t.shape:
            raise ValueError(f"metric {self.name!r}: series returned shape {x.shape}, expected {traj.t.shape} "
                             "(one value per sample)")
        return np.abs(x) / self.scale

    def drift(self, scene, traj):
        """The largest ``drift_series`` over the trajectory (NaN when a value is not finite); None when not
        measured: the harness then stores nothing under the metric's name, and the judge counts it as not
        measured (``Judgement.not_measured``), never as within its bound (``dalembert.judge``)."""
        d = self.drift_series(scene, traj)
        if d is None:
            return None
        return float(np.max(d)) if np.all(np.isfinite(d)) else float("nan")


def constant(traj, value):
    """An event's figure ``value`` held at every sample of ``traj``: ndarray (n,)."""
    return np.full(len(traj.t), float(value))


def first_crossing(t, x, level, start=0.0):
    """The first time from ``start`` (s) at which ``x`` (n,) comes down to ``level`` or below, interpolated linearly
    between the two samples around it (s); None when it never does.

    Parameters
    ----------
    t : ndarray (n,) — sample times, s
    x : ndarray (n,) — the sampled figure
    level : float — in the unit of ``x``
    start : float — s; samples before it are ignored
    """
    t, x = np.asarray(t, dtype=float), np.asarray(x, dtype=float)
    k0 = int(np.searchsorted(t, start))
    below = np.flatnonzero(x[k0:] <= level)
    if len(below) == 0:
        return None
    k = k0 + int(below[0])
    if k == k0:
        return float(t[k])
    x0, x1 = x[k - 1], x[k]
    return float(t[k - 1] + (t[k] - t[k - 1]) * (x0 - level) / (x0 - x1))


def apexes(t, z, start=0.0):
    """Strict local maxima of ``z`` (n,) after ``start`` (s), each as ``(time, value)`` of the parabola through the
    sample at the maximum and its two neighbours (exact for a free flight, whose height is quadratic in t)."""
    t, z = np.asarray(t, dtype=float), np.asarray(z, dtype=float)
    out = []
    for k in range(max(1, int(np.searchsorted(t, start))), len(t) - 1):
        if z[k] > z[k - 1] and z[k] >= z[k + 1]:
            (t0, t1, t2), (z0, z1, z2) = t[k - 1:k + 2], z[k - 1:k + 2]
            # the parabola through the three samples (Lagrange), its vertex
            d0, d2 = (z1 - z0) / (t1 - t0), (z2 - z1) / (t2 - t1)
            a = (d2 - d0) / (t2 - t0)
            if a >= 0.0:  # flat top: keep the sample
                out.append((float(t1), float(z1)))
                continue
            tv = 0.5 * (t0 + t1) - d0 / (2.0 * a)
            out.append((float(tv), float(z1 + d0 * (tv - t1) + a * (tv - t0) * (tv - t1))))
    return out
