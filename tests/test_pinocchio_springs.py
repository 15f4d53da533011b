"""Pinocchio's spring-dampers (``adapters/pinocchio/springs.py``): the single-body oscillators against their closed
forms (the scenes and closed forms of tests/test_springs.py), two bodies on a spring against the reduced-mass
closed form, the off-centre spring on a tumbling box against the reference solver, Andrews' squeezer against the
Test Set's own equations (``andrews_test_set``), and the audit's identification of each spring from the engine's
dynamics."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from installed import needs

pytestmark = needs("pinocchio")

import andrews_test_set as test_set  # noqa: E402
from dalembert import spatial  # noqa: E402
from dalembert.adapters.registry import get_adapter  # noqa: E402
from dalembert.case import make_case  # noqa: E402
from dalembert.cases.andrews_squeezer import ANGLES, INITIAL_ANGLES, PARAMETERS, REFERENCE_T  # noqa: E402
from dalembert.reference import simulate  # noqa: E402
from dalembert.scene import Joint, Scene, Spring  # noqa: E402
from dalembert.settings import Settings  # noqa: E402
from test_springs import (DAMPING, GRAVITY, MASS, ORDER_RATIO, POSITION_TOL, REST, STEPS, STIFFNESS,  # noqa: E402
                          STRETCH, TIMES, _box, _damped_stretch, _oscillator)

ADAPTER = get_adapter("pinocchio")
LOOPS = ("native", "python")

# Semi-implicit Euler halving its step: a first-order error halves (measured 2.00 on both oscillators at dt = 1e-3
# and 5e-4: 7.5e-4 and 3.8e-4 m).
FIRST_ORDER_RATIO = (1.8, 2.2)
EULER_STEPS = (1e-3, 5e-4)
# Adaptive at rtol = atol = 1e-9, one solver over the horizon (steps set by the tolerance, not by the 0.01-s
# samples): measured rk45 4.0e-9 m and dop853 4.1e-9 m on the undamped oscillator (2.2e-9 and 2.5e-9 m damped):
# the global error of local error control, a few rtol; ~2.5x the worst. (Restarted at every sample, as before,
# the sample interval was their step: 9.1e-12 and 1.1e-15 m, whatever the tolerance.)
ADAPTIVE_RTOL = 1e-9
ADAPTIVE_TOL = 1e-8
# The force stays on the spring's line (here the z axis): the sideways position is exactly zero (measured 0.0).
SIDEWAYS_TOL = 1e-15
# The compiled and the Python loops run the same arithmetic (no fused multiply-add: native.FLAGS): measured
# 1.1e-15 to 3.4e-15 m and 3.3e-15 in the quaternion on the tumbling box over 2 s at dt = 1e-3.
LOOPS_AGREE_TOL = 1e-13
# The tumbling box (off-centre spring) with rk4 at dt = 1e-3 against the reference's DOP853 at rtol 1e-12
# (an independent formulation, Newton-Euler in body states, converged far below these): measured 7.3e-11 m,
# 3.7e-9 rad/s and 6.9e-10 rad of attitude at dt = 1e-3 (4.8e-8 m, 2.4e-6 rad/s, 4.7e-7 rad at dt = 5e-3 and
# 2.9e-9 m, 1.5e-7 rad/s, 2.8e-8 rad at 2.5e-3: fourth order); the bounds leave the machine a factor ~3-7.
TUMBLING_DT = 1e-3
TUMBLING_REF_RTOL = 1e-12
TUMBLING_POSITION_TOL = 5e-10     # m
TUMBLING_RATE_TOL = 2e-8          # rad/s
TUMBLING_ATTITUDE_TOL = 2e-9      # rad
# The audit's identification (springs.identify) from generalized forces at two lengths and a rate: exact up to
# roundoff in M a (measured within 1e-13 of the scene's stiffness, damping and rest length, relative; the part of
# the force off the spring's line 1.5e-16); a spring wrong at any of them, or off its line, misses by O(1).
IDENTIFY_REL_TOL = 1e-9
LINE_RESIDUAL_TOL = 1e-12
# Andrews' squeezer over its 30 ms against the Test Set's own equations (DOP853 at 1e-13; they agree with the
# case's truth to 5e-11 rad, tests/test_andrews_squeezer.py). Measured, largest angle error over the samples:
# dop853 at rtol 1e-11: 2.7e-12 rad (rates 1.4e-9 rad/s of 1424, loop forces 6.7e-12 of 199 N); rk4 at dt =
# 2e-5 / 1e-5: 7.1e-8 / 4.4e-9 rad (16.4-fold: fourth order), loop forces 2.9e-8 / 1.8e-9 relative.
SQUEEZER_RTOL = 1e-11
SQUEEZER_ADAPTIVE_ANGLE_TOL = 2e-11     # rad
SQUEEZER_ADAPTIVE_RATE_TOL = 1e-8       # rad/s
SQUEEZER_STEPS = (2e-5, 1e-5)
SQUEEZER_RK4_ANGLE_TOL = 1e-8           # rad, dt = 1e-5
# The loops' forces (N) against the Test Set's multipliers, relative to the largest (199 N): measured above.
SQUEEZER_FORCE_REL_TOL = {"dop853": 5e-11, "rk4": 5e-9}
TEST_SET_RTOL = 1e-13


def _run(scene, times, settings):
    ADAPTER.check(scene, times, settings)
    assert ADAPTER.unsupported(scene, settings) is None
    prepared = ADAPTER.prepare(scene, times, settings)
    outcome = ADAPTER.run(prepared)
    return prepared, outcome


def _exact_z(damping, gravity):
    return -(REST + MASS * gravity / STIFFNESS + _damped_stretch(TIMES, damping))


def _z_error(damping, gravity, settings):
    _, outcome = _run(_oscillator(damping, gravity), TIMES, settings)
    position = outcome.trajectory.bodies["b"].position
    assert np.abs(position[:, :2]).max() <= SIDEWAYS_TOL
    return np.abs(position[:, 2] - _exact_z(damping, gravity)).max(), outcome


@pytest.mark.parametrize("loop", LOOPS)
@pytest.mark.parametrize("damping,gravity", [(0.0, 0.0), (DAMPING, GRAVITY)])
def test_oscillator_rk4_converges_to_its_closed_form_at_fourth_order(damping, gravity, loop):
    runs = [_z_error(damping, gravity, Settings("rk4", dt=dt, options={"loop": loop})) for dt in STEPS]
    errors = [e for e, _ in runs]
    assert runs[0][1].info["loop"].startswith("C++" if loop == "native" else "Python")
    assert ORDER_RATIO[0] < errors[0] / errors[1] < ORDER_RATIO[1], errors
    assert errors[1] < POSITION_TOL


@pytest.mark.parametrize("damping,gravity", [(0.0, 0.0), (DAMPING, GRAVITY)])
def test_oscillator_euler_converges_at_first_order(damping, gravity):
    errors = [_z_error(damping, gravity, Settings("euler", dt=dt))[0] for dt in EULER_STEPS]
    assert FIRST_ORDER_RATIO[0] < errors[0] / errors[1] < FIRST_ORDER_RATIO[1], errors


@pytest.mark.parametrize("method", ["rk45", "dop853"])
@pytest.mark.parametrize("damping,gravity", [(0.0, 0.0), (DAMPING, GRAVITY)])
def test_oscillator_adaptive_integrators_meet_the_closed_form(damping, gravity, method):
    error, _ = _z_error(damping, gravity, Settings(method, rtol=ADAPTIVE_RTOL, atol=ADAPTIVE_RTOL))
    assert error < ADAPTIVE_TOL


def test_two_bodies_oscillate_at_the_reduced_mass_frequency():
    """The spring between two free bodies (both ends on joints that move): the separation is
    REST + STRETCH cos(sqrt(k / mu) t), mu = m1 m2 / (m1 + m2) (as tests/test_springs.py checks the reference)."""
    m1, m2 = 2.0, 3.0
    scene = Scene("pair", [_box("a", m1), _box("b", m2)],
                  [Joint("free", "world", "a", q0=[0, 0, 0, 1, 0, 0, 0], v0=[0, 0.1, 0, 0, 0, 0]),
                   Joint("free", "world", "b", q0=[REST + STRETCH, 0, 0, 1, 0, 0, 0], v0=[0, 0.1, 0, 0, 0, 0])],
                  [0, 0, 0], springs=[Spring("a", "b", stiffness=STIFFNESS, rest_length=REST)])
    _, outcome = _run(scene, TIMES, Settings("rk4", dt=STEPS[1]))
    bodies = outcome.trajectory.bodies
    separation = bodies["b"].position[:, 0] - bodies["a"].position[:, 0]
    omega = np.sqrt(STIFFNESS * (m1 + m2) / (m1 * m2))
    assert np.abs(separation - (REST + STRETCH * np.cos(omega * TIMES))).max() < POSITION_TOL


def _tumbling_box():
    return _oscillator(point_b=(0.05, 0.1, 0.15), w0=(1.0, -2.0, 3.0))


def _attitude_error(q1, q2):
    """The largest angle (rad) between two nearby attitudes (n, 4), scalar first, each normalised first: the sine
    from the skew part of ``R1^T R2`` (the arccos of its trace loses half the digits near zero)."""
    R1 = spatial.quat_to_matrix(spatial.quat_normalize(q1))
    R2 = spatial.quat_to_matrix(spatial.quat_normalize(q2))
    R = np.einsum("nji,njk->nik", R1, R2)
    axial = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], axis=1)
    return np.arcsin(np.minimum(np.linalg.norm(axial, axis=1) / 2.0, 1.0)).max()


def test_off_centre_spring_on_a_tumbling_box_against_the_reference():
    """The lever of the spring's force (its end off the COM) turns the box: position, attitude and angular velocity
    against the reference solver at tight tolerance."""
    scene = _tumbling_box()
    ref = simulate(scene, TIMES, Settings("dop853", rtol=TUMBLING_REF_RTOL, atol=TUMBLING_REF_RTOL))[0].bodies["b"]
    _, outcome = _run(scene, TIMES, Settings("rk4", dt=TUMBLING_DT))
    got = outcome.trajectory.bodies["b"]
    assert np.abs(got.position - ref.position).max() < TUMBLING_POSITION_TOL
    assert np.abs(got.angular_velocity - ref.angular_velocity).max() < TUMBLING_RATE_TOL
    assert _attitude_error(got.quaternion, ref.quaternion) < TUMBLING_ATTITUDE_TOL
    # and the box does tumble: the spring's moment is not negligible
    assert np.abs(got.angular_velocity - got.angular_velocity[0]).max() > 1.0


@pytest.mark.parametrize("method", ["euler", "rk4", "rk4-naive"])
def test_the_compiled_loop_applies_the_springs_as_the_python_loop(method):
    scene = _tumbling_box()
    a = _run(scene, TIMES, Settings(method, dt=TUMBLING_DT))[1]
    b = _run(scene, TIMES, Settings(method, dt=TUMBLING_DT, options={"loop": "python"}))[1]
    assert a.info["loop"].startswith("C++") and b.info["loop"].startswith("Python")
    A, B = a.trajectory.bodies["b"], b.trajectory.bodies["b"]
    assert np.abs(A.position - B.position).max() < LOOPS_AGREE_TOL
    assert np.abs(A.quaternion - B.quaternion).max() < LOOPS_AGREE_TOL


def _assert_identified(audit, scene):
    for sp in scene.springs:
        found = audit["springs"][sp.name]
        for name in ("stiffness", "damping", "rest_length"):
            want = getattr(sp, name)
            assert abs(found[name] - want) <= IDENTIFY_REL_TOL * max(abs(want), 1.0), (name, found, want)
        assert found["line_residual"] < LINE_RESIDUAL_TOL


@pytest.mark.parametrize("settings,source", [
    (Settings("rk4", dt=1e-2), "compiled right-hand side"),
    (Settings("rk4", dt=1e-2, options={"loop": "python"}), "Python right-hand side"),
    (Settings("dop853", rtol=1e-6, atol=1e-6), "Python right-hand side")])
def test_audit_identifies_each_spring_from_the_engines_dynamics(settings, source):
    scene = _oscillator(DAMPING, GRAVITY, point_b=(0.05, 0.1, 0.15), w0=(1.0, -2.0, 3.0))
    prepared, outcome = _run(scene, TIMES[:3], settings)
    audit = ADAPTER.audit(prepared, outcome)
    assert source in audit["springs_identified_from"]
    _assert_identified(audit, scene)
    frames = audit["springs"]["spring_world_b"]["frames"]
    assert frames == {"a": "spring_world_b:a on joint 'universe' at [0.0, 0.0, 0.0] m",
                      "b": "spring_world_b:b on joint 'b' at [0.05, 0.1, 0.15] m"}
    assert audit["external_forces_per_evaluation"] == ["spring_damper spring_world_b: frames spring_world_b:a -> "
                                                       "spring_world_b:b"]
    # no passive effect of Pinocchio's joints came with the springs
    assert audit["joint_passive_effects"] == {"damping": 0.0, "friction": 0.0, "armature": 0.0, "rotorInertia": 0.0}


def test_audit_identification_sees_a_spring_the_engine_applies_wrongly():
    """The identification reads the forces the right-hand side computes, not the scene: an element built with a
    doubled stiffness and its end moved off its frame is caught (a test that can fail)."""
    scene = _oscillator(DAMPING, GRAVITY, point_b=(0.05, 0.1, 0.15))
    prepared, outcome = _run(scene, TIMES[:3], Settings("rk4", dt=1e-2, options={"loop": "python"}))
    pm = prepared.pm
    el = pm.springs[0]
    pm.springs = (dataclasses.replace(el, stiffness=2.0 * el.stiffness),)
    found = ADAPTER.audit(prepared, outcome)["springs"][el.name]
    assert found["stiffness"] == pytest.approx(2.0 * STIFFNESS, rel=IDENTIFY_REL_TOL)
    pm.springs = (dataclasses.replace(el, p_b=el.p_b + np.array([0.0, 0.0, 0.1])),)
    assert ADAPTER.audit(prepared, outcome)["springs"][el.name]["line_residual"] > 1e-3


def test_welds_as_constraints_with_springs_are_refused_with_the_reason():
    scene = _oscillator()
    welded = Scene("welded", [*scene.bodies, _box("c")], [*scene.joints, Joint("weld", "b", "c",
                                                                              parent_point=(0, 0, 0.5))],
                   scene.gravity, springs=scene.springs)
    reason = ADAPTER.unsupported(welded, Settings("rk4", dt=1e-2, options={"welds": "constraint"}))
    assert reason.startswith("welds=constraint with spring-dampers") and "use welds=tree" in reason
    assert ADAPTER.unsupported(welded, Settings("rk4", dt=1e-2)) is None


# ---------------------------------------------------------------- Andrews' squeezer
@pytest.fixture(scope="module")
def squeezer():
    """The case, and the Test Set's own equations' motion and multipliers at its samples."""
    c = make_case("andrews_squeezer")
    Q, V = test_set.integrate(np.array(list(INITIAL_ANGLES.values())), c.times, PARAMETERS, TEST_SET_RTOL)
    lam = np.array([test_set.accelerations(q, v, PARAMETERS)[1] for q, v in zip(Q, V)])
    return c, Q, V, lam


def _squeezer_errors(squeezer, settings):
    """``(angle error (rad), rate error (rad/s), loop force error relative to the largest, audit)``: largest over
    the samples."""
    c, Q, V, lam = squeezer
    prepared, outcome = _run(c.scene, c.times, settings)
    traj = outcome.trajectory
    angles = np.stack([traj.joints[body].q[:, 0] for body in ANGLES.values()], axis=1)
    rates = np.stack([traj.joints[body].v[:, 0] for body in ANGLES.values()], axis=1)
    forces = np.concatenate([traj.extras[f"reaction_force:E_body{k}"][:, :2] for k in (3, 4, 6)], axis=1)
    assert traj.t[-1] == REFERENCE_T
    return (np.abs(angles - Q).max(), np.abs(rates - V).max(), np.abs(forces - lam).max() / np.abs(lam).max(),
            ADAPTER.audit(prepared, outcome))


def test_squeezer_dop853_meets_the_test_sets_equations(squeezer):
    angle, rate, force, audit = _squeezer_errors(squeezer, Settings("dop853", rtol=SQUEEZER_RTOL, atol=SQUEEZER_RTOL))
    assert angle < SQUEEZER_ADAPTIVE_ANGLE_TOL and rate < SQUEEZER_ADAPTIVE_RATE_TOL
    assert force < SQUEEZER_FORCE_REL_TOL["dop853"]
    assert "constraintDynamics" in audit["springs_identified_from"]
    _assert_identified(audit, squeezer[0].scene)


def test_squeezer_rk4_converges_at_fourth_order(squeezer):
    runs = [_squeezer_errors(squeezer, Settings("rk4", dt=dt)) for dt in SQUEEZER_STEPS]
    angles = [r[0] for r in runs]
    assert ORDER_RATIO[0] < angles[0] / angles[1] < ORDER_RATIO[1], angles
    assert angles[1] < SQUEEZER_RK4_ANGLE_TOL
    assert runs[1][2] < SQUEEZER_FORCE_REL_TOL["rk4"]
    assert runs[1][3]["loop"].startswith("Python (constraint dynamics")
