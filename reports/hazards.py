"""The hazards a user must know before trusting a setting, found per engine on one case from its stored
records (``dalembert.reports.findings`` gathers them with the cheapest runs):

* ``diverged`` — runs that blew up, and when (their stored verdict);
* ``failed`` — runs that stopped with an error or at the time limit;
* ``energy`` — finished runs that lost or gained more than ``ENERGY_HAZARD`` of
  their energy over the horizon;
* ``creep`` — finished runs of a case that measures ``creep`` (a ``dalembert.metrics.Metric``: the slip speed
  while the closed form sticks) whose creep is beyond the case's bound: the body slides where it must stick
  (soft contacts, a pyramidal friction cone), named with its speed;
* ``closure`` — finished runs of a closed-loop case whose loop-closure residual leaves the case's
  bound and is still growing at the end: its largest value over the horizon's last quarter is more
  than ``CLOSURE_GROWTH`` times that over its first half (read from the stored trajectories); a
  residual that stays bounded (soft or stabilised constraints) or spikes at a singular position
  and recovers is a ``drifts`` verdict only;
* ``reactions`` — finished runs whose motion is within the case's tolerance (the headline error)
  but whose joint or loop reactions are not (compared modulo the truth's self-stresses,
  ``dalembert.errors``): the loads a user would read off a trustworthy-looking run are wrong;
* ``tolerance`` — runs that stay finite but leave the case's tolerance (and of
  those, the ones whose conserved quantities hold: only the truth shows them);
* ``inert`` — runs of one engine, integrator, options and step at different tolerances
  whose stored errors are all the same, bit for bit (every quantity, its largest and its
  final value): the tolerance changed nothing (e.g. the sample interval capped every step,
  and the error at that step already met each tolerance; or the method is exact on the
  motion, its steps growing at the controller's largest rate whatever the tolerance);
* ``disagreement`` — engines that, with the same integrator and the same step
  or tolerance, differ by more than ``DISAGREEMENT_FACTOR`` in the headline error
  beyond the case's tolerance, or where one finishes within it and another does not.
  Only comparable runs are compared: a run whose tolerance changed nothing (``inert``)
  is left out (its error says nothing of its tolerance), and so is any run
  whose settings do not mean what the others' do (``_comparable``);
* ``unsupported`` — integrators an engine cannot run on the case, with its reason: from the matrix's
  manifest (``dalembert.refusal``: each refusal listed once, no run made) and from the runs stored
  ``unsupported`` (a refusal only the built model shows, and every refusal of a store written before).

Every sentence names the runs it is about (engine and settings) and quotes
stored numbers only; verdicts are the stored ones, never judged again here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from itertools import islice

import numpy as np

from dalembert.case import LOOP_RESIDUALS
from dalembert.errors import QUANTITIES
from dalembert.invariants import loop_residual
from dalembert.record import BAD_STATUSES
from dalembert.refusal import settings_text as refused_text
from dalembert.reports.formatting import value_text
from dalembert.reports.names import settings_text, speed_text
from dalembert.reports.work_precision import sweep_key

__all__ = ["ENERGY_HAZARD", "DISAGREEMENT_FACTOR", "CLOSURE_GROWTH", "HAZARDS", "LISTED", "listed", "ENERGY_LIKE", "CREEP_METRIC", "NAMED",
           "LISTED_RUNS", "Hazard", "case_hazards", "list_text"]

# Energy lost or gained over the horizon beyond which a simulation is visibly not the physics
# any more (a pendulum's amplitude, a top's spin, off by about the square root of it): 1%.
ENERGY_HAZARD = 0.01
# Two engines running the same integrator at the same step that differ in error by more than an
# order of magnitude are not computing the same method (or not the same model).
DISAGREEMENT_FACTOR = 10.0
# A loop-closure residual whose largest value over the horizon's last quarter exceeds that over its first
# half by more than this is still growing: an index-1 drift grows like t^2 (x4 from the half to the end),
# a linear one x2; a bounded residual (soft constraints, Baumgarte, projection) x1 once it has peaked, and a
# spike at a singular position mid-horizon falls outside both windows' comparison unless it stays. Measured
# on the four-bar (0.5 s, through its flat position at 0.26 s): MuJoCo rk4 at dt = 1e-2 x1.9 after a 7.5e-5 m
# spike, Drake discrete x2.2, MuJoCo discrete x3.0 (its soft residual follows the growing constraint load).
CLOSURE_GROWTH = 3.0
# Hazard kinds, in the order the report lists them.
HAZARDS = ("diverged", "failed", "energy", "creep", "closure", "reactions", "tolerance", "inert", "disagreement",
           "unsupported")
# The kinds that mean something on their own, listed where the report lists hazards (a disagreement only with a
# cause the store names, ``Hazard.causes``); the rest (beyond the tolerance: the tables' business) are folded.
LISTED = ("diverged", "failed", "energy", "creep", "closure", "reactions", "disagreement")
ENERGY_LIKE = ("energy", "energy_balance")
# The metric a contact case names its creep by (``cases/block_on_incline``): the slip speed, m/s, over a phase
# in which its closed form sticks.
CREEP_METRIC = "creep"
# A hazard of more runs than this lists the first ones (in sweep order) and counts the rest: a map of a million probes
# would otherwise list most of them (a 60 MB page at 1e6 rows, benchmarks/map.py), and the lines of the runs not
# listed are not made at all (a line for each of 1e5 runs was ~0.5 s of its report, profiled); the default
# matrix's hazards name far fewer (it runs 1,754), and every run is in the store (``dalembert export --all``).
LISTED_RUNS = 1000


@dataclass(frozen=True)
class Hazard:
    """A finding against one engine (``engine``) or between engines (``engine`` "").

    ``text`` is one sentence (naming the runs when they are few, else what they share and the
    worst); ``details`` one line per run it is about, naming it, for its first ``LISTED_RUNS`` runs (``runs``
    counts them all), or none where the hazard lists no runs. Plain text: the renderer escapes.
    """

    kind: str  # one of HAZARDS
    engine: str
    runs: tuple  # the runs it is about
    text: str
    details: tuple = ()
    causes: tuple = ()  # a disagreement's causes the store attributes (``reports.causes``), sentences


def case_hazards(engines, runs, case, quantity, store=None, refused=()):
    """Every hazard of one case version: per engine (``engines``: summaries with ``engine`` and ``runs``), then
    between engines over the comparable ``runs``, in ``HAZARDS`` order; ``refused``: the manifest's
    ``dalembert.refusal.Refusal``s of this case version (listed with the runs stored ``unsupported``, by engine)."""
    hazards = []
    for e in engines:
        # the engine's runs in sweep order, sorted once: the kinds that keep a subset of them in that order filter these
        # (a stable sort: a subset of the sorted runs is the sorted subset)
        swept = replace(e, runs=tuple(_by_sweep(e.runs)))
        hazards += (_diverged(swept, case) + _failed(swept) + _energy(swept, case) + _creep(e, case)
                    + _closure(e, case, store) + _reactions(swept, case, quantity) + _beyond(swept, case)
                    + _inert(e, quantity))
    inert = {r.key for h in hazards if h.kind == "inert" for r in h.runs}
    hazards += _disagreements([r for r in runs if r.key not in inert], quantity, case)
    unsupported = [h for e in engines for h in _unsupported(e)] + [
        Hazard("unsupported", r.engine, (), f"{r.engine} cannot run {r.what}: {r.reason}")
        for r in sorted(refused, key=lambda r: r.reason)]
    hazards += sorted(unsupported, key=lambda h: h.engine)
    hazards.sort(key=lambda h: HAZARDS.index(h.kind))
    return hazards


def listed(h):
    """Whether hazard ``h`` means something on its own (``LISTED``; a disagreement with a cause named)."""
    return h.kind in LISTED and (h.kind != "disagreement" or bool(h.causes))


def list_text(items):
    """'a', 'a and b', 'a, b and c'."""
    items = list(items)
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def _runs_word(n):
    return f"{n} run" + ("" if n == 1 else "s")


def _verb(n, one, many):
    return one if n == 1 else many


def _by_sweep(runs):
    """``runs`` sorted (stably) by integrator, options and ``sweep_key``: what ``sorted`` with that key gives, made
    by grouping the runs under their key, each key made once per distinct ``Settings`` (it is the settings'; runs
    share them), and sorting the distinct keys only (1e5 runs: 0.24 -> 0.08 s, measured)."""
    keys, groups = {}, {}
    for r in runs:
        key = keys.get(id(r.settings))
        if key is None:
            key = keys[id(r.settings)] = (r.settings.integrator, r.options_label, sweep_key(r))
        group = groups.get(key)
        if group is None:
            groups[key] = [r]
        else:
            group.append(r)
    return [r for key in sorted(groups) for r in groups[key]]


# A hazard sentence names its runs when they are at most this many; past it, what they share and
# the worst, and the list of every run beside it.
NAMED = 3


def _shared(runs):
    """What every one of ``runs`` has in common ("all rk44 with node=rxyz"), or ""."""
    if len(runs) < 2:
        return ""
    parts = [word + value for value, word in ((_the_one(r.settings.integrator for r in runs), ""),
                                              (_the_one_text(runs, lambda s: (s.dt, s.rtol), "sweep_label"), "at "),
                                              (_the_one_text(runs, lambda s: s.options, "options_text"), "with "))
             if value]
    return ("all " + " ".join(parts)) if parts else ""


def _the_one(values):
    """The value every one of ``values`` (an iterable) is, or None: read up to the first that differs."""
    values = iter(values)
    first = next(values, None)
    return first if all(v == first for v in values) else None


def _the_one_text(runs, raw, text):
    """The run property ``text`` (words made of the settings' ``raw(settings)``) every one of ``runs`` has, or None:
    the first run's where every run's ``raw`` is the same (compared as it is, not made into words run by run: a
    hazard's runs of a map, 1e4-1e5, mostly share their options and many their step); made for a run only where its
    ``raw`` differs from the first's (values that differ may read alike: ``option_text`` keeps 4 significant digits,
    ``:g`` 6)."""
    first_raw, first = raw(runs[0].settings), getattr(runs[0], text)
    for r in runs:
        if raw(r.settings) != first_raw and getattr(r, text) != first:
            return None
    return first


def _hazard(kind, e, runs, lead, line, worst=None, tail=""):
    """A hazard of ``runs`` of engine summary ``e``: ``lead`` (what happened), then the runs named by
    ``line(run)`` — every one when few, else what they share and the ``worst`` — then ``tail``."""
    runs = tuple(runs)
    if len(runs) <= NAMED:
        text = f"{e.engine}: {lead}: {list_text(map(line, runs))}."
    else:
        shared = _shared(runs)
        text = f"{e.engine}: {lead}" + (f", {shared}" if shared else "")
        text += f"; worst: {line(worst)}." if worst is not None else "."
    return Hazard(kind, e.engine, runs, text + (f" {tail}" if tail else ""), tuple(map(line, runs[:LISTED_RUNS])))


def _diverged(e, case):
    bad = [r for r in e.runs if r.judgement.verdict == "diverged"]  # (``e.runs`` in sweep order)
    if not bad:
        return []
    times = [r.t_diverged for r in bad if r.t_diverged is not None]

    def line(r):
        if r.t_diverged is not None:
            return f"{settings_text(r)} at t = {value_text(r.t_diverged, 's')}"
        return f"{settings_text(r)} ({r.judgement.reason or r.message})"

    when = (f" between t = {value_text(min(times), 's')} and {value_text(max(times), 's')}"
            if len(times) > 1 and len(bad) > NAMED else "")
    return [_hazard("diverged", e, bad,
                    f"{_runs_word(len(bad))} diverged{when} (horizon {value_text(case.t_final, 's')})",
                    line, min(bad, key=lambda r: r.t_diverged if r.t_diverged is not None else math.inf))]


def _failed(e):
    bad = [r for r in e.runs if r.status in BAD_STATUSES and r.judgement.verdict != "diverged"]  # (in sweep order)
    if not bad:
        return []

    def line(r):
        return f"{settings_text(r)} ({r.status}: {r.message.splitlines()[0] if r.message else 'no message'})"

    return [_hazard("failed", e, bad, f"{_runs_word(len(bad))} stopped early", line, bad[0])]


def _energy_name(case):
    return next((n for n in ENERGY_LIKE if n in case.conserved), None)


def _energy(e, case):
    name = _energy_name(case)
    if name is None:
        return []
    bad = [r for r in e.runs  # (in sweep order)
           if r.ok and r.judgement.verdict != "diverged" and r.drifts.get(name, 0.0) > ENERGY_HAZARD]
    if not bad:
        return []
    what = "energy" if name == "energy" else "energy balance (energy less the work of the loads)"

    def line(r):
        rate = r.drift_rates.get(name, math.nan)
        trend = "" if math.isnan(rate) else (f", losing {-100 * rate:.3g} %/s" if rate < 0
                                              else f", gaining {100 * rate:.3g} %/s")
        return f"{settings_text(r)} (up to {100 * r.drifts[name]:.3g} %{trend})"

    return [_hazard("energy", e, bad, f"{_runs_word(len(bad))} {_verb(len(bad), 'changes', 'change')} the {what} by "
                                      f"more than {100 * ENERGY_HAZARD:g} % over the "
                                      f"{value_text(case.t_final, 's')} horizon",
                    line, max(bad, key=lambda r: r.drifts[name]))]


def _creep(e, case):
    """Finished runs whose creep (``CREEP_METRIC``, a metric: stored over its scale) is beyond the case's bound."""
    label = next((inv for inv in case.invariants if inv.name == CREEP_METRIC and inv.kind == "metric"), None)
    tol = case.tolerances.get(CREEP_METRIC)
    if label is None or tol is None:
        return []
    speed = {r.key: r.drifts[CREEP_METRIC] * label.scale for r in e.runs
             if r.ok and r.judgement.verdict != "diverged" and r.drifts.get(CREEP_METRIC, 0.0) > tol.value}
    bad = _by_sweep(r for r in e.runs if r.key in speed)
    if not bad:
        return []

    def line(r):
        return f"{settings_text(r)} at {speed_text(speed[r.key])}"

    return [_hazard("creep", e, bad, f"{_runs_word(len(bad))} {_verb(len(bad), 'creeps', 'creep')} where the "
                                     f"closed form sticks (bound {speed_text(tol.value * label.scale)})",
                    line, max(bad, key=lambda r: speed[r.key]))]


def _growth_to_the_end(t, residual):
    """Largest residual over the last quarter of the horizon over that over its first half."""
    span = t - t[0]
    first = np.max(residual[span < 0.5 * span[-1]], initial=0.0)
    last = np.max(residual[span >= 0.75 * span[-1]], initial=0.0)
    return last / first if first > 0.0 else (math.inf if last > 0.0 else 1.0)


def _closure(e, case, store):
    """Runs whose loop closure leaves its bound and still grows (``CLOSURE_GROWTH``), per level."""
    if store is None or not case.scene.loops:
        return []
    found = {}
    for r in e.runs:
        if not (r.ok and r.judgement.verdict != "diverged" and r.trajectory):
            continue
        beyond = [(level, name) for level, name in LOOP_RESIDUALS.items()
                  if name in case.tolerances and r.drifts.get(name, 0.0) > case.tolerances[name].value]
        traj = store.trajectory(r.key) if beyond else None  # (read once for both levels)
        for level, _ in beyond:
            with np.errstate(invalid="ignore", over="ignore"):
                ratio = _growth_to_the_end(traj.t, loop_residual(case.scene, traj, level))
            if ratio > CLOSURE_GROWTH:
                found.setdefault(r.key, (r, []))[1].append((level, ratio))
    if not found:
        return []
    bad = _by_sweep(r for r, _ in found.values())

    def line(r):
        return f"{settings_text(r)} (" + ", ".join(f"{level} x{ratio:.3g}" for level, ratio in found[r.key][1]) + ")"

    worst = max(bad, key=lambda r: max(ratio for _, ratio in found[r.key][1]))
    return [_hazard("closure", e, bad, f"{_runs_word(len(bad))} {_verb(len(bad), 'leaves', 'leave')} the loop-closure "
                                       f"bound and {_verb(len(bad), 'is', 'are')} still opening the loop at the end of the "
                                       f"{value_text(case.t_final, 's')} horizon (largest residual over its last "
                                       "quarter against its first half)", line, worst)]


def _reactions(e, case, quantity):
    """Runs whose motion is within tolerance and whose reactions are not."""
    tol, motion = case.tolerances.get("reaction_force"), case.tolerances.get(quantity) if quantity else None
    if tol is None or motion is None:
        return []
    bad = [r for r in e.runs if r.ok and r.judgement.verdict != "diverged" and r.max_error(quantity) <= motion.value
           and not r.max_error("reaction_force") <= tol.value]  # (in sweep order)

    if not bad:
        return []

    def line(r):
        return f"{settings_text(r)} ({quantity} {r.max_error(quantity):.2e}, reactions {r.max_error('reaction_force'):.2e})"

    return [_hazard("reactions", e, bad, f"{_runs_word(len(bad))} {_verb(len(bad), 'moves', 'move')} within the "
                                         f"{quantity} tolerance ({motion.value:g} {QUANTITIES[quantity]}) but "
                                         f"{_verb(len(bad), 'misses', 'miss')} the reactions' ({tol.value:g} of the "
                                         "largest true reaction, modulo self-stresses)", line,
                    max(bad, key=lambda r: r.max_error("reaction_force")))]


def _beyond(e, case):
    finished = [r for r in e.runs if r.ok and r.judgement.verdict != "diverged"]
    bad = [r for r in finished if r.judgement.within_tolerance is False]  # (in sweep order)
    if not bad:
        return []
    counts = {}
    for r in bad:
        for name in r.judgement.beyond:
            counts[name] = counts.get(name, 0) + 1
    quiet = [r for r in bad if r.judgement.verdict == "stable"]
    tail = ""
    if quiet:
        if len(quiet) == len(bad):
            who = {1: "It keeps", 2: "Both keep"}.get(len(bad), f"All {len(bad)} keep")
        elif len(quiet) <= NAMED:
            who = f"{list_text(settings_text(r) for r in quiet)} {_verb(len(quiet), 'keeps', 'keep')}"
        else:
            shared = _shared(quiet)
            who = f"{len(quiet)} of them{' (' + shared + ')' if shared else ''} keep"
        tail = (f"{who} every conserved quantity within its bound: only the comparison with the truth shows "
                + _verb(len(quiet), "it.", "them."))
    lead = (f"{len(bad)} of {len(finished)} finished runs stay finite but leave the case's tolerance ("
            + ", ".join(f"{name} {n}" for name, n in sorted(counts.items(), key=lambda kv: -kv[1])) + ")")

    def line(r):
        return f"{settings_text(r)} (beyond {', '.join(r.judgement.beyond)})"

    return [_hazard("tolerance", e, bad, lead, line, tail=tail)]


def _inert(e, quantity):
    """Runs of one integrator, options and step at two or more tolerances whose stored errors are identical."""
    groups = {}
    for r in e.runs:
        if (r.ok and r.settings.rtol is not None and r.errors
                and all(math.isfinite(v) for pair in r.errors.values() for v in pair)):
            signature = tuple(sorted((q, tuple(pair)) for q, pair in r.errors.items()))
            groups.setdefault((r.settings.integrator, r.options_label, r.settings.dt, signature), []).append(r)
    same = [sorted(rs, key=lambda r: (-r.settings.rtol, -(r.settings.atol or 0.0))) for rs in groups.values()
            if len({(r.settings.rtol, r.settings.atol) for r in rs}) > 1]
    if not same:
        return []
    same.sort(key=lambda rs: (rs[0].settings.integrator, rs[0].options_label))
    unit = QUANTITIES.get(quantity, "")

    def group_text(rs):
        r = rs[0]
        knobs = [x.settings for x in rs]
        atols = any(k.atol != k.rtol for k in knobs)  # named unless each equals its rtol (the matrix's default)
        tols = list_text([f"{k.rtol:g}" + (f" (atol {'default' if k.atol is None else f'{k.atol:g}'})" if atols else "")
                      for k in knobs])
        steps = {x.cost.n_steps for x in rs}
        what = [f"{quantity} {r.max_error(quantity):.2e} {unit}".rstrip()] if quantity in r.errors else []
        what += [f"{next(iter(steps))} steps"] if len(steps) == 1 else []
        options = f" with {r.options_text}" if r.options_label else ""
        return f"{r.settings.integrator}{options} at rtol {tols}" + (f" ({', '.join(what)} each)" if what else "")

    runs = [r for rs in same for r in rs]
    text = (f"{e.engine}: a tolerance changed nothing: {'; '.join(group_text(rs) for rs in same)} — every stored "
            "error the same, bit for bit: the tolerance did not decide their steps (something else did, such as the "
            "sample interval), so they say nothing of what it buys, and are compared with no other engine.")
    details = tuple(islice((f"{settings_text(r)} (the same errors as "
                            f"{list_text([settings_text(x) for x in rs if x is not r])})" for rs in same for r in rs),
                           LISTED_RUNS))
    return [Hazard("inert", e.engine, tuple(runs), text, details)]


def _comparable(r):
    """Whether ``r``'s settings mean the same in every engine: a fixed step always does; an adaptive run's only
    with both tolerances given, as each engine fills in a missing one with its own default (Pinocchio's
    scipy solvers 1e-8, the reference's DOP853 1e-12, Exudyn atol = rtol, Drake no atol at all)."""
    return r.settings.dt is not None or (r.settings.rtol is not None and r.settings.atol is not None)


def _representative(runs):
    """An engine's run at one setting: its default variant (no options) if it ran one, else its
    most accurate variant."""
    plain = [r for r in runs if not r.settings.options]
    return plain[0] if plain else runs[0]


def _disagreements(runs, quantity, case):
    """Engines that disagree at one setting, among comparable runs: ``runs`` less those whose tolerance changed
    nothing (``_inert``, left out by the caller). A setting is an integrator name and its step or tolerances
    (rtol and atol): one name means one method in every engine that offers it (``dop853``: scipy's DOP853, in
    the reference and in Pinocchio; ``rk4``: the classical RK4; ``euler``: semi-implicit Euler), and an engine's
    own variants of it are compared through its default one (``_representative``). Runs whose settings do
    not mean the same in every engine are left out too (``_comparable``)."""
    if quantity is None or len({r.engine for r in runs}) < 2:  # (one engine disagrees with none: a map's not grouped)
        return []
    unit = QUANTITIES[quantity]
    tol = case.tolerances.get(quantity)
    groups, keys = {}, {}  # (a run's group key is its settings': made once per distinct Settings, None: not comparable)
    for r in runs:
        if r.status != "unsupported":
            s = r.settings
            key = keys.get(id(s), False)
            if key is False:
                key = keys[id(s)] = (s.integrator, s.dt, s.rtol, s.atol) if _comparable(r) else None
            if key is not None:
                groups.setdefault(key, {}).setdefault(r.engine, []).append(r)
    out = []
    shared = [kv for kv in groups.items() if len(kv[1]) >= 2]  # (a setting one engine ran disagrees with none)
    for (integrator, dt, rtol, _), by_engine in sorted(shared, key=lambda kv: (kv[0][0], kv[0][1] is None,
                                                                               -(kv[0][1] or kv[0][2] or 0))):
        chosen = {e: _representative(sorted(rs, key=lambda r: (bool(r.settings.options), _err(r, quantity))))
                  for e, rs in sorted(by_engine.items())}
        finite = {e: r for e, r in chosen.items() if r.ok and math.isfinite(r.max_error(quantity))}
        within = [e for e, r in finite.items() if tol is None or r.max_error(quantity) <= tol.value]
        broken = ([e for e, r in chosen.items() if r.judgement.verdict in ("diverged", "failed", "timeout")]
                  if within else ())
        if within and broken:
            text = (f"at {_setting(integrator, chosen)}, {list_text(within)} {'stays' if len(within) == 1 else 'stay'} "
                    f"within the {quantity} tolerance while "
                    + list_text(f"{e} {chosen[e].judgement.verdict}" for e in broken) + ".")
            out.append(Hazard("disagreement", "", tuple(chosen.values()), text))
            continue
        if len(finite) < 2:
            continue
        errs = {e: max(r.max_error(quantity), 1e-300) for e, r in finite.items()}
        hi, lo = max(errs.values()), min(errs.values())
        if hi / lo > DISAGREEMENT_FACTOR and (tol is None or hi > tol.value):
            values = list_text(f"{e} {errs[e]:.2e}" + (f" ({finite[e].options_text})" if finite[e].settings.options else "")
                           for e in sorted(errs, key=errs.get))
            bound = f" (tolerance {tol.value:g} {unit})" if tol else ""
            out.append(Hazard("disagreement", "", tuple(finite.values()),
                              f"at {_setting(integrator, chosen)} the engines' {quantity} errors differ {hi / lo:.2g}-fold: "
                              f"{values} {unit}{bound}."))
    return out


def _setting(integrator, chosen):
    """A disagreement's setting in words (made only for a hazard: most of a map's settings are none)."""
    return " ".join([integrator, next(iter(chosen.values())).sweep_label.replace("tol=", "rtol=")])


def _err(r, quantity):
    e = r.max_error(quantity)
    return e if math.isfinite(e) else math.inf


def _unsupported(e):
    by_reason = {}
    for r in e.runs:
        if r.status == "unsupported":
            by_reason.setdefault(r.message, []).append(r)
    out = []
    for reason, rs in sorted(by_reason.items()):
        what = refused_text([(r.settings.integrator, r.options_text) for r in rs])
        out.append(Hazard("unsupported", e.engine, tuple(_by_sweep(rs)), f"{e.engine} cannot run {what}: {reason}"))
    return out


