"""What a store shows, computed once from its records and case records: the findings
the report opens with.

Per case, for each engine: the cheapest run that reaches each of
``ACCURACY_TARGETS`` in the case's headline error (or "never", with the best it
reached), and the hazards (``dalembert.reports.hazards``: what each kind means and when it is raised).

Every sentence names the runs it is about (engine and settings) and quotes
stored numbers only; verdicts are the stored ones, never judged again here.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from dalembert.errors import QUANTITIES
from dalembert.refusal import manifest_refusals
from dalembert.reports.causes import case_orders, disagreement_causes
from dalembert.reports.formatting import value_text
from dalembert.reports.hazards import (CLOSURE_GROWTH, CREEP_METRIC, DISAGREEMENT_FACTOR, ENERGY_HAZARD, ENERGY_LIKE,
                                       HAZARDS, NAMED, Hazard, case_hazards, list_text,
                                       listed)
from dalembert.reports.names import run_name, settings_text, speed_text
from dalembert.reports.work_precision import (cheapest_reaching, headline_metric, headline_quantity, metric_label,
                                              pareto_front, points)

# (the hazards' and the names' spellings re-exported: what the report's sections import from here)
__all__ = ["ACCURACY_TARGETS", "ENERGY_HAZARD", "DISAGREEMENT_FACTOR", "CLOSURE_GROWTH", "HAZARDS", "CREEP_METRIC",
           "ENERGY_LIKE", "NAMED", "Reach", "EngineSummary", "Hazard", "CaseFindings", "find", "known_points", "run_name",
           "settings_text", "speed_text"]

# Three accuracies a user asks for, three decades apart: an engineering answer (1e-3),
# a careful simulation (1e-6), and near what double precision can resolve over a horizon (1e-9).
ACCURACY_TARGETS = (1e-3, 1e-6, 1e-9)
@dataclass(frozen=True)
class Reach:
    """The cheapest run of an engine whose headline error is at most ``target`` (``point`` None: never)."""

    target: float
    point: object  # work_precision.Point or None


@dataclass(frozen=True)
class EngineSummary:
    """One engine on one case."""

    engine: str
    runs: tuple  # every run of the engine on the case
    reaches: tuple  # Reach per ACCURACY_TARGETS
    best: object  # the Point of its most accurate finished run, or None
    front: tuple  # its Pareto front (Points by increasing cost)


@dataclass(frozen=True)
class CaseFindings:
    """Everything found about one case (one case version)."""

    case: object  # CaseRecord
    runs: tuple
    quantity: str | None  # the headline error
    engines: tuple  # EngineSummary per engine, by name
    hazards: tuple  # Hazard, in HAZARDS order
    sentences: tuple  # the case's findings in prose
    headline: object = None  # the case's headline metric (InvariantLabel) where it declares one: engines rank by it
    # the work-precision Point of every finished run of ``ranked`` (``work_precision.points``), in ``runs``' order: made
    # once, for the engines' summaries and for what else reads them (``known_points``, ``recommend``); None: made here
    points: tuple | None = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        if self.points is None:
            object.__setattr__(self, "points", tuple(points(self.runs, self.ranked, self.case)) if self.ranked else ())

    @property
    def unit(self):
        return QUANTITIES.get(self.quantity, "")

    @property
    def tolerance(self):
        """The case's tolerance on its headline error, or None."""
        tol = self.case.tolerances.get(self.quantity)
        return tol.value if tol else None

    @property
    def ranked(self):
        """What the engines are ranked by (``engines``' reaches, best and front): the headline metric's name, else
        the headline error ``quantity``."""
        return self.headline.name if self.headline is not None else self.quantity

    @property
    def ranked_unit(self):
        return self.headline.unit if self.headline is not None else self.unit

    @property
    def ranked_tolerance(self):
        """The case's bound on ``ranked``, in its unit (a metric's: its tolerance times its scale), or None."""
        if self.headline is None:
            return self.tolerance
        tol = self.case.tolerances.get(self.headline.name)
        return tol.value * self.headline.scale if tol else None

    def hazards_of(self, engine, kind=None):
        return [h for h in self.hazards if h.engine == engine and (kind is None or h.kind == kind)]


def find(store, records=None):
    """The ``CaseFindings`` of every case version in ``store`` (``records``: its records, if read
    already), by case name."""
    groups, refused = {}, {}
    for r in records if records is not None else store.records():
        groups.setdefault((r.case, r.case_version), []).append(r)
    for f in manifest_refusals(store.manifest()):  # each engine's refusal of a case, listed once (no run made)
        refused.setdefault((f.case, f.case_version), []).append(f)
    return [_case_findings(store.case(name, version), runs, store, refused.get((name, version), ()))
            for (name, version), runs in sorted(groups.items())]


def _case_findings(case, runs, store=None, refused=()):
    quantity = headline_quantity(runs)
    headline = headline_metric(case, runs)
    ranked = headline.name if headline is not None else quantity
    made = tuple(points(runs, ranked, case)) if ranked else ()
    by_engine = {}
    for p in made:  # (each engine's points in the runs' order: ``points`` of its runs alone)
        by_engine.setdefault(p.run.engine, []).append(p)
    engines = []
    for engine in sorted({r.engine for r in runs}):
        mine = tuple(r for r in runs if r.engine == engine)
        pts = by_engine.get(engine, [])
        best = min(pts, key=lambda p: p.error) if pts else None
        engines.append(EngineSummary(engine, mine, tuple(Reach(t, cheapest_reaching(pts, t)) for t in ACCURACY_TARGETS),
                                     best, tuple(pareto_front(pts))))
    hazards = case_hazards(engines, runs, case, quantity, store, refused)
    if any(h.kind == "disagreement" for h in hazards):
        orders = case_orders(case, runs, quantity)
        hazards = [replace(h, causes=tuple(disagreement_causes(h.runs, case, runs, quantity, orders)))
                   if h.kind == "disagreement" else h for h in hazards]
    found = CaseFindings(case, tuple(runs), quantity, tuple(engines), tuple(hazards), (), headline, made)
    return replace(found, sentences=tuple(_sentences(found)))  # the prose reads the rest


def known_points(found):
    """``known(case name, version, quantity)`` for ``maps.stability_maps``: a case version's work-precision points of
    error ``quantity`` as its findings (``found``) made them, where it ranks by that error (no headline metric, none
    named like it), else None."""
    by_version = {(f.case.name, f.case.version): f for f in found}

    def known(name, version, quantity):
        f = by_version.get((name, version))
        if f is None or f.headline is not None or f.quantity != quantity or metric_label(quantity, f.case) is not None:
            return None
        return f.points

    return known


# ---------------------------------------------------------------------------------------------- prose
def _sentences(f):
    if f.ranked is None:
        return ["No run measured an error against the truth."]
    unit = f.ranked_unit
    tol = f.ranked_tolerance
    if f.headline is not None:  # the case's own headline figure
        out = [f"Headline figure: {f.headline.name} ({unit}), {f.headline.description}"
               + (f"; the case's bound is {tol:g} {unit}." if tol else ".")]
    else:
        out = [f"Headline error: {f.quantity} ({unit}), the max over the {value_text(f.case.t_final, 's')} horizon"
               + (f"; the case's tolerance is {tol:g} {unit}." if tol else ".")]
    ranked = sorted((e for e in f.engines if e.best), key=lambda e: e.best.error)
    if ranked:
        top = ranked[0]
        out.append(f"Most accurate: {top.engine}, {top.best.error:.2e} {unit} with {settings_text(top.best.run)}"
                   + (f"; least: {ranked[-1].engine}, best {ranked[-1].best.error:.2e} {unit}." if len(ranked) > 1
                      else "."))
    for i, target in enumerate(ACCURACY_TARGETS):
        reached = sorted((e for e in f.engines if e.reaches[i].point), key=lambda e: e.reaches[i].point.cost)
        never = [e.engine for e in f.engines if e.best and not e.reaches[i].point]
        if not reached:
            out.append(f"No engine reaches {target:g} {unit}.")
            continue
        first = reached[0].reaches[i].point
        text = f"Cheapest to {target:g} {unit}: {reached[0].engine} with {settings_text(first.run)} ({first.cost:.2g} s/s)"
        if len(reached) > 1:
            second = reached[1].reaches[i].point
            text += f", {second.cost / first.cost:.2g}x cheaper than {reached[1].engine} ({second.cost:.2g} s/s)"
        text += f"; never: {list_text(never)}." if never else "."
        out.append(text)
    counts = {}
    for h in f.hazards:
        if listed(h):
            counts[h.kind] = counts.get(h.kind, 0) + (len(h.runs) if h.kind != "disagreement" else 1)
    words = {"diverged": "runs diverged", "failed": "runs stopped early",
             "energy": f"runs change the energy by more than {100 * ENERGY_HAZARD:g} %",
             "creep": "runs creep where the closed form sticks",
             "closure": "runs still opening their loops", "reactions": "runs with the motion right and the reactions wrong",
             "tolerance": "finished runs leave the tolerance", "inert": "runs whose tolerance changed nothing",
             "disagreement": "settings where engines disagree for a named cause"}
    if counts.get("disagreement") == 1:
        words["disagreement"] = "setting where engines disagree for a named cause"
    if counts:
        out.append("Hazards: " + list_text(f"{n} {words[k]}" for k, n in counts.items()) + " (listed below).")
    else:
        out.append("No run diverged, stopped early or drifted in energy beyond "
                   f"{100 * ENERGY_HAZARD:g} %, and no disagreement has a named cause.")
    return out
