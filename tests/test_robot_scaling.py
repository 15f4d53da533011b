"""Real robots beside the chain: the report's costs against degrees of freedom (reports/scaling.py's
``robot_costs``, the scaling section's robots) and the benchmark's interpolation of the chain's line."""

import math
from types import SimpleNamespace

import pytest
from benchmark_modules import benchmark

from dalembert import Settings
from dalembert.record import Cost, RunRecord
from dalembert.reports import figures
from dalembert.reports.scaling import robot_costs
from dalembert.reports.sections.scaling import scaling
from dalembert.scene import Body, Joint, Scene


def _scene(n, free=False):
    """A chain of ``n`` bodies on revolute joints (a free first body with ``free``): n or n + 5 dof."""
    bodies = [Body(f"b{i}", 1.0, ((0.1, 0, 0), (0, 0.1, 0), (0, 0, 0.1))) for i in range(n)]
    joints = [Joint("free", "world", "b0", q0=(0, 0, 0, 1, 0, 0, 0), v0=(0,) * 6) if free
              else Joint("revolute", "world", "b0", q0=(0.0,), v0=(0.0,), axis=(0, 1, 0))]
    joints += [Joint("revolute", f"b{i - 1}", f"b{i}", q0=(0.0,), v0=(0.0,), axis=(0, 1, 0), parent_point=(0, 0, -0.5))
               for i in range(1, n)]
    return Scene("s", bodies, joints, (0.0, 0.0, -9.81))


CASES = {("robot_arm", "ur5"): SimpleNamespace(tags=("robot",), params={"model": "ur5"}, scene=_scene(6)),
         ("robot_arm", "mine"): SimpleNamespace(tags=("robot",), params={"model": "/home/me/mine.urdf"},
                                                scene=_scene(3)),
         ("robot_free_fall", "v"): SimpleNamespace(tags=("robot",), params={"model": "solo12"},
                                                   scene=_scene(13, free=True)),
         ("chain", "n4"): SimpleNamespace(tags=("jointed",), params={"n": 4}, scene=_scene(4))}


def _record(key, case, version, engine, wall, status="ok", dt=1e-3):
    return RunRecord(key, case, version, engine, Settings("rk4", dt), status=status, t_final=2.0,
                     cost=Cost(wall_s_median=wall))


RECORDS = [_record("a", "robot_arm", "ur5", "mujoco", 0.06), _record("b", "robot_free_fall", "v", "mujoco", 0.2),
           _record("c", "robot_arm", "mine", "mujoco", 0.04), _record("d", "chain", "n4", "mujoco", 0.05),
           _record("e", "robot_arm", "ur5", "mujoco", 0.1, status="diverged"),  # a shorter motion's cost
           _record("f", "robot_arm", "ur5", "mujoco", 0.02, dt=1e-2)]


def test_robot_runs_are_placed_by_their_degrees_of_freedom_per_engine_line():
    found = robot_costs(RECORDS, lambda name, version: CASES[name, version])
    assert found == {("mujoco", "rk4 dt=0.001"): [(3, 0.02, "mine"), (6, 0.03, "ur5"), (18, 0.1, "solo12")],
                     ("mujoco", "rk4 dt=0.01"): [(6, 0.01, "ur5")]}


def _rep(records):
    return SimpleNamespace(records=records, store=SimpleNamespace(case=lambda name, version: CASES[name, version]),
                           colours=figures.engine_colours({r.engine for r in records}))


def test_the_scaling_section_draws_robots_against_dof_and_not_one_robot_alone():
    part = scaling(_rep(RECORDS))
    md = "\n".join(x for x in part.md if isinstance(x, str))
    figures_ = [x for x in part.md if not isinstance(x, str)]
    assert {f.name for f in figures_} == {"robots-scaling"} and "degrees of freedom" in figures_[0].svg
    assert "Real robots: cost against degrees of freedom" in md
    assert "- mujoco rk4 dt=0.001: mine (3 dof) 0.02 s/s, ur5 (6 dof) 0.03 s/s, solo12 (18 dof) 0.1 s/s" in md
    assert not scaling(_rep(RECORDS[:1] + RECORDS[3:4]))  # one robot (the default matrix's UR5): no section


@pytest.fixture()
def bench():
    with benchmark("scaling") as module:
        yield module


def test_the_benchmark_reads_the_chain_s_cost_at_a_robot_s_joints_on_its_log_log_line(bench):
    sizes, costs = [2, 4, 8, 16], [0.01, 0.02, float("nan"), 0.16]
    assert bench.at_size(sizes, costs, 4) == pytest.approx(0.02)
    assert bench.at_size(sizes, costs, 8) == pytest.approx(0.02 * 2 ** 1.5)  # across the size not run: N^1.5
    assert math.isnan(bench.at_size(sizes, costs, 32))  # outside the sizes run: not extrapolated
