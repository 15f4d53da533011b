"""The report: a self-contained ``report.html``, ``report.md`` with its figures
beside it, and ``summary.csv`` — built from a results store only (it never runs
an engine: truths and trajectories are read from the store; cases are rebuilt
from their names and parameters only to know masses and tolerances).
"""

from __future__ import annotations

import html
import json
import math
import os

import numpy as np
import pandas as pd

from dalembert import invariants
from dalembert.case import make_case
from dalembert.errors import error_series
from dalembert.stability import verdict
from dalembert.store import atomic_write
from dalembert.reports import figures
from dalembert.reports.work_precision import TARGETS, cost_to_reach, headline_error, series

__all__ = ["build_report"]

QUANTITY_OF = {"err_joint_max": "joint", "err_orientation_max": "orientation", "err_position_max": "position"}
UNIT_OF = {"joint": "rad", "orientation": "rad", "position": "m"}
SUMMARY_TARGET = 1e-6  # the accuracy whose cost the summary quotes


def _num(x, fmt="{:.2e}"):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    return fmt.format(x)


def _params(text):
    return {k: tuple(v) if isinstance(v, list) else v for k, v in json.loads(text or "{}").items()}


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
    rl = f"{r['engine']} {r['integrator']}" + ("" if r.get("options") in ("{}", None) else f" {r['options']}")
    cl = f"dt={r['dt']:g}" if isinstance(r.get("dt"), float) and not math.isnan(r["dt"]) else f"tol={r['rtol']:g}"
    return rl, cl


def _drift_rates(doc, sub):
    """Energy drift per simulated second, engine + integrator x step: a steady slope is secular
    drift (most integrators), a slope near zero bounded oscillation (symplectic, geometric ones)."""
    cols = [c for c in ("drift_rate_energy", "drift_rate_energy_balance") if c in sub and sub[c].notna().any()]
    if not cols:
        return
    col = cols[0]
    ok = sub[(sub["status"] == "ok") & sub[col].notna()]
    if ok.empty:
        return
    rates, row_labels, col_labels = {}, set(), set()
    for _, r in ok.iterrows():
        rl, cl = _grid_labels(r)
        rates[(rl, cl)] = r[col]
        row_labels.add(rl)
        col_labels.add(cl)
    col_labels = sorted(col_labels, key=lambda c: (c.startswith("tol"), -float(c.split("=")[1])))
    what = "energy" if col == "drift_rate_energy" else "energy balance (E - work of the loads)"
    doc.heading("Energy drift rate", 3)
    doc.para(html.escape(f"Least-squares slope of the relative change of the {what}, per simulated second "
                         f"(negative: lost). Bounded oscillation shows as a slope near zero, secular drift as a "
                         f"steady one; successful runs only."))
    doc.table(["engine + integrator"] + col_labels,
              [[html.escape(rl)] + [_num(rates.get((rl, c)), "{:+.2e} /s") if (rl, c) in rates else "—"
                                    for c in col_labels] for rl in sorted(row_labels)])


def _case_section(doc, store, case_name, sub, summary_rows):
    version = sub["case_version"].iloc[0]
    case = make_case(case_name, **_params(sub["params"].iloc[0]))
    truth = store.truth(case_name, version)
    # each run's verdict and its reason, once (the grid, the run table and the summary use them)
    judged = [verdict(r, case.tolerances) for r in sub.to_dict("records")]
    sub = sub.assign(verdict=[v for v, _ in judged], verdict_why=[why for _, why in judged])
    doc.heading(f"{case_name}", 2, anchor=f"case-{case_name}")
    doc.para(html.escape(f"version {version}; parameters {json.loads(sub['params'].iloc[0]) or 'defaults'}; "
                         f"horizon {case.t_final:g} s; effects {', '.join(sorted(case.scene.effects))}."))
    doc.table(["tolerance", "value", "reason"], [[k, f"{t.value:g}", html.escape(t.reason)]
                                                  for k, t in case.tolerances.items()])
    # --- work-precision
    lines, col = series(sub)
    quantity = QUANTITY_OF.get(col, "")
    if lines:
        doc.heading("What accuracy costs", 3)
        floor = case.floor().get(quantity)
        doc.figure(figures.work_precision(lines, f"max {quantity} error ({UNIT_OF.get(quantity, '')})",
                                          floor=floor, title=f"{case_name}: work-precision"),
                   f"{case_name}: max {quantity} error against stepping time per simulated second", f"{case_name}-wp")
        rows = []
        for label, pts in sorted(lines.items()):
            costs = [cost_to_reach(pts, t) for t in TARGETS]
            rows.append([html.escape(label), _num(min(p[1] for p in pts))]
                        + [_num(c, "{:.3g} s/s") if c is not None else "not reached" for c in costs])
        doc.table(["engine + integrator", "best error"] + [f"cost to reach {t:g}" for t in TARGETS], rows)
    # --- stability grid
    cells, row_labels, col_labels, reasons = {}, [], [], []
    for _, r in sub.iterrows():
        rl, cl = _grid_labels(r)
        v, why = r["verdict"], r["verdict_why"]
        cells[(rl, cl)] = v
        row_labels.append(rl)
        col_labels.append(cl)
        if why and v != "stable":
            reasons.append([html.escape(rl), cl, v, html.escape(why)])
    row_labels, col_labels = sorted(set(row_labels)), sorted(set(col_labels), key=lambda c: -float(c.split("=")[1]))
    doc.heading("Stability", 3)
    doc.figure(figures.stability_grid(row_labels, col_labels, cells, title=f"{case_name}: verdicts"),
               f"{case_name}: stability verdict per engine, integrator and step", f"{case_name}-stability")
    if reasons:
        doc.details(f"why {len(reasons)} run(s) are not stable",
                    "\n".join(f"{r[0]} {r[1]}: {r[2]} — {html.unescape(r[3])}" for r in reasons))
    _drift_rates(doc, sub)
    # --- every run
    doc.heading("Every run", 3)
    errs = [c for c in ("err_position_max", "err_orientation_max", "err_velocity_max", "err_angular_velocity_max",
                        "err_joint_max", "err_reaction_force_max") if c in sub and sub[c].notna().any()]
    drifts = sorted(c for c in sub.columns if c.startswith("drift_") and sub[c].notna().any())
    table_rows, classes = [], []
    for _, r in sub.sort_values(["engine", "integrator", "dt", "rtol"], na_position="last").iterrows():
        v = r["verdict"]
        status = r["status"] if r["status"] == "ok" else f"{r['status']}: {html.escape(str(r['message']))}"
        ok = r.get("within_tolerance")
        okcell = "—" if r["status"] != "ok" else ("yes" if ok is True else f"<b>no</b>: {r.get('beyond_tolerance')}")
        table_rows.append([r["engine"], html.escape(r["settings"]), status, _num(r.get("wall_s_median"))]
                          + [_num(r.get(c)) for c in errs + drifts] + [okcell, v])
        classes.append(v)
    doc.table(["engine", "settings", "status", "wall s"] + [c[4:-4] for c in errs] + [c[6:] + " drift" for c in drifts]
              + ["within tol", "verdict"], table_rows, classes)
    # --- trajectories of each engine's most accurate run
    best = {}
    if col:
        for _, r in sub[sub["status"] == "ok"].iterrows():
            if r.get("trajectory") and (r["engine"] not in best or r[col] < best[r["engine"]][col]):
                best[r["engine"]] = r
    if truth is not None and best:
        doc.heading("Trajectories (each engine's most accurate run)", 3)
        t = truth.t
        trajs = {e: store.trajectory(r["key"]) for e, r in best.items()}
        label = {e: f"{e} {r['settings']}" for e, r in best.items()}
        if quantity == "joint":
            jname = next(iter(truth.joints))
            doc.figure(figures.time_series(t, {label[e]: tr.joints[jname].q[:, 0] for e, tr in trajs.items()},
                                           "joint angle (rad)", truth=truth.joints[jname].q[:, 0],
                                           title=f"{case_name}: joint angle"),
                       f"{case_name}: joint angle against the truth", f"{case_name}-angle")
        else:
            bname = next(iter(truth.bodies))
            doc.figure(figures.time_series(t, {label[e]: tr.bodies[bname].angular_velocity_body
                                               for e, tr in trajs.items()}, "w_B components (rad/s)",
                                           truth=truth.bodies[bname].angular_velocity_body,
                                           title=f"{case_name}: body angular velocity"),
                       f"{case_name}: body-frame angular velocity against the truth", f"{case_name}-omega")
        doc.figure(figures.time_series(t, {label[e]: error_series(tr, truth)[quantity] for e, tr in trajs.items()},
                                       f"{quantity} error ({UNIT_OF[quantity]})", log=True,
                                       title=f"{case_name}: error against time"),
                   f"{case_name}: {quantity} error against time", f"{case_name}-error")
        if case.conserved:
            name = case.conserved[0]
            doc.figure(figures.time_series(t, {label[e]: invariants.drift_series(name, case.scene, tr)
                                               for e, tr in trajs.items()}, f"{name} drift", log=True,
                                           title=f"{case_name}: {name} drift ({invariants.CONSERVED[name]})"),
                       f"{case_name}: {name} drift against time", f"{case_name}-drift")
    # --- what each engine computed
    doc.heading("What each engine simulated", 3)
    for engine, r in sorted(best.items()) or [(e, sub[sub.engine == e].iloc[0]) for e in sorted(sub.engine.unique())]:
        audit = r.get("audit")
        if isinstance(audit, str):
            doc.details(f"{engine}: effects audit ({r['settings']})", json.dumps(json.loads(audit), indent=2))
        if isinstance(r.get("model"), str):
            doc.details(f"{engine}: generated model", r["model"])
    # --- summary rows
    for engine in sorted(sub["engine"].unique()):
        es = sub[sub["engine"] == engine]
        ok = es[es["status"] == "ok"]
        passing = bool(ok["within_tolerance"].fillna(False).astype(bool).any()) if "within_tolerance" in ok else False
        best_err = float(ok[col].min()) if col and len(ok) else float("nan")
        best_set = ok.loc[ok[col].idxmin(), "settings"] if col and len(ok) and ok[col].notna().any() else ""
        costs = [cost_to_reach(pts, SUMMARY_TARGET) for label, pts in lines.items() if label.startswith(engine + " ")]
        costs = [c for c in costs if c is not None]
        counts = es["verdict"].value_counts().to_dict()
        summary_rows.append(dict(case=case_name, engine=engine, agrees=passing, best_error=best_err,
                                 best_settings=best_set, quantity=quantity,
                                 cost_of_1e_6=min(costs) if costs else float("nan"),
                                 verdicts=", ".join(f"{n} {v}" for v, n in sorted(counts.items())),
                                 runs=len(es)))


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
    df = store.table()
    manifest = store.manifest()
    doc = _Doc(files_dir, "report_files")
    summary_rows = []
    cases = sorted(df["case"].unique()) if not df.empty else []
    body = _Doc(files_dir, "report_files")
    for case_name in cases:
        _case_section(body, store, case_name, df[df["case"] == case_name], summary_rows)
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
             f"{_num(r.best_error)} {UNIT_OF.get(r.quantity, '')}", html.escape(r.best_settings),
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
