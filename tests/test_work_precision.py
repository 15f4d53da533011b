"""A run's figures as the report's sections read them: ``figure_reader`` (a case's metric looked up once) reads
what ``figure_of`` reads, and ``cost_per_sim_s`` (computed once per record) is the median stepping time over the
horizon, NaN where there is no horizon."""

import math
from types import SimpleNamespace

from dalembert.record import Cost, RunRecord
from dalembert.reports.work_precision import cost_per_sim_s, figure_of, figure_reader
from dalembert.settings import Settings
from dalembert.tolerance import InvariantLabel


def _run(wall=0.2, t_final=2.0, errors=None, drifts=None):
    return RunRecord(key="k", case="c", case_version="v", engine="e", settings=Settings("rk4", dt=1e-3), status="ok",
                     t_final=t_final, cost=Cost(wall_s_median=wall), errors=errors or {}, drifts=drifts or {})


def test_cost_per_simulated_second_is_the_median_over_the_horizon_and_nan_without_one():
    assert cost_per_sim_s(_run(wall=0.2, t_final=2.0)) == 0.2 / 2.0
    assert math.isnan(cost_per_sim_s(_run(t_final=0.0)))
    assert math.isnan(cost_per_sim_s(_run(t_final=math.nan)))
    assert math.isnan(cost_per_sim_s(_run(wall=math.nan)))


def test_the_figure_reader_reads_an_error_a_metric_in_its_unit_and_nan_where_none_is_stored():
    creep = InvariantLabel("creep", "slip speed while the closed form sticks", "m/s", 0.5, kind="metric")
    case = SimpleNamespace(invariants=(creep,))
    run = _run(errors={"position": (3e-4, 1e-4)}, drifts={"creep": 0.25})
    for quantity, expected in (("position", 3e-4), ("creep", 0.25 * 0.5)):
        assert figure_reader(quantity, case)(run) == figure_of(run, quantity, case) == expected
    assert figure_reader("position")(run) == 3e-4  # (no case: an error quantity)
    assert math.isnan(figure_reader("joint", case)(run)) and math.isnan(figure_of(run, "joint", case))
    assert math.isnan(figure_reader("creep", case)(_run()))  # (a metric the run did not store)
