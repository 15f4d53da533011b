"""The Kovalevskaya top: its truth (the reference) against a 40-digit Taylor integration, and its four
integrals on that truth."""

import numpy as np

from dalembert import invariants, make_case, spatial
from dalembert.cases._fixed_point import inertia_about_pivot
from dalembert.reference import truth
from taylor import integrate_body_on_pivot

# rad over 10 s: the truth is DOP853 at rtol = atol = 1e-12; 100x that for the global error local control
# lets accumulate (measured 1.3e-11 rad at 10 s; 2.1e-9 rad over the case's 100 s, once)
TRUTH_TOL = 1e-10


def test_truth_against_40_digit_taylor_integration():
    case = make_case("kovalevskaya_top", t_final=10.0, sample_interval=2.0)
    joint, body = case.scene.joints[0], case.scene.bodies[0]
    c_B = -np.array(joint.child_point)
    q, w, _ = integrate_body_on_pivot(inertia_about_pivot(body, c_B), body.mass * 9.81 * c_B, [0, 0, 1], joint.v0,
                                      joint.q0, case.times, 5.0)
    tr = truth(case).bodies["top"]
    assert np.max(spatial.rotation_angle(tr.quaternion, q)) < TRUTH_TOL
    assert np.max(np.abs(tr.angular_velocity_body - w)) < TRUTH_TOL * 5.0  # rad/s at rates up to ~5 rad/s


def test_the_moments_and_the_centre_of_mass_are_kovalevskayas():
    """Principal moments (2C, 2C, C) about the fixed point, the centre of mass in the plane of the equal ones."""
    case = make_case("kovalevskaya_top")
    body, c_B = case.scene.bodies[0], -np.array(case.scene.joints[0].child_point)
    assert np.allclose(inertia_about_pivot(body, c_B), np.diag([2.0, 2.0, 1.0]), atol=1e-15)
    assert c_B[2] == 0.0 and c_B[0] != 0.0


def test_all_four_integrals_hold_on_the_truth_and_one_breaks_when_spoiled():
    case = make_case("kovalevskaya_top", t_final=10.0)
    tr = truth(case)
    drifts = invariants.summary(case.scene, tr, case.conserved, case.invariants).drifts
    assert set(drifts) == {"energy", "vertical_angular_momentum", "vertical_norm", "kovalevskaya_integral"}
    assert max(drifts.values()) < 1e-10
    # Kovalevskaya's integral is not a consequence of the other three: a top with the moments off by 1%
    # (no longer integrable) keeps those three but not it
    from dalembert.scene import Body, Scene
    b = case.scene.bodies[0]
    spoiled = Scene("spoiled", [Body("top", b.mass, b.inertia_matrix * np.array([1.0, 1.01, 1.0]))],
                    case.scene.joints, case.scene.gravity)
    from dalembert import Settings
    from dalembert.reference import simulate
    other = simulate(spoiled, case.times, Settings("dop853", rtol=1e-12, atol=1e-12))[0]
    k = next(i for i in case.invariants if i.name == "kovalevskaya_integral")
    assert invariants.drift("energy", spoiled, other) < 1e-10
    assert k.drift(spoiled, other) > 1e-4
