"""The report: a self-contained ``report.html``, ``report.md`` with its figures
beside it, and ``summary.csv`` — built from a results store only: runs as
stored records (their verdicts judged when they ran), each case as its stored
record (scene, tolerances, floor), truths and trajectories from the store. It
never rebuilds a case from code and never runs an engine or an integrator.

It opens with what was found (``sections.findings``): per case and engine, the
cheapest run reaching each target accuracy, the Pareto fronts, the hazards naming
their runs. Each case's section then shows what accuracy costs (work-precision
small multiples), stability (drift magnitude with the stored verdicts), the runs
that matter against time, a contact case's figures against its closed form, and every run in a sortable table.

This module only orders the sections (``reports/sections/``, one module each) and
hands them to the page writer (``reports/page.py``).
"""

from __future__ import annotations

import gc
import numbers
import os

import pandas as pd

from dalembert.reports import figures
from dalembert.reports.drawn import DETAILED_VERSIONS
from dalembert.reports.findings import find
from dalembert.reports.page import Part, write_page
from dalembert.reports.sections.against_time import against_time
from dalembert.reports.sections.case import case_header
from dalembert.reports.sections.common import Report, section_id, title
from dalembert.reports.sections.contact import contact
from dalembert.reports.sections.engines import beyond_the_scene, engines_simulated
from dalembert.reports.sections.file_models import file_models
from dalembert.reports.sections.findings import findings
from dalembert.reports.sections.hazards import hazards
from dalembert.reports.sections.header import header, page_title
from dalembert.reports.sections.loops import loops
from dalembert.reports.sections.maps import maps
from dalembert.reports.sections.order import observed_order
from dalembert.reports.sections.parity import parity
from dalembert.reports.sections.recommend import what_to_use
from dalembert.reports.sections.runs import every_run
from dalembert.reports.sections.scaling import scaling
from dalembert.reports.sections.stability import stability
from dalembert.reports.sections.versions import versions
from dalembert.reports.sections.work_precision import work_precision
from dalembert.store import atomic_write

__all__ = ["build_report", "DETAILED_VERSIONS", "YOUNG_COLLECTION", "in_page_order"]

# New objects between two collections of the youngest generation while a report is built (Python's default: 700):
# the build's objects are few and short-lived beside the records it holds, and a pass per 700 of them made a 1e5-run
# build's aggregation 1.8x slower than with no collector; at 10,000 it is within 7 % of none (``find``, measured).
YOUNG_COLLECTION = 10_000


def _value_key(v):
    """Sorts a parameter's values: numbers by value, before anything else (by its text)."""
    if isinstance(v, numbers.Real) and not isinstance(v, bool):
        return (0, float(v), "")
    return (1, 0.0, str(v))


def in_page_order(found):
    """Case findings by case name, then a case's versions by their parameters' values (a sweep reads
    in the order it was swept: spin 1, 2, 10 — not by the versions' content hashes)."""
    def key(f):
        params = f.runs[0].params
        return (f.case.name, tuple((k, _value_key(params[k])) for k in sorted(params)), f.case.version)

    return sorted(found, key=key)


def _case_sections(rep, f, names, mapped):
    """The sections of case version ``f`` (a list of ``Part``): all of them, or, for a case mapped or
    swept over many versions, one note under the case's name for its first version and none for the rest."""
    count = names.count(f.case.name)
    if f.case.name in mapped or count > DETAILED_VERSIONS:
        if f is not next(g for g in rep.found if g.case.name == f.case.name):
            return []
        part = Part()
        part.heading(f.case.name, 2, anchor=section_id(f))
        part.para(f"{count} version(s) of {f.case.name}: "
                  + ("its stability map" if f.case.name in mapped else "a sweep: its rows in the summary")
                  + " above stand(s) for them; every run is in the store (dalembert export --all).")
        return [part]
    name = f"{f.case.name}-{f.case.version}" if count > 1 else f.case.name
    # the case says what it is; its evidence is folded, one line each (the page stays a few screens long), and
    # in Markdown moved to report_details.md, a link each in report.md
    return [case_header(rep, f)] + [part.folded(summary, details=True) for part, summary in (
        (work_precision(rep, f, name), "What accuracy costs: the work-precision figure and each line's best"),
        (stability(rep, f, name), "Stability: the drift figure and the stored verdicts"),
        (against_time(rep, f, name), "Against time: the runs that matter"),
        (contact(rep, f, name), "Against the closed form: the contact figures and events"),
        (every_run(rep, f), f"Every run ({len(f.runs)}): the table"),
        (engines_simulated(rep, f), "What each engine simulated: raw audits and models"))]


def build_report(store, out_dir=None):
    """Write ``report.html``, ``report.md`` (+ ``report_files/``) and ``summary.csv``; returns their paths."""
    out_dir = out_dir or store.path
    # Python's cyclic garbage collector, tuned for the records (a dozen objects each, 1e5-1e6 runs, no cycles among
    # them, kept to the end): paused while they are read, then kept out of its passes (``gc.freeze``), its youngest
    # generation collected every YOUNG_COLLECTION new objects; all as it was after. Each pass otherwise revisits what
    # the aggregation holds, again and again: measured on a 1e5-run map store, the read 2.7 -> 1.9 s, ``find``
    # 2.4 -> 1.4 s (1.3 s with no collector at all).
    enabled, thresholds = gc.isenabled(), gc.get_threshold()
    gc.disable()
    try:
        records = store.table_records()
        gc.freeze()
        gc.set_threshold(YOUNG_COLLECTION, *thresholds[1:])
        if enabled:
            gc.enable()
        return _build(store, records, out_dir)
    finally:
        gc.set_threshold(*thresholds)
        gc.unfreeze()
        if enabled:
            gc.enable()


def _build(store, records, out_dir):
    found = in_page_order(find(store, records))
    names = [f.case.name for f in found]
    rep = Report(store=store, records=records, manifest=store.manifest(), found=found,
                 titles={f: title(f, names.count(f.case.name) > 1) for f in found},
                 colours=figures.engine_colours({r.engine for r in records}))
    summary, summary_rows = findings(rep)
    mapped_part, mapped = maps(rep)
    # the answers first (what to use, the observed order), then what was run and the evidence
    answers = [(what_to_use(rep), "what-to-use", "what to use"),
               (observed_order(rep), "observed-order", "observed order")]
    parts = [page_title(rep)] + [p for p, _, _ in answers]
    parts += [header(rep, [(a, t) for p, a, t in answers if p]),
              summary.folded("The Pareto fronts, the summary table and each case's findings", keep=1),
              hazards(rep), beyond_the_scene(rep), mapped_part, loops(rep).folded("Per case and engine line", keep=2),
              scaling(rep), file_models(rep), parity(rep), versions(rep)]
    for f in found:
        parts += _case_sections(rep, f, names, mapped)
    html_path, md_path = write_page([p for p in parts if p], out_dir)
    csv_path = os.path.join(out_dir, "summary.csv")
    sm = pd.DataFrame(summary_rows)
    atomic_write(csv_path, sm.to_csv(index=False, float_format="%.17g") if len(sm) else "")
    return html_path, md_path, csv_path
