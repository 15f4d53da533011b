"""Drake builds spring-dampers (``dalembert.adapters.drake.springs``): ``LinearSpringDamper`` force elements,
against the oscillators' closed forms (``test_springs``), the reference solver on an off-centre spring, and
Andrews' squeezer's published values (``test_andrews_squeezer``: the Test Set's); its audit reads the springs
back from the plant; a rest length of zero is unsupported."""

from dataclasses import replace

import numpy as np
import pytest

from dalembert import invariants, spatial
from dalembert.adapters import get_adapter
from dalembert.case import make_case
from dalembert.cases.andrews_squeezer import ANGLES, REFERENCE_ANGLES, REFERENCE_T
from dalembert.reference import simulate
from dalembert.scene import Body, Joint, Scene, Spring
from dalembert.settings import Settings
from test_andrews_squeezer import INITIAL_ACCELERATIONS, INITIAL_MULTIPLIERS
from test_springs import MASS, REST, STEPS, STIFFNESS, STRETCH, TIMES, _damped_stretch, _oscillator
from installed import needs

pytestmark = needs("pydrake")

ADAPTER = get_adapter("drake")
OMEGA = np.sqrt(STIFFNESS / MASS)  # rad/s, the oscillators' undamped frequency

# Drake's third-order schemes (RK3, two-stage Radau IIA) halving the step: the error falls 8-fold (measured 8.0 on
# both oscillators, both schemes); a second-order error falls 4-fold, a fourth-order 16-fold, and a wrong stiffness,
# damping or rest length does not converge to the closed form at all.
THIRD_ORDER_RATIO = (6.5, 10.0)
# ... and at dt = 5e-3 they reach (measured: RK3 1.9e-6 / 7.2e-7 m undamped / damped, Radau3 6.2e-7 / 2.4e-7 m):
THIRD_ORDER_TOL = 5e-6  # m
# Discrete mode and semi-explicit Euler are symplectic Euler: on x'' = -w^2 x from rest at amplitude a its orbit is
# the tilted ellipse w^2 x^2 + v^2 - dt w^2 x v = const, reached with a phase offset of w dt / 2, so its largest
# position error is a w dt / 2 to first order; the next terms (the phase drift w^3 dt^2 t / 24, O(dt^2)) add
# 3.3 % at dt = 1e-2 and 1.6 % at 5e-3 over the 2 s (measured). A stiffness 1 % off shifts the phase by 0.05 rad
# over the 2 s: 0.015 m, twice the leading term at dt = 1e-2.
LEADING_TERM_RTOL = 0.05
# Halving the step halves a first-order error (measured 2.03 undamped, 2.01 damped under gravity).
FIRST_ORDER_RATIO = (1.8, 2.3)
# One discrete step, against the explicit formula: a handful of roundoffs of the velocity (~1 m/s).
ONE_STEP_TOL = 1e-12  # m/s
# Two free bodies on a spring, RK3 at dt = 5e-3: separation 5.3e-6 m from the reduced-mass closed form (measured;
# its 6.5 rad/s against the single box's 5 rad/s: an RK3 error ~omega^4 dt^3 t);
# the spring's forces are equal and opposite, so the linear momentum keeps to roundoff (measured ~1e-16 kg m/s).
PAIR_TOL = 1.5e-5  # m
MOMENTUM_TOL = 1e-12  # kg m/s
# The tumbling box hung off-centre (0.05, 0.1, 0.15) m, Drake's RK5 at dt = 1e-3 against the reference's DOP853 at
# rtol 1e-12 (within 4e-11 m of the reference's own RK4 at 1e-3), over 2 s: measured 6.2e-13 m, 1.6e-11 in R_WB,
# 7.9e-11 rad/s. A lever off by a millimetre changes the rotation at O(1e-3).
REFERENCE_RTOL = 1e-12
TUMBLE_POSITION_TOL = 1e-11  # m
TUMBLE_ROTATION_TOL = 2e-10  # entries of R_WB
TUMBLE_RATE_TOL = 1e-9  # rad/s
# Discrete mode on the tumbling box, first order: a decade of dt buys a decade (measured 10.06 from 1e-3 to 1e-4).
DECADE_RATIO = (8.0, 12.0)
# Andrews' squeezer at rest at its initial angles: Drake's mass matrix and loop rows with the generalized force of
# its own force elements (gravity field, the spring) and of the motor, projected onto the rigid loops, against the
# Test Set's 30-digit consistent accelerations and multipliers: one solve in double precision (measured 2.0e-15
# relative; the multipliers 4e-16).
RIGID_ACCELERATION_RTOL = 1e-12
# Drake's own step from that state is not rigid: SAP regularizes each near-rigid constraint by
# beta^2 / (4 pi^2) ~ 2.5e-4 of its Delassus diagonal (loops.py), so a fraction of the spring's pull, which the
# loops hold statically, leaks into the motion: Theta'' is 1.6 % short (measured -10496.9 against -10666.8 rad/s^2,
# 1.98e-2 of the largest, the same at every dt from 1e-3 to 1e-6; 9e-6 without the spring, which leaves nothing to
# hold). The loops' reactions at t = 0 from the step (loops.LoopForces) are 2.6e-3 of the largest off (measured).
SAP_ACCELERATION_RTOL = 3e-2
SAP_MULTIPLIER_RTOL = 1e-2
# The squeezer in discrete mode at dt = 1e-5 (3000 steps): the largest of the seven angles at t = 0.03 s from the
# Test Set's published values (themselves within 1.4e-9 rad of the case's truth), measured 2.7e-4 rad (beta turns
# 16 rad, Theta 16 rad back); 0.12 rad at 1e-4, 1.9e-2 at 5e-5, 7.8e-5 at 1e-6. Over all samples, against the
# case's truth (dalembert run), first order: 0.12 / 2.8e-2 / 5.9e-3 / 6.0e-4 rad at 1e-4 / 5e-5 / 1e-5 / 1e-6, so
# at 0.03 s the error at 1e-5 happens to be 20 times below its largest over the samples. Bound: 3x the measured value.
SQUEEZER_DT = 1e-5  # s
SQUEEZER_ANGLE_TOL = 1e-3  # rad
# The loops' gap there: relaxed over one step, ~dt^2 (measured 1.14e-6 m at dt = 1e-5, 1.1e-8 at 1e-6, the largest
# over the samples).
SQUEEZER_GAP_TOL = 5e-6  # m


def _run(scene, settings, times=TIMES):
    prepared = ADAPTER.prepare(scene, times, settings)
    outcome = ADAPTER.run(prepared)
    return prepared, outcome


def _z_error(scene, settings, damping, gravity):
    exact = -(REST + MASS * gravity / STIFFNESS + _damped_stretch(TIMES, damping))
    traj = _run(scene, settings)[1].trajectory
    assert np.abs(traj.bodies["b"].position[:, :2]).max() == 0.0  # the force stays on the line
    return np.abs(traj.bodies["b"].position[:, 2] - exact).max()


@pytest.mark.parametrize("integrator", ["rk3", "radau3"])
@pytest.mark.parametrize("damping,gravity", [(0.0, 0.0), (2.0, 9.81)])
def test_continuous_oscillators_converge_to_their_closed_forms(integrator, damping, gravity):
    scene = _oscillator(damping, gravity)
    errors = [_z_error(scene, Settings(integrator, dt=dt), damping, gravity) for dt in STEPS]
    assert THIRD_ORDER_RATIO[0] < errors[0] / errors[1] < THIRD_ORDER_RATIO[1], errors
    assert errors[1] < THIRD_ORDER_TOL, errors


@pytest.mark.parametrize("integrator", ["discrete", "semi-explicit-euler"])
def test_discrete_undamped_oscillator_error_is_symplectic_eulers_leading_term(integrator):
    scene = _oscillator()
    for dt in STEPS:
        error = _z_error(scene, Settings(integrator, dt=dt), 0.0, 0.0)
        lead = STRETCH * OMEGA * dt / 2.0
        assert 1.0 <= error / lead < 1.0 + LEADING_TERM_RTOL, (dt, error, lead)


def test_discrete_damped_oscillator_converges_at_first_order():
    scene = _oscillator(2.0, 9.81)
    errors = [_z_error(scene, Settings("discrete", dt=dt), 2.0, 9.81) for dt in STEPS]
    assert FIRST_ORDER_RATIO[0] < errors[0] / errors[1] < FIRST_ORDER_RATIO[1], errors
    assert errors[1] < (1.0 + LEADING_TERM_RTOL) * STRETCH * OMEGA * STEPS[1] / 2.0


@pytest.mark.parametrize("damping", [2.0, 2000.0])
def test_the_discrete_update_takes_spring_and_damper_at_the_steps_start(damping):
    """One step from a moving state: ``v1 = v0 + dt s(q0, v0) / m`` (explicit), not the implicit damper's
    ``(v0 + dt k (l0 - l) / m) / (1 + dt c / m)``; with c = 2000 N s/m the two differ 100-fold (``springs``)."""
    dt, l, rate = 1e-2, REST + STRETCH, 0.5  # s, m, m/s (the box moves away from the world origin along -z)
    scene = Scene("one_step", [Body.box("b", MASS, (0.1, 0.2, 0.3))],
                  [Joint("free", "world", "b", q0=[0, 0, -l, 1, 0, 0, 0], v0=[0, 0, -rate, 0, 0, 0])], [0, 0, 0],
                  springs=[Spring("world", "b", stiffness=STIFFNESS, damping=damping, rest_length=REST)])
    traj = _run(scene, Settings("discrete", dt=dt), times=np.array([0.0, dt]))[1].trajectory
    tension = STIFFNESS * (l - REST) + damping * rate  # N, pulls the box back up (+z)
    explicit = -rate + dt * tension / MASS
    implicit = (-rate + dt * STIFFNESS * (l - REST) / MASS) / (1.0 + dt * damping / MASS)
    v1 = traj.bodies["b"].velocity[1, 2]
    assert abs(v1 - explicit) < ONE_STEP_TOL, (v1, explicit, implicit)
    assert traj.bodies["b"].position[1, 2] == pytest.approx(-l + dt * v1, abs=ONE_STEP_TOL * dt)  # q from v1


def test_two_bodies_oscillate_at_the_reduced_mass_frequency():
    """A spring between two bodies (neither the world): the separation REST + STRETCH cos(sqrt(k / mu) t)."""
    m1, m2 = 2.0, 3.0
    scene = Scene("pair", [Body.box("a", m1, (0.1, 0.2, 0.3)), Body.box("b", m2, (0.1, 0.2, 0.3))],
                  [Joint("free", "world", "a", q0=[0, 0, 0, 1, 0, 0, 0], v0=[0, 0.1, 0, 0, 0, 0]),
                   Joint("free", "world", "b", q0=[REST + STRETCH, 0, 0, 1, 0, 0, 0], v0=[0, 0.1, 0, 0, 0, 0])],
                  [0, 0, 0], springs=[Spring("a", "b", stiffness=STIFFNESS, rest_length=REST)])
    traj = _run(scene, Settings("rk3", dt=STEPS[1]))[1].trajectory
    separation = traj.bodies["b"].position[:, 0] - traj.bodies["a"].position[:, 0]
    omega = np.sqrt(STIFFNESS * (m1 + m2) / (m1 * m2))
    assert np.abs(separation - (REST + STRETCH * np.cos(omega * TIMES))).max() < PAIR_TOL
    p = invariants.linear_momentum(scene, traj)
    assert np.abs(p - p[0]).max() < MOMENTUM_TOL


def _tumble_errors(traj, ref):
    b, r = traj.bodies["b"], ref.bodies["b"]
    R = spatial.quat_to_matrix(spatial.quat_normalize(b.quaternion))
    R_ref = spatial.quat_to_matrix(spatial.quat_normalize(r.quaternion))
    return (np.abs(b.position - r.position).max(), np.abs(R - R_ref).max(),
            np.abs(b.angular_velocity - r.angular_velocity).max())


def test_an_off_centre_spring_on_a_tumbling_box_matches_the_reference():
    scene = _oscillator(point_b=(0.05, 0.1, 0.15), w0=(1.0, -2.0, 3.0))
    ref = simulate(scene, TIMES, Settings("dop853", rtol=REFERENCE_RTOL, atol=REFERENCE_RTOL))[0]
    position, rotation, rate = _tumble_errors(_run(scene, Settings("rk5", dt=1e-3))[1].trajectory, ref)
    assert position < TUMBLE_POSITION_TOL and rotation < TUMBLE_ROTATION_TOL and rate < TUMBLE_RATE_TOL, \
        (position, rotation, rate)
    coarse, fine = (_tumble_errors(_run(scene, Settings("discrete", dt=dt))[1].trajectory, ref) for dt in (1e-3, 1e-4))
    for a, b in zip(coarse, fine):
        assert DECADE_RATIO[0] < a / b < DECADE_RATIO[1], (coarse, fine)


@pytest.fixture(scope="module")
def squeezer():
    return make_case("andrews_squeezer")


def _angles(traj, k):
    return np.array([traj.joints[body].q[k, 0] for body in ANGLES.values()])


def test_squeezer_forces_in_drakes_model_give_the_published_initial_accelerations(squeezer):
    """The spring and the motor as Drake holds them, at rest at the initial angles (no loop solver involved):
    the rigid projection of Drake's generalized forces onto the loops, against the Test Set's accelerations and
    multipliers. The loops hold the spring's pull statically (the accelerations are the same without it); the
    multipliers carry it."""
    from pydrake.multibody.tree import MultibodyForces

    from dalembert.adapters.drake.loops import _Rows

    model = ADAPTER.prepare(squeezer.scene, squeezer.times, Settings("discrete", dt=1e-4)).model
    plant = model.plant
    context = model.diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    q0, v0 = model.initial_state()
    plant.SetPositionsAndVelocities(plant_context, np.concatenate([q0, v0]))
    forces = MultibodyForces(plant)
    plant.CalcForceElementsContribution(plant_context, forces)  # gravity (zero) and the LinearSpringDamper
    for F in model.loads.get_output_port(0).Eval(model.loads.GetMyContextFromRoot(context)):  # the motor
        plant.get_body(F.body_index).AddInForce(plant_context, F.p_BoBq_B, F.F_Bq_W, plant.world_frame(), forces)
    tau = plant.CalcGeneralizedForces(plant_context, forces)
    J = np.vstack([Jl for Jl, _ in _Rows(model)(plant_context)])
    J = J[np.abs(J).max(axis=1) > 0.0]  # the out-of-plane rows are zero: the tree keeps the bodies in the plane
    Minv = np.linalg.inv(plant.CalcMassMatrix(plant_context))
    a_free = Minv @ tau
    f = -np.linalg.solve(J @ Minv @ J.T, J @ a_free)  # the loops' forces ON bodies 3, 4, 6 (x, y; N)
    a = a_free + Minv @ J.T @ f
    index = [model.joints[body].velocity_start() for body in ANGLES.values()]
    want = np.array([*INITIAL_ACCELERATIONS, 0, 0, 0, 0, 0])
    assert np.abs(a[index] - want).max() < RIGID_ACCELERATION_RTOL * np.abs(want).max()
    lam = np.array([*INITIAL_MULTIPLIERS, 0, 0, 0, 0])  # these hold the spring: without it (0.016, -0.033) N
    assert np.abs(f - lam).max() < RIGID_ACCELERATION_RTOL * np.abs(lam).max(), f
    # Drake's own (SAP) step from that state: near-rigid loops, short by the regularization's leak
    a_sap = plant.get_generalized_acceleration_output_port().Eval(plant_context)
    assert np.abs(a_sap[index] - want).max() < SAP_ACCELERATION_RTOL * np.abs(want).max()


def test_squeezer_runs_in_discrete_mode_to_the_published_angles(squeezer):
    prepared, outcome = _run(squeezer.scene, Settings("discrete", dt=SQUEEZER_DT), squeezer.times)
    traj = outcome.trajectory
    assert traj.t[-1] == REFERENCE_T
    error = np.abs(_angles(traj, -1) - np.array(list(REFERENCE_ANGLES.values()))).max()
    assert error < SQUEEZER_ANGLE_TOL, error
    assert invariants.loop_residual(squeezer.scene, traj, "position").max() < SQUEEZER_GAP_TOL
    lam = np.concatenate([traj.extras[f"reaction_force:E_body{k}"][0, :2] for k in (3, 4, 6)])
    want = np.array([*INITIAL_MULTIPLIERS, 0, 0, 0, 0])
    assert np.abs(lam - want).max() < SAP_MULTIPLIER_RTOL * np.abs(want).max(), lam
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["springs_as_scene"] and audit["other_passive_elements"] == [] and audit["max_joint_damping"] == 0.0
    assert audit["loop_constraints"] == 3 and "explicit" in audit["spring_force_path"]


def test_the_squeezer_is_unsupported_in_continuous_mode_for_its_loops_only(squeezer):
    assert ADAPTER.unsupported(squeezer.scene, Settings("discrete", dt=SQUEEZER_DT)) is None
    for integrator in ("rk3", "radau3"):
        reason = ADAPTER.unsupported(squeezer.scene, Settings(integrator, dt=SQUEEZER_DT))
        assert "loop:ball" in reason and "Continuous time does not support constraints" in reason
        assert "spring" not in reason


def test_the_audit_reads_the_springs_back_from_the_plant():
    scene = _oscillator(2.0, 9.81, point_b=(0.05, 0.1, 0.15))
    prepared, outcome = _run(scene, Settings("rk3", dt=STEPS[0]), times=TIMES[:3])
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["springs"] == {"spring_world_b": "LinearSpringDamper world [0.0, 0.0, 0.0] -> b [0.05, 0.1, 0.15], "
                                                  "free length 1.0 m, stiffness 50.0 N/m, damping 2.0 N s/m"}
    assert audit["springs_as_scene"] and audit["other_passive_elements"] == []
    assert audit["force_elements"] == 2 and audit["max_joint_damping"] == 0.0 and audit["actuators"] == 0
    assert audit["spring_force_path"].startswith("force element: at every stage")
    # the check compares the plant with the scene: a plant built from another spring fails it
    prepared.model.scene = Scene(scene.name, scene.bodies, scene.joints, scene.gravity,
                                    springs=[replace(scene.springs[0], stiffness=1.01 * STIFFNESS)])
    assert not ADAPTER.audit(prepared, outcome)["springs_as_scene"]


def test_a_spring_of_rest_length_zero_is_unsupported_with_drakes_reason():
    scene = Scene("zero", [Body.box("b", MASS, (0.1, 0.2, 0.3))],
                  [Joint("free", "world", "b", q0=[0, 0, -1, 1, 0, 0, 0], v0=[0] * 6)], [0, 0, 0],
                  springs=[Spring("world", "b", stiffness=STIFFNESS, name="zero_length")])
    for integrator in ("rk3", "discrete"):
        reason = ADAPTER.unsupported(scene, Settings(integrator, dt=1e-2))
        assert "'zero_length' (rest length 0)" in reason and "strictly positive free length" in reason
    from pydrake.multibody.plant import MultibodyPlant  # Drake's own refusal, the reason's source
    from pydrake.multibody.tree import LinearSpringDamper, SpatialInertia

    plant = MultibodyPlant(0.0)
    body = plant.AddRigidBody("b", SpatialInertia.SolidSphereWithMass(1.0, 0.1))
    with pytest.raises(SystemExit, match="free_length > 0"):  # pydrake's failed internal assertion
        LinearSpringDamper(plant.world_body(), np.zeros(3), body, np.zeros(3), 0.0, STIFFNESS, 0.0)
