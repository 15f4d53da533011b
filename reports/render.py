"""The report: a self-contained ``report.html``, ``report.md`` with its figures
beside it, and ``summary.csv`` — built from a results store only: runs as
stored records (their verdicts judged when they ran), each case as its stored
record (scene, tolerances, floor), truths and trajectories from the store. It
never rebuilds a case from code and never runs an engine or an integrator.

It opens with what was found (``findings``): per case and engine, the cheapest
run reaching each target accuracy, the Pareto fronts, the hazards naming their
runs. Each case's section then shows what accuracy costs (work-precision small
multiples), stability (drift magnitude with the stored verdicts), the runs that
matter against time, and every run in a sortable table.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np
import pandas as pd

from dalembert.errors import QUANTITIES
from dalembert.invariants import CONSERVED
from dalembert.reports import figures, time_series
from dalembert.reports.loops import LOOP_TARGET, RESIDUALS, loop_lines
from dalembert.reports.maps import COST_TARGET, stability_maps
from dalembert.reports.parity import parities
from dalembert.reports.scaling import size_sweeps
from dalembert.reports.findings import (ACCURACY_TARGETS, CLOSURE_GROWTH, DISAGREEMENT_FACTOR, ENERGY_HAZARD,
                                         ENERGY_LIKE, HAZARDS, NAMED, find, run_name, settings_text)
from dalembert.reports.tables import MISSING, SORT_SCRIPT, Cell, Table, escape_html, escape_md, num
from dalembert.reports.timing import once_note, timing_note
from dalembert.reports.work_precision import cheapest_reaching, cost_per_sim_s, headline_quantity, series, sweep_key
from dalembert.store import atomic_write

__all__ = ["build_report"]

DECADES = 100.0  # a time plot's values spanning more than this factor (two decades) get a log axis
HAZARD_TITLES = {"diverged": "Diverged", "failed": "Stopped early", "energy": "Energy not kept",
                 "closure": "Loops still opening", "reactions": "Motion right, reactions wrong",
                 "tolerance": "Finite but beyond the tolerance", "inert": "A tolerance changed nothing",
                 "disagreement": "Engines disagree",
                 "unsupported": "Not supported (not run, not drawn)"}


class _Doc:
    """Collects the same content as HTML and Markdown; figures go to ``files_dir``."""

    def __init__(self, files_dir, rel):
        self.html, self.md = [], []
        self.files_dir, self.rel = files_dir, rel
        self.n_fig = 0

    def heading(self, text, level, anchor=None):
        a = f' id="{escape_html(anchor)}"' if anchor else ""
        self.html.append(f"<h{level}{a}>{escape_html(text)}</h{level}>")
        self.md += ["#" * level + " " + escape_md(text), ""]

    def para(self, text, cls=None):
        """A paragraph of plain text (escaped here)."""
        c = f' class="{cls}"' if cls else ""
        self.html.append(f"<p{c}>{escape_html(text)}</p>")
        self.md += [("> **" + escape_md(text) + "**") if cls == "warning" else escape_md(text), ""]

    def items(self, texts):
        self.html.append("<ul>" + "".join(f"<li>{escape_html(t)}</li>" for t in texts) + "</ul>")
        self.md += [f"- {escape_md(t)}" for t in texts] + [""]

    def table(self, table, note_constant=True, caption="", collapsed=None):
        """A ``Table``; its constant columns become one sentence; ``collapsed``: inside a closed <details>."""
        shown, constant = table.split_constant() if note_constant else (table, [])
        inner = shown.html(caption)
        md = shown.markdown()
        if constant:
            note = "In every row: " + "; ".join(f"{h} {v}" for h, v in constant) + "."
            inner = f'<p class="note">{escape_html(note)}</p>' + inner
            md = [escape_md(note), ""] + md
        if collapsed:
            self.html.append(f"<details><summary>{escape_html(collapsed)}</summary>{inner}</details>")
            self.md += [f"<details><summary>{escape_html(collapsed)}</summary>", ""] + md + ["</details>", ""]
        else:
            self.html.append(inner)
            self.md += md

    def figure(self, svg, caption, name):
        self.n_fig += 1
        fname = f"{self.n_fig:02d}-{name}.svg"
        atomic_write(os.path.join(self.files_dir, fname), svg)
        self.html.append(f'<figure class="plot" id="fig-{escape_html(name)}">{svg}'
                         f"<figcaption>{escape_html(caption)}</figcaption></figure>")
        self.md += [f"![{escape_md(caption)}]({self.rel}/{fname})", ""]

    def details(self, summary, text):
        self.html.append(f"<details><summary>{escape_html(summary)}</summary><pre>{escape_html(text)}</pre></details>")
        self.md += [f"<details><summary>{escape_html(summary)}</summary>", "", "```",
                    text.rstrip().replace("```", "'''"), "```", "", "</details>", ""]


def _run_link(r, text=None, wrap=False):
    """A cell naming a run, linked to its row in its case's every-run table."""
    text = text if text is not None else settings_text(r)
    return Cell(text, html=f'<a href="#run-{escape_html(r.key)}">{escape_html(text)}</a>', wrap=wrap)


def _section_id(f):
    return f"case-{f.case.name}-{f.case.version}"


def _title(f, several_versions):
    """A case's name, with its version and parameters when the store holds more than one of it."""
    if not several_versions:
        return f.case.name
    given = f.runs[0].params
    return f"{f.case.name} ({', '.join(f'{k}={v}' for k, v in sorted(given.items())) or 'defaults'}; {f.case.version})"


# ---------------------------------------------------------------------------------------------- findings
def _summary_table(found, titles):
    head = ["case", "engine", "best error", "best at"] + [f"cheapest to {t:g} (s/s)" for t in ACCURACY_TARGETS]
    head += ["diverged", "stopped", f"energy > {100 * ENERGY_HAZARD:g} %", "beyond tol.", "runs"]
    rows, csv_rows = [], []
    for f in found:
        for e in f.engines:
            cells = [Cell(titles[f], html=f'<a href="#{escape_html(_section_id(f))}">{escape_html(titles[f])}</a>',
                          wrap=True), Cell(e.engine)]
            if e.best:
                cells += [num(e.best.error, suffix=f" {f.unit}"), _run_link(e.best.run, wrap=True)]
            else:
                cells += [Cell(MISSING, math.nan), Cell("no finished run")]
            for reach in e.reaches:
                p = reach.point
                if p:  # the setting on one line, its cost below it
                    link = _run_link(p.run)
                    cells.append(Cell(f"{link.text} · {p.cost:.2g}", p.cost, wrap=True,
                                      html=f'{link.html}<br><span class="cost">{p.cost:.2g}</span>'))
                else:
                    cells.append(Cell("never", math.nan))
            counts = {k: sum(len(h.runs) for h in f.hazards_of(e.engine, k)) for k in ("diverged", "failed",
                                                                                     "energy", "tolerance")}
            cells += [Cell(str(counts[k]), float(counts[k])) for k in ("diverged", "failed", "energy", "tolerance")]
            cells.append(Cell(str(len(e.runs)), float(len(e.runs))))
            rows.append(cells)
            csv_rows.append(dict(case=f.case.name, case_version=f.case.version, engine=e.engine,
                                 quantity=f.quantity or "", unit=f.unit,
                                 best_error=e.best.error if e.best else math.nan,
                                 best_settings=e.best.run.settings_label if e.best else "",
                                 **{f"cheapest_to_{t:g}": (r.point.run.settings_label if r.point else "never")
                                    for t, r in zip(ACCURACY_TARGETS, e.reaches)},
                                 **{f"cost_to_{t:g}": (r.point.cost if r.point else math.nan)
                                    for t, r in zip(ACCURACY_TARGETS, e.reaches)},
                                 **{k: n for k, n in counts.items()}, runs=len(e.runs)))
    return Table(head, rows, cls="summary"), csv_rows


def _findings(doc, found, titles, colours):
    doc.heading("Findings", 2, anchor="findings")
    panels = [dict(title=titles[f], ylabel=f"best {f.quantity} error ({f.unit})",
                   fronts={e.engine: [(p.cost, p.error) for p in e.front] for e in f.engines if e.front},
                   floor=f.case.floor.get(f.quantity), tolerance=f.tolerance) for f in found if f.quantity]
    panels = [p for p in panels if p["fronts"]]
    if panels:
        doc.figure(figures.pareto_summary(panels, colours),
                   "Each engine's best error at each cost (Pareto front: a point is a run no cheaper run of the "
                   "engine beats); lower left is better. Dashed: the case's tolerance; dotted: the double-precision "
                   "roundoff floor.", "summary")
    table, csv_rows = _summary_table(found, titles)
    doc.para("Per case and engine: the most accurate run, the cheapest run that reaches each accuracy in the "
             "case's headline error (stepping seconds per simulated second; \"never\": no run did), and how many "
             "of its runs are hazards (listed below). Click a header to sort, a setting to see its run.")
    doc.table(table)
    for f in found:
        doc.html.append(f'<p class="case"><a href="#{escape_html(_section_id(f))}">{escape_html(titles[f])}</a></p>')
        doc.md += [f"**{escape_md(titles[f])}**", ""]
        doc.items(f.sentences)
    return csv_rows


def _hazards(doc, found, titles):
    doc.heading("Hazards", 2, anchor="hazards")
    doc.para("What to know before trusting a setting: every run named is in its case's table of runs. Energy is "
             f"judged against {100 * ENERGY_HAZARD:g} % of its scale over the horizon, disagreement at a factor "
             f"{DISAGREEMENT_FACTOR:g} between engines with the same integrator and step, beyond the case's "
             f"tolerance; a loop is still opening when its closure residual is beyond the case's bound and its "
             f"largest value over the horizon's last quarter is more than {CLOSURE_GROWTH:g} times that over its first half.")
    for f in found:
        if not f.hazards:
            continue
        doc.heading(titles[f], 3)
        for kind in HAZARDS:
            mine = [h for h in f.hazards if h.kind == kind]
            if not mine:
                continue
            doc.html.append(f'<p class="hz">{escape_html(HAZARD_TITLES[kind])}</p><ul>')
            doc.md += [f"*{escape_md(HAZARD_TITLES[kind])}*", ""]
            for h in mine:
                listed = len(h.details) > NAMED  # the sentence names only a few: every run in a list beside it
                runs = (f"<details><summary>the {len(h.details)} runs</summary><ul>"
                        + "".join(f"<li>{escape_html(d)}</li>" for d in h.details) + "</ul></details>") if listed else ""
                doc.html.append(f"<li>{escape_html(h.text)}{runs}</li>")
                doc.md.append(f"- {escape_md(h.text)}")
                if listed:
                    doc.md += [f"  <details><summary>the {len(h.details)} runs</summary>", ""]
                    doc.md += [f"  - {escape_md(d)}" for d in h.details] + ["", "  </details>"]
            doc.html.append("</ul>")
            doc.md.append("")


# ---------------------------------------------------------------------------------------------- a case
def _case_header(doc, f, title):
    case = f.case
    doc.heading(title, 2, anchor=_section_id(f))
    doc.para(f"Version {case.version}; parameters {f.runs[0].params or 'defaults'}; horizon {case.t_final:g} s; "
             f"effects {', '.join(sorted(case.scene.effects))}; truth: {case.truth}; {len(f.runs)} runs.")
    doc.table(Table(["tolerance", "value", "reason"],
                    [[k, num(t.value, "{:g}"), Cell(t.reason, wrap=True)] for k, t in sorted(case.tolerances.items())]),
              note_constant=False, collapsed=f"the case's {len(case.tolerances)} tolerances and their reasons")


def _work_precision(doc, f, name):
    lines = series(f.runs, f.quantity)
    if not lines:
        return
    doc.heading("What accuracy costs", 3)
    panels = {}  # a panel per engine and option variant, the engine's defaults first
    for pts in lines.values():
        r = pts[0].run
        panel = panels.setdefault((r.engine, bool(r.options), r.options_label), dict(
            title=" ".join(x for x in (r.engine, r.options_label) if x), engine=r.engine, lines=[]))
        panel["lines"].append(dict(integrator=r.integrator, points=[(p.cost, p.error, p.run.sweep_label) for p in pts]))
    panels = [panels[k] for k in sorted(panels)]
    doc.figure(figures.work_precision(panels, f"max {f.quantity} error ({f.unit})", floor=f.case.floor.get(f.quantity),
                                      tolerance=f.tolerance),
               f"{name}: max {f.quantity} error against stepping time per simulated second, a panel per engine and "
               "option variant on shared axes (lower left is better); colour: integrator; open marker: the "
               "coarsest step or tolerance, filled: the finest. Dashed: the case's tolerance; dotted: the roundoff "
               "floor.", f"{name}-wp")
    rows = []
    for label, pts in sorted(lines.items()):
        r = pts[0].run
        best = min(pts, key=lambda p: p.error)
        cells = [Cell(r.engine), Cell(r.integrator), Cell(r.options_label or "defaults"),
                 num(best.error), Cell(best.run.sweep_label)]
        for t in ACCURACY_TARGETS:
            p = cheapest_reaching(pts, t)
            cells.append(Cell(f"{p.run.sweep_label} · {p.cost:.2g}", p.cost) if p else Cell("never", math.nan))
        rows.append(cells)
    doc.table(Table(["engine", "integrator", "options", f"best ({f.unit})", "at"]
                    + [f"cheapest to {t:g} (s/s)" for t in ACCURACY_TARGETS], rows),
              collapsed=f"per integrator: best error and the cheapest run to each accuracy ({len(rows)} lines)")


def _grid_row(r):
    return " ".join(x for x in (r.engine, r.integrator, r.options_label) if x)


def _stability(doc, f, name):
    energy = next((n for n in ENERGY_LIKE if n in f.case.conserved), None)
    measure = energy or f.quantity
    if measure is None:
        return
    label = (f"{measure} drift (relative)" if energy else f"max {measure} error ({f.unit})")
    shown = [r for r in f.runs if r.status != "unsupported"]
    blocks = []
    for title, fixed in (("fixed step", True), ("adaptive", False)):
        runs = sorted((r for r in shown if (r.dt is not None) == fixed), key=lambda r: (_grid_row(r), sweep_key(r)))
        if not runs:
            continue
        cells = {}
        for r in runs:
            value = r.drifts.get(measure) if energy else r.max_error(measure)
            note = f"t={r.t_diverged:.3g} s" if r.t_diverged is not None else ""
            cells[(_grid_row(r), r.sweep_label)] = (value if r.ok and value is not None and math.isfinite(value)
                                                    else None, r.verdict, note)
        blocks.append(dict(title=title, cells=cells,
                           rows=sorted({k[0] for k in cells}),
                           columns=[c for c in dict.fromkeys(r.sweep_label for r in sorted(runs, key=sweep_key))]))
    if not blocks:
        return
    doc.heading("Stability", 3)
    bound = f.case.tolerances.get(measure)
    doc.figure(figures.stability(blocks, label, bound.value if bound else None),
               f"{name}: {label} per run (colour, log scale; the bar marks the case's bound) and its stored verdict "
               "(word: it weighs every conserved quantity the case bounds, the colour this one); fixed-step and "
               "adaptive runs apart. Black: diverged (at the time shown); grey, hatched: stopped early.",
               f"{name}-stability")
    n_unsupported = len(f.runs) - len(shown)
    if n_unsupported:
        doc.para(f"{n_unsupported} unsupported runs are not drawn; the hazards above list them with the reason.")
    reasons = [f"{run_name(r)}: {r.verdict} — {r.verdict_reason}" for r in shown if r.verdict_reason
               and r.verdict != "stable"]
    if reasons:
        doc.details(f"why {len(reasons)} run(s) are not stable (stored verdict reasons)", "\n".join(reasons))
    _drift_rates(doc, f)


def _drift_rates(doc, f):
    """Energy drift per simulated second: a steady slope is secular drift (most integrators), a
    slope near zero bounded oscillation (symplectic, geometric ones)."""
    name = next((n for n in ENERGY_LIKE if any(n in r.drift_rates for r in f.runs)), None)
    ok = [r for r in f.runs if r.ok and name and not math.isnan(r.drift_rates.get(name, math.nan))]
    if not ok:
        return
    rates = {(_grid_row(r), r.sweep_label): r.drift_rates[name] for r in ok}
    cols = list(dict.fromkeys(r.sweep_label for r in sorted(ok, key=sweep_key)))
    rows = [[Cell(row)] + [num(rates.get((row, c)), "{:+.2e}", " /s") for c in cols]
            for row in sorted({k[0] for k in rates})]
    what = "energy" if name == "energy" else "energy balance (E less the work of the loads)"
    doc.heading("Energy drift rate", 3)
    doc.para(f"Least-squares slope of the relative change of the {what} per simulated second (negative: lost); "
             "bounded oscillation shows as a slope near zero, secular drift as a steady one. Finished runs only.")
    doc.table(Table(["engine integrator options"] + [f"{c} (1/s)" for c in cols], rows), note_constant=False,
              collapsed=f"{len(rows)} rows")


def _against_time(doc, store, f, name):
    truth = store.truth(f.case.name, f.case.version)
    if truth is None or f.quantity is None:
        return
    reps = time_series.representatives(f.runs, f.quantity)
    divs = time_series.diverged(f.runs)
    if not reps and not divs:
        return
    doc.heading("Against time", 3)
    if reps:
        sweeps = list(dict.fromkeys(r.sweep_label for rs in reps.values() for r in sorted(rs, key=sweep_key)))
        sweeps.sort(key=lambda s: (s.startswith("tol"), -float(s.split("=")[1])))
        colours = {s: figures.SWEEP_COLOURS[i % len(figures.SWEEP_COLOURS)] for i, s in enumerate(sweeps)}
        rows = [dict(ylabel=f"{f.quantity} error ({f.unit})", log=True, series={}, bound=f.tolerance)]
        for e, rs in reps.items():
            for r in rs:
                s = time_series.headline_series(store, r, truth, f.quantity)
                if s:
                    label = " ".join(x for x in (r.sweep_label, r.integrator, r.options_label) if x)
                    rows[0]["series"].setdefault(e, []).append((label, r.sweep_label, *s))
        for cname in f.case.conserved:
            tol = f.case.tolerances.get(cname)
            row = dict(ylabel=f"{cname} drift ({_drift_unit(cname)})", log=True, series={},
                       bound=tol.value if tol else None)
            for e, rs in reps.items():
                for r in rs:
                    if r.drifts.get(cname, 0.0) > 0.0:  # identically conserved: nothing to draw on a log axis
                        row["series"].setdefault(e, []).append((r.sweep_label, r.sweep_label,
                                                                *time_series.drift_series(store, r, f.case, cname)))
            if row["series"]:
                rows.append(row)
        for level, rname in (RESIDUALS.items() if f.case.scene.loops else ()):
            tol = f.case.tolerances.get(rname)
            row = dict(ylabel=f"loop closure, {level} ({'m' if level == 'position' else 'm/s'})", log=True,
                       series={}, bound=tol.value if tol else None)
            for e, rs in reps.items():
                for r in rs:
                    if r.drifts.get(rname, 0.0) > 0.0:
                        row["series"].setdefault(e, []).append(
                            (r.sweep_label, r.sweep_label, *time_series.loop_residual_series(store, r, f.case, level)))
            if row["series"]:
                rows.append(row)
        for row in rows:  # a log axis where the values span decades, a linear one where they do not
            values = [v for runs in row["series"].values() for *_, y in runs for v in y[np.isfinite(y) & (y > 0)]]
            row["log"] = bool(values) and max(values) > DECADES * min(values)
        doc.figure(figures.time_grid(rows, list(reps), colours),
                   f"{name}: each engine's most accurate run at each step size and tolerance (colour), its "
                   f"{f.quantity} error and the drift of each conserved quantity against time (log scales where "
                   "they span decades); dashed: the case's tolerance on each.",
                   f"{name}-time")
    if divs:
        panels = {}
        for e, rs in divs.items():
            for r in rs:
                s = time_series.headline_series(store, r, truth, f.quantity)
                if s:
                    panels.setdefault(e, []).append((settings_text(r), *s, r.t_diverged))
        if panels:
            n = sum(len(v) for v in panels.values())
            doc.figure(figures.diverged_runs(panels, f"{f.quantity} error ({f.unit})"),
                       f"{name}: the {n} runs that diverged, their {f.quantity} error until it stopped being finite; "
                       "x and dotted line: the time the run diverged.", f"{name}-diverged")


def _drift_unit(name):
    """The unit of a stored drift, from how ``invariants.CONSERVED`` scales it."""
    how = CONSERVED.get(name, "")
    if how.startswith("relative"):
        return "relative"
    if how.startswith("absolute, "):
        return how[len("absolute, "):]
    return "absolute when zero, else relative"


def _every_run(doc, f):
    runs = sorted(f.runs, key=lambda r: (r.engine, r.integrator, r.options_label, sweep_key(r)))
    errs = [q for q in QUANTITIES if any(not math.isnan(r.max_error(q)) for r in runs)]
    errs.sort(key=lambda q: q != f.quantity)  # the headline error first
    drifts = [n for n in f.case.conserved if any(not math.isnan(r.drifts.get(n, math.nan)) for r in runs)]
    head = (["engine", "settings", "status", "cost (s/s)", "cost min–max (s/s)"]
            + [f"{q} ({QUANTITIES[q]})" for q in errs] + [f"{n} drift ({_drift_unit(n)})" for n in drifts]
            + ["beyond tolerance", "verdict"])
    rows = []
    for r in runs:
        status = Cell(r.status, title=r.message) if r.ok or not r.message else Cell(
            f"{r.status}" + (f" t={r.t_diverged:.3g} s" if r.t_diverged is not None else ""), title=r.message)
        horizon = r.t_final if math.isfinite(r.t_final) and r.t_final > 0 else math.nan
        spread = (Cell(f"{r.cost.wall_s_min / horizon:.2g}–{r.cost.wall_s_max / horizon:.2g}",
                       r.cost.wall_s_max / horizon - r.cost.wall_s_min / horizon,
                       title=f"{r.cost.repeats} timed repeats; {r.cost.concurrent} runs in flight")
                  if math.isfinite(r.cost.wall_s_min) else Cell(MISSING, math.nan))
        rows.append([Cell(r.engine), Cell(settings_text(r), wrap=True), status, num(cost_per_sim_s(r), "{:.2g}"), spread]
                    + [num(r.max_error(q)) for q in errs] + [num(r.drifts.get(n)) for n in drifts]
                    + [Cell(", ".join(r.beyond) if r.ok else MISSING, wrap=True), Cell(r.verdict, title=r.verdict_reason)])
    doc.heading("Every run", 3)
    doc.table(Table(head, rows, row_ids=[f"run-{r.key}" for r in runs], row_classes=[r.verdict for r in runs]),
              collapsed=f"all {len(runs)} runs of {f.case.name}: click to open; click a header to sort")


def _engines_simulated(doc, f):
    doc.heading("What each engine simulated", 3)
    for e in f.engines:
        r = e.best.run if e.best else e.runs[0]
        if r.audit:
            doc.details(f"{e.engine}: effects audit ({settings_text(r)})", json.dumps(r.audit, indent=2))
        if r.model:
            doc.details(f"{e.engine}: generated model", r.model)


# ---------------------------------------------------------------------------------------------- maps
# A case swept over more versions than this shows its summary rows, not a full section per version
# (ten spins would otherwise be ten copies of every figure); a case with a stability map shows the
# map instead of its versions' sections, however few (their probes would fill the grids).
DETAILED_VERSIONS = 4


def _range(values, fmt="{:.3g}"):
    lo, hi = min(values), max(values)
    return fmt.format(lo) if lo == hi else f"{fmt.format(lo)}–{fmt.format(hi)}"


def _maps(doc, store, records):
    """A stability map per swept case: boundaries against the swept parameter, per engine."""
    units = {}
    for r in records:
        units.setdefault(r.case, store.case(r.case, r.case_version).units)
    found = stability_maps(records, lambda name: units.get(name, {}))
    if not found:
        return set()
    doc.heading("Stability maps", 2, anchor="maps")
    for m in found:
        what = f"{m.parameter} x dt" if m.rate else "dt (s)"
        unit = f" ({m.unit})" if m.unit else ""
        values = sorted({v for points in m.curves.values() for v, _ in points})
        doc.heading(f"{m.case} against {m.parameter}", 3, anchor=f"map-{m.case}")
        lines = []
        for (engine, label), points in sorted(m.curves.items()):
            stable = [b.stable.passed * (v if m.rate else 1.0) for v, b in points if b.stable.passed is not None]
            finite = [b.finite.passed * (v if m.rate else 1.0) for v, b in points if b.finite.passed is not None]
            never = [v for v, b in points if b.stable.passed is None]
            lines.append(f"{engine} {label}: stable up to {what} = {_range(stable) if stable else 'none probed'}, "
                         f"finite up to {_range(finite) if finite else 'none probed'}"
                         + (f"; never stable at {m.parameter} = {', '.join(f'{v:g}' for v in never)}" if never else ""))
        doc.para(f"{m.case} swept over {m.parameter}{unit} = {', '.join(f'{v:g}' for v in values)}. Per engine and "
                 "integrator, the largest step probed that stays stable (every conserved quantity within the case's "
                 f"bound) and that stays finite, as {what}"
                 + (", the angle turned per step for a spin rate" if m.rate else "") + ":")
        doc.items(lines)
        panels = [dict(title=engine, lines={label: pts for (e, label), pts in m.curves.items() if e == engine})
                  for engine in sorted({e for e, _ in m.curves})]
        doc.figure(figures.stability_map(panels, f"{m.parameter}{unit}", what, m.rate),
                   f"{m.case}: per engine, the largest stable step (filled, solid) and the largest finite one "
                   f"(hollow, dashed) against {m.parameter}; a bar spans the bracket up to the smallest failing step "
                   "probed.", f"{m.case}-map")
        cost_panels = [dict(title=engine, lines={label: pts for (e, label), pts in m.costs.items() if e == engine})
                       for engine in sorted({e for e, _ in m.costs})]
        if any(c is not None for p in cost_panels for pts in p["lines"].values() for _, c in pts):
            doc.figure(figures.map_costs(cost_panels, f"{m.parameter}{unit}",
                                         f"cost of {COST_TARGET:g} {m.quantity} (s/s)"),
                       f"{m.case}: stepping time per simulated second of the cheapest run reaching {COST_TARGET:g} "
                       f"of the {m.quantity} error, against {m.parameter} (values never reaching it left out).",
                       f"{m.case}-map-cost")
    return {m.case for m in found}


def _parity(doc, store, records):
    """Ports against their originals (MJX against MuJoCo C), from the stored trajectories."""
    floors = {}

    def floor_of(name, version):
        if (name, version) not in floors:
            floors[name, version] = store.case(name, version).floor
        return floors[name, version]

    found = parities(records, store.trajectory, floor_of)
    if not found:
        return
    doc.heading("MJX against MuJoCo C", 2, anchor="parity")
    worst32 = [p for p in found if p.number_type == "float32"]
    worst64 = [p for p in found if p.number_type == "float64"]
    said = []
    for name, group in (("float64", worst64), ("float32", worst32)):
        if group:
            w = max(group, key=lambda p: p.orientation)
            said.append(f"{'in' if said else 'In'} {name}, MJX ends at most {w.orientation:.2g} rad from MuJoCo C "
                        f"({w.case}, {w.label})")
    doc.para("The same compiled model and integrator in both; the largest difference between the two stored "
             "trajectories over the horizon, against the floors no double-precision (and, for float32, no "
             "single-precision) computation beats. " + ("; ".join(said) + "." if said else ""))
    head = ["case", "settings", "orientation (rad)", "position (m)", "case floor (rad)", "float32 floor (rad)",
            "orientation / floor (float32 floor where known)"]
    rows = []
    for p in found:
        floor = p.number_floor if math.isfinite(p.number_floor) else p.floor
        rows.append([Cell(p.case), Cell(f"{p.label} ({p.number_type})" if p.number_type else p.label, wrap=True),
                     num(p.orientation), num(p.position), num(p.floor), num(p.number_floor),
                     num(p.orientation / floor if floor and math.isfinite(floor) else math.nan, "{:.3g}")])
    doc.table(Table(head, rows), collapsed=f"{len(found)} MJX runs with a MuJoCo C run at the same settings")


def _scaling(doc, store, records, colours):
    """Per case swept over its size: stepping cost per simulated second against the body count, per engine."""
    counts = {}

    def bodies_of(name, version):
        if (name, version) not in counts:
            counts[name, version] = len(store.case(name, version).scene.bodies)
        return counts[name, version]

    found = size_sweeps(records, bodies_of)
    if not found:
        return
    doc.heading("Scaling with the number of bodies", 2, anchor="scaling")
    for sw in found:
        doc.heading(f"{sw.case}: cost against size", 3, anchor=f"scaling-{sw.case}")
        doc.para(f"{sw.case} run with {', '.join(str(n) for n in sw.sizes)} bodies. Per engine, integrator and step, "
                 "the fitted exponent p of stepping time per simulated second ~ N^p (least squares on the logs):")
        doc.items([f"{engine} {label}: p = {p:.2f} (N = {pts[0][0]}..{pts[-1][0]}, "
                   f"{pts[0][1]:.3g} to {pts[-1][1]:.3g} s/s)"
                   for (engine, label), pts in sorted(sw.lines.items())
                   for p in [sw.exponents[engine, label]]])
        lines = {(engine, f"{label} (p = {sw.exponents[engine, label]:.2f})"): pts
                 for (engine, label), pts in sw.lines.items()}
        doc.figure(figures.scaling(lines, colours, sw.sizes),
                   f"{sw.case}: stepping wall time per simulated second against the number of bodies; a colour per "
                   "engine, a line per integrator and step, its fitted exponent p in the legend.", f"{sw.case}-scaling")


def _loops(doc, store, records):
    """Per case that closes kinematic loops: each engine line's accuracy, closure and the cost of LOOP_TARGET."""
    cases = {}
    for r in records:
        if (r.case, r.case_version) not in cases:
            cases[r.case, r.case_version] = store.case(r.case, r.case_version)
    looped = [(key, c) for key, c in sorted(cases.items()) if c.scene.loops]
    if not looped:
        return
    doc.heading("Closed loops", 2, anchor="loops")
    doc.para("Per engine and integrator over its finished runs: the best error it reached, the worst loop-closure "
             "residual at position level (m; for an axis, the sine of its tilt) and at velocity level (m/s), the worst "
             "error of the loop and joint reactions (relative to the largest true reaction), and the stepping time "
             f"per simulated second of its cheapest run reaching {LOOP_TARGET:g} in the headline error.")
    for (name, version), c in looped:
        runs = [r for r in records if r.case == name and r.case_version == version]
        quantity = headline_quantity(runs)
        lines = loop_lines(runs, quantity) if quantity else []
        title = f"{name} ({version})" if sum(k[0] == name for k, _ in looped) > 1 else name
        doc.heading(title, 3, anchor=f"loops-{name}-{version}")
        doc.para(f"{c.scene.loop_summary()}. Headline error: {quantity or 'none measured'}.", cls="note")
        if not lines:
            continue
        unsupported = sorted({r.engine for r in runs if r.status == "unsupported"} - {ln.engine for ln in lines})
        rows = [[Cell(ln.engine), Cell(ln.line.removeprefix(ln.engine + " "), wrap=True), num(ln.runs, "{:d}"), num(ln.best_error),
                 num(ln.worst_position_residual), num(ln.worst_velocity_residual), num(ln.worst_reaction_error),
                 num(ln.target_cost, "{:.3g}"), Cell(ln.target_settings or "not reached", wrap=True)]
                for ln in lines]
        doc.table(Table(["engine", "integrator and options", "runs", f"best {quantity} error", "worst closure, position",
                         "worst closure, velocity", "worst reaction error", f"s/s to reach {LOOP_TARGET:g}",
                         "cheapest run reaching it"], rows))
        if unsupported:
            doc.para("Not run (unsupported; the reason is in each run's row): " + ", ".join(unsupported) + ".",
                     cls="note")


# ---------------------------------------------------------------------------------------------- page
CSS = """body{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1320px;padding:0 12px;color:#222;
font-size:14px;line-height:1.4}h2{border-bottom:1px solid #ddd;padding-bottom:2px;margin-top:1.8em}
table{border-collapse:collapse;margin:0.4em 0 1.2em;font-size:12px;max-width:100%}
td,th{border:1px solid #ccc;padding:2px 5px;vertical-align:top}td{white-space:nowrap}
td.w{white-space:normal;overflow-wrap:anywhere;min-width:7em}
th{background:#f3f3f3;cursor:pointer;position:sticky;top:0}th[data-dir]{background:#e3ecf7}
tr.stable td:last-child{background:#dff0d8}tr.drifts td:last-child{background:#fcf1d0}
tr.diverged td:last-child{background:#f4cccc}tr.failed td:last-child,tr.timeout td:last-child{background:#e7d7ef}
tr:target{outline:2px solid #0072B2}figure.plot{margin:0.8em 0}figure.plot svg{max-width:100%;height:auto}
figcaption{font-size:12px;color:#555}pre{background:#f7f7f7;padding:0.5em;overflow:auto;font-size:11px;
max-height:30em}nav a{margin-right:1em}p.warning{background:#fff3cd;border:1px solid #e0c36b;padding:6px 10px}
p.note{font-size:12px;color:#555;margin:0.2em 0}p.hz{font-weight:bold;margin:0.6em 0 0.1em}
ul{margin-top:0.2em}li{margin:0.15em 0}details{margin:0.3em 0 0.8em}summary{cursor:pointer;color:#0b5394}
li>details{display:inline;margin:0 0 0 0.4em}li>details[open]{display:block}p.case{font-weight:bold;margin:0.8em 0 0}
table.summary{width:100%}
span.cost{color:#555}"""

# Self-check for readers and for the browser test: counts figures drawn with a non-zero size and,
# with every <details> open, whether anything is wider than the window (then closes them again).
SELF_CHECK = """<script>
window.addEventListener('load', function () {
  var figs = document.querySelectorAll('figure.plot svg'), drawn = 0;
  figs.forEach(function (s) { var r = s.getBoundingClientRect(); if (r.width > 0 && r.height > 0) drawn++; });
  document.body.setAttribute('data-figures', drawn + '/' + figs.length);
  var closed = Array.prototype.filter.call(document.querySelectorAll('details'), function (d) { return !d.open; });
  closed.forEach(function (d) { d.open = true; });
  var wide = [];
  document.querySelectorAll('body *').forEach(function (el) {
    if (el.closest('pre')) return;
    var r = el.getBoundingClientRect();
    if (r.right > document.documentElement.clientWidth + 1) wide.push(el.tagName.toLowerCase() + (el.id ? '#' + el.id : ''));
  });
  var page = document.documentElement.scrollWidth <= window.innerWidth;
  document.body.setAttribute('data-overflow', page && !wide.length ? 'none' : wide.slice(0, 5).join(' ') || 'page');
  closed.forEach(function (d) { d.open = false; });
  var at = {};  // where each figure and section starts, for screenshots of one of them
  document.querySelectorAll('figure[id], h2[id]').forEach(function (el) {
    at[el.id] = Math.round(el.getBoundingClientRect().top + window.scrollY);
  });
  document.body.setAttribute('data-at', JSON.stringify(at));
  document.body.setAttribute('data-height', document.documentElement.scrollHeight);
});
</script>"""


def build_report(store, out_dir=None):
    """Write ``report.html``, ``report.md`` (+ ``report_files/``) and ``summary.csv``; returns their paths."""
    out_dir = out_dir or store.path
    files_dir = os.path.join(out_dir, "report_files")
    os.makedirs(files_dir, exist_ok=True)
    records = store.records()
    manifest = store.manifest()
    found = find(store, records)
    names = [f.case.name for f in found]
    titles = {f: _title(f, names.count(f.case.name) > 1) for f in found}
    colours = figures.engine_colours({r.engine for r in records})
    doc = _Doc(files_dir, "report_files")
    machine = manifest.get("machine", {})
    doc.heading("dalembert report", 1)
    doc.para(f"{len(records)} runs on {machine.get('cpu')} ({machine.get('cores')} cores), {machine.get('os')}, "
             f"Python {machine.get('python')}; engines "
             + ", ".join(f"{k} {v}" for k, v in sorted(manifest.get("engines", {}).items()))
             + f"; harness {manifest.get('harness_version')} at {manifest.get('harness_commit')}; "
             f"command: {manifest.get('command')}; {manifest.get('started')} to {manifest.get('ended')}.")
    for note in (timing_note(manifest, records), once_note(manifest)):
        if note:
            doc.para(note, cls="warning")
    doc.html.append("<nav>" + "".join(f'<a href="#{escape_html(a)}">{escape_html(t)}</a>' for a, t in
                                      [("findings", "findings"), ("hazards", "hazards")]
                                      + [(_section_id(f), titles[f]) for f in found]) + "</nav>")
    summary_rows = _findings(doc, found, titles, colours)
    _hazards(doc, found, titles)
    mapped = _maps(doc, store, records)
    _loops(doc, store, records)
    _scaling(doc, store, records, colours)
    _parity(doc, store, records)
    for f in found:
        name = f"{f.case.name}-{f.case.version}" if names.count(f.case.name) > 1 else f.case.name
        if f.case.name in mapped or names.count(f.case.name) > DETAILED_VERSIONS:
            if f is next(g for g in found if g.case.name == f.case.name):
                doc.heading(f.case.name, 2, anchor=_section_id(f))
                doc.para(f"{names.count(f.case.name)} version(s) of {f.case.name}: "
                         + ("its stability map" if f.case.name in mapped else "a sweep: its rows in the summary")
                         + " above stand(s) for them; every run is in the store (dalembert export --all).")
            continue
        _case_header(doc, f, titles[f])
        if f.quantity:
            _work_precision(doc, f, name)
        _stability(doc, f, name)
        _against_time(doc, store, f, name)
        _every_run(doc, f)
        _engines_simulated(doc, f)
    page = (f"<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>dalembert report</title>"
            f"<style>{CSS}</style></head><body>{''.join(doc.html)}{SORT_SCRIPT}{SELF_CHECK}</body></html>")
    html_path, md_path = os.path.join(out_dir, "report.html"), os.path.join(out_dir, "report.md")
    csv_path = os.path.join(out_dir, "summary.csv")
    atomic_write(html_path, page)
    atomic_write(md_path, "\n".join(doc.md) + "\n")
    sm = pd.DataFrame(summary_rows)
    atomic_write(csv_path, sm.to_csv(index=False, float_format="%.17g") if len(sm) else "")
    return html_path, md_path, csv_path
