"""ContactBench's residuals (``dalembert.contact_residuals``) on hand-made forces and velocities whose residuals are
known: zero for a complementary pair (sticking inside the cone, sliding at the cone's edge against the slip,
resting with no normal speed), the value worked out by hand for a violated one; and the not-measured path: a run
whose engine reports no contact force has no residual, and its judgement says so instead of counting it within."""

import math

import numpy as np
import pytest

from dalembert import contact, contact_residuals, invariants
from dalembert.case import Tolerance, make_case
from dalembert.contact_residuals import friction_cone, max_dissipation, pair_residuals, residual_metrics, signorini
from dalembert.judge import judge
from dalembert.trajectory import BodyStates, Trajectory

MU = 0.5
LOAD = 10.0  # N
# Exact for these inputs (small integers and halves): products and sums of them round to nothing.
EXACT = 0.0


def test_a_complementary_contact_has_no_residual():
    # sticking: no slip, friction inside the cone (3 N < mu 10 N), no normal speed
    lam_n, lam_t, v_n, v_t = np.array([LOAD]), np.array([[3.0, 0.0]]), np.array([0.0]), np.array([[0.0, 0.0]])
    assert signorini(lam_n, v_n)[0] == EXACT
    assert friction_cone(lam_n, lam_t, MU)[0] == EXACT
    assert max_dissipation(lam_n, lam_t, v_t, MU)[0] == EXACT
    # sliding at 2 m/s along x: friction mu N against the slip, on the cone's edge
    lam_t, v_t = np.array([[-MU * LOAD, 0.0]]), np.array([[2.0, 0.0]])
    assert friction_cone(lam_n, lam_t, MU)[0] == EXACT
    assert max_dissipation(lam_n, lam_t, v_t, MU)[0] == EXACT
    # separating with no force: Signorini's other branch
    assert signorini(np.array([0.0]), np.array([3.0]))[0] == EXACT


def test_a_violated_contact_has_the_residual_worked_out_by_hand():
    lam_n = np.array([LOAD])
    # pushing while leaving at 0.5 m/s: |10 * 0.5| = 5 W
    assert signorini(lam_n, np.array([0.5]))[0] == 5.0
    # friction 8 N where the cone allows 5 N: 3 N outside it
    assert friction_cone(lam_n, np.array([[8.0, 0.0]]), MU)[0] == 3.0
    # a pulling contact is outside the cone even without friction: 2 N
    assert friction_cone(np.array([-2.0]), np.array([[0.0, 0.0]]), 0.0)[0] == 2.0
    # sliding at 2 m/s with friction 3 N against it, short of mu N = 5 N: -3 * 2 + 5 * 2 = 4 W
    assert max_dissipation(lam_n, np.array([[-3.0, 0.0]]), np.array([[2.0, 0.0]]), MU)[0] == 4.0
    # friction at the cone's edge but along the slip, not against it: 5 * 2 + 5 * 2 = 20 W
    assert max_dissipation(lam_n, np.array([[5.0, 0.0]]), np.array([[2.0, 0.0]]), MU)[0] == 20.0
    # at the edge but at right angles to the slip: 0 + 5 * 2 = 10 W
    assert max_dissipation(lam_n, np.array([[0.0, 5.0]]), np.array([[2.0, 0.0]]), MU)[0] == 10.0


def _ball_on_ground(force, velocity, spin=(0.0, 0.0, 0.0)):
    """A ``ball_slide_to_roll`` scene and a two-sample trajectory of its ball at rest height with the given COM
    ``velocity`` and ``spin`` (world), the engine's contact force ``force`` (world, on the ball) or none."""
    case = make_case("ball_slide_to_roll")
    n = 2
    ball = BodyStates(np.tile([0.0, 0.0, 0.1], (n, 1)), np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
                      np.tile(velocity, (n, 1)), np.tile(spin, (n, 1)))
    extras = {} if force is None else {contact.FORCE_PREFIX + case.scene.contacts[0].name: np.tile(force, (n, 1))}
    return case, Trajectory(np.array([0.0, 0.01]), {"ball": ball}, extras=extras)


def test_a_trajectory_feeds_the_residuals_from_its_force_and_its_contact_point_velocity():
    # the ball (mu 0.1, radius 0.1) slides at 2 m/s along x and spins at 5 rad/s about y: its contact point slips
    # at 2 - 5 * 0.1 = 1.5 m/s; the engine's force: 9.81 N up, 0.5 N of friction against the slip; no normal speed
    case, traj = _ball_on_ground([-0.5, 0.0, 9.81], [2.0, 0.0, 0.0], [0.0, 5.0, 0.0])
    found = pair_residuals(case.scene, case.scene.contacts[0], traj)
    assert found["signorini_residual"] == pytest.approx([0.0, 0.0], abs=1e-15)
    assert found["cone_residual"] == pytest.approx([0.0, 0.0], abs=1e-15)  # 0.5 N < 0.981 N
    # -0.5 * 1.5 + 0.1 * 9.81 * 1.5 = 0.7215 W
    assert found["dissipation_residual"] == pytest.approx([0.7215, 0.7215], rel=1e-12)


def test_an_engine_without_contact_forces_is_not_measured_never_within():
    case, traj = _ball_on_ground(None, [1.0, 0.0, 0.0])
    assert pair_residuals(case.scene, case.scene.contacts[0], traj) is None
    metrics = {m.name: m for m in case.invariants}
    assert metrics["signorini_residual"].drift(case.scene, traj) is None
    assert metrics["normal_force_error"].drift(case.scene, traj) is None
    drifts = invariants.summary(case.scene, traj, case.conserved, case.invariants).drifts
    assert not set(contact_residuals.RESIDUALS) & set(drifts) and "normal_force_error" not in drifts
    assert "penetration" in drifts  # measured from the states alone
    # judged on the penetration (0 here: within) and the residuals (not measured)
    bounds = {k: case.tolerances[k] for k in ("penetration", *contact_residuals.RESIDUALS)}
    verdict = judge("ok", "", {}, drifts, bounds)
    assert verdict.within_tolerance is None and verdict.beyond == ()
    assert set(verdict.not_measured) == set(contact_residuals.RESIDUALS)


def test_the_residual_metrics_need_a_bound_for_each():
    bounds = {name: Tolerance(1e-3, "test bound") for name in contact_residuals.RESIDUALS}
    assert [m.name for m in residual_metrics(0, LOAD, bounds)] == list(contact_residuals.RESIDUALS)
    del bounds["cone_residual"]
    with pytest.raises(ValueError, match=r"residual_metrics\.tolerances: .*missing \['cone_residual'\]"):
        residual_metrics(0, LOAD, bounds)


def test_the_closed_forms_contact_forces_have_no_residual():
    # the truth of each contact case that carries its contact force: sticking, sliding, rolling
    for name, params in (("block_on_incline", {}), ("block_on_incline", dict(v0=1.0)),
                         ("block_on_incline", dict(angle=math.radians(40.0), v0=0.5)),
                         ("ball_slide_to_roll", {}), ("ball_slide_to_roll", dict(v0=-1.0, omega0=3.0)),
                         ("ball_rolling_incline", {})):
        case = make_case(name, **params)
        truth = case.exact(case.times)
        found = pair_residuals(case.scene, case.scene.contacts[0], truth)
        for residual, values in found.items():
            assert np.max(values) < 1e-12 * case.scene.bodies[0].mass * 9.81, (name, params, residual)
