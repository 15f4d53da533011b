"""What the report's sections share: the data they are built from (``Report``), read once,
and the few ways every section names a case, a run, a drift or a metric."""

from __future__ import annotations

from dataclasses import dataclass

from dalembert.invariants import CONSERVED
from dalembert.reports.findings import settings_text
from dalembert.reports.formatting import params_text, value_text
from dalembert.reports.tables import Cell, escape_html

__all__ = ["Report", "run_link", "section_id", "title", "grid_row", "drift_unit", "declared", "drifts_of",
           "is_metric", "stored_label", "shown_value", "has_contact"]


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
    return " ".join(x for x in (r.engine, r.settings.integrator, r.options_text) if x)


def declared(case, name):
    """The case's declared invariant ``name`` (an ``InvariantLabel``), or None for a built-in one."""
    return next((inv for inv in case.invariants if inv.name == name), None)


def is_metric(case, name):
    """Whether the case's stored figure ``name`` is a metric (``dalembert.metrics.Metric``: the figure itself, in
    its unit, over its scale), not a conserved quantity's drift."""
    inv = declared(case, name) if case is not None else None
    return inv is not None and inv.kind == "metric"


def stored_label(name, case=None):
    """How a table or an axis names the stored figure ``name``: a metric by its name and unit ("creep (m/s)"), a
    drift as "name drift (its unit)"."""
    if is_metric(case, name):
        return f"{name} ({declared(case, name).unit})"
    return f"{name} drift ({drift_unit(name, case)})"


def shown_value(r, name, case=None):
    """The figure a report shows for run ``r``'s stored ``drifts[name]``: a metric in its unit (the stored value is
    over its scale), a drift as stored; NaN when the run stored none."""
    value = r.drifts.get(name, float("nan"))
    return value * declared(case, name).scale if is_metric(case, name) else value


def has_contact(case):
    """Whether the case's scene names contact pairs (``Scene.contacts``)."""
    return bool(getattr(case.scene, "contacts", ()))


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
