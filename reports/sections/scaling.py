"""Scaling with the number of bodies: per case swept over its size, the stepping cost per simulated
second against the body count, per engine, with its fitted exponent; and real robots (cases tagged ``robot``)
against their degrees of freedom, beside the chain's line where the store holds one."""

from __future__ import annotations

from dalembert.reports import figures
from dalembert.reports.page import Part
from dalembert.reports.scaling import robot_costs, size_sweeps

__all__ = ["scaling"]


def scaling(rep):
    """The scaling section (a ``Part``; empty when no case is swept over its size)."""
    part = Part()
    # a robot case's versions are other robots, not one system's sizes: they are placed by dof below instead
    sized = [r for r in rep.records if "robot" not in rep.store.case(r.case, r.case_version).tags]
    found = size_sweeps(sized, lambda name, version: len(rep.store.case(name, version).scene.bodies))
    robots = robot_costs(rep.records, rep.store.case)
    if len({dof for pts in robots.values() for dof, _, _ in pts}) < 2:  # one robot (the default matrix's): no line
        robots = {}
    if not found and not robots:
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
    if robots:
        _robots(part, robots, next((sw for sw in found if sw.case == "chain"), None), rep.colours)
    return part


def _robots(part, robots, chain, colours):
    """Real robots against their degrees of freedom, each engine's line beside the chain's at the same setting
    (a chain of N rods has N joints: its N is its degrees of freedom)."""
    part.heading("Real robots: cost against degrees of freedom", 3, anchor="scaling-robots")
    part.para("Stepping time per simulated second of each robot case run (cases tagged robot: a fixed-base arm, a "
              "floating base, a large tree) against its degrees of freedom" + (", beside the chain's line at the "
              "same engine, integrator and step (N rods: N joints)" if chain else "") + ":")
    part.items([f"{engine} {label}: " + ", ".join(f"{robot} ({dof} dof) {cost:.3g} s/s" for dof, cost, robot in pts)
                for (engine, label), pts in sorted(robots.items())])
    lines = {(engine, f"{label} (robots)"): [(dof, cost) for dof, cost, _ in pts]
             for (engine, label), pts in robots.items()}
    if chain is not None:
        lines.update({(engine, f"{label} (chain)"): pts for (engine, label), pts in chain.lines.items()
                      if (engine, label) in robots})
    sizes = sorted({n for pts in lines.values() for n, _ in pts})
    part.figure(figures.scaling(lines, colours, sizes, xlabel="degrees of freedom"),
                "Real robots: stepping wall time per simulated second against their degrees of freedom; a colour per "
                "engine, its robots joined by a line, the chain's line beside them where it was run at the same "
                "setting.", "robots-scaling")
