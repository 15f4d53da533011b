"""A case's head: its version, parameters, horizon, effects and truth, its tolerances with their
reasons, the conserved quantities it declares and the metrics it measures, with their descriptions and units."""

from __future__ import annotations

from dalembert.kinds import JOINT_KINDS
from dalembert.reports.formatting import counted, params_text, value_text
from dalembert.reports.page import Part
from dalembert.reports.recommend import problem_class
from dalembert.reports.sections.common import section_id
from dalembert.reports.sections.recommend import grid_text
from dalembert.reports.tables import Cell, Table, num

__all__ = ["case_header", "what_it_is", "degrees_of_freedom"]

FREE_BODY_DOF = JOINT_KINDS["free"][1]  # a body no joint holds moves freely: 6 speeds
# Tags that say where a case sits in the matrix, not what it tests.
MATRIX_TAGS = ("canonical", "hard", "variant")


def degrees_of_freedom(scene):
    """The scene's degrees of freedom at its initial state: its tree's speeds (``JOINT_KINDS``; a body no joint
    holds, 6) less the rank of its loop closures (``Scene.loop_summary``)."""
    if scene.loops:
        return scene.loop_summary().dof
    held = {j.child for j in scene.joints}
    return (sum(JOINT_KINDS[j.kind][1] for j in scene.joints)
            + FREE_BODY_DOF * sum(1 for b in scene.bodies if b.name not in held))


def what_it_is(f):
    """One sentence saying what case version ``f`` is: its class of problem, bodies, degrees of freedom, joints and
    loops, what it tests (its tags) and its sweep (the integrators, steps and tolerances its runs used)."""
    case, scene = f.case, f.case.scene
    kinds = {}
    for j in scene.joints:
        kinds[j.kind] = kinds.get(j.kind, 0) + 1
    joints = ", ".join(f"{n} {k}" for k, n in sorted(kinds.items())) or "none"
    loops = f", {counted(len(scene.loops), 'loop closure')}" if scene.loops else ""
    problem = problem_class(case)
    tests = ", ".join(t for t in case.tags if t not in MATRIX_TAGS)
    integrators = sorted({r.settings.integrator for r in f.runs if r.status != "unsupported"})
    return (f"What it is: {problem.name + ' — ' + problem.what if problem else 'a case no class holds'}. "
            f"{counted(len(scene.bodies), 'body', 'bodies')}, "
            f"{counted(degrees_of_freedom(scene), 'degree of freedom', 'degrees of freedom')}; joints: {joints}{loops}. "
            f"Tests: {tests or 'its tags say nothing more'}. Sweep: {counted(len(integrators), 'integrator')} at "
            f"{grid_text(f.runs)}, over a {value_text(case.t_final, 's')} horizon.")


def case_header(rep, f):
    """The head of case version ``f``'s section (a ``Part``)."""
    part, case = Part(), f.case
    part.heading(rep.titles[f], 2, anchor=section_id(f))
    part.para(what_it_is(f))
    part.para(f"Version {case.version}; parameters {params_text(f.runs[0].params) or 'defaults'}; horizon "
              f"{value_text(case.t_final, 's')}; effects {', '.join(sorted(case.scene.effects))}; truth: {case.truth}; "
              f"{counted(len(f.runs), 'run')}.")
    conserved = [inv for inv in case.invariants if inv.kind != "metric"]
    metrics = [inv for inv in case.invariants if inv.kind == "metric"]
    if conserved:  # a declared quantity is shown with what it is wherever its drift is shown
        part.para("Conserved quantities the case declares (each drift is max |x(t) - x(0)| / scale):")
        part.table(Table(["quantity", "description", "unit", "scale", "bound on the drift"],
                         [[Cell(inv.name), Cell(inv.description, wrap=True), Cell(inv.unit),
                           Cell(value_text(inv.scale, inv.unit), inv.scale),
                           num(case.tolerances[inv.name].value, "{:g}") if inv.name in case.tolerances
                           else Cell("none")] for inv in conserved]), note_constant=False)
    if metrics:  # a metric is a figure in its unit, not a drift: its bound is shown in that unit too
        part.para("Metrics the case measures on every run (each the largest |figure| over the run, in its unit):")
        part.table(Table(["metric", "what is measured", "unit", "bound"],
                         [[Cell(m.name), Cell(m.description, wrap=True), Cell(m.unit),
                           Cell(value_text(case.tolerances[m.name].value * m.scale, m.unit),
                                case.tolerances[m.name].value * m.scale) if m.name in case.tolerances
                           else Cell("none")] for m in metrics]), note_constant=False)
    part.table(Table(["tolerance", "value", "reason"],
                     [[k, num(t.value, "{:g}"), Cell(t.reason, wrap=True)] for k, t in sorted(case.tolerances.items())]),
               note_constant=False, collapsed=f"the case's {len(case.tolerances)} tolerances and their reasons")
    return part
