"""Stability maps: per case swept over a parameter, each engine's largest stable and largest finite
step against the parameter, and the cost of an accuracy against it."""

from __future__ import annotations

from dalembert.reports import figures
from dalembert.reports.findings import known_points
from dalembert.reports.formatting import value_text
from dalembert.reports.maps import COST_TARGET, stability_maps
from dalembert.reports.page import Part

__all__ = ["maps"]


def _range(values, fmt="{:.3g}"):
    lo, hi = min(values), max(values)
    return fmt.format(lo) if lo == hi else f"{fmt.format(lo)}–{fmt.format(hi)}"


def maps(rep):
    """``(Part, names of the cases mapped)``: a stability map per swept case (an empty part and
    set when no case is swept over a parameter)."""
    part = Part()
    units = {}
    for r in rep.records:
        if r.case not in units:
            units[r.case] = rep.case_of(r).units
    found = stability_maps(rep.records, lambda name: units.get(name, {}), known_points(rep.found))
    if not found:
        return part, set()
    part.heading("Stability maps", 2, anchor="maps")
    for m in found:
        what = f"{m.parameter} x dt" if m.rate else "dt (s)"
        unit = f" ({m.unit})" if m.unit else ""
        values = sorted({v for points in m.curves.values() for v, _ in points})
        part.heading(f"{m.case} against {m.parameter}", 3, anchor=f"map-{m.case}")
        lines = []
        for (engine, label), points in sorted(m.curves.items()):
            stable = [b.stable.passed * (v if m.rate else 1.0) for v, b in points if b.stable.passed is not None]
            finite = [b.finite.passed * (v if m.rate else 1.0) for v, b in points if b.finite.passed is not None]
            never = [v for v, b in points if b.stable.passed is None]
            lines.append(f"{engine} {label}: stable up to {what} = {_range(stable) if stable else 'none probed'}, "
                         f"finite up to {_range(finite) if finite else 'none probed'}"
                         + (f"; never stable at {m.parameter} = {', '.join(value_text(v) for v in never)}"
                            if never else ""))
        part.para(f"{m.case} swept over {m.parameter}{unit} = {', '.join(value_text(v) for v in values)}. Per engine "
                  "and integrator, the largest step probed that stays stable (every conserved quantity within the "
                  f"case's bound) and that stays finite, as {what}"
                  + (", the angle turned per step for a spin rate" if m.rate else "")
                  + (f". Probes of one step ran as batches of worlds across {m.parameter} (up to {m.batch} in one "
                     "engine call): their costs are per world, the batch's share" if m.batch > 1 else "") + ":")
        part.items(lines)
        panels = [dict(title=engine, lines={label: pts for (e, label), pts in m.curves.items() if e == engine})
                  for engine in sorted({e for e, _ in m.curves})]
        part.figure(figures.stability_map(panels, f"{m.parameter}{unit}", what, m.rate),
                    f"{m.case}: per engine, the largest stable step (filled, solid) and the largest finite one "
                    f"(hollow, dashed) against {m.parameter}; a bar spans the bracket up to the smallest failing step "
                    "probed.", f"{m.case}-map")
        cost_panels = [dict(title=engine, lines={label: pts for (e, label), pts in m.costs.items() if e == engine})
                       for engine in sorted({e for e, _ in m.costs})]
        if any(c is not None for p in cost_panels for pts in p["lines"].values() for _, c in pts):
            part.figure(figures.map_costs(cost_panels, f"{m.parameter}{unit}",
                                          f"cost of {COST_TARGET:g} {m.quantity} (s/s)"),
                        f"{m.case}: stepping time per simulated second of the cheapest run reaching {COST_TARGET:g} "
                        f"of the {m.quantity} error, against {m.parameter} (values never reaching it left out).",
                        f"{m.case}-map-cost")
    return part, {m.case for m in found}
