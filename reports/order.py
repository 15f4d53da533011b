"""The observed order of convergence of each engine's fixed-step integrators, from the step pairs of a
matrix, beside the order each integrator declares (``IntegratorSpec.order`` as each run stored it:
``RunRecord.integrator_order``; the report reads the store only).

A *step pair* is two fixed-step runs of one case version, engine, integrator and options (an option can
change the computation: MJX's ``precision``) at successive
steps of the matrix, ``dt1 > dt2``, with headline errors ``e1`` and ``e2`` (the case's headline quantity,
``reports.work_precision.headline_quantity``: the max over the horizon). Its observed order is

    p = log(e1 / e2) / log(dt1 / dt2).

Only pairs in the asymptotic range count — the rule:

* both runs finished (status ``ok``) and did not diverge (stored verdict not ``diverged``: a blow-up,
  even a finite one, is no convergence), and both errors are finite;
* both errors are at least ``FLOOR_MARGIN`` times the run's roundoff floor for the quantity: the largest of
  the case's (``CaseRecord.floor``, the floor the report draws on its work-precision plots;
  ``DEFAULT_FLOOR`` where the case estimates none) and, for a single-precision run (its audit's
  ``precision``), the float32 floor its audit carries or else ``SINGLE_FLOOR``: nearer the floor, roundoff
  flattens the slope;
* an angle error (``orientation``, ``joint``, rad) of the coarser run is below ``SATURATED_ANGLE``: beyond
  it the error is no small perturbation of the true motion (the geodesic angle saturates at pi), and a
  ratio of two such errors says nothing of the order;
* the case has no contact: an impact or a stick-slip switch is an event whose timing error is first
  order in the step whatever the integrator, so no order is declared for it.

Per engine, integrator and options the table gives the median of its pairs' orders and their range, the cases they
came from, and a flag where the median is below the declared order by more than ``ORDER_MARGIN``; the
cases whose own median is that far below are named too (one joint kind can lose an order that the others
keep: MJX's RK4 on ball joints). Stored numbers only: nothing is run here.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass

__all__ = ["FLOOR_MARGIN", "DEFAULT_FLOOR", "SINGLE_FLOOR", "SATURATED_ANGLE", "ORDER_MARGIN", "StepPair",
           "ObservedOrder", "step_pairs", "observed_orders", "left_out"]

# An error 100 times its roundoff floor carries at most ~1 % of roundoff, which moves the order observed over a
# decade of step by at most log10(1.01) ~ 0.004 (over a halving, 0.015): well inside ORDER_MARGIN.
FLOOR_MARGIN = 100.0
# The floor where a case estimates none: double precision's roundoff on errors of order-one states (the floor
# below which ``reports.compare`` calls errors roundoff, ``compare.ERROR_FLOOR``).
DEFAULT_FLOOR = 1e-13
# The floor of a single-precision run where its audit carries none: float32's epsilon, 1.2e-7, accumulated over
# the 1e2 to 1e4 steps of a case's horizon as a random walk (sqrt(N) eps: 1e-6 to 1e-5), at its lower end.
SINGLE_FLOOR = 1e-6
# The largest angle error (rad) of the asymptotic range: a tenth of a radian, 1/30 of the geodesic angle's
# range; measured errors beyond it (the heavy top at 1e-2 s: ~2 rad) no longer scale as dt^p.
SATURATED_ANGLE = 0.1
ANGLES = ("orientation", "joint")
# How far below its declared order an integrator's observed median may be before it is flagged: the error
# constant of a smooth problem drifts over a decade of step by less than a factor of 3 (0.5 in the order);
# an integrator that lost an order (a stage dropped, a first-order update of the attitude) is 1 or more below.
ORDER_MARGIN = 0.5


@dataclass(frozen=True)
class StepPair:
    """Two runs at successive steps and the order they show.

    Attributes
    ----------
    case, case_version, engine, integrator, options : str — what the two runs share (options as ``key=value``)
    quantity : str — the headline error compared (``dalembert.errors.QUANTITIES``)
    dts : (float, float) — the coarse and the fine step, s
    errors : (float, float) — their max errors, the quantity's unit
    keys : (str, str) — the two runs' keys
    order : float — ``log(e1/e2) / log(dt1/dt2)``
    declared : int or None — the order the integrator declared when the two ran (None: none, or they differ)
    """

    case: str
    case_version: str
    engine: str
    integrator: str
    options: str
    quantity: str
    dts: tuple
    errors: tuple
    keys: tuple
    order: float
    declared: int | None = None


@dataclass(frozen=True)
class ObservedOrder:
    """One engine's integrator: its declared order and what its step pairs show.

    Attributes
    ----------
    engine, integrator : str
    options : str — the engine options its runs share (``key=value`` words; "" for the defaults)
    declared : int or None — the order its runs declared (``RunRecord.integrator_order``; None: none declared, or
        its runs declared different orders: a version of the engine changed it)
    pairs : tuple of StepPair
    median, low, high : float — the median of the pairs' orders and their range
    cases : tuple of str — the cases the pairs came from
    below : tuple of str — the cases whose median is below ``declared`` by more than the margin
    flagged : bool — the median is below ``declared`` by more than the margin
    """

    engine: str
    integrator: str
    options: str
    declared: int | None
    pairs: tuple
    median: float
    low: float
    high: float
    cases: tuple
    below: tuple
    flagged: bool


def _usable(r, e, floor):
    """Why run ``r``, of headline error ``e``, is outside the asymptotic range ("" when it is in it)."""
    if not r.ok or r.judgement.verdict == "diverged":
        return "diverged or did not finish"
    if not math.isfinite(e):
        return "diverged or did not finish"
    if e < FLOOR_MARGIN * _floor(r, floor):
        return "at the roundoff floor"
    return ""


def _floor(r, case_floor):
    """Run ``r``'s roundoff floor: the case's, or a single-precision run's own where it is larger."""
    if r.audit.get("precision") != "float32":
        return case_floor
    own = r.audit.get("float32_floor")
    own = float(own) if isinstance(own, (int, float)) and math.isfinite(own) else SINGLE_FLOOR
    return max(case_floor, own)


def step_pairs(groups, excluded=None):
    """The step pairs in the asymptotic range (module docstring), in a stable order.

    Parameters
    ----------
    groups : iterable of (CaseRecord, records, quantity) — per case version, its stored records and its headline
        quantity (``reports.findings.CaseFindings``: ``case``, ``runs``, ``quantity``)
    excluded : dict or None — filled with why -> count of the successive pairs left out

    Returns
    -------
    list of StepPair
    """
    excluded = {} if excluded is None else excluded
    out = []
    for case, records, quantity in groups:
        if quantity is None:
            continue
        floor = case.floor.get(quantity) or DEFAULT_FLOOR
        contact, angle = bool(case.scene.contacts), quantity in ANGLES
        lines, params = {}, {}  # (the parameters' words made once per distinct dict: records read together share them)
        for r in records:
            if r.settings.dt is not None:
                words = params.get(id(r.params))
                if words is None:
                    words = params[id(r.params)] = _params(r)
                lines.setdefault((r.engine, r.settings.integrator, r.options_label, words), []).append(r)
        for (engine, integrator, options, _), runs in sorted(lines.items()):
            runs = sorted(runs, key=lambda r: -r.settings.dt)
            # each run's step, error and why it is outside the asymptotic range, asked once (most are in two pairs)
            dts = [r.settings.dt for r in runs]
            errors = [r.max_error(quantity) for r in runs]
            usable = [""] * len(runs) if contact else [_usable(r, e, floor) for r, e in zip(runs, errors)]
            for i in range(len(runs) - 1):
                dt1, dt2 = dts[i], dts[i + 1]
                if not dt1 > dt2:
                    continue
                e1, e2 = errors[i], errors[i + 1]
                why = "of a contact case" if contact else usable[i] or usable[i + 1]
                if not why and angle and not e1 < SATURATED_ANGLE:
                    why = "with an angle error saturated"
                if why:
                    excluded[why] = excluded.get(why, 0) + 1
                    continue
                coarse, fine = runs[i], runs[i + 1]
                declared = coarse.integrator_order if coarse.integrator_order == fine.integrator_order else None
                out.append(StepPair(case.name, case.version, engine, integrator, options, quantity, (dt1, dt2),
                                    (e1, e2), (coarse.key, fine.key), math.log(e1 / e2) / math.log(dt1 / dt2),
                                    declared))
    return out


def _params(r):
    return tuple(sorted((k, str(v)) for k, v in r.params.items()))


def observed_orders(pairs, margin=ORDER_MARGIN):
    """Per engine, integrator and options, its ``ObservedOrder`` (``margin``: how far below the declared order a
    median is flagged), sorted by engine, integrator and options."""
    groups = {}
    for p in pairs:
        groups.setdefault((p.engine, p.integrator, p.options), []).append(p)
    out = []
    for (engine, integrator, options), mine in sorted(groups.items()):
        declared = {p.declared for p in mine}
        declared = declared.pop() if len(declared) == 1 else None
        orders = [p.order for p in mine]
        median = statistics.median(orders)
        cases = tuple(sorted({p.case for p in mine}))
        below = ()
        if declared is not None:
            below = tuple(c for c in cases
                          if statistics.median(p.order for p in mine if p.case == c) < declared - margin)
        out.append(ObservedOrder(engine, integrator, options, declared, tuple(mine), median, min(orders), max(orders),
                                 cases, below, declared is not None and median < declared - margin))
    return out


def left_out(excluded):
    """The pairs left out of the orders, in words ("" when none): ``3 at the roundoff floor, 2 of a contact case``."""
    return ", ".join(f"{n} {why}" for why, n in sorted(excluded.items()))
