"""The runs whose trajectories the report draws: what a store that keeps ``drawn`` keeps.

The report reads a run's trajectory (``Store.trajectory``) for, and only for:

- **against time** (``sections.against_time``): each engine's most accurate run per step or tolerance
  (``time_series.representatives``) and every run that diverged (``time_series.diverged``), of each case
  version whose sections are shown in full;
- **the contact figures** (``sections.contact``): every finished run of a shown contact case that has a figure
  (``sections.contact.FIGURES``);
- **the verdict words** (``trend.trend_words``, in the stability and run tables): each run judged ``drifts``
  with a conserved quantity beyond its bound, of a shown case version;
- **the loop-closure hazard** (``hazards._closure``, every case version): each finished run of a case with
  loops, not diverged, with a loop residual beyond its bound;
- **parity** (``parity.pairs``): each port's run and its original engine's.

A case version's sections are shown in full unless its case is mapped (``maps.stability_maps``) or swept over
more than ``DETAILED_VERSIONS`` versions (``render._case_sections``). Every choice above is the report's own
function or predicate, so ``drawn_keys`` follows it; ``tests/test_trajectory_store.py`` builds the report of
stores holding every kind and checks that every trajectory it reads is here.

Which runs are drawn is known when the matrix ends; which can never be is known as each run ends
(``may_be_drawn``): a run of a case swept over more than ``DETAILED_VERSIONS`` versions (a map's probes), of
an engine without a port or an original, whose loop closure (if any) stays within its bounds. A matrix that
keeps ``drawn`` does not write those at all, so a large map's disk never holds its probes' trajectories.
"""

from __future__ import annotations

from dalembert.case import LOOP_RESIDUALS
from dalembert.reports import time_series
from dalembert.reports.maps import stability_maps
from dalembert.reports.parity import PORTS, pairs
from dalembert.reports.trend import beyond_conserved
from dalembert.reports.work_precision import headline_quantity

__all__ = ["DETAILED_VERSIONS", "drawn_keys", "may_be_drawn"]

# A case swept over more versions than this shows its summary rows, not a full section per version
# (ten spins would otherwise be ten copies of every figure); a case with a stability map shows the
# map instead of its versions' sections, however few (their probes would fill the grids).
DETAILED_VERSIONS = 4
# (Here, not in ``render``, which imports matplotlib: a pool's worker asks ``may_be_drawn`` after every run.)


def _closure_read(r, case):
    """Whether the loop-closure hazard reads finished run ``r`` of ``case`` (``hazards._closure``)."""
    return bool(case.scene.loops) and r.ok and r.judgement.verdict != "diverged" and any(
        n in case.tolerances and r.drifts.get(n, 0.0) > case.tolerances[n].value for n in LOOP_RESIDUALS.values())


def may_be_drawn(specs, case_of):
    """``test(record) -> bool``, False for a finished run whose trajectory the report never draws, whatever the
    matrix's other runs (the module docstring).

    Parameters
    ----------
    specs : list of dict
        The manifest's run specs (``case`` and ``case_version`` read): the versions each case is run at.
    case_of : callable(name, version) -> CaseRecord
        The store's case records (``Store.case``).
    """
    versions = {}
    for s in specs:
        versions.setdefault(s["case"], set()).add(s["case_version"])
    ports = set(PORTS) | set(PORTS.values())

    def test(r):
        return (r.engine in ports or len(versions.get(r.case, ())) <= DETAILED_VERSIONS
                or _closure_read(r, case_of(r.case, r.case_version)))
    return test


def drawn_keys(store, records=None):
    """The keys of the runs of ``store`` (``records``: its records, if read already) whose trajectories its
    report reads (the module docstring). Reads rows and case records only, never a trajectory."""
    from dalembert.reports.sections.common import has_contact
    from dalembert.reports.sections.contact import FIGURES

    records = store.table_records() if records is None else records
    groups = {}
    for r in records:
        groups.setdefault((r.case, r.case_version), []).append(r)
    mapped = {m.case for m in stability_maps(records, lambda name: {})}
    versions = {}
    for name, _ in groups:
        versions[name] = versions.get(name, 0) + 1
    keys = {k for r, o in pairs(records) for k in (r.key, o.key)}
    for (name, version), runs in groups.items():
        case = store.case(name, version)
        kept = [r for r in runs if r.trajectory]
        keys |= {r.key for r in kept if _closure_read(r, case)}  # the loop-closure hazard
        if name in mapped or versions[name] > DETAILED_VERSIONS:
            continue  # its sections are one note: nothing drawn
        quantity = headline_quantity(runs)
        if quantity is not None:
            keys |= {r.key for rs in time_series.representatives(kept, quantity).values() for r in rs}
        keys |= {r.key for rs in time_series.diverged(kept).values() for r in rs}
        if has_contact(case) and FIGURES.get(name) is not None:
            keys |= {r.key for r in kept if r.ok}
        keys |= {r.key for r in kept if r.judgement.verdict == "drifts" and beyond_conserved(r, case)}
    return keys
