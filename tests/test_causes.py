"""Causes beside disagreements (``reports.causes``) on synthetic records made from one real run: float32, an
integrator below its declared order where another engine's keeps it, soft against hard loops, a step cap; and in
the report, a disagreement with a cause listed, one without folded with the runs beyond the tolerance."""

import os
import shutil
from dataclasses import replace
from types import SimpleNamespace

import pytest

from dalembert.reports.causes import case_orders, disagreement_causes
from dalembert.reports.findings import find
from dalembert.reports.render import build_report
from dalembert.store import Store
from stores import add_run, base, changed, seed_store


@pytest.fixture(scope="module")
def seed(tmp_path_factory):
    return seed_store(tmp_path_factory.mktemp("seed"))


@pytest.fixture
def store(seed, tmp_path):
    shutil.copytree(seed.path, tmp_path / "s")
    return Store.open(tmp_path / "s")


def _case(seed):
    return seed.case(base(seed).case, base(seed).case_version)


def _run(first, key, engine, error, dt=1e-2, order=4, **changes):
    return changed(first, key=key, engine=engine, integrator="rk4", dt=dt, integrator_order=order,
                   errors={**first.errors, "orientation": (error, error)}, **changes)


def test_float32_is_named(seed):
    first = base(seed)
    group = [_run(first, "a", "alpha", 1e-3, audit={"precision": "float32"}), _run(first, "b", "beta", 1e-8)]
    causes = disagreement_causes(group, _case(seed), group, "orientation")
    assert any("alpha ran in float32" in c for c in causes) and not any("beta" in c for c in causes)
    best = [_run(first, "a", "alpha", 1e-9, audit={"precision": "float32"}), _run(first, "b", "beta", 1e-3)]
    assert disagreement_causes(best, _case(seed), best, "orientation") == []  # float32 the more accurate: no cause
    plain = [replace(group[0], audit={"precision": "float64"}), group[1]]
    assert disagreement_causes(plain, _case(seed), plain, "orientation") == []


def test_an_order_below_the_declared_one_is_named_beside_an_engine_that_keeps_it(seed):
    first = base(seed)
    runs = [_run(first, "a1", "alpha", 1e-3), _run(first, "a2", "alpha", 1e-5, dt=1e-3),  # order 2
            _run(first, "b1", "beta", 1e-4), _run(first, "b2", "beta", 1e-8, dt=1e-3)]  # order 4
    causes = disagreement_causes([runs[0], runs[2]], _case(seed), runs, "orientation")
    assert causes == ["alpha's rk4 shows order 2 here where it declares 4 (beta 4): a method of the same name "
                      "that is not the same"]
    declared_two = [replace(r, integrator_order=2) if r.engine == "alpha" else r for r in runs]
    assert disagreement_causes([declared_two[0], declared_two[2]], _case(seed), declared_two, "orientation") == []


def test_soft_loops_beside_hard_ones_are_named():
    case = SimpleNamespace(scene=SimpleNamespace(loops=("C",)), sample_times=(0.0, 0.5, 1.0))
    settings = SimpleNamespace(integrator="rk4", dt=1e-2)
    soft = SimpleNamespace(engine="mujoco", audit={"loop_softness": "soft"}, settings=settings, options_label="",
                           max_error=lambda q: 1e-4)
    hard = SimpleNamespace(engine="pinocchio", audit={}, settings=settings, options_label="", max_error=lambda q: 1e-8)
    assert disagreement_causes([soft, hard], case, [], "joint", orders={}) == [
        "mujoco closes the loop with soft constraints (audit loop_softness), the others hard: the residual is part "
        "of the motion"]
    assert disagreement_causes([soft, soft], case, [], "joint", orders={}) == []  # both soft: no contrast


def test_an_adaptive_run_capped_by_the_samples_is_named(seed):
    first = base(seed)
    intervals = len(_case(seed).sample_times) - 1
    capped = changed(first, key="c", engine="alpha", integrator="dop853", dt=None, rtol=1e-6, atol=1e-6,
                     cost=replace(first.cost, n_steps=intervals))
    free = replace(capped, key="d", engine="beta", cost=replace(first.cost, n_steps=10 * intervals))
    causes = disagreement_causes([capped, free], _case(seed), [capped, free], "orientation")
    assert causes == [f"alpha's dop853 took one step per sample interval ({intervals}): the samples, not its "
                      "tolerance, set its steps"]
    dense = replace(capped, cost=replace(first.cost, n_steps=intervals // 10))  # dense output: fewer steps, no cap
    assert disagreement_causes([dense, free], _case(seed), [dense, free], "orientation") == []


def test_a_disagreement_with_a_cause_is_listed_and_one_without_is_folded(store):
    first = base(store)
    add_run(store, "f32", engine="mjx", errors={**first.errors, "orientation": (1e-2, 1e-2)},
            audit={"precision": "float32"}, within_tolerance=False, beyond=("orientation",))
    (case,) = find(store)
    (h,) = [h for h in case.hazards if h.kind == "disagreement"]
    assert any("mjx ran in float32" in c for c in h.causes)
    build_report(store)
    md = open(os.path.join(store.path, "report.md")).read()
    hazards = md[md.index("## Hazards"):]
    assert "*Engines disagree (cause named)*" in hazards.split("<details>")[0]
    assert "Cause: mjx ran in float32" in hazards
    assert "finite but beyond the tolerance (1)" in hazards  # folded, not listed
    assert "*Finite but beyond the tolerance*" not in hazards.split("<details>")[0]

    tamper_audit = os.path.join(store.rows_dir, "f32.json")
    os.remove(tamper_audit)
    add_run(store, "f32", engine="mjx", errors={**first.errors, "orientation": (1e-2, 1e-2)},
            audit={"precision": "float64"}, within_tolerance=False, beyond=("orientation",))
    build_report(store)
    md = open(os.path.join(store.path, "report.md")).read()
    hazards = md[md.index("## Hazards"):]
    assert "Engines disagree" not in hazards.split("<details>")[0]
    assert "engines disagree (1)" in hazards


def test_case_orders_use_the_case_s_step_pairs(seed):
    first = base(seed)
    runs = [_run(first, "a1", "alpha", 1e-3), _run(first, "a2", "alpha", 1e-5, dt=1e-3)]
    (o,) = case_orders(_case(seed), runs, "orientation").values()
    assert o.median == pytest.approx(2.0) and o.declared == 4
