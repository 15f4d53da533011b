"""Closed kinematic loops in a report: how closely each engine keeps a loop closed, and at what cost.

For every case whose stored scene closes loops (``Scene.loops``), per engine and line (integrator
and options), over its finished runs: the best headline error it reached, the worst loop-closure
residual at position and at velocity level (the case's declared invariants ``loop_residual_position``
and ``loop_residual_velocity``: each run's largest over the horizon, the worst over the line's runs),
the worst error of the loop and joint reactions against the truth's, and the cost of the cheapest
run that reached ``LOOP_TARGET`` in the headline error (a run that was made, never an
interpolation: ``work_precision.cheapest_reaching``). The residuals against time are drawn with the
case's other drifts (``render._against_time``), from the stored trajectories.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dalembert.case import LOOP_RESIDUALS
from dalembert.reports.work_precision import cheapest_reaching, lines_of, points

__all__ = ["LOOP_TARGET", "RESIDUALS", "LoopLine", "loop_lines"]

# The accuracy whose cost the table gives: a mechanism's angles to a microradian, its points to a
# micrometre on 1-m links — tighter than drawings, looser than every closed form's roundoff.
LOOP_TARGET = 1e-6

# The declared invariants a closed-loop case carries (``case.loop_closure_invariants``), by level.
RESIDUALS = LOOP_RESIDUALS


@dataclass(frozen=True)
class LoopLine:
    """One engine line on one closed-loop case.

    Attributes
    ----------
    case, engine, line : str — the line is ``work_precision.line_label`` (engine, integrator, options)
    runs : int — finished runs of the line
    quantity : str — the headline error quantity (``work_precision.headline_quantity``)
    best_error : float — its smallest max-over-horizon error among the runs (rad or m)
    worst_position_residual : float — m (NaN when no run measured it)
    worst_velocity_residual : float — m/s
    worst_reaction_error : float — relative to the largest true reaction (NaN when not read back)
    target_cost : float — stepping time per simulated second (s/s) of the cheapest run reaching
        ``LOOP_TARGET`` in ``quantity``; NaN when none did
    target_settings : str — that run's settings ("" when none)
    """

    case: str
    engine: str
    line: str
    runs: int
    quantity: str
    best_error: float
    worst_position_residual: float
    worst_velocity_residual: float
    worst_reaction_error: float
    target_cost: float
    target_settings: str


def _worst(values):
    finite = [v for v in values if v is not None and math.isfinite(v)]
    return max(finite) if finite else math.nan


def loop_lines(records, quantity, target=LOOP_TARGET):
    """The ``LoopLine`` of every engine line in ``records`` (the finished runs of one closed-loop case),
    by engine and line; ``quantity`` is the case's headline error quantity."""
    lines = {(pts[0].run.engine, label): pts for label, pts in lines_of(points(records, quantity)).items()}
    out = []
    for (engine, line), pts in sorted(lines.items()):
        runs = [p.run for p in pts]
        reached = cheapest_reaching(pts, target)
        out.append(LoopLine(
            runs[0].case, engine, line, len(runs), quantity, min(p.error for p in pts),
            _worst(r.drifts.get(RESIDUALS["position"], math.nan) for r in runs),
            _worst(r.drifts.get(RESIDUALS["velocity"], math.nan) for r in runs),
            _worst(r.max_error("reaction_force") for r in runs),
            reached.cost if reached else math.nan, reached.run.settings_label if reached else ""))
    return out
