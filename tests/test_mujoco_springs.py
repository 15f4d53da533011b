"""MuJoCo builds spring-dampers as spatial tendons (``adapters/mujoco/mjcf.py``): the oscillators of
``test_springs`` against their closed forms, one step of a damper alone against each integrator's exact
update (explicit or implicit in velocity), the off-centre spring on a tumbling box against the reference,
the audit read back from the compiled model, Andrews' squeezer against its case truth, and MJX (one
compile)."""

import numpy as np
import pytest
from installed import needs

pytestmark = needs("mujoco")

from dalembert import Settings, invariants, make_case  # noqa: E402
from dalembert.cases.andrews_squeezer import ANGLES, REFERENCE_ANGLES, REFERENCE_T, energy_with_motor_work  # noqa: E402
from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.errors import error_series  # noqa: E402
from engine_runs import run_with_audit  # noqa: E402
from dalembert.reference import simulate  # noqa: E402
from dalembert.scene import Body, Joint, Scene, Spring  # noqa: E402
from test_springs import (DAMPING, GRAVITY, MASS, ORDER_RATIO, POSITION_TOL, REST, STIFFNESS, STRETCH, TIMES,  # noqa: E402
                          TUMBLING_STEPS, _damped_stretch, _oscillator)

ADAPTER = get_adapter("mujoco")
STEPS = (1e-2, 5e-3)
# A first-order method halving its step halves its error: measured 2.03 (euler, implicit, implicitfast) on the
# oscillators at dt = 1e-2 -> 5e-3; a force with the wrong sign or rate does not converge at all.
FIRST_ORDER_RATIO = (1.8, 2.2)
# First-order bound at dt = 5e-3 (m): measured 3.8e-3 (euler, undamped), 2.8e-3 (implicit, damped); ~ h omega^2 t
# STRETCH / 2 = 5e-3 * 25 * 2 * 0.3 / 2 = 3.8e-2 is the crude estimate, the measured ones sit 10x under it.
FIRST_ORDER_POSITION_TOL = 6e-3
# One step of a damper alone is a linear map of the velocity: the integrators' updates are polynomials or a
# fraction of h c / m, exact up to a few roundings of a ~1 m/s velocity.
ONE_STEP_TOL = 1e-14
# The tumbling box (MuJoCo RK4 at dt = 2.5e-3) against the reference's DOP853 at rtol 1e-12 (itself within ~1e-11
# of its converged motion: 1.3e-9 rad from its rtol 1e-10 run): measured 1.8e-9 m, 3.2e-8 rad and 7.9e-9 relative
# momentum drift (fourth order: 3.1e-8 m, 5.3e-7 rad at 5e-3); a lever in the wrong frame gives O(1e-2).
TUMBLING_TOL = 1e-7
# The passive force MuJoCo applies beyond the springs' J^T f, per sample (N or N m): roundoff of forces of ~20 N.
OTHER_PASSIVE_TOL = 1e-12
REFERENCE_RTOL = 1e-12


_run = run_with_audit  # (trajectory, audit) of one fixed-step run


def _z_error(scene, integrator, dt, damping, gravity, engine="mujoco", **options):
    traj, _ = _run(scene, TIMES, integrator, dt, engine, **options)
    exact_z = -(REST + MASS * gravity / STIFFNESS + _damped_stretch(TIMES, damping))
    return np.abs(traj.bodies["b"].position[:, 2] - exact_z).max()


@pytest.mark.parametrize("damping,gravity", [(0.0, 0.0), (DAMPING, GRAVITY)])
def test_rk4_oscillator_converges_at_fourth_order_to_its_closed_form(damping, gravity):
    scene = _oscillator(damping, gravity)
    e = [_z_error(scene, "rk4", dt, damping, gravity) for dt in STEPS]
    assert ORDER_RATIO[0] < e[0] / e[1] < ORDER_RATIO[1], e
    assert e[1] < POSITION_TOL


@pytest.mark.parametrize("integrator", ["euler", "implicit", "implicitfast"])
def test_first_order_integrators_converge_on_the_damped_oscillator(integrator):
    scene = _oscillator(DAMPING, GRAVITY)
    e = [_z_error(scene, integrator, dt, DAMPING, GRAVITY) for dt in STEPS]
    assert FIRST_ORDER_RATIO[0] < e[0] / e[1] < FIRST_ORDER_RATIO[1], e
    assert e[1] < FIRST_ORDER_POSITION_TOL


# One step of a damper alone (no stiffness): a body leaving the world point along the line at v0. With
# a = h c / m, the exact updates of the velocity are: explicit (Euler) 1 - a; backward Euler 1 / (1 + a);
# RK4 on a linear ODE the Taylor polynomial of exp(-a) to fourth order.
ONE_STEP_H, ONE_STEP_C, ONE_STEP_V0 = 0.1, 10.0, 1.0  # s, N s/m, m/s: a = 0.5, far apart updates
_A = ONE_STEP_H * ONE_STEP_C / MASS
ONE_STEP_FACTOR = {"euler": 1.0 - _A, "implicit": 1.0 / (1.0 + _A), "implicitfast": 1.0 / (1.0 + _A),
                   "rk4": 1.0 - _A + _A**2 / 2 - _A**3 / 6 + _A**4 / 24}


@pytest.mark.parametrize("integrator", sorted(ONE_STEP_FACTOR))
def test_one_step_of_a_damper_is_explicit_or_implicit_as_the_audit_says(integrator):
    scene = Scene("damper", [Body.box("b", MASS, (0.1, 0.2, 0.3))],
                  [Joint("free", "world", "b", q0=[0, 0, -REST, 1, 0, 0, 0], v0=[0, 0, -ONE_STEP_V0, 0, 0, 0])],
                  [0.0, 0.0, 0.0], springs=[Spring("world", "b", damping=ONE_STEP_C)])
    traj, audit = _run(scene, np.array([0.0, ONE_STEP_H]), integrator, ONE_STEP_H)
    v1 = -traj.bodies["b"].velocity[1, 2]
    assert v1 == pytest.approx(ONE_STEP_V0 * ONE_STEP_FACTOR[integrator], abs=ONE_STEP_TOL)
    assert ("damping implicit" in audit["spring_integration"]) == integrator.startswith("implicit")


def test_off_centre_spring_on_a_tumbling_box_follows_the_reference():
    """The spring's point off the COM: its moment (lever in the body frame, turned to the world) makes the box
    tumble; MuJoCo RK4 against the reference's DOP853, converging at fourth order."""
    scene = _oscillator(point_b=(0.05, 0.1, 0.15), w0=(1.0, -2.0, 3.0))
    ref = simulate(scene, TIMES, Settings("dop853", rtol=REFERENCE_RTOL, atol=REFERENCE_RTOL))[0]
    errors = [error_series(_run(scene, TIMES, "rk4", dt)[0], ref) for dt in TUMBLING_STEPS]
    for key in ("position", "orientation"):
        assert ORDER_RATIO[0] < errors[0][key].max() / errors[1][key].max() < ORDER_RATIO[1], key
        assert errors[1][key].max() < TUMBLING_TOL, key
    L = invariants.angular_momentum_about(scene, _run(scene, TIMES, "rk4", TUMBLING_STEPS[1])[0], (0.0, 0.0, 0.0))
    assert np.linalg.norm(L - L[0], axis=1).max() / np.linalg.norm(L, axis=1).max() < TUMBLING_TOL


def test_the_audit_reads_the_spring_back_and_nothing_else_passive():
    """The audit's spring comes from the compiled model (its tendon's parameters and sites), every other
    passive parameter is zero, and the passive force MuJoCo applied is the spring's J^T f, no more."""
    scene = _oscillator(DAMPING, GRAVITY, point_b=(0.05, 0.1, 0.15), w0=(1.0, -2.0, 3.0))
    _, audit = _run(scene, TIMES, "implicitfast", 1e-2)
    (got,) = audit["springs"]
    sp = scene.springs[0]
    assert (got["body_a"], got["body_b"], got["sites"]) == ("world", "b", 2)
    assert got["stiffness"] == sp.stiffness and got["damping"] == sp.damping
    assert got["rest_length"] == (sp.rest_length, sp.rest_length)
    assert np.allclose(got["point_b"], sp.point_b, rtol=0, atol=1e-15) and got["point_a"] == [0.0, 0.0, 0.0]
    assert not any(audit["passive_not_springs"].values()), audit["passive_not_springs"]
    assert audit["max_abs_passive_force_not_springs"] < OTHER_PASSIVE_TOL
    assert audit["max_abs_passive_force"] > 1.0  # the spring does act
    assert "spring" not in audit["disabled"] and "damper" not in audit["disabled"]
    plain = Scene("plain", scene.bodies, scene.joints, scene.gravity)
    _, plain_audit = _run(plain, TIMES[:3], "euler", 1e-2)
    assert {"spring", "damper"} <= set(plain_audit["disabled"]) and "springs" not in plain_audit


def test_a_model_whose_spring_is_not_the_scenes_is_refused(monkeypatch):
    """The compiled spring is checked against the scene before anything runs: a wrong stiffness in the MJCF
    (as a generator bug would write it) stops ``prepare``."""
    from dalembert.adapters.mujoco import adapter as mj_adapter

    scene = _oscillator(DAMPING)
    real = mj_adapter.mjcf
    monkeypatch.setattr(mj_adapter, "mjcf", lambda s, st: real(s, st).replace(f'stiffness="{STIFFNESS!r}"',
                                                                                'stiffness="49.0"'))
    with pytest.raises(RuntimeError, match=r"spring 'spring_world_b' with stiffness 49.0, not 50.0"):
        ADAPTER.prepare(scene, TIMES, Settings("rk4", dt=1e-2))


# Andrews' squeezer, MuJoCo RK4 at dt = 1e-5 (3000 steps, its loops MuJoCo's soft connects at a 1-step time
# constant): the seven angles at t = 0.03 s against the published [TS-F] values (themselves within 1.4e-9 rad of the
# case's truth, cases/andrews_squeezer.py): measured 6.7e-6 rad (3.1e-7 at dt = 2e-6, 1.8e-4 at 1e-4: the soft
# loops cost RK4 its order, ~1.4-1.9 here); without the spring it misses them by 11 rad (beta).
SQUEEZER_DT = 1e-5
SQUEEZER_ANGLE_TOL = 2e-5
# Its loops stay closed to the softness's residual (measured 2.8e-8 m at dt = 1e-5), and the energy with the motor's
# work, the spring's included, to 2.7e-6 of the largest kinetic energy (measured; the soft loops' work).
SQUEEZER_RESIDUAL_TOL = 1e-7
SQUEEZER_ENERGY_TOL = 1e-5


def test_andrews_squeezer_reaches_the_published_angles():
    c = make_case("andrews_squeezer")
    assert ADAPTER.unsupported(c.scene, Settings("rk4", dt=SQUEEZER_DT)) is None
    traj, audit = _run(c.scene, c.times, "rk4", SQUEEZER_DT)
    k = int(np.argmin(np.abs(c.times - REFERENCE_T)))
    errors = {angle: traj.joints[body].q[k, 0] - REFERENCE_ANGLES[angle] for angle, body in ANGLES.items()}
    assert max(map(abs, errors.values())) < SQUEEZER_ANGLE_TOL, errors
    assert invariants.loop_residual(c.scene, traj, "position").max() < SQUEEZER_RESIDUAL_TOL
    E = energy_with_motor_work(c.scene, traj)
    assert np.abs(E - E[0]).max() / invariants.kinetic_energy(c.scene, traj).max() < SQUEEZER_ENERGY_TOL
    assert [s["name"] for s in audit["springs"]] == ["spring_DC"] and audit["springs"][0]["body_b"] == "world"


@pytest.mark.long
def test_mjx_runs_the_damped_oscillator():
    """One compile (MJX rk4, float64, dt = 5e-3): MJX puts the tendon's spring and damper on the device and its
    oscillator meets the closed form as MuJoCo C's does (measured 3.5e-9 m, MuJoCo C 3.5e-9 m)."""
    pytest.importorskip("mujoco.mjx")
    scene = _oscillator(DAMPING, GRAVITY)
    assert get_adapter("mjx").unsupported(scene, Settings("rk4", dt=STEPS[1])) is None
    assert _z_error(scene, "rk4", STEPS[1], DAMPING, GRAVITY, "mjx", precision="float64") < POSITION_TOL


# A double pendulum (hinges about z and y) under gravity with an off-centre spring-damper from the world to the
# second link, MuJoCo RK4 at dt = 1e-3 against the reference's DOP853 at rtol 1e-12: measured 1.0e-10 m, 1.2e-10
# rad and 1.0e-10 (relative) on the joint reactions, each ~15x less at 5e-4 (fourth order). A spring force wrongly
# taken out of the reaction read from cfrc_int (MuJoCo counts a tendon's force in cfrc_ext) moves it by the tension.
CHAIN_TOL = 1e-9


def test_spring_on_a_jointed_chain_follows_the_reference_reactions_included():
    times = np.linspace(0.0, 2.0, 201)
    links = [Body.box("l1", 1.0, (1.0, 0.1, 0.1)), Body.box("l2", 0.5, (1.0, 0.1, 0.1))]
    joints = [Joint("revolute", "world", "l1", q0=[0.3], v0=[0.0], axis=(0, 0, 1), child_point=(-0.5, 0, 0)),
              Joint("revolute", "l1", "l2", q0=[0.2], v0=[1.0], axis=(0, 1, 0), parent_point=(0.5, 0, 0),
                    child_point=(-0.5, 0, 0))]
    scene = Scene("chain_spring", links, joints, [0.0, 0.0, -GRAVITY],
                  springs=[Spring("world", "l2", point_a=(1.0, 1.0, 0.5), point_b=(0.3, 0.05, 0.0), stiffness=40.0,
                                  damping=1.5, rest_length=0.5)])
    ref = simulate(scene, times, Settings("dop853", rtol=REFERENCE_RTOL, atol=REFERENCE_RTOL))[0]
    e = error_series(_run(scene, times, "rk4", 1e-3)[0], ref)
    for key in ("position", "orientation", "joint", "reaction_force"):
        assert e[key].max() < CHAIN_TOL, (key, e[key].max())


# MuJoCo's tendon length and velocity against dalembert.springs at the same state: one formula each side, in
# double precision (lengths ~1 m, rates ~1 m/s).
CONVENTION_TOL = 1e-14


def test_the_tendons_length_rate_and_force_are_dalembert_springs():
    """At a tumbling state of the off-centre oscillator, MuJoCo's ten_length and ten_velocity are the spring's
    length and rate (``dalembert.springs.state``), and qfrc_passive is the spring's force and its moment about the
    COM (free joint: force in world axes, moment in body axes)."""
    import mujoco

    from dalembert import spatial, springs
    from dalembert.closure import world_state

    scene = _oscillator(DAMPING, point_b=(0.05, 0.1, 0.15))
    prepared = ADAPTER.prepare(scene, TIMES, Settings("rk4", dt=1e-2))
    model, d = prepared.model, prepared.scratch
    p, quat = np.array([0.2, -0.1, -1.1]), spatial.quat_normalize(np.array([0.9, 0.2, -0.3, 0.1]))
    v, w_B = np.array([0.3, -0.4, 0.5]), np.array([1.0, -2.0, 3.0])
    d.qpos[:], d.qvel[:] = np.concatenate([p, quat]), np.concatenate([v, w_B])
    mujoco.mj_forward(model, d)
    R = spatial.quat_to_matrix(quat)
    s = springs.state(scene.springs[0], world_state(), dict(R=R, p=p, v=v, w=R @ w_B))
    assert d.ten_length[0] == pytest.approx(s.length, abs=CONVENTION_TOL)
    assert d.ten_velocity[0] == pytest.approx(s.rate, abs=CONVENTION_TOL)
    (F, tau), = springs.wrenches(scene.springs, {"world": world_state(), "b": dict(R=R, p=p, v=v, w=R @ w_B)}).values()
    assert np.abs(d.qfrc_passive[:3] - F).max() < CONVENTION_TOL * np.abs(F).max()
    assert np.abs(d.qfrc_passive[3:] - R.T @ tau).max() < CONVENTION_TOL * np.abs(tau).max()
