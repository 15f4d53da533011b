"""DART's loop closures (``adapters/dart/loops.py``): ball and revolute joint constraints, distance refused."""

import numpy as np
import pytest

from dalembert import Settings, make_case, spatial
from dalembert.adapters import get_adapter
from dalembert.errors import trajectory_errors
from dalembert.scene import Body, Joint, Loop, Scene
from installed import needs

pytestmark = needs("dartpy")

ADAPTER = get_adapter("dart")

# The four-bar (canonical) at dt = 1e-3 over 0.5 s against its closed form: measured 3.0e-6 rad on the angles and
# 5.9e-3 m/s on the velocities (3.0e-8 rad and 5.9e-4 m/s at dt = 1e-4): semi-implicit Euler's first order
# in the velocities, the closure held by DART's velocity-level rows with its error reduction; 3x the angles'.
FOUR_BAR_ANGLE_TOL = 1e-5
# The four-bar's reactions (crank, coupler, rocker joints and the loop C) relative to the largest true reaction,
# modulo the closed form's self-stress: measured 3.6e-2 at dt = 1e-3 (the largest near a singular position) and
# 2.3e-4 at 1e-4; 3x and 4x. Read from forward dynamics alone, without the step, there is no loop force (measured:
# NaN, the test fails), and with the loop force's sign flipped the test fails too.
FOUR_BAR_REACTION_TOL = {1e-3: 0.1, 1e-4: 1e-3}
# A body on a free joint held to the world by a revolute constraint against the same body on a revolute joint,
# dt = 1e-3 over 1 s: the constraint's first-order error, measured 2.4e-4 m (0.36 m with the axes given in body
# coordinates); 4x.
CONSTRAINT_AS_JOINT_TOL = 1e-3


def test_the_four_bar_closes_with_a_revolute_constraint_and_converges():
    case = make_case("four_bar")
    exact = case.exact(case.times)
    coarse, fine = (trajectory_errors(ADAPTER.run(ADAPTER.prepare(case.scene, case.times, Settings("euler", dt=dt)))
                                      .trajectory, exact) for dt in (1e-3, 1e-4))
    assert coarse["joint"][0] < FOUR_BAR_ANGLE_TOL
    assert coarse["velocity"][0] / fine["velocity"][0] == pytest.approx(10.0, rel=0.05)  # first order
    # every joint's and the loop's reaction, from one step at each sample (readback): relative to the largest
    assert coarse["reaction_force"][0] < FOUR_BAR_REACTION_TOL[1e-3] and fine["reaction_force"][0] < FOUR_BAR_REACTION_TOL[1e-4]


def test_the_audit_reads_the_constraints_back():
    case = make_case("four_bar", t_final=0.1)
    prepared = ADAPTER.prepare(case.scene, case.times, Settings("euler", dt=1e-2))
    audit = ADAPTER.audit(prepared, ADAPTER.run(prepared))
    assert audit["loops"] == {"C": "RevoluteJointConstraint, 5 rows"} and audit["constraints"] == 1
    assert audit["loop_parameters"]["error_reduction_parameter"] > 0.0
    assert audit["lcp_solvers"][0] == "DantzigBoxedLcpSolver" and "Newton" in audit["reactions"]


def _hinged(loop):
    """A body off its COM about a world axis: on a revolute joint (``loop`` False), or free and held by a
    revolute loop to the world (True); its frame turned, so body and world axes differ."""
    R0 = spatial.so3_exp([0.3, -0.5, 0.7])
    body = Body("b", 1.0, np.diag([0.1, 0.2, 0.3]))
    pivot, com, axis = np.array([0.0, 0.0, 1.0]), np.array([0.4, 0.0, -0.3]), np.array([0.0, 1.0, 0.0])
    com = pivot + com
    if not loop:
        joint = Joint("revolute", "world", "b", (0.0,), (0.0,), axis=tuple(axis), parent_point=tuple(pivot),
                      child_point=tuple(R0.T @ (pivot - com)), child_quat=tuple(spatial.matrix_to_quat(R0.T)))
        return Scene("hinge", (body,), (joint,), (0.0, 0.0, -9.81))
    free = Joint("free", "world", "b", (*com, *spatial.matrix_to_quat(R0)), (0.0,) * 6)
    hinge = Loop("revolute", "world", "b", point_a=tuple(pivot), point_b=tuple(R0.T @ (pivot - com)),
                 quat_b=tuple(spatial.matrix_to_quat(R0.T)), axis=tuple(axis))
    return Scene("hinge_loop", (body,), (free,), (0.0, 0.0, -9.81), loops=(hinge,))


def test_a_revolute_constraint_to_the_world_swings_as_a_revolute_joint():
    times, s = np.linspace(0.0, 1.0, 11), Settings("euler", dt=1e-3)
    joint, loop = (ADAPTER.run(ADAPTER.prepare(_hinged(k), times, s)).trajectory.bodies["b"] for k in (False, True))
    assert np.abs(loop.position - joint.position).max() < CONSTRAINT_AS_JOINT_TOL
    assert np.abs(joint.position[-1] - joint.position[0]).max() > 0.1  # it swings


def test_a_distance_loop_is_refused_with_the_reason():
    rod = Body.cylinder("rod", 1.0, 1.0, 0.01, axis=2)
    scene = Scene("tethered", (rod,), (Joint("revolute", "world", "rod", (0.0,), (0.0,), axis=(0, 1, 0),
                                             child_point=(0.0, 0.0, 0.5)),),
                  (0.0, 0.0, -9.81), loops=(Loop("distance", "world", "rod", point_a=(1.0, 0.0, -1.0),
                                                 point_b=(0.0, 0.0, -0.5), length=1.0),))
    reason = ADAPTER.unsupported(scene, Settings("euler", dt=1e-3))
    assert "loop:distance" in reason and "no distance constraint" in reason


def test_the_four_bar_s_constraint_blows_up_at_small_steps_and_the_run_says_so():
    """A finding, kept visible: DART 6.20's revolute constraint on the (planar, so redundant) four-bar loop runs at
    dt >= 5e-5 and turns non-finite within the first 0.01 s at dt <= 2e-5 (measured at 2e-5, 1.25e-5, 1e-5);
    DART warns and steps on with an identity transform, and the run is NaN from that sample with DART's message."""
    case = make_case("four_bar", t_final=0.02)
    outcome = ADAPTER.run(ADAPTER.prepare(case.scene, case.times, Settings("euler", dt=1e-5)))
    assert outcome.trajectory.first_nonfinite_time() == pytest.approx(0.01)
    assert outcome.info["message"].startswith("DART: Warning") and "Non-finite" in outcome.info["message"]
