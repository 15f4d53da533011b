"""Stability maps: where each integrator stops being trustworthy, against a swept case parameter.

A case swept over a parameter (several versions of one case, ``--param KEY=V1,V2,...``) whose
fixed-step runs probe several steps (``--search dt``, or a ``--dt`` list) gives, per engine,
integrator and options, a *curve*: at each swept value, the bracket of the largest step that
stays stable and of the largest that stays finite (``dalembert.boundary``). Where the swept
parameter is a rate (its unit 1/s or rad/s), the map shows the dimensionless product
parameter x step, on which steps of one integrator at different rates line up (a spin rate
times the step is the angle turned per step). Also per curve: the cost of its cheapest run
reaching ``COST_TARGET`` of the case's headline error at each swept value.
"""

from __future__ import annotations

from dataclasses import dataclass

from dalembert.boundary import boundaries
from dalembert.reports.work_precision import cheapest_reaching, headline_quantity, series, series_of

__all__ = ["StabilityMap", "stability_maps", "RATE_UNITS", "COST_TARGET"]

# Units of a parameter that is a rate: times a step, it is dimensionless.
RATE_UNITS = ("1/s", "rad/s", "Hz")
# The headline accuracy whose cost a map shows against the swept parameter (the report's summary target).
COST_TARGET = 1e-6


@dataclass(frozen=True)
class StabilityMap:
    """One swept case's map.

    Attributes
    ----------
    case : str
    parameter, unit : str — the swept parameter and its unit ("" when unknown)
    rate : bool — the parameter is a rate: boundaries are shown as parameter x step
    curves : dict (engine, line label) -> list of (value, Boundary), by value
    costs : dict (engine, line label) -> list of (value, cost s/s of its cheapest run reaching
        COST_TARGET, or None), by value
    quantity : str or None — the headline error the costs reach COST_TARGET of
    batch : int — the most worlds one engine call stepped among its runs (``Cost.batch_size``; 1: every probe ran
        alone). Probes of one step batch across the swept parameter (``dalembert.harness.batches``); the costs of
        batched probes are per world, on lines of their own (``work_precision.batch_text``)
    """

    case: str
    parameter: str
    unit: str
    rate: bool
    curves: dict
    costs: dict
    quantity: str | None
    batch: int = 1


def _swept(params_by_version):
    """The parameters whose value differs between versions, in a stable order."""
    keys = sorted({k for p in params_by_version for k in p})
    return [k for k in keys if len({repr(p.get(k)) for p in params_by_version}) > 1]


def stability_maps(records, units_of, known=None):
    """The ``StabilityMap`` of every case swept over a scalar parameter whose fixed-step runs probe
    at least two steps on some curve. ``units_of(case name) -> {parameter: unit}``; ``known(case name, version,
    quantity)``: that version's ``work_precision.points`` of error ``quantity`` where made already
    (``findings.known_points``), else None (made here)."""
    out = []
    by_case = {}  # (grouped once: a map's case holds most of a store's runs)
    for r in records:
        by_case.setdefault(r.case, []).append(r)
    for name in sorted(by_case):
        runs = by_case[name]
        versions = {r.case_version: r.params for r in runs}
        swept = [k for k in _swept(list(versions.values()))
                 if all(isinstance(p.get(k), (int, float)) for p in versions.values())]
        if len(versions) < 2 or not swept:
            continue
        parameter = swept[0]
        found = [b for b in boundaries(runs) if b.probes >= 2]
        if not found:
            continue
        curves = {}
        for b in found:
            label = " ".join(x for x in (b.integrator, b.options) if x)
            curves.setdefault((b.engine, label), []).append((float(b.params[parameter]), b))
        quantity = headline_quantity(runs)
        costs, by_version = {}, {}
        for r in runs:
            by_version.setdefault(r.case_version, []).append(r)
        for version, params in versions.items():
            made = known(name, version, quantity) if known is not None and quantity else None
            lines = (series_of(made) if made is not None else series(by_version[version], quantity)) if quantity else {}
            for full, points in lines.items():
                engine, _, label = full.partition(" ")
                best = cheapest_reaching(points, COST_TARGET)
                costs.setdefault((engine, label), []).append((float(params[parameter]),
                                                              best.cost if best else None))
        unit = units_of(name).get(parameter, "")
        out.append(StabilityMap(name, parameter, unit, unit in RATE_UNITS,
                                {k: sorted(v, key=lambda p: p[0]) for k, v in curves.items()},
                                {k: sorted(v, key=lambda p: p[0]) for k, v in costs.items()}, quantity,
                                max(r.cost.batch_size for r in runs)))
    return out
