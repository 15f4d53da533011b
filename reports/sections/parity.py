"""Ports against their originals (MJX and MuJoCo Warp against MuJoCo C), from the stored trajectories."""

from __future__ import annotations

import math

from dalembert.reports.page import Part
from dalembert.reports.parity import PORT_NAMES, parities
from dalembert.reports.tables import Cell, Table, num

__all__ = ["parity"]


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
    part.para("The same compiled model and integrator in both; the largest difference between the two stored "
              "trajectories over the horizon, against the floors no double-precision (and, for float32, no "
              "single-precision) computation beats. " + ("; ".join(said) + "." if said else ""))
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
