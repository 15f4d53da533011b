"""What to use: per class of problem the matrix covers and per accuracy target, the engine and setting to pick,
its cost, the runner-up, and whether the store can tell them apart — the answer the report opens with.

A *class* of problem is a set of case versions (``PROBLEM_CLASSES``: decided from a case's tags and scene, in
one place; the first class that claims a case keeps it), answered per headline unit: a class whose cases'
headlines are in different units (a free top's orientation in rad, a particle's position in m) has one answer per
unit, each over the cases in that unit, since a target bounds one unit. A *setting* is one engine, integrator, options and
step (or tolerance). A setting *reaches* a target on a class when, on every case version of the class, its
finished, non-diverged run has a headline figure (``reports.work_precision``: the headline error, or the case's
headline metric, in the case's unit) at most the target. Its *cost* on the class is the geometric mean over the
class's cases of its stepping seconds per simulated second (cases differ in cost by orders of magnitude: a
geometric mean weighs each case alike), and its *spread* the same mean of its timed repeats' min and max
(``Cost.wall_s_repeats``); a run timed once has no spread, and is given ``SINGLE_SAMPLE_SPREAD`` either side.

Per class and target, each engine's cheapest reaching setting competes; the cheapest is *recommended* and the
next engine's is the *runner-up*. The two are *apart* only when the recommended's spread ends below the
runner-up's: otherwise the store cannot rank them (a tie within the spread). The answer says "the grid decides"
when the step grid, not the engines, may have decided it:

* the recommended setting reaches the target only at its line's finest step or tolerance in the store (no
  finer one ran, a coarser one missed): its cost to the target lies somewhere between the two; or
* another line missed the target at a step that costs less than the recommendation and reached it at the next
  finer step: a step between the two, not in the grid, might win.

Stored numbers only (a run that was made, never an interpolation); nothing is judged again here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from dalembert.reports.names import settings_text
from dalembert.reports.work_precision import figure_reader, sweep_key

__all__ = ["TARGETS", "SINGLE_SAMPLE_SPREAD", "ProblemClass", "PROBLEM_CLASSES", "problem_class", "Candidate",
           "Recommendation", "recommend"]

# The two accuracies a person choosing an engine asks for: an engineering answer (1e-3 in the headline error's
# unit, rad or m) and a careful simulation (1e-6); the report's tables go on to 1e-9 (``findings.ACCURACY_TARGETS``).
TARGETS = (1e-3, 1e-6)
# A cost timed once (``dalembert run --quick``) has no spread of its own: repeats of one run on one machine
# scatter by ~10 % (the stores' min-max spreads, ``reports.compare.COST_NOTICE``), so it is given 10 % either side.
SINGLE_SAMPLE_SPREAD = 0.10


@dataclass(frozen=True)
class ProblemClass:
    """A class of problem: ``name`` (how the page says it), ``what`` (one line) and which cases it claims: any
    case with one of ``tags``, or whose scene has loop closures (``loops``) or contact pairs (``contact``)."""

    name: str
    what: str
    tags: tuple = ()
    loops: bool = False
    contact: bool = False

    def claims(self, case):
        scene = case.scene
        return (any(t in case.tags for t in self.tags) or (self.loops and bool(getattr(scene, "loops", ())))
                or (self.contact and bool(getattr(scene, "contacts", ()))))


# The classes, most specific first (a case goes to the first that claims it: a fast-spinning free top is
# "fast spin", not "free bodies"; a spring in a loop is "closed loops").
PROBLEM_CLASSES = (
    ProblemClass("contact", "impacts, stick-slip, rolling: events against a closed form", ("contact",), contact=True),
    ProblemClass("closed loops", "mechanisms whose joints close a loop (four-bar)", ("loop", "loops"), loops=True),
    ProblemClass("stiff springs", "spring-dampers, stiff and damped", ("stiff", "spring")),
    ProblemClass("fast spin", "bodies spinning fast about a joint or freely", ("fast-spin",)),
    ProblemClass("free bodies", "unjointed rigid bodies: torque-free tops, particles under gravity", ("free",)),
    ProblemClass("trees", "jointed open chains under gravity or follower loads (pendulum, chain, heavy top)",
                 ("jointed",)),
)


def problem_class(case):
    """The ``ProblemClass`` that claims ``case`` (a ``CaseRecord``), or None."""
    return next((c for c in PROBLEM_CLASSES if c.claims(case)), None)


@dataclass(frozen=True)
class Candidate:
    """One setting on one class: what it is, what it costs there and the runs behind it.

    Attributes
    ----------
    engine : str
    setting : str — ``integrator dt=... options`` as the report writes it
    cost, low, high : float — s/s: the geometric mean over the class's cases of the stepping time per simulated
        second (median of the repeats), of the repeats' min and of their max (``SINGLE_SAMPLE_SPREAD`` for one)
    error : float — its largest headline figure over the class's cases (each in its case's unit)
    runs : tuple of RunRecord — one per case version of the class
    """

    engine: str
    setting: str
    cost: float
    low: float
    high: float
    error: float
    runs: tuple


@dataclass(frozen=True)
class Recommendation:
    """The answer for one class and target.

    Attributes
    ----------
    problem : ProblemClass
    target : float — the headline figure's bound, in each case's unit
    cases : tuple of str — the case versions' titles the class holds whose headline is in ``units``
    units : tuple of str — their headline unit (one: a target bounds one unit)
    best, runner_up : Candidate or None — the cheapest reaching setting and the next engine's (None: none)
    apart : bool — the two costs are apart beyond their spreads (True where there is no runner-up)
    grid : str — why the step grid may have decided it ("" when it did not)
    closest : Candidate or None — where nothing reaches: the setting whose largest error came nearest
    """

    problem: ProblemClass
    target: float
    cases: tuple
    units: tuple
    best: object
    runner_up: object
    apart: bool
    grid: str
    closest: object = None


def _spread(r):
    """``(low, high)`` s/s of run ``r``: its repeats' min and max per simulated second (or the single sample's
    ``SINGLE_SAMPLE_SPREAD`` either side)."""
    cost = r.cost_per_sim_s
    reps = [x for x in r.cost.wall_s_repeats if math.isfinite(x)]
    if len(reps) >= 2:
        return min(reps) / r.t_final, max(reps) / r.t_final
    return cost * (1 - SINGLE_SAMPLE_SPREAD), cost * (1 + SINGLE_SAMPLE_SPREAD)


def _geomean(xs):
    return math.exp(sum(math.log(x) for x in xs) / len(xs))


def _line(r):
    return (r.engine, r.settings.integrator, r.options_label)


def _candidates(members):
    """Every setting that ran (finished, measured) on every case version of ``members`` (``CaseFindings``), as a
    ``Candidate``."""
    by_key = {}
    for f in members:
        figure = figure_reader(f.ranked, f.case) if f.ranked else None
        # the runs measured: finished, not diverged, a finite headline figure and a finite positive cost — from the
        # work-precision points the findings made (``CaseFindings.points``: the finished runs of a finite figure and
        # cost), the rest asked here
        for p in f.points:
            r = p.run
            if r.judgement.verdict != "diverged" and p.cost > 0:
                s = r.settings  # (a setting: its line, ``_line``, and its step or tolerances)
                by_key.setdefault((r.engine, s.integrator, r.options_label, s.dt, s.rtol, s.atol), {})[id(f)] = (
                    r, figure(r))
    out = []
    for found in by_key.values():
        if len(found) != len(members):
            continue
        runs = tuple(r for r, _ in found.values())
        spreads = [_spread(r) for r in runs]
        out.append(Candidate(runs[0].engine, settings_text(runs[0]), _geomean([r.cost_per_sim_s for r in runs]),
                             _geomean([lo for lo, _ in spreads]), _geomean([hi for _, hi in spreads]),
                             max(err for _, err in found.values()), runs))
    return out


def _grid_decides(best, candidates, target):
    """Why the step grid may have decided ``best`` among ``candidates`` ("" when it did not): ``best`` reached the
    target only at its line's finest sweep value, or another line missed it at a cheaper value and reached it at
    the next finer one."""
    lines = {}
    for c in candidates:
        lines.setdefault(_line(c.runs[0]), []).append(c)
    for line in lines.values():
        line.sort(key=lambda c: sweep_key(c.runs[0]))  # coarse to fine
    reasons = []
    mine = lines[_line(best.runs[0])]
    at = mine.index(best)
    if at == len(mine) - 1 and at > 0 and mine[at - 1].error > target:
        reasons.append(f"{best.engine} {best.setting} reaches it only at the finest step the grid ran "
                       f"({mine[at - 1].setting} missed, {mine[at - 1].error:.2g})")
    bracketed = []  # (coarse, fine) of the other lines: missed at a step cheaper than the pick, reached at the next
    for key, line in sorted(lines.items()):
        if key == _line(best.runs[0]):
            continue
        bracketed += [(c, f) for c, f in zip(line, line[1:]) if c.error > target >= f.error and c.cost < best.cost][:1]
    if bracketed:
        coarse, fine = min(bracketed, key=lambda cf: cf[0].cost)
        others = "" if len(bracketed) == 1 else f" and {len(bracketed) - 1} more line(s)"
        reasons.append(f"{coarse.engine} {coarse.setting} missed it ({coarse.error:.2g}) at {coarse.cost:.2g} s/s, "
                       f"less than the pick, and {fine.setting} reached it{others}: a step between might win")
    return "; ".join(reasons)


def recommend(found, titles=None, targets=TARGETS):
    """The ``Recommendation`` of every class of problem ``found`` (``CaseFindings``, any order) holds, per headline
    unit and target in ``targets``; classes in ``PROBLEM_CLASSES`` order, a class's units in name order (a class
    whose cases' headlines are in rad and in m is answered for each unit apart: one target bounds one unit). ``titles``: each ``CaseFindings``' heading (default:
    its case's name)."""
    groups = {}
    for f in found:
        problem = problem_class(f.case)
        if problem is not None and f.ranked:
            # a target bounds one unit: a class whose cases' headlines differ in unit (rad, m) is answered per unit
            groups.setdefault((problem, f.ranked_unit), []).append(f)
    out = []
    for problem, unit in sorted(groups, key=lambda pu: (PROBLEM_CLASSES.index(pu[0]), pu[1])):
        members = groups[(problem, unit)]
        names = tuple(dict.fromkeys((titles or {}).get(f, f.case.name) for f in members))
        units = (unit,)
        candidates = _candidates(members)
        for target in targets:
            reaching = [c for c in candidates if c.error <= target]
            per_engine = {}
            for c in sorted(reaching, key=lambda c: (c.cost, c.setting)):
                per_engine.setdefault(c.engine, c)
            ranked = sorted(per_engine.values(), key=lambda c: c.cost)
            if not ranked:
                closest = min(candidates, key=lambda c: c.error, default=None)
                out.append(Recommendation(problem, target, names, units, None, None, True, "", closest))
                continue
            best = ranked[0]
            runner = ranked[1] if len(ranked) > 1 else None
            apart = runner is None or best.high < runner.low
            out.append(Recommendation(problem, target, names, units, best, runner, apart,
                                      _grid_decides(best, candidates, target)))
    return out
