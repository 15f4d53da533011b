"""Ports against their originals (MJX and MuJoCo Warp against MuJoCo C), from the stored trajectories: the
systematic gaps first (``reports.port_gaps``: number type, order, an integrator computing another's), then every
run's difference in a folded table."""

from __future__ import annotations

import math

from dalembert.errors import QUANTITIES as QUANTITY_UNITS
from dalembert.reports.page import Part
from dalembert.reports.formatting import counted
from dalembert.reports.order import SATURATED_ANGLE
from dalembert.reports.parity import PORT_NAMES, parities
from dalembert.reports.port_gaps import AGREE_ROUNDOFF, SAME_RESULT, joint_kinds, number_floors, order_gaps, same_as
from dalembert.reports.tables import Cell, Table, num

__all__ = ["parity", "gap_sentences"]


def _cases(names, scenes):
    """Cases with their joints: ``free_top (free), particle_box (free)``."""
    return ", ".join(f"{n} ({', '.join(joint_kinds(scenes[n]))})" for n in names)


def gap_sentences(rep, found):
    """The ports' systematic gaps from their originals (``reports.port_gaps``), one sentence each, in the order
    number type, order, same numbers as another integrator ([] when the store shows none)."""
    scenes = {f.case.name: f.case.scene for f in rep.found}
    out = []
    for g in number_floors(found, {r.key: r for r in rep.records}):
        out.append(f"Number type: {PORT_NAMES.get(g.port, g.port)}'s float32 (its default) puts a floor of "
                   f"{g.low:.2g} to {g.high:.2g} rad under its orientation — its float32 runs' difference from "
                   f"{_original(g.original)} on the {counted(g.settings, 'setting')} where its float64 twin is the "
                   f"same computation (within {AGREE_ROUNDOFF:g} rad) and near the truth (within "
                   f"{SATURATED_ANGLE:g} rad): {', '.join(g.cases)}.")
    for g in order_gaps(rep.found):
        case, dts, mine, theirs = g.example
        kept = f"; it keeps the order on {_cases(g.kept, scenes)}" if g.kept else ""
        out.append(f"Order: {PORT_NAMES.get(g.port, g.port)}'s {g.integrator}{' ' + g.options if g.options else ''} "
                   f"converges at order {g.port_order:.2g} on {_cases(g.cases, scenes)}, where "
                   f"{_original(g.original)}'s shows at least {g.original_order:.2g} ({case}: {mine[0]:.3g} → "
                   f"{mine[1]:.3g} against {theirs[0]:.3g} → {theirs[1]:.3g} {QUANTITY_UNITS.get(g.quantity, '')} "
                   f"{g.quantity} error from dt {dts[0]:g} to {dts[1]:g} s){kept}.")
    for g in same_as(rep.found):
        case, dt, quantity, mine, theirs = g.example
        out.append(f"Same numbers as {g.like}: {PORT_NAMES.get(g.port, g.port)}'s {g.integrator} gives its "
                   f"{g.like}'s errors (to {SAME_RESULT:g} relative) on {_cases(g.cases, scenes)}, where "
                   f"{_original(g.original)}'s "
                   f"{g.integrator} does not ({case} at dt {dt:g} s: {mine:.3g} against {theirs:.3g} "
                   f"{QUANTITY_UNITS.get(quantity, '')}).")
    return out


def _original(name):
    return "MuJoCo C" if name == "mujoco" else name


def parity(rep):
    """The parity section (a ``Part``; empty when no run of a port has a MuJoCo C run at its settings)."""
    part = Part()
    found = parities(rep.records, rep.store.trajectory, lambda name, version: rep.store.case(name, version).floor)
    if not found:
        return part
    ports = sorted({p.port for p in found})
    part.heading(" and ".join(PORT_NAMES.get(p, p) for p in ports) + " against MuJoCo C", 2, anchor="parity")
    worst32 = [p for p in found if p.number_type == "float32"]
    worst64 = [p for p in found if p.number_type == "float64"]
    said = []
    for name, group in (("float64", worst64), ("float32", worst32)):
        if group:
            w = max(group, key=lambda p: p.orientation)
            said.append(f"{'in' if said else 'In'} {name}, {PORT_NAMES.get(w.port, w.port)} ends at most "
                        f"{w.orientation:.2g} rad from MuJoCo C ({w.case}, {w.label})")
    gaps = gap_sentences(rep, found)
    if gaps:
        part.para("Its systematic gaps from MuJoCo C, from the stored runs (each where it shows, with the joints of "
                  "its cases):")
        part.items(gaps)
    part.para(("Beyond these gaps, each" if gaps else "Each") + " port run against MuJoCo C's at the same settings "
              "(the same compiled model and integrator): the largest difference between the two stored trajectories "
              "over the horizon, against the floors no double-precision (and, for float32, no single-precision) "
              "computation beats (an unstable motion grows any difference, roundoff included, up to the largest). "
              + ("; ".join(said) + "." if said else ""))
    head = ["case", "settings", "orientation (rad)", "position (m)", "case floor (rad)", "float32 floor (rad)",
            "orientation / floor (float32 floor where known)"]
    rows = []
    for p in found:
        floor = p.number_floor if math.isfinite(p.number_floor) else p.floor
        label = f"{p.label} ({p.number_type})" if p.number_type else p.label
        if len(ports) > 1:
            label = f"{PORT_NAMES.get(p.port, p.port)}: {label}"
        rows.append([Cell(p.case), Cell(label, wrap=True),
                     num(p.orientation), num(p.position), num(p.floor), num(p.number_floor),
                     num(p.orientation / floor if floor and math.isfinite(floor) else math.nan, "{:.3g}")])
    part.table(Table(head, rows), collapsed=f"{len(found)} runs of a port with a MuJoCo C run at the same settings")
    return part
