"""A contact case against its closed form: the figure a reader needs for each case (the distance down the slope,
the speed and the spin, the height and the apex of each bounce, the velocities through an impact), every finished
run against the stored truth, a table of the figures' events (apex heights, the time the slip ends, the speeds at
the end) read the same way off the truth and off every run, the creep speed of every engine and setting on a log
scale, and the contact force each engine reports against the closed form's with ContactBench's residuals
(``dalembert.contact_residuals``), "not measured" where an engine reports no force.

Read from the store only: the trajectories, the truth and the stored metrics (``RunRecord.drifts`` of a case's
``dalembert.metrics.Metric``). A case's figures are chosen by its name (``FIGURES``); its geometry (the plane's
normal, a sphere's radius, the bodies that touch) is read from its stored scene.
"""

from __future__ import annotations

import numpy as np

from dalembert.metrics import apexes, first_crossing
from dalembert.reports import contact_figures, figures
from dalembert.reports.findings import CREEP_METRIC, run_name, settings_text
from dalembert.reports.formatting import value_text
from dalembert.reports.page import Part
from dalembert.reports.sections.common import declared, has_contact, is_metric
from dalembert.reports.sections.contact_maps import contact_maps
from dalembert.reports.tables import Cell, Table, num
from dalembert.reports.work_precision import sweep_key

__all__ = ["contact", "FIGURES", "CREEP_UNIT", "ROLL_FRACTION", "FORCE_FIGURES", "NOT_MEASURED"]

# The creep figure's unit: the measurements read in mm/s (1.8 mm/s, MuJoCo's default cone), and the case's
# bound (0.1 mm/s) sits inside the axis.
CREEP_UNIT = ("mm/s", 1e-3)
# The ball rolls from where its slip speed (speed less spin x radius) falls to this fraction of its launch value,
# read the same way off the truth and every run (the closed form's slip falls linearly: it reaches 1 % at 0.99 t*).
ROLL_FRACTION = 0.01
# The figures made from the contact force an engine reports (``cases/_contact.normal_force_error``,
# ``dalembert.contact_residuals.RESIDUALS``), in the force table's order; and what a run without them shows.
FORCE_FIGURES = ("normal_force_error", "signorini_residual", "cone_residual", "dissipation_residual")
NOT_MEASURED = "not measured"


def contact(rep, f, name):
    """Case version ``f``'s contact figures (a ``Part``; empty for a case without contact, without a stored truth, or
    without a finished run); ``name`` prefixes its figures."""
    part = Part()
    if not has_contact(f.case):
        return part
    truth = rep.store.truth(f.case.name, f.case.version)
    runs = sorted((r for r in f.runs if r.ok and r.trajectory), key=lambda r: (r.engine, r.settings.integrator,
                                                                                r.options_label, sweep_key(r)))
    draw = FIGURES.get(f.case.name)
    if truth is None or not runs:
        return part
    part.heading("Contact against the closed form", 3)
    if draw is not None:
        styles = _styles(runs, rep.colours)
        trajs = [(r, rep.store.trajectory(r.key)) for r in runs]
        panels, caption, events = draw(f.case, truth, trajs, styles)
        part.figure(contact_figures.contact_panels(panels), f"{name}: {caption} Every finished run (engine by colour, its "
                    "settings by line style); dashed black: the closed form.", f"{name}-contact")
        head, values = events
        part.para("The figures' events, read the same way off the closed form and off every finished run:")
        part.table(Table(["run"] + head, [[Cell("closed form")] + [num(v, "{:.4g}") for v in values(truth)]]
                         + [[Cell(run_name(r))] + [num(v, "{:.4g}") for v in values(traj)] for r, traj in trajs]),
                   note_constant=False)
    _creep(part, rep, f, name, runs)
    _forces(part, f, runs)
    maps = contact_maps(rep, f, name)
    part.html += maps.html
    part.md += maps.md
    return part


def _styles(runs, colours):
    """Per run, ``(label, colour, linestyle)``: the engine's colour, a line style per setting within the engine."""
    out, seen = {}, {}
    for r in runs:
        k = seen.setdefault(r.engine, [])
        k.append(r.key)
        out[r.key] = (run_name(r), colours[r.engine], figures.OPTION_STYLES[(len(k) - 1) % len(figures.OPTION_STYLES)])
    return out


def _creep(part, rep, f, name, runs):
    """The creep speed of every engine and setting on a log axis, where the case measures ``CREEP_METRIC``."""
    if not is_metric(f.case, CREEP_METRIC):
        return
    scale = declared(f.case, CREEP_METRIC).scale
    unit, per = CREEP_UNIT
    bars = [(r.engine, settings_text(r), r.drifts[CREEP_METRIC] * scale / per) for r in runs
            if CREEP_METRIC in r.drifts]
    if not bars:
        return
    tol = f.case.tolerances.get(CREEP_METRIC)
    bound = tol.value * scale / per if tol else None
    part.figure(contact_figures.creep_bars(bars, rep.colours, bound, f"creep speed ({unit}, log scale)"),
                f"{name}: the creep of each engine and setting: {declared(f.case, CREEP_METRIC).description}; the "
                "closed form sticks (0)"
                + (f"; dashed: the case's bound, {value_text(bound, unit)}." if bound else "."),
                f"{name}-creep")


def _forces(part, f, runs):
    """Per finished run, the figures made from the contact force it reports, in their units against the case's
    bounds; "not measured" for a run whose engine reports no force (never a value within the bound)."""
    names = [n for n in FORCE_FIGURES if is_metric(f.case, n)]
    if not names:
        return
    rows = []
    for r in runs:
        cells = [Cell(run_name(r))]
        for n in names:
            label, tol = declared(f.case, n), f.case.tolerances.get(n)
            if n not in r.drifts:
                cells.append(Cell(NOT_MEASURED, float("nan")))
                continue
            beyond = " (beyond)" if tol is not None and r.drifts[n] > tol.value else ""
            cells.append(num(r.drifts[n] * label.scale, "{:.3g}", f" {label.unit}{beyond}"))
        rows.append(cells)
    bounds = "; ".join(f"{n}: {declared(f.case, n).description}, bound "
                       f"{value_text(f.case.tolerances[n].value * declared(f.case, n).scale, declared(f.case, n).unit)}"
                       for n in names if n in f.case.tolerances)
    part.para("The contact force each engine reports (its largest normal-force error against the closed form's, "
              "and ContactBench's residuals, the largest over the run; Le Lidec et al., IEEE T-RO 2024): " + bounds
              + f". An engine that reports no contact force: {NOT_MEASURED}.")
    part.table(Table(["run"] + names, rows), note_constant=False)


# ---------------------------------------------------------------------------------------------- geometry
def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def _plane(case):
    """The scene's first plane: its unit normal (3,) and a point of it (3,), world, m."""
    plane = case.scene.planes[0]
    return _unit(plane.normal), np.asarray(plane.point, dtype=float)


def _geom_body(case, kind):
    """The first geom of ``kind`` in a contact pair: its body's name and the geom."""
    named = {g.name: g for g in case.scene.geoms}
    for pair in case.scene.contacts:
        for side in (pair.a, pair.b):
            if side in named and named[side].kind == kind:
                return named[side].body, named[side]
    raise ValueError(f"case {case.name!r}: no {kind} geom in a contact pair")


def _downhill(case, normal):
    """The unit direction down the plane: gravity's component in it (3,)."""
    g = np.asarray(case.scene.gravity, dtype=float)
    return _unit(g - (g @ normal) * normal)


def _lines(trajs, styles, fn):
    """``(label, colour, style, t, fn(traj))`` per run."""
    return [(*styles[r.key], traj.t, fn(traj)) for r, traj in trajs]


# ---------------------------------------------------------------------------------------------- per case
def _along_slope(case, truth, trajs, styles):
    """The distance along the slope against time (a body on a tilted plane)."""
    normal, _ = _plane(case)
    named = {g.name: g.body for g in case.scene.geoms}
    pair = case.scene.contacts[0]
    body = named.get(pair.a, named.get(pair.b))  # the body whose geom touches the plane
    down = _downhill(case, normal)

    def distance(traj):
        p = traj.bodies[body].position
        return (p - p[0]) @ down

    def at_end(traj):
        return [distance(traj)[-1], traj.bodies[body].velocity[-1] @ down]

    panels = [dict(title="distance down the slope", xlabel="t (s)", ylabel="distance (m)",
                   lines=_lines(trajs, styles, distance), truth=(truth.t, distance(truth)))]
    return (panels, f"the {body}'s distance down the slope from where it started, against time.",
            (["distance at t_final (m)", "speed down the slope at t_final (m/s)"], at_end))


def _slide_to_roll(case, truth, trajs, styles):
    """The speed and the spin (omega x radius, as a rolling speed) against time."""
    normal, _ = _plane(case)
    body, geom = _geom_body(case, "sphere")
    radius = float(geom.size[0])
    tb = truth.bodies[body]
    # the launch direction: the truth's velocity at t = 0 (its spin's rolling direction when launched at rest)
    v0 = tb.velocity[0] - (tb.velocity[0] @ normal) * normal
    along = _unit(v0 if np.linalg.norm(v0) > 0.0 else radius * np.cross(tb.angular_velocity[0], normal))

    def speed(traj):
        return traj.bodies[body].velocity @ along

    def spin(traj):  # the speed the spin would roll at: (omega x R n) . along
        return radius * np.cross(traj.bodies[body].angular_velocity, normal) @ along

    def events(traj):
        slip = speed(traj) - spin(traj)
        onset = first_crossing(traj.t, slip, ROLL_FRACTION * slip[0])
        return [onset, speed(traj)[-1], spin(traj)[-1]]

    panels = [dict(title="speed", xlabel="t (s)", ylabel="speed along the launch (m/s)",
                   lines=_lines(trajs, styles, speed), truth=(truth.t, speed(truth))),
              dict(title="spin x radius", xlabel="t (s)",
                   ylabel=f"omega x radius (m/s; radius {value_text(radius, 'm')})",
                   lines=_lines(trajs, styles, spin), truth=(truth.t, spin(truth)))]
    return (panels, ("the ball's speed along its launch and its spin times its radius (the speed it would roll at), "
                     "against time: they meet where it starts to roll."),
            ([f"slip down to {100 * ROLL_FRACTION:g} % at (s)", "speed at t_final (m/s)",
              "spin x radius at t_final (m/s)"], events))


def _bounce(case, truth, trajs, styles):
    """The height of the lowest point against time, and the apex height of each bounce."""
    normal, point = _plane(case)
    body, geom = _geom_body(case, "sphere")
    radius = float(geom.size[0])

    def height(traj):
        return (traj.bodies[body].position - point) @ normal - radius

    true_tops = apexes(truth.t, height(truth))
    bounces = len(true_tops)

    def tops(traj):  # the first apexes, as many as the truth's within the horizon
        found = [z for _, z in apexes(traj.t, height(traj))][:bounces]
        return np.arange(1, len(found) + 1), np.array(found)

    panels = [dict(title="height", xlabel="t (s)", ylabel="height of the lowest point (m)",
                   lines=_lines(trajs, styles, height), truth=(truth.t, height(truth)))]
    if bounces:
        panels.append(dict(title="apex height per bounce", xlabel="bounce", ylabel="apex height (m)",
                           lines=[(*styles[r.key], *tops(traj)) for r, traj in trajs], markers=True,
                           truth=(np.arange(1, bounces + 1), np.array([z for _, z in true_tops]))))
    def events(traj):
        _, found = tops(traj)
        return list(found) + [None] * (bounces - len(found))  # a bounce not found: missing

    return (panels, ("the height of the ball's lowest point above the plane against time, and the apex of each "
                     f"bounce (the closed form's e^(2k) h; the first {bounces} within the horizon)."),
            ([f"apex {k} (m)" for k in range(1, bounces + 1)], events))


def _collision(case, truth, trajs, styles):
    """Each sphere's velocity along the line of centres against time."""
    bodies = [g.body for g in case.scene.geoms if g.kind == "sphere"][:2]
    axis = _unit(truth.bodies[bodies[1]].position[0] - truth.bodies[bodies[0]].position[0])
    panels = [dict(title=f"{b}", xlabel="t (s)", ylabel=f"{b} velocity along the line of centres (m/s)",
                   lines=_lines(trajs, styles, lambda traj, b=b: traj.bodies[b].velocity @ axis),
                   truth=(truth.t, truth.bodies[b].velocity @ axis)) for b in bodies]
    def after(traj):
        return [traj.bodies[b].velocity[-1] @ axis for b in bodies]

    return (panels, (f"the velocity of {bodies[0]} and {bodies[1]} along the line from the first's centre to the "
                     "second's at t = 0, against time: the jump at the impact."),
            ([f"{b} at t_final (m/s)" for b in bodies], after))


# The figure each contact case needs, by case name: ``(case, truth, [(run, trajectory)], styles) -> (panels,
# caption, (event headers, trajectory -> event values))``; a contact case without one shows its creep (if measured)
# and its metrics in the tables only.
FIGURES = {"block_on_incline": _along_slope, "ball_rolling_incline": _along_slope,
           "ball_slide_to_roll": _slide_to_roll, "bouncing_ball": _bounce, "sphere_collision": _collision}
