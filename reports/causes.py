"""Why engines disagree: the causes a store can attribute to a disagreement (``reports.hazards``: engines with the
same integrator and step whose headline errors differ beyond the case's tolerance), from what the runs stored.

* *number type* — a run computed in single precision (its audit's ``precision`` or ``dtype_qpos`` is
  ``float32``): its roundoff floor, ~1e-6 over a horizon (``reports.order.SINGLE_FLOOR``), is not the method's;
* *a method of the same name that is not the same* — the run's integrator shows, on this case's step pairs, an
  observed order below the one it declares by more than ``reports.order.ORDER_MARGIN`` (``reports.order``'s rule
  for which pairs count): e.g. an RK4 whose rotation update is first order on free or ball joints;
* *soft against hard loop constraints* — on a case with loop closures, a run whose audit describes its closure
  as soft (``SOFT_LOOP_KEYS``) beside one that does not: its loop residual is part of its motion;
* *a step cap* — an adaptive run that took exactly one step per sample interval of the case: the sample grid,
  not its tolerance, set its steps (fewer steps than samples is dense output, no cap).

Stored numbers only: each cause quotes the audit key or the orders it comes from.
"""

from __future__ import annotations

import math

from dalembert.reports.order import ORDER_MARGIN, observed_orders, step_pairs

__all__ = ["SOFT_LOOP_KEYS", "single_precision", "case_orders", "disagreement_causes"]

# The audit keys with which an engine's audit says its loop closures are soft (``adapters/*/audit.py``):
# MuJoCo's and MJX's soft equality constraints (``loop_softness``), Drake's SAP near-rigid constraints
# (``loop_stiffness``).
SOFT_LOOP_KEYS = ("loop_softness", "loop_stiffness")


def single_precision(r):
    """Whether run ``r`` computed in float32 (its audit's ``precision`` or ``dtype_qpos``)."""
    return "float32" in (r.audit.get("precision"), r.audit.get("dtype_qpos"))


def case_orders(case, runs, quantity):
    """Per (engine, integrator, options) the ``ObservedOrder`` of this case's step pairs."""
    return {(o.engine, o.integrator, o.options): o for o in observed_orders(step_pairs([(case, runs, quantity)]))}


def disagreement_causes(group, case, runs, quantity, orders=None):
    """The causes of a disagreement among ``group`` (its runs), as sentences ([] when none can be attributed).

    Parameters
    ----------
    group : sequence of RunRecord — the runs that disagree (one per engine)
    case : CaseRecord
    runs : sequence of RunRecord — every run of the case version (for its step pairs)
    quantity : str — the headline error
    orders : dict or None — ``case_orders(case, runs, quantity)``, when computed already
    """
    orders = case_orders(case, runs, quantity) if orders is None else orders
    out = []
    least = min((r.max_error(quantity) for r in group), default=math.nan)
    for r in group:
        if single_precision(r) and r.max_error(quantity) > least:  # (the least accurate side of it, not the best)
            out.append(f"{r.engine} ran in float32 (audit precision): its roundoff floor, ~1e-6, is not the method's")
    flagged = []
    for r in group:
        o = orders.get((r.engine, r.settings.integrator, r.options_label))
        if o is not None and o.declared is not None and o.median < o.declared - ORDER_MARGIN:
            flagged.append(r)
            kept = [orders[k] for k in orders if k[1] == r.settings.integrator and k[0] != r.engine
                    and orders[k].declared is not None and orders[k].median >= orders[k].declared - ORDER_MARGIN]
            also = f" ({', '.join(f'{k.engine} {k.median:.2g}' for k in kept)})" if kept else ""
            out.append(f"{r.engine}'s {r.settings.integrator} shows order {o.median:.2g} here where it declares "
                       f"{o.declared}{also}: a method of the same name that is not the same")
    if case.scene.loops:
        soft = [r for r in group if any(k in r.audit for k in SOFT_LOOP_KEYS)]
        if soft and len(soft) < len(group):
            keys = sorted({k for r in soft for k in SOFT_LOOP_KEYS if k in r.audit})
            out.append(f"{', '.join(r.engine for r in soft)} close{'s' if len(soft) == 1 else ''} the loop with soft "
                       f"constraints (audit {', '.join(keys)}), the others hard: the residual is part of the motion")
    intervals = max(len(case.sample_times) - 1, 1)
    for r in group:
        # (one step per sample interval exactly: a controller free to choose would not land on it; fewer steps
        # than samples is dense output, not a cap)
        if r.settings.dt is None and r.cost.n_steps == intervals:
            out.append(f"{r.engine}'s {r.settings.integrator} took one step per sample interval ({intervals}): the "
                       "samples, not its tolerance, set its steps")
    return out
