"""The observed order of each engine's fixed-step integrators from the step pairs of a matrix
(``reports.order``), against the order it declares, and its report section."""

import math
from dataclasses import replace
from types import SimpleNamespace

import pytest

from dalembert.judge import Judgement
from dalembert.record import RunRecord
from dalembert.reports.order import (DEFAULT_FLOOR, FLOOR_MARGIN, ORDER_MARGIN, SATURATED_ANGLE, SINGLE_FLOOR,
                                     left_out, observed_orders, step_pairs)
from dalembert.reports.sections.order import observed_order
from dalembert.settings import Settings

STABLE = Judgement((), "stable", "", True)


def _case(name, floor=None, contacts=()):
    """What ``step_pairs`` reads of a ``CaseRecord``: its name, version, scene's contacts and floor."""
    return SimpleNamespace(name=name, version="v1", scene=SimpleNamespace(contacts=contacts),
                           floor={"orientation": floor} if floor else {})


def _runs(case, engine, integrator, order, dts=(1e-2, 5e-3, 2.5e-3, 1.25e-3), constant=10.0, status="ok",
          verdicts=None, declared=None, audit=None):
    """Runs whose headline error is exactly ``constant * dt ** order`` (a known order), their integrator declaring
    ``declared``."""
    out = []
    for i, dt in enumerate(dts):
        verdict = (verdicts or {}).get(i, "stable")
        out.append(RunRecord(f"{case}-{engine}-{integrator}-{i}", case, "v1", engine, Settings(integrator, dt),
                             status=status, errors={"orientation": (constant * dt ** order, 0.0)},
                             judgement=Judgement((), verdict, "", True), integrator_order=declared,
                             audit=dict(audit or {})))
    return out


def test_a_known_order_is_observed_and_matches_its_declaration():
    case = _case("top")
    runs = _runs("top", "eng", "rk4", 4, declared=4) + _runs("top", "eng", "euler", 1, declared=1, constant=1.0)
    pairs = step_pairs([(case, runs, "orientation")])
    assert len(pairs) == 6 and {p.dts for p in pairs if p.integrator == "rk4"} == {(1e-2, 5e-3), (5e-3, 2.5e-3),
                                                                                     (2.5e-3, 1.25e-3)}
    found = {o.integrator: o for o in observed_orders(pairs)}
    assert (found["rk4"].declared, found["euler"].declared) == (4, 1)
    assert found["rk4"].median == pytest.approx(4.0, abs=1e-9) and found["euler"].median == pytest.approx(1.0, abs=1e-9)
    assert not found["rk4"].flagged and not found["rk4"].below and found["rk4"].cases == ("top",)


def test_runs_pair_only_with_runs_of_their_parameters_whether_or_not_they_share_one_dict():
    case = _case("top")
    slow, fast = {"spin": 1.0}, {"spin": 2.0}  # (records read together share a dict: ``bulk_records``)
    runs = [replace(r, params=slow if i % 2 == 0 else dict(slow)) for i, r in enumerate(_runs("top", "eng", "rk4", 4))]
    runs += [replace(r, key=r.key + "-fast", params=fast) for r in _runs("top", "eng", "rk4", 2, dts=(8e-3, 4e-3))]
    pairs = step_pairs([(case, runs, "orientation")])
    assert sorted(p.dts for p in pairs) == [(2.5e-3, 1.25e-3), (5e-3, 2.5e-3), (8e-3, 4e-3), (1e-2, 5e-3)]
    assert {round(p.order, 9) for p in pairs if p.dts == (8e-3, 4e-3)} == {2.0}
    assert {round(p.order, 9) for p in pairs if p.dts != (8e-3, 4e-3)} == {4.0}


def test_an_order_below_its_declaration_is_flagged_and_the_case_that_loses_it_named():
    hinge, ball = _case("hinge"), _case("ball")
    # RK4 keeps its order on the hinge and is second order on the ball joint (as MJX's is)
    groups = [(hinge, _runs("hinge", "eng", "rk4", 4, declared=4), "orientation"),
              (ball, _runs("ball", "eng", "rk4", 2, dts=(1e-2, 5e-3), declared=4), "orientation")]
    (o,) = observed_orders(step_pairs(groups))
    assert o.median == pytest.approx(4.0) and (o.low, o.high) == (pytest.approx(2.0), pytest.approx(4.0))
    assert not o.flagged and o.below == ("ball",)  # the median keeps its order; the ball case is named
    (o,) = observed_orders(step_pairs(groups[1:]))
    assert o.flagged and o.below == ("ball",)
    # within the margin: not flagged
    (o,) = observed_orders(step_pairs([(hinge, _runs("hinge", "eng", "rk4", 4 - ORDER_MARGIN / 2, declared=4),
                                        "orientation")]))
    assert not o.flagged and not o.below
    # no declared order: shown, never flagged
    (o,) = observed_orders(step_pairs([(ball, _runs("ball", "eng", "rk4", 2), "orientation")]))
    assert o.declared is None and not o.flagged and not o.below
    # runs that declared different orders (the engine changed it between versions): no declaration to judge by
    mixed = _runs("ball", "eng", "rk4", 2, declared=4)
    mixed[-1] = replace(mixed[-1], integrator_order=2)
    (o,) = observed_orders(step_pairs([(ball, mixed, "orientation")]))
    assert o.declared is None and not o.flagged


def test_only_pairs_in_the_asymptotic_range_count():
    floor = 1e-12
    case = _case("top", floor=floor)
    # 10 dt^4 from 1e-7 down to 1.5e-12: the last two errors are within FLOOR_MARGIN of the floor
    runs = _runs("top", "eng", "rk4", 4, dts=(1e-2, 5e-3, 2.5e-3, 1.25e-3, 6.25e-4))
    excluded = {}
    pairs = step_pairs([(case, runs, "orientation")], excluded)
    usable = [r.settings.dt for r in runs if r.max_error("orientation") >= FLOOR_MARGIN * floor]
    assert len(pairs) == len(usable) - 1 >= 1 and excluded == {"at the roundoff floor": len(runs) - len(usable)}
    # a diverged run breaks the pairs it is in; a contact case has no order
    diverged = _runs("top", "eng", "rk4", 4, verdicts={0: "diverged"})
    excluded = {}
    assert len(step_pairs([(_case("top"), diverged, "orientation")], excluded)) == 2
    assert excluded == {"diverged or did not finish": 1}
    excluded = {}
    assert step_pairs([(_case("block", contacts=("c",)), _runs("block", "eng", "rk4", 4), "orientation")],
                      excluded) == []
    assert excluded == {"of a contact case": 3} and left_out(excluded) == "3 of a contact case"
    # an angle error of a tenth of a radian or more has saturated: the first pair (0.1 rad -> 0.05) is out
    excluded = {}
    assert len(step_pairs([(_case("top"), _runs("top", "eng", "euler", 1), "orientation")], excluded)) == 2
    assert excluded == {"with an angle error saturated": 1} and 0.1 == SATURATED_ANGLE
    # a single-precision run's floor is its own: its audit's, or SINGLE_FLOOR (10 dt^4 reaches 1e-4 at ~1.8e-2 s)
    single = _runs("top", "eng", "rk4", 4, audit={"precision": "float32", "float32_floor": float("nan")})
    excluded = {}
    assert step_pairs([(_case("top"), single, "orientation")], excluded) == [] and SINGLE_FLOOR * FLOOR_MARGIN > 1e-7
    assert excluded == {"at the roundoff floor": 3}
    single = _runs("top", "eng", "rk4", 4, audit={"precision": "float32", "float32_floor": 1e-12})
    assert len(step_pairs([(_case("top"), single, "orientation")])) == 2  # its audit's floor (1e-12), not SINGLE_FLOOR
    # adaptive runs (no dt) and cases without a headline quantity are not pairs
    assert step_pairs([(_case("top"), _runs("top", "eng", "rk4", 4), None)]) == []
    assert DEFAULT_FLOOR * FLOOR_MARGIN < 1e-10  # the default floor leaves errors of real runs usable


def test_the_section_shows_declared_observed_cases_and_flag():
    hinge, ball = _case("hinge"), _case("ball")
    rep = SimpleNamespace(found=[
        SimpleNamespace(case=hinge, runs=_runs("hinge", "eng", "rk4", 4, declared=4), quantity="orientation"),
        SimpleNamespace(case=ball, runs=_runs("ball", "eng", "rk4", 2, declared=4), quantity="orientation"),
        SimpleNamespace(case=hinge, runs=_runs("hinge", "eng", "euler", 1, declared=1, constant=1.0),
                        quantity="orientation")])
    part = observed_order(rep)
    html = "".join(part.html)
    assert "Observed order of convergence" in html
    assert "3.00 (2.00 to 4.00)" in html and "below declared (on ball)" in html  # rk4: 3 pairs each case
    assert "1.00 (1.00 to 1.00)" in html and "ball, hinge" in html
    assert "1 flagged: eng rk4" in html
    assert not observed_order(SimpleNamespace(found=[]))  # nothing to pair: no section


def test_a_real_matrix_shows_rk4_fourth_order_and_euler_first(tmp_path):
    """The reference engine's classical RK4 and symplectic Euler on the free top at 1e-2 and 5e-3 s."""
    from dalembert.reports.findings import find
    from stores import small_store

    store = small_store(tmp_path / "s", cases=("free_top",), integrators=("rk4", "euler"), dts=(1e-2, 5e-3))
    f = find(store)
    found = {o.integrator: o for o in observed_orders(step_pairs((x.case, x.runs, x.quantity) for x in f))}
    assert math.isclose(found["rk4"].median, 4.0, abs_tol=0.1) and math.isclose(found["euler"].median, 1.0, abs_tol=0.1)
