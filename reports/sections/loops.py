"""Closed loops: per case that closes kinematic loops, each engine line's accuracy, closure,
reaction error and the cost of ``LOOP_TARGET``."""

from __future__ import annotations

from dalembert.refusal import manifest_refusals
from dalembert.reports.loops import LOOP_TARGET, loop_lines
from dalembert.reports.page import Part
from dalembert.reports.tables import Cell, Table, num
from dalembert.reports.work_precision import headline_quantity

__all__ = ["loops"]


def loops(rep):
    """The closed-loops section (a ``Part``; empty when no stored case closes a loop)."""
    part = Part()
    cases = {}
    for r in rep.records:
        cases.setdefault((r.case, r.case_version), rep.case_of(r))
    looped = [(key, c) for key, c in sorted(cases.items()) if c.scene.loops]
    if not looped:
        return part
    part.heading("Closed loops", 2, anchor="loops")
    part.para("Per engine and integrator over its finished runs: the best error it reached, the worst loop-closure "
              "residual at position level (m; for an axis, the sine of its tilt) and at velocity level (m/s), the "
              "worst error of the loop and joint reactions (relative to the largest true reaction), and the stepping "
              f"time per simulated second of its cheapest run reaching {LOOP_TARGET:g} in the headline error.")
    for (name, version), c in looped:
        runs = [r for r in rep.records if r.case == name and r.case_version == version]
        quantity = headline_quantity(runs)
        lines = loop_lines(runs, quantity) if quantity else []
        title = f"{name} ({version})" if sum(k[0] == name for k, _ in looped) > 1 else name
        part.heading(title, 3, anchor=f"loops-{name}-{version}")
        part.para(f"{c.scene.loop_summary()}. Headline error: {quantity or 'none measured'}.", cls="note")
        if not lines:
            continue
        unsupported = sorted({r.engine for r in runs if r.status == "unsupported"} - {ln.engine for ln in lines})
        refused = sorted({f.engine for f in manifest_refusals(rep.manifest)
                          if (f.case, f.case_version) == (name, version)} - {ln.engine for ln in lines})
        rows = [[Cell(ln.engine), Cell(ln.line.removeprefix(ln.engine + " "), wrap=True), num(ln.runs, "{:d}"),
                 num(ln.best_error), num(ln.worst_position_residual), num(ln.worst_velocity_residual),
                 num(ln.worst_reaction_error), num(ln.target_cost, "{:.3g}"),
                 Cell(ln.target_settings or "not reached", wrap=True)] for ln in lines]
        part.table(Table(["engine", "integrator and options", "runs", f"best {quantity} error",
                          "worst closure, position", "worst closure, velocity", "worst reaction error",
                          f"s/s to reach {LOOP_TARGET:g}", "cheapest run reaching it"], rows))
        if unsupported:
            part.para("Not run (unsupported; the reason is in each run's row): " + ", ".join(unsupported) + ".",
                      cls="note")
        if refused:  # (refused before the matrix ran: no row, the manifest lists each once)
            part.para("Not run (refused; the hazards give each reason): " + ", ".join(refused) + ".", cls="note")
    return part
