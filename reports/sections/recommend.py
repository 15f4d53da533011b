"""What to use, the section the page opens with: per class of problem and accuracy target, the engine and setting
to pick with its cost and the runner-up (``reports.recommend``), and the caveats that apply, in the same place."""

from __future__ import annotations

from dalembert.reports.causes import single_precision
from dalembert.reports.formatting import counted
from dalembert.reports.page import Part
from dalembert.reports.recommend import PROBLEM_CLASSES, SINGLE_SAMPLE_SPREAD, TARGETS, recommend
from dalembert.reports.work_precision import figure_reader
from dalembert.reports.sections.common import run_link
from dalembert.reports.tables import Cell, Table, escape_html
from dalembert.reports.timing import loaded_runs

__all__ = ["what_to_use", "grid_text"]


def grid_text(records):
    """The steps and tolerances the store's runs swept, as a phrase ("dt 0.01, 0.001 s; rtol 1e-06, 1e-09")."""
    dts = sorted({r.settings.dt for r in records if r.settings.dt is not None}, reverse=True)
    rtols = sorted({r.settings.rtol for r in records if r.settings.dt is None and r.settings.rtol is not None},
                   reverse=True)
    parts = ([("dt " + ", ".join(f"{d:g}" for d in dts) + " s")] if dts else []) + (
        [("rtol " + ", ".join(f"{t:g}" for t in rtols))] if rtols else [])
    return "; ".join(parts) or "no steps"


def _pick(c, extra=""):
    """A candidate as a cell: engine and setting linked to its first run, the cost below."""
    link = run_link(c.runs[0], f"{c.engine} {c.setting}")
    cost = f"{c.cost:.2g} s/s ({c.low:.2g}–{c.high:.2g})"
    return Cell(f"{link.text} · {cost}{extra}", c.cost, wrap=True,
                html=f'{link.html}<br><span class="cost">{escape_html(cost + extra)}</span>')


def _verdict(rec):
    if rec.best is None:
        return "nothing reaches it"
    if rec.runner_up is None:
        return "the only engine reaching it"
    if not rec.apart:
        return "a tie: the spreads overlap"
    return f"{rec.runner_up.cost / rec.best.cost:.3g}x cheaper"


def _caveats(rep, recs):
    """The caveats that apply to every answer, as sentences."""
    manifest, records = rep.manifest, rep.records
    machine = manifest.get("machine") or {}
    single = any(r.ok and len(r.cost.wall_s_repeats) < 2 for r in records)
    out = [f"Costs are stepping seconds per simulated second on this machine ({machine.get('cpu')}, "
           f"{machine.get('cores')} cores), CPU only (MJX ran on JAX's CPU backend): on a GPU its costs differ. "
           "A pick is \"apart\" only where its min–max spread over the timed repeats ends below the runner-up's"
           + (f"; a run with a single timed repeat is given {100 * SINGLE_SAMPLE_SPREAD:g} % either side."
              if single else ".")]
    cores = machine.get("cores")
    loaded = loaded_runs(records, cores) if cores else []
    if loaded:
        out.append(f"Machine load: {len(loaded)} of {len(records)} runs were timed with the load above the cores "
                   "(the warning below): their costs are upper bounds.")
    out.append(f"The step grid: {grid_text(records)}. A target is met by a run that was made, never between two: "
               "where \"the grid decides\", a step the grid did not run may change the answer.")
    return out


def _best_of(rep, keep):
    """The smallest headline figure over every case of the finished runs ``keep(run)`` accepts, and how many
    engine lines (engine, integrator, options) those runs are; (None, 0) when none."""
    best, lines = None, set()
    for f in rep.found:
        if not f.ranked:  # (asked once per case, not per run)
            continue
        figure = figure_reader(f.ranked, f.case)
        for r in f.runs:
            if r.ok and r.judgement.verdict != "diverged" and keep(r):
                lines.add((r.engine, r.settings.integrator, r.options_label))
                e = figure(r)
                best = e if best is None or e < best else best
    return best, len(lines)


def _takeaways(rep):
    """What holds across the matrix, in sentences: whether first-order schemes or float32 runs reach the finest
    target on any case."""
    finest, out = min(TARGETS), []
    for what, keep in (("Integrators declaring order 1", lambda r: r.integrator_order == 1),
                       ("Runs in float32", single_precision)):
        best, n = _best_of(rep, keep)
        if best is None:
            continue
        verdict = "never reach" if best > finest else "reach"
        out.append(f"{what} ({counted(n, 'engine line')}) {verdict} {finest:g} on any case here: their best is "
                   f"{best:.2g}.")
    return out


def what_to_use(rep):
    """The section (a ``Part``; empty when no class of problem holds a case with a headline figure)."""
    part = Part()
    recs = recommend(rep.found, rep.titles)
    if not recs:
        return part
    part.heading("What to use", 2, anchor="what-to-use")
    part.para("Per class of problem, the cheapest engine setting whose headline error (each case's own, in its unit) "
              "is within the target on every case of the class, its cost (geometric mean over the cases; its spread "
              "in brackets), and the next engine's cheapest. Click a setting to see its run.")
    head = ["problem (cases)", "target", "use · cost (s/s)", "runner-up · cost (s/s)", "apart?", "caveat"]
    rows = []
    for rec in recs:
        problem = Cell(f"{rec.problem.name} ({', '.join(rec.cases)})", rec.problem.name, title=rec.problem.what,
                       wrap=True)
        target = Cell(f"{rec.target:g} {'/'.join(rec.units)}", rec.target)
        if rec.best is None:
            near = rec.closest
            use = Cell("nothing" + (f"; closest {near.engine} {near.setting}, {near.error:.2g}" if near else ""),
                       wrap=True)
            rows.append([problem, target, use, Cell("—"), Cell(_verdict(rec)), Cell("")])
            continue
        runner = _pick(rec.runner_up) if rec.runner_up else Cell("—")
        caveat = f"the grid decides: {rec.grid}" if rec.grid else ""
        rows.append([problem, target, _pick(rec.best), runner, Cell(_verdict(rec), wrap=True),
                     Cell(caveat, wrap=True)])
    part.table(Table(head, rows, cls="recommend", row_classes=["warning" if r.grid or not r.apart else ""
                                                               for r in recs]), note_constant=False)
    part.items(_takeaways(rep) + _caveats(rep, recs))
    uncovered = [rep.titles[f] for f in rep.found if not any(c.claims(f.case) for c in PROBLEM_CLASSES)]
    if uncovered:
        part.para("Cases no class holds: " + ", ".join(uncovered) + ".")
    return part
