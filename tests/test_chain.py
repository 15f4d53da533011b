"""The chain: its truth (the reference, planar formulation) against a second formulation (Kane's) and,
at small amplitude, against the linearised normal modes; the planar formulation on its own."""

import numpy as np
import pytest

from dalembert import Settings, make_case, spatial
from dalembert.errors import trajectory_errors
from dalembert.reference import simulate, truth, truth_settings
from dalembert.reference.closed_form import NormalModes, rod_chain_matrices
from dalembert.reference.planar import why_not
from dalembert.scene import Body, Joint, Load, Scene

KANE = Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "kane"})
# Kane's equations by LSODA (a second formulation and a second integrator, the cheaper of Kane's two
# here) against the truth (planar, DOP853), both at rtol = atol = 1e-12.
SECOND = Settings("lsoda", rtol=1e-12, atol=1e-12, options={"formulation": "kane"})
# rad over the chain's 10 s: 1000x the local tolerance, for the global error local control lets a
# multistep method accumulate (measured 6.5e-11 rad; DOP853 on both formulations: 2.1e-11)
FORMULATIONS_TOL = 1e-9
# rad over the chaotic chain's 10 s, where the motion amplifies differences ~1e3 (measured 5.5e-8 rad;
# DOP853 on both: 1.1e-9); the case's own bound is 1e-5 rad
CHAOTIC_FORMULATIONS_TOL = 1e-6


def _joint_angles(traj, n):
    return np.column_stack([traj.joints[f"link{i}"].q[:, 0] for i in range(n)])


def test_chain_truth_is_the_planar_formulation_and_agrees_with_kanes():
    case = make_case("chain", sample_interval=0.1)
    assert truth_settings(case.scene).options == {"formulation": "planar"}
    errors = trajectory_errors(simulate(case.scene, case.times, SECOND)[0], truth(case))
    assert errors["joint"][0] < FORMULATIONS_TOL
    assert errors["orientation"][0] < FORMULATIONS_TOL


def test_chaotic_chain_truth_agrees_with_kanes_over_its_horizon():
    case = make_case("chain_chaotic", sample_interval=0.1)
    errors = trajectory_errors(simulate(case.scene, case.times, SECOND)[0], truth(case))
    assert errors["joint"][0] < CHAOTIC_FORMULATIONS_TOL


@pytest.mark.parametrize("n", [2, 5])
def test_small_amplitude_chain_tends_to_the_normal_modes_as_the_amplitude_cubed(n):
    """The linearised motion (normal modes, closed form) differs from the truth by O(e^3) for joint angles
    e: halving e divides the difference by 8 (the neglected terms of the equations are cubic). Measured
    2.58 e^3 rad (n = 2) and 45.1 e^3 (n = 5) over 5 s; the ratio is 8.00 to three digits."""
    diffs = []
    for eps in (1e-2, 5e-3):
        case = make_case("chain", n=n, angle0=eps, bend0=eps, t_final=5.0, sample_interval=0.05)
        rod = case.scene.bodies[0]
        modes = NormalModes(*rod_chain_matrices(n, rod.mass, 1.0, rod.inertia[2][2], 9.81), np.full(n, eps),
                            np.zeros(n))
        diffs.append(np.max(np.abs(_joint_angles(truth(case), n) - modes.coordinates(case.times))))
    assert diffs[0] / diffs[1] == pytest.approx(8.0, rel=0.01)


def test_planar_formulation_on_a_general_planar_chain_agrees_with_kanes():
    """Links of different shapes, joint frames turned about the axis, centres of mass off the line
    between the joints, gravity with a component along the axes: the planar formulation (absolute
    angles, closed-form Lagrange equations) and Kane's agree, reactions included."""
    axis_tilt = spatial.quat_from_axis_angle([0.0, 0.0, 1.0], 0.4)
    bodies = [Body("a", 1.0, np.diag([0.02, 0.1, 0.11])), Body("b", 0.5, np.diag([0.01, 0.05, 0.04])),
              Body("c", 2.0, np.diag([0.1, 0.2, 0.25]))]
    joints = [Joint("revolute", "world", "a", q0=[0.7], v0=[1.0], axis=[0, 0, 1], parent_point=[0.1, 0.2, 0.3],
                    child_point=[-0.4, 0.05, 0.0]),
              Joint("revolute", "a", "b", q0=[-0.5], v0=[0.5], axis=[0, 0, 2], parent_point=[0.4, -0.05, 0.1],
                    parent_quat=axis_tilt, child_point=[-0.3, 0.0, 0.02]),
              Joint("revolute", "b", "c", q0=[1.2], v0=[-2.0], axis=[0, 0, 1], parent_point=[0.3, 0.1, 0.0],
                    child_quat=axis_tilt, child_point=[-0.2, -0.1, 0.0])]
    scene = Scene("planar", bodies, joints, gravity=(0.0, -9.81, -2.0))
    assert why_not(scene) is None
    times = np.linspace(0.0, 2.0, 21)
    planar = simulate(scene, times, Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "planar"}))[0]
    kane = simulate(scene, times, KANE)[0]
    errors = trajectory_errors(planar, kane)
    # both DOP853 at 1e-12 over 2 s: 100x the local tolerance (measured at most 6.1e-11 m, rad; 1.6e-10 rad/s)
    for quantity in ("position", "orientation", "joint", "reaction_force"):
        assert errors[quantity][0] < 1e-10, (quantity, errors[quantity])
    for quantity in ("velocity", "angular_velocity"):  # m/s, rad/s at rates up to 15 rad/s
        assert errors[quantity][0] < 1e-9, (quantity, errors[quantity])


def test_planar_formulation_names_what_it_cannot_take():
    chain = make_case("chain").scene
    loaded = Scene("x", chain.bodies, chain.joints, chain.gravity, [Load("link0", "torque", [0, 0, 1.0], "body")])
    assert "loads" in why_not(loaded)
    bent = list(chain.joints)
    bent[1] = Joint("revolute", "link0", "link1", q0=[0.0], v0=[0.0], axis=[1.0, 0.0, 0.0],
                    parent_point=[0.5, 0, 0], child_point=[-0.5, 0, 0])
    assert "parallel" in why_not(Scene("x", chain.bodies, bent, chain.gravity))
    assert "revolute" in why_not(make_case("heavy_top").scene)


def test_chain_builds_fast_for_the_scaling_sweep():
    """n = 64 links: the scene is built in one pass (no truth, no floor computed when the case is made)."""
    case = make_case("chain", n=64)
    assert len(case.scene.bodies) == 64 and case.floor() == {} and case.exact is None
