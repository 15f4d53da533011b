"""The report: a self-contained ``report.html``, ``report.md`` with its figures
beside it, and ``summary.csv`` — built from a results store only: runs as
stored records (their verdicts judged when they ran), each case as its stored
record (scene, tolerances, floor), truths and trajectories from the store. It
never rebuilds a case from code and never runs an engine or an integrator.
"""

from __future__ import annotations

import html
import json
import math
import os

import pandas as pd

from dalembert import invariants
from dalembert.errors import QUANTITIES, error_series
from dalembert.store import atomic_write
from dalembert.reports import figures
from dalembert.reports.work_precision import TARGETS, cost_to_reach, line_label, series

__all__ = ["build_report"]

SUMMARY_TARGET = 1e-6  # the accuracy whose cost the summary quotes


def _num(x, fmt="{:.2e}"):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    return fmt.format(x)


class _Doc:
    """Collects the same content as HTML and Markdown."""

    def __init__(self, files_dir, rel):
        self.html, self.md = [], []
        self.files_dir, self.rel = files_dir, rel
        self.n_fig = 0

    def heading(self, text, level, anchor=None):
        a = f' id="{anchor}"' if anchor else ""
        self.html.append(f"<h{level}{a}>{html.escape(text)}</h{level}>")
        self.md += ["#" * level + " " + text, ""]

    def para(self, text_html, text_md=None):
        self.html.append(f"<p>{text_html}</p>")
        self.md += [text_md if text_md is not None else text_html, ""]

    def table(self, head, rows, classes=None):
        h = "".join(f"<th>{html.escape(c)}</th>" for c in head)
        body = []
        for k, r in enumerate(rows):
            cls = f' class="{classes[k]}"' if classes and classes[k] else ""
            body.append(f"<tr{cls}>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>")
        self.html.append(f"<table><thead><tr>{h}</tr></thead><tbody>{''.join(body)}</tbody></table>")
        strip = lambda c: str(c).replace("|", "\\\\|").replace("<b>", "**").replace("</b>", "**")  # noqa: E731
        self.md += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        self.md += ["| " + " | ".join(strip(_plain(c)) for c in r) + " |" for r in rows]
        self.md.append("")

    def figure(self, svg, caption, name):
        self.n_fig += 1
        fname = f"{self.n_fig:02d}-{name}.svg"
        atomic_write(os.path.join(self.files_dir, fname), svg)
        self.html.append(f'<figure class="plot">{svg}<figcaption>{html.escape(caption)}</figcaption></figure>')
        self.md += [f"![{caption}]({self.rel}/{fname})", ""]

    def details(self, summary, text):
        self.html.append(f"<details><summary>{html.escape(summary)}</summary><pre>{html.escape(text)}</pre></details>")
        self.md += [f"<details><summary>{summary}</summary>", "", "```", text.rstrip(), "```", "", "</details>", ""]


def _plain(c):
    import re

    return re.sub(r"<(?!/?b>)[^>]+>", "", str(c))


def _grid_labels(r):
    """(row, column) of a run in the per-case grids: engine + integrator (+ options), dt or tol."""
    return line_label(r), r.sweep_label


def _sweep_order(label):
    """Grid columns: fixed steps first, then tolerances, each from coarse to fine."""
    return label.startswith("tol"), -float(label.split("=")[1])


def _drift_rates(doc, runs):
    """Energy drift per simulated second, engine + integrator x step: a steady slope is secular
    drift (most integrators), a slope near zero bounded oscillation (symplectic, geometric ones)."""
    names = [n for n in ("energy", "energy_balance") if any(n in r.drift_rates for r in runs)]
    if not names:
        return
    name = names[0]
    ok = [r for r in runs if r.ok and not math.isnan(r.drift_rates.get(name, math.nan))]
    if not ok:
        return
    rates = {_grid_labels(r): r.drift_rates[name] for r in ok}
    row_labels = sorted({rl for rl, _ in rates})
    col_labels = sorted({cl for _, cl in rates}, key=_sweep_order)
    what = "energy" if name == "energy" else "energy balance (E - work of the loads)"
    doc.heading("Energy drift rate", 3)
    doc.para(html.escape(f"Least-squares slope of the relative change of the {what}, per simulated second "
                         f"(negative: lost). Bounded oscillation shows as a slope near zero, secular drift as a "
                         f"steady one; successful runs only."))
    doc.table(["engine + integrator"] + col_labels,
              [[html.escape(rl)] + [_num(rates[(rl, c)], "{:+.2e} /s") if (rl, c) in rates else "—"
                                    for c in col_labels] for rl in row_labels])


def _case_section(doc, store, runs, summary_rows):
    """The section of one case: ``runs`` are its records (one case version)."""
    case = store.case(runs[0].case, runs[0].case_version)
    name = case.name
    truth = store.truth(name, case.version)
    doc.heading(f"{name}", 2, anchor=f"case-{name}")
    doc.para(html.escape(f"version {case.version}; parameters {runs[0].params or 'defaults'}; "
                         f"horizon {case.t_final:g} s; effects {', '.join(sorted(case.scene.effects))}; "
                         f"truth: {case.truth}."))
    doc.table(["tolerance", "value", "reason"], [[k, f"{t.value:g}", html.escape(t.reason)]
                                                  for k, t in case.tolerances.items()])
    # --- work-precision
    lines, quantity = series(runs)
    if lines:
        doc.heading("What accuracy costs", 3)
        unit = QUANTITIES[quantity]
        doc.figure(figures.work_precision(lines, f"max {quantity} error ({unit})", floor=case.floor.get(quantity),
                                          title=f"{name}: work-precision"),
                   f"{name}: max {quantity} error against stepping time per simulated second", f"{name}-wp")
        rows = []
        for label, pts in sorted(lines.items()):
            costs = [cost_to_reach(pts, t) for t in TARGETS]
            rows.append([html.escape(label), _num(min(p[1] for p in pts))]
                        + [_num(c, "{:.3g} s/s") if c is not None else "not reached" for c in costs])
        doc.table(["engine + integrator", "best error"] + [f"cost to reach {t:g}" for t in TARGETS], rows)
    # --- stability grid
    cells, reasons = {}, []
    for r in runs:
        rl, cl = _grid_labels(r)
        cells[(rl, cl)] = r.verdict
        if r.verdict_reason and r.verdict != "stable":
            reasons.append(f"{rl} {cl}: {r.verdict} — {r.verdict_reason}")
    row_labels = sorted({rl for rl, _ in cells})
    col_labels = sorted({cl for _, cl in cells}, key=_sweep_order)
    doc.heading("Stability", 3)
    doc.figure(figures.stability_grid(row_labels, col_labels, cells, title=f"{name}: verdicts"),
               f"{name}: stability verdict per engine, integrator and step", f"{name}-stability")
    if reasons:
        doc.details(f"why {len(reasons)} run(s) are not stable", "\n".join(reasons))
    _drift_rates(doc, runs)
    # --- every run
    doc.heading("Every run", 3)
    errs = [q for q in ("position", "orientation", "velocity", "angular_velocity", "joint", "reaction_force")
            if any(not math.isnan(r.max_error(q)) for r in runs)]
    drifts = sorted({n for r in runs for n, v in r.drifts.items() if not math.isnan(v)})
    table_rows, classes = [], []
    for r in sorted(runs, key=lambda r: (r.engine, r.integrator, r.dt or math.inf, r.rtol or math.inf)):
        status = r.status if r.ok else f"{r.status}: {html.escape(r.message)}"
        okcell = "—" if not r.ok else ("yes" if r.within_tolerance else f"<b>no</b>: {' '.join(r.beyond)}")
        table_rows.append([r.engine, html.escape(r.settings_label), status, _num(r.cost.wall_s_median)]
                          + [_num(r.max_error(q)) for q in errs] + [_num(r.drifts.get(n)) for n in drifts]
                          + [okcell, r.verdict])
        classes.append(r.verdict)
    doc.table(["engine", "settings", "status", "wall s"] + errs + [f"{n} drift" for n in drifts]
              + ["within tol", "verdict"], table_rows, classes)
    # --- trajectories of each engine's most accurate run
    best = {}
    if quantity:
        for r in runs:
            if r.ok and r.trajectory and (r.engine not in best
                                          or r.max_error(quantity) < best[r.engine].max_error(quantity)):
                best[r.engine] = r
    if truth is not None and best:
        doc.heading("Trajectories (each engine's most accurate run)", 3)
        t = truth.t
        trajs = {e: store.trajectory(r.key) for e, r in best.items()}
        label = {e: f"{e} {r.settings_label}" for e, r in best.items()}
        if quantity == "joint":
            jname = next(iter(truth.joints))
            doc.figure(figures.time_series(t, {label[e]: tr.joints[jname].q[:, 0] for e, tr in trajs.items()},
                                           "joint angle (rad)", truth=truth.joints[jname].q[:, 0],
                                           title=f"{name}: joint angle"),
                       f"{name}: joint angle against the truth", f"{name}-angle")
        else:
            bname = next(iter(truth.bodies))
            doc.figure(figures.time_series(t, {label[e]: tr.bodies[bname].angular_velocity_body
                                               for e, tr in trajs.items()}, "w_B components (rad/s)",
                                           truth=truth.bodies[bname].angular_velocity_body,
                                           title=f"{name}: body angular velocity"),
                       f"{name}: body-frame angular velocity against the truth", f"{name}-omega")
        doc.figure(figures.time_series(t, {label[e]: error_series(tr, truth)[quantity] for e, tr in trajs.items()},
                                       f"{quantity} error ({QUANTITIES[quantity]})", log=True,
                                       title=f"{name}: error against time"),
                   f"{name}: {quantity} error against time", f"{name}-error")
        if case.conserved:
            cname = case.conserved[0]
            doc.figure(figures.time_series(t, {label[e]: invariants.drift_series(cname, case.scene, tr)
                                               for e, tr in trajs.items()}, f"{cname} drift", log=True,
                                           title=f"{name}: {cname} drift ({invariants.CONSERVED[cname]})"),
                       f"{name}: {cname} drift against time", f"{name}-drift")
    # --- what each engine computed
    doc.heading("What each engine simulated", 3)
    shown = best or {e: next(r for r in runs if r.engine == e) for e in sorted({r.engine for r in runs})}
    for engine, r in sorted(shown.items()):
        if r.audit:
            doc.details(f"{engine}: effects audit ({r.settings_label})", json.dumps(r.audit, indent=2))
        if r.model:
            doc.details(f"{engine}: generated model", r.model)
    # --- summary rows
    for engine in sorted({r.engine for r in runs}):
        mine = [r for r in runs if r.engine == engine]
        ok = [r for r in mine if r.ok and not math.isnan(r.max_error(quantity or ""))]
        top = min(ok, key=lambda r: r.max_error(quantity)) if ok else None
        costs = [c for c in (cost_to_reach(pts, SUMMARY_TARGET) for label, pts in lines.items()
                             if label.startswith(engine + " ")) if c is not None]
        counts = {}
        for r in mine:
            counts[r.verdict] = counts.get(r.verdict, 0) + 1
        summary_rows.append(dict(case=name, engine=engine, agrees=any(r.ok and r.within_tolerance for r in mine),
                                 best_error=top.max_error(quantity) if top else math.nan,
                                 best_settings=top.settings_label if top else "", quantity=quantity or "",
                                 cost_of_1e_6=min(costs) if costs else math.nan,
                                 verdicts=", ".join(f"{n} {v}" for v, n in sorted(counts.items())),
                                 runs=len(mine)))


CSS = """body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1200px;color:#222}
table{border-collapse:collapse;margin:0.5em 0 1.5em;font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px}
th{background:#f3f3f3}tr.stable td:last-child{background:#dff0d8}tr.drifts td:last-child{background:#fcf1d0}
tr.diverged td:last-child{background:#f4cccc}tr.failed td:last-child{background:#e7d7ef}
figure.plot{margin:1em 0}figure.plot svg{max-width:100%;height:auto}figcaption{font-size:12px;color:#555}
pre{background:#f7f7f7;padding:0.5em;overflow:auto;font-size:11px}nav a{margin-right:1em}"""

# Self-check for readers and for the browser test: counts figures drawn with a non-zero size.
SELF_CHECK = """<script>
window.addEventListener('load', function () {
  var figs = document.querySelectorAll('figure.plot svg');
  var drawn = 0;
  figs.forEach(function (s) { var r = s.getBoundingClientRect(); if (r.width > 0 && r.height > 0) drawn++; });
  document.body.setAttribute('data-figures', drawn + '/' + figs.length);
});
</script>"""


def build_report(store, out_dir=None):
    """Write ``report.html``, ``report.md`` (+ ``report_files/``) and ``summary.csv``; returns their paths."""
    out_dir = out_dir or store.path
    files_dir = os.path.join(out_dir, "report_files")
    os.makedirs(files_dir, exist_ok=True)
    records = store.records()
    manifest = store.manifest()
    doc = _Doc(files_dir, "report_files")
    summary_rows = []
    cases = sorted({r.case for r in records})
    body = _Doc(files_dir, "report_files")
    for case_name in cases:
        _case_section(body, store, [r for r in records if r.case == case_name], summary_rows)
    machine = manifest.get("machine", {})
    doc.heading("dalembert report", 1)
    doc.para(html.escape(f"harness {manifest.get('harness_version')} at commit {manifest.get('harness_commit')}; "
                         f"{machine.get('cpu')} ({machine.get('cores')} cores), {machine.get('os')}, "
                         f"Python {machine.get('python')}; engines: "
                         + ", ".join(f"{k} {v}" for k, v in sorted(manifest.get("engines", {}).items()))
                         + f"; command: {manifest.get('command')}; {manifest.get('started')} to {manifest.get('ended')}."))
    doc.html.append("<nav>" + "".join(f'<a href="#case-{c}">{c}</a>' for c in cases) + "</nav>")
    doc.heading("Summary", 2)
    doc.para("Per case and engine: whether any run agrees with the truth within every one of the case's tolerances, "
             "the best accuracy reached (the case's headline error: joint angle, else orientation), the cheapest "
             f"interpolated cost of reaching {SUMMARY_TARGET:g} (stepping seconds per simulated second), and the "
             "stability verdicts of all its runs.")
    sm = pd.DataFrame(summary_rows)
    rows = [[f'<a href="#case-{r.case}">{r.case}</a>', r.engine, "yes" if r.agrees else "<b>no</b>",
             f"{_num(r.best_error)} {QUANTITIES.get(r.quantity, '')}", html.escape(r.best_settings),
             _num(r.cost_of_1e_6, "{:.3g} s/s") if not math.isnan(r.cost_of_1e_6) else "not reached",
             r.verdicts] for r in sm.itertuples()] if len(sm) else []
    doc.table(["case", "engine", "agrees", "best accuracy", "at", f"cost of {SUMMARY_TARGET:g}", "verdicts"], rows)
    doc.html += body.html
    doc.md += body.md
    page = (f"<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>dalembert report</title>"
            f"<style>{CSS}</style></head><body>{''.join(doc.html)}{SELF_CHECK}</body></html>")
    html_path, md_path = os.path.join(out_dir, "report.html"), os.path.join(out_dir, "report.md")
    csv_path = os.path.join(out_dir, "summary.csv")
    atomic_write(html_path, page)
    atomic_write(md_path, "\n".join(doc.md) + "\n")
    atomic_write(csv_path, sm.to_csv(index=False, float_format="%.17g") if len(sm) else "")
    return html_path, md_path, csv_path
