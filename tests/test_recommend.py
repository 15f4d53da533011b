"""What to use (``reports.recommend``): on synthetic records made from one real run — a clear winner, a tie
within the timing spread, nothing reaching the target, the grid deciding — and the section first in the page."""

import os
import shutil
from dataclasses import replace

import pytest

from dalembert.reports.findings import CaseFindings
from dalembert.reports.recommend import SINGLE_SAMPLE_SPREAD, problem_class, recommend
from dalembert.reports.render import build_report
from dalembert.store import Store
from stores import add_run, base, changed, seed_store, tamper


@pytest.fixture(scope="module")
def seed(tmp_path_factory):
    return seed_store(tmp_path_factory.mktemp("seed"))


def _run(first, key, engine, cost, error, dt=1e-2, integrator="rk4", repeats=None):
    """A finished run of ``engine`` made from ``first``: its orientation error ``error`` (rad), its cost ``cost``
    (s/s), its timed repeats ``repeats`` (s/s; default: one sample)."""
    t = first.t_final
    reps = tuple(x * t for x in (repeats or (cost,)))
    return changed(first, key=key, engine=engine, integrator=integrator, dt=dt, status="ok", verdict="stable",
                   errors={**first.errors, "orientation": (error, error)},
                   cost=replace(first.cost, wall_s_median=cost * t, wall_s_repeats=reps, repeats=len(reps)))


def _found(seed, *runs):
    case = seed.case(base(seed).case, base(seed).case_version)
    return [CaseFindings(case, tuple(runs), "orientation", (), (), ())]


def _one(recs, target):
    (rec,) = [r for r in recs if r.target == target]
    return rec


def test_the_free_top_is_a_free_body(seed):
    case = seed.case(base(seed).case, base(seed).case_version)
    assert problem_class(case).name == "free bodies"


def test_a_clear_winner_is_recommended_with_the_next_engine_as_runner_up(seed):
    first = base(seed)
    runs = [_run(first, "a", "alpha", 0.1, 1e-4, repeats=(0.09, 0.1, 0.11)),
            _run(first, "a2", "alpha", 0.5, 1e-7, dt=1e-3, repeats=(0.5, 0.5)),
            _run(first, "b", "beta", 1.0, 1e-4, repeats=(0.95, 1.0, 1.05)),
            _run(first, "c", "gamma", 0.05, 1e-2, repeats=(0.05, 0.05))]  # cheaper, but misses 1e-3
    rec = _one(recommend(_found(seed, *runs)), 1e-3)
    assert rec.best.engine == "alpha" and rec.best.runs[0].key == "a"
    assert rec.runner_up.engine == "beta" and rec.apart
    assert rec.best.cost == pytest.approx(0.1) and (rec.best.low, rec.best.high) == pytest.approx((0.09, 0.11))
    assert rec.grid == ""  # alpha reaches it at its coarsest step; gamma never does
    fine = _one(recommend(_found(seed, *runs)), 1e-6)
    assert fine.best.runs[0].key == "a2" and fine.runner_up is None


def test_only_measured_runs_are_candidates_and_an_exact_run_s_error_is_its_own(seed):
    first = base(seed)
    runs = [_run(first, "blew", "alpha", 0.01, 1e-5),  # finite, but judged a blow-up: no candidate
            _run(first, "free", "beta", 0.0, 1e-5),  # no cost measured: no candidate
            _run(first, "exact", "gamma", 0.5, 0.0), _run(first, "ok", "delta", 1.0, 1e-5)]
    runs[0] = changed(runs[0], verdict="diverged")
    rec = _one(recommend(_found(seed, *runs)), 1e-3)
    assert (rec.best.runs[0].key, rec.runner_up.runs[0].key) == ("exact", "ok")
    assert rec.best.error == 0.0  # (the stored error, not the floor a plot draws it at)


def test_costs_within_their_spreads_are_a_tie(seed):
    first = base(seed)
    runs = [_run(first, "a", "alpha", 0.10, 1e-4, repeats=(0.08, 0.10, 0.13)),
            _run(first, "b", "beta", 0.11, 1e-4, repeats=(0.09, 0.11, 0.14))]
    rec = _one(recommend(_found(seed, *runs)), 1e-3)
    assert rec.best.engine == "alpha" and rec.runner_up.engine == "beta" and not rec.apart


def test_a_single_sample_gets_the_named_spread(seed):
    first = base(seed)
    gap = (1 + SINGLE_SAMPLE_SPREAD) / (1 - SINGLE_SAMPLE_SPREAD)  # the ratio at which two single samples part
    near = [_run(first, "a", "alpha", 1.0, 1e-4), _run(first, "b", "beta", 0.99 * gap, 1e-4)]
    far = [_run(first, "a", "alpha", 1.0, 1e-4), _run(first, "b", "beta", 1.01 * gap, 1e-4)]
    assert not _one(recommend(_found(seed, *near)), 1e-3).apart
    assert _one(recommend(_found(seed, *far)), 1e-3).apart


def test_nothing_reaching_the_target_says_so_with_the_closest(seed):
    first = base(seed)
    runs = [_run(first, "a", "alpha", 0.1, 3e-3), _run(first, "b", "beta", 1.0, 2e-3)]
    rec = _one(recommend(_found(seed, *runs)), 1e-3)
    assert rec.best is None and rec.runner_up is None and rec.closest.engine == "beta"


def test_a_line_missing_at_a_cheaper_step_lets_the_grid_decide(seed):
    """The issue's case: beta reaches 1e-6 only at its finest step (costly), missing it at a coarser step that
    costs less than the pick: a step between might win."""
    first = base(seed)
    runs = [_run(first, "a", "alpha", 0.2, 5e-7),
            _run(first, "b1", "beta", 0.1, 3e-6), _run(first, "b2", "beta", 1.0, 3e-10, dt=1e-3)]
    rec = _one(recommend(_found(seed, *runs)), 1e-6)
    assert rec.best.engine == "alpha"
    assert "beta rk4 dt=0.01 missed it" in rec.grid and "a step between might win" in rec.grid
    # beta's coarse step costing more than the pick: the grid did not decide
    runs[1] = _run(first, "b1", "beta", 0.3, 3e-6)
    assert _one(recommend(_found(seed, *runs)), 1e-6).grid == ""


def test_a_class_whose_headlines_differ_in_unit_is_answered_per_unit(seed):
    """A target bounds one unit: a free top's orientation (rad) and a particle's position (m) are not one answer."""
    first = base(seed)
    case = seed.case(first.case, first.case_version)
    runs = [_run(first, "a", "alpha", 0.1, 1e-4), _run(first, "b", "beta", 0.2, 1e-4)]
    moved = [changed(r, errors={**r.errors, "position": (5e-3, 5e-3)}) for r in runs]
    found = [CaseFindings(case, tuple(runs), "orientation", (), (), ()),
             CaseFindings(case, tuple(moved), "position", (), (), ())]
    recs = [r for r in recommend(found, {found[0]: "top", found[1]: "particle"}) if r.target == 1e-3]
    assert [(r.problem.name, r.units, r.cases) for r in recs] == [("free bodies", ("m",), ("particle",)),
                                                                  ("free bodies", ("rad",), ("top",))]
    assert recs[0].best is None and recs[1].best.engine == "alpha"  # the position misses 1e-3 m; the angle meets it


def test_a_pick_met_only_at_the_finest_step_lets_the_grid_decide(seed):
    first = base(seed)
    runs = [_run(first, "a1", "alpha", 0.1, 3e-3), _run(first, "a2", "alpha", 1.0, 1e-5, dt=1e-3)]
    rec = _one(recommend(_found(seed, *runs)), 1e-3)
    assert rec.best.runs[0].key == "a2" and "only at the finest step the grid ran" in rec.grid


def test_the_answers_open_the_page(seed, tmp_path):
    shutil.copytree(seed.path, tmp_path / "s")
    store = Store.open(tmp_path / "s")
    tamper(store, lambda r: changed(r, engine="alpha", cost=replace(r.cost, wall_s_repeats=())))
    add_run(store, "beta-rk4", engine="beta", errors={**base(store).errors},
            cost=replace(base(store).cost, wall_s_median=100 * base(store).cost.wall_s_median, wall_s_repeats=()))
    build_report(store)
    md = open(os.path.join(store.path, "report.md")).read()
    assert md.index("## What to use") < md.index("## Findings")
    assert "| free bodies (free_top) | 0.001 rad | alpha rk4 dt=0.005" in md
    assert "beta rk4 dt=0.005" in md and "The step grid: dt 0.005 s." in md
    assert "100x cheaper" in md


def test_first_order_and_float32_runs_are_said_to_miss_the_finest_target(seed, tmp_path):
    shutil.copytree(seed.path, tmp_path / "s")
    store = Store.open(tmp_path / "s")
    first = base(store)  # (the seed's run: rk4, order 4, in double)
    add_run(store, "euler", engine="alpha", integrator="euler", dt=1e-3, integrator_order=1,
            errors={**first.errors, "orientation": (2e-5, 2e-5)})
    add_run(store, "f32", engine="beta", integrator="rk4", dt=5e-3, integrator_order=4, audit={"precision": "float32"},
            errors={**first.errors, "orientation": (3e-6, 3e-6)})
    build_report(store)
    md = open(os.path.join(store.path, "report.md")).read()
    assert ("Integrators declaring order 1 (1 engine line) never reach 1e-06 on any case here: their best is 2e-05."
            in md)
    assert "Runs in float32 (1 engine line) never reach 1e-06 on any case here: their best is 3e-06." in md
