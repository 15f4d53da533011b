"""What the report's sections share: the data they are built from (``Report``), read once,
and the few ways every section names a case, a run or a drift."""

from __future__ import annotations

from dataclasses import dataclass

from dalembert.invariants import CONSERVED
from dalembert.reports.findings import settings_text
from dalembert.reports.formatting import params_text, value_text
from dalembert.reports.tables import Cell, escape_html

__all__ = ["Report", "run_link", "section_id", "title", "grid_row", "drift_unit", "declared", "drifts_of"]


@dataclass(frozen=True)
class Report:
    """Everything a section reads, read from the store once (its case records are cached by the
    store itself: ``Store.case``).

    Attributes
    ----------
    store : dalembert.store.Store — for case records, truths and trajectories
    records : list of RunRecord — every stored run, sorted by key
    manifest : dict — the store's manifest (machine, engines, command, times)
    found : list of reports.findings.CaseFindings — per case version, in page order
    titles : dict CaseFindings -> str — each case version's heading
    colours : dict engine -> colour — the same in every figure
    """

    store: object
    records: list
    manifest: dict
    found: list
    titles: dict
    colours: dict

    def case_of(self, record):
        """The stored ``CaseRecord`` of a run."""
        return self.store.case(record.case, record.case_version)


def run_link(r, text=None, wrap=False):
    """A cell naming a run, linked to its row in its case's every-run table."""
    text = text if text is not None else settings_text(r)
    return Cell(text, html=f'<a href="#run-{escape_html(r.key)}">{escape_html(text)}</a>', wrap=wrap)


def section_id(f):
    """The HTML id of a case version's section."""
    return f"case-{f.case.name}-{f.case.version}"


def title(f, several_versions):
    """A case's name, with its parameters and version when the store holds more than one of it."""
    if not several_versions:
        return f.case.name
    return f"{f.case.name} ({params_text(f.runs[0].params) or 'defaults'}; {f.case.version})"


def grid_row(r):
    """A run's row in a per-setting grid: engine, integrator and options."""
    return " ".join(x for x in (r.engine, r.integrator, r.options_label) if x)


def declared(case, name):
    """The case's declared invariant ``name`` (an ``InvariantLabel``), or None for a built-in one."""
    return next((inv for inv in case.invariants if inv.name == name), None)


def drift_unit(name, case=None):
    """The unit of a stored drift: a built-in one's ``invariants.CONSERVED`` label; a declared one is
    relative to its scale (in its unit)."""
    inv = declared(case, name) if case is not None else None
    if inv is not None:
        return f"relative to {value_text(inv.scale, inv.unit)}"
    # a built-in one's label says it (``invariants.Conserved``); a name neither declares is read as the
    # store wrote it before the labels: absolute when zero, else relative
    return CONSERVED[name].drift_unit if name in CONSERVED else "absolute when zero, else relative"


def drifts_of(case):
    """The names of every drift a run of ``case`` stores: its built-in conserved quantities, then the
    ones it declares (``case.invariants``; their series are code, so only their drifts are in the store)."""
    return list(case.conserved) + [inv.name for inv in case.invariants if inv.name not in case.conserved]
