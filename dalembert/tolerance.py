"""What judges a run: ``Tolerance`` (a bound with its reason) and ``Invariant`` (a conserved quantity a
case declares for itself, computed, stored and judged like the built-in ones), with ``InvariantLabel``
(what a store keeps of one) and the loop-closure invariants of a case that closes loops.

``dalembert.case`` re-exports every name: ``from dalembert.case import Tolerance, Invariant``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Callable

import numpy as np

from dalembert.errors import QUANTITIES
from dalembert.invariants import CONSERVED, loop_residual

__all__ = ["Tolerance", "Invariant", "InvariantLabel", "LOOP_RESIDUALS", "loop_closure_invariants",
           "invariant_problems"]


@dataclass(frozen=True)
class Tolerance:
    """A bound with its reason: ``value`` in the unit of the quantity it bounds."""

    value: float
    reason: str


# A declared invariant's name becomes the column ``drift_<name>`` of a stored run
# (``dalembert.record``): an identifier, and not ``rate_...`` (``drift_rate_<name>`` columns).
_INVARIANT_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class InvariantLabel:
    """What a results store keeps of a declared ``Invariant``: its label, no code.

    Attributes
    ----------
    name : str — the key of its drift (``RunRecord.drifts``, column ``drift_<name>``)
    description : str — what is conserved, with its frame and reference point
    unit : str — unit of the quantity (and of ``scale``)
    scale : float — the drift is ``max_t |x(t) - x(0)| / scale`` (dimensionless)
    kind : str — "invariant", or "metric" for a ``dalembert.metrics.Metric`` (its stored value is
        ``max_t |x(t)| / scale``: the figure itself, nothing subtracted), so a report shows it as what it is
    headline : bool — a metric the case declares its headline figure: what a report ranks its runs by in
        "What accuracy costs" (e.g. the creep of a box that must stick), in place of an error against the truth
    """

    name: str
    description: str
    unit: str
    scale: float
    kind: str = "invariant"
    headline: bool = False


@dataclass(frozen=True, eq=False)
class Invariant:
    """A conserved quantity a case declares for itself: a named scalar function of the
    scene and a trajectory, computed by the harness from every run (never taken from an
    engine) and stored and judged like the built-in ones (``dalembert.invariants.CONSERVED``).

    Attributes
    ----------
    name : str — lowercase identifier, not a built-in conserved quantity or error name; its drift
        is stored under it (``RunRecord.drifts[name]``, column ``drift_<name>``)
    description : str — what is conserved, with its frame and reference point
        (e.g. "angular momentum about the pivot, world z component")
    unit : str — unit of ``series`` (e.g. "kg m^2/s")
    scale : float — positive, in ``unit``: the typical size of the quantity; the drift is
        ``max_t |x(t) - x(0)| / scale``
    tolerance : Tolerance — bound on that drift (dimensionless), with its reason; the case's
        ``tolerances[name]``
    series : callable ``(scene, traj) -> ndarray (n,)`` — the quantity at each sample of ``traj``
        (a ``dalembert.trajectory.Trajectory``), in ``unit``
    """

    name: str
    description: str
    unit: str
    scale: float
    tolerance: Tolerance
    series: Callable

    def drift_series(self, scene, traj):
        """``|x(t) - x(0)| / scale`` at each sample, ndarray (n,), dimensionless."""
        x = np.asarray(self.series(scene, traj), dtype=float)
        if x.shape != traj.t.shape:
            raise ValueError(f"invariant {self.name!r}: series returned shape {x.shape}, expected {traj.t.shape} "
                             "(one value per sample)")
        return np.abs(x - x[0]) / self.scale

    def drift(self, scene, traj):
        """The largest ``drift_series`` over the trajectory (NaN when a value is not finite)."""
        d = self.drift_series(scene, traj)
        return float(np.max(d)) if np.all(np.isfinite(d)) else float("nan")

    @property
    def label(self):
        """The ``InvariantLabel`` a store keeps."""
        return InvariantLabel(self.name, self.description, self.unit, float(self.scale))


# The declared invariants of a case that closes loops, by level: their drifts are the worst closure
# residuals over a run (``RunRecord.drifts``), and reports look them up by these names.
LOOP_RESIDUALS = {"position": "loop_residual_position", "velocity": "loop_residual_velocity"}


def loop_closure_invariants(where, length, speed, tolerance):
    """The two ``Invariant`` of a scene's loop closures (``invariants.loop_residual``), position and
    velocity level, scaled by the mechanism's ``length`` (m) and its fastest point's ``speed`` (m/s),
    each bounded by ``tolerance``; ``where`` names the closures (e.g. "the coupler-rocker revolute at C")."""
    def one(level, scale, unit, per_s):
        return Invariant(LOOP_RESIDUALS[level], f"largest loop-closure residual at {level} level ({where}; {unit}, "
                         f"or the sine of an axis' tilt{per_s})", unit, scale, tolerance,
                         lambda scene, traj: loop_residual(scene, traj, level))

    return one("position", length, "m", ""), one("velocity", speed, "m/s", ", per s")


def invariant_problems(invariants):
    """What is wrong with a case's declared ``invariants``, one message per problem, "where.field: what is
    wrong — the fix" (``Case`` raises them with every other problem of its declaration)."""
    problems, seen = [], set()
    for i, inv in enumerate(invariants):
        where = f"invariants[{i}]"
        if not isinstance(inv, Invariant):
            problems.append(f"{where}: expected an Invariant(name, description, unit, scale, tolerance, series), "
                            f"got {type(inv).__name__}")
            continue
        where = f"{where} ({inv.name!r})"
        if not (isinstance(inv.name, str) and _INVARIANT_NAME.match(inv.name)) or inv.name.startswith("rate_"):
            problems.append(f"{where}.name: must be a lowercase identifier (letters, digits, _) not starting with "
                            "'rate_' — it names the stored column drift_<name>")
        elif inv.name in CONSERVED or inv.name in QUANTITIES:
            problems.append(f"{where}.name: {inv.name!r} is a built-in name — list it in conserved, or rename yours")
        elif inv.name in seen:
            problems.append(f"{where}.name: declared twice — give every invariant its own name")
        seen.add(inv.name)
        if not (isinstance(inv.scale, (int, float)) and math.isfinite(inv.scale) and inv.scale > 0.0):
            problems.append(f"{where}.scale: must be a positive number in {inv.unit!r}, got {inv.scale!r} — the "
                            "typical size of the quantity, which makes its drift relative")
        if not (isinstance(inv.description, str) and inv.description.strip()):
            problems.append(f"{where}.description: empty — say what is conserved, with its frame and point")
        if not (isinstance(inv.unit, str) and inv.unit.strip()):
            problems.append(f"{where}.unit: empty — give the unit of the series (\"1\" if dimensionless)")
        if not isinstance(inv.tolerance, Tolerance):
            problems.append(f"{where}.tolerance: must be a Tolerance(value, reason)")
        if not callable(inv.series):
            problems.append(f"{where}.series: must be a function (scene, traj) -> ndarray (n,)")
    return problems
