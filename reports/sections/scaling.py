"""Scaling with the number of bodies: per case swept over its size, the stepping cost per simulated
second against the body count, per engine, with its fitted exponent."""

from __future__ import annotations

from dalembert.reports import figures
from dalembert.reports.page import Part
from dalembert.reports.scaling import size_sweeps

__all__ = ["scaling"]


def scaling(rep):
    """The scaling section (a ``Part``; empty when no case is swept over its size)."""
    part = Part()
    found = size_sweeps(rep.records, lambda name, version: len(rep.store.case(name, version).scene.bodies))
    if not found:
        return part
    part.heading("Scaling with the number of bodies", 2, anchor="scaling")
    for sw in found:
        part.heading(f"{sw.case}: cost against size", 3, anchor=f"scaling-{sw.case}")
        part.para(f"{sw.case} run with {', '.join(str(n) for n in sw.sizes)} bodies. Per engine, integrator and step, "
                  "the fitted exponent p of stepping time per simulated second ~ N^p (least squares on the logs):")
        part.items([f"{engine} {label}: p = {p:.2f} (N = {pts[0][0]}..{pts[-1][0]}, "
                    f"{pts[0][1]:.3g} to {pts[-1][1]:.3g} s/s)"
                    for (engine, label), pts in sorted(sw.lines.items())
                    for p in [sw.exponents[engine, label]]])
        lines = {(engine, f"{label} (p = {sw.exponents[engine, label]:.2f})"): pts
                 for (engine, label), pts in sw.lines.items()}
        part.figure(figures.scaling(lines, rep.colours, sw.sizes),
                    f"{sw.case}: stepping wall time per simulated second against the number of bodies; a colour per "
                    "engine, a line per integrator and step, its fitted exponent p in the legend.",
                    f"{sw.case}-scaling")
    return part
