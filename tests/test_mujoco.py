"""MuJoCo adapter against the closed forms and the reference solver."""

import os

import numpy as np
import pytest

from dalembert.adapters import get_adapter
from dalembert import Settings, make_case, spatial
from dalembert.errors import trajectory_errors
from dalembert.reference import simulate
from bounds import (BOX_COM_TOL, BOX_ORIENTATION_TOL, CROSS_CHECK_TOL, ORDER_SLACK, ROD_ANGLE_TOL,
                    ROD_REACTION_TOL, TOP_ORIENTATION_TOL)
from scenes import chain_case, free_body_world_loads_case

mujoco = pytest.importorskip("mujoco")  # CI installs it: this never skips there

ADAPTER = get_adapter("mujoco")


def run(case, settings):
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    return prepared, ADAPTER.run(prepared)


def errors(case, settings):
    return trajectory_errors(run(case, settings)[1].trajectory, case.exact(case.times))


def test_rk4_matches_the_closed_forms():
    s = Settings("rk4", dt=1e-3)
    rod = errors(make_case("pivoted_rod"), s)
    assert rod["joint"][0] < ROD_ANGLE_TOL and rod["reaction_force"][0] < ROD_REACTION_TOL
    assert errors(make_case("free_top"), s)["orientation"][0] < TOP_ORIENTATION_TOL
    box = errors(make_case("particle_box"), s)
    assert box["position"][0] < BOX_COM_TOL and box["orientation"][0] < BOX_ORIENTATION_TOL


@pytest.mark.parametrize("integrator", ["euler", "implicit", "implicitfast"])
def test_first_order_integrators_converge_at_first_order_on_the_rod(integrator):
    rod = make_case("pivoted_rod")
    coarse, fine = (errors(rod, Settings(integrator, dt=dt))["joint"][0] for dt in (1e-2, 1e-3))
    assert coarse / fine == pytest.approx(10.0, rel=0.05)


def test_rk4_is_fourth_order_on_the_top():
    top = make_case("free_top", t_final=2.0)
    coarse, fine = (errors(top, Settings("rk4", dt=dt))["orientation"][0] for dt in (1e-2, 5e-3))
    assert np.log2(coarse / fine) == pytest.approx(4.0, abs=ORDER_SLACK)


# The xfrc_applied path's error at dt = h, from the analysis in the test below: alpha^3 h^2 t^4 / 144.
# Its next term is O(h / t) relative to that (measured 0.8% at h = 1e-2, t = 2 s; 0.19% at
# 2.5e-3, where the constant is checked), which moves log2 of a ratio of errors by < 0.01.
LAG_ORDER_SLACK = 0.05
LAG_CONSTANT_TOL = 0.01  # relative, at the finest step: 5x the next term there
LAG_STEPS = (1e-2, 5e-3, 2.5e-3)


def test_xfrc_applied_path_is_second_order_and_the_actuator_path_exact():
    """``loads=xfrc_applied`` sets each load once per step, from the pose at the step's start, in
    world axes, so RK4's four stages all see the follower force pointing where the rod was. With
    Delta = phi - phi_n the angle turned since, the held force at the COM plus its held moment
    about the COM give the pivot torque (l F / 2)(1 + cos Delta), not l F: with alpha = l F / I_O
    (the closed form's phi''), phi'' = alpha (1 - Delta^2 / 4 + ...). Delta is first order in the
    step, but the torque depends on it only through cos Delta (the force is perpendicular to the
    rod; a component along it would enter through sin Delta and make the error first order), so
    the rate loses alpha w^2 h^3 / 12 per step of size h: alpha w^2 h^2 / 12 per unit time. With
    w = alpha t the rate falls behind by alpha^3 h^2 t^3 / 36 and the angle by
    alpha^3 h^2 t^4 / 144: second order, 2.4e-3 rad at t = 2 s for h = 1e-2 (alpha = 6.0 rad/s^2).

    The default path (site actuators) applies the load inside every stage: phi is quadratic in t,
    so RK4 (any Runge-Kutta method of order >= 2) is exact up to roundoff at every step.
    """
    rod = make_case("pivoted_rod")
    exact = rod.exact(rod.times).joints["rod"].q[:, 0]
    alpha = 2.0 * exact[-1] / rod.t_final**2  # the closed form starts at rest: phi = alpha t^2 / 2
    lag = {}
    for h in LAG_STEPS:
        actuator = run(rod, Settings("rk4", dt=h))[1].trajectory.joints["rod"].q[:, 0]
        assert np.max(np.abs(actuator - exact)) < ROD_ANGLE_TOL, h
        held = run(rod, Settings("rk4", dt=h, options={"loads": "xfrc_applied"}))[1].trajectory.joints["rod"].q[:, 0]
        lag[h] = exact[-1] - held[-1]
        assert lag[h] > 0.0 and np.max(np.abs(held - exact)) == lag[h]  # behind, most at the end
    for coarse, fine in zip(LAG_STEPS, LAG_STEPS[1:]):
        assert np.log2(lag[coarse] / lag[fine]) == pytest.approx(2.0, abs=LAG_ORDER_SLACK), lag
    h = LAG_STEPS[-1]
    assert lag[h] == pytest.approx(alpha**3 * h**2 * rod.t_final**4 / 144, rel=LAG_CONSTANT_TOL)


def test_audit_proves_only_the_scene_physics():
    for name in ("pivoted_rod", "free_top", "particle_box"):
        case = make_case(name)
        prepared, outcome = run(case, Settings("rk4", dt=1e-2))
        audit = ADAPTER.audit(prepared, outcome)
        assert audit["gravity"] == case.scene.gravity
        assert audit["max_contacts"] == 0 and audit["max_constraint_rows"] == 0
        assert audit["max_abs_passive_force"] == 0.0
        assert audit["max_armature"] == 0.0 and audit["max_damping"] == 0.0 and audit["ngeom"] == 0
        assert {"contact", "constraint", "spring", "damper", "autoreset", "clampctrl"} <= set(audit["disabled"])
        assert ("gravity" in audit["disabled"]) == (case.scene.gravity == (0.0, 0.0, 0.0))
        assert len(audit["actuators"]) == len(case.scene.loads)


@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case])
def test_every_joint_kind_frame_and_load_against_the_reference(make):
    case = make()
    ref = simulate(case.scene, case.times, Settings("dop853", rtol=1e-12, atol=1e-12,
                                                    options={"formulation": "kane"}))[0]
    mj = run(case, Settings("rk4", dt=1e-3))[1].trajectory
    e = trajectory_errors(mj, ref)
    for q in ("position", "orientation", "velocity", "angular_velocity", "reaction_force"):
        if q in e:
            assert e[q][0] < CROSS_CHECK_TOL, (q, e[q])
    for name, j in ref.joints.items():
        if name in mj.joints and j.q.shape[1] == 1:
            assert np.max(np.abs(mj.joints[name].q - j.q)) < CROSS_CHECK_TOL


# welds=equality, rk4 at dt = 1e-3 over 0.5 s on the welded particle box (measured: COM
# 2.7e-8 m, attitude 1.2e-8 rad, welds stretched 3.6e-8 m — MuJoCo's soft constraints at the
# stiffest it allows); 3x the measurements.
WELD_EQUALITY_TOL = 1e-7
# The chain's weld as a constraint, rk4 at dt = 1e-3 against Kane (measured 3.7e-8 m and 1.8e-7
# rad, both falling as dt^2: the weld's softness; a wrong relative pose would be ~0.1): 5x.
CHAIN_WELD_TOL = 1e-6


def test_welds_as_equality_constraints_hold_the_box_and_soften_with_the_step():
    """27 free bodies held by 26 weld constraints through MuJoCo's constraint solver: it follows the
    rigid body's closed form, and the welds' stretch (the constraints' softness, time constant
    2 dt) falls as dt^2."""
    from dalembert import invariants

    case = make_case("particle_box_welded", t_final=0.5)
    stretch = {}
    for dt in (1e-3, 1e-4):
        prepared, outcome = run(case, Settings("rk4", dt=dt, options={"welds": "equality"}))
        stretch[dt] = invariants.drift("pairwise_distance", case.scene, outcome.trajectory)
        if dt == 1e-3:
            e = trajectory_errors(outcome.trajectory, case.exact(case.times))
            assert e["position"][0] < WELD_EQUALITY_TOL and e["orientation"][0] < WELD_EQUALITY_TOL
            audit = ADAPTER.audit(prepared, outcome)
            assert audit["max_constraint_rows"] == 6 * 26 and "equality" not in audit["disabled"]
    assert stretch[1e-3] < WELD_EQUALITY_TOL and stretch[1e-3] / stretch[1e-4] > 50


def test_a_weld_constraint_on_a_turned_revolute_link_against_the_reference():
    """The weld's relative pose is the scene's, not MuJoCo's reference configuration (which has the
    revolute joints at zero)."""
    case = chain_case()
    ref = simulate(case.scene, case.times, Settings("dop853", rtol=1e-12, atol=1e-12,
                                                    options={"formulation": "kane"}))[0]
    mj = run(case, Settings("rk4", dt=1e-3, options={"welds": "equality"}))[1].trajectory
    e = trajectory_errors(mj, ref)
    assert e["position"][0] < CHAIN_WELD_TOL and e["orientation"][0] < CHAIN_WELD_TOL, e


def test_mass_properties_round_trip_full_inertia_and_com_offset():
    case = chain_case()
    prepared = ADAPTER.prepare(case.scene, case.times, Settings("rk4", dt=1e-3))
    model = prepared.model
    for body in case.scene.bodies:
        i = prepared.ids[body.name]
        p_MB, R_MB = prepared.frames[body.name]
        assert np.linalg.norm(p_MB) > 0.1  # the COM is offset from MuJoCo's body frame
        R = spatial.quat_to_matrix(model.body_iquat[i])
        I_B = R_MB.T @ R @ np.diag(model.body_inertia[i]) @ R.T @ R_MB
        assert np.allclose(I_B, body.inertia_matrix, rtol=0, atol=1e-14)
        assert np.allclose(model.body_ipos[i], p_MB, rtol=0, atol=1e-15)
        assert model.body_mass[i] == body.mass


def test_divergence_is_reported_not_reset(tmp_path, monkeypatch):
    """Euler at a violent spin: MuJoCo flags a bad acceleration; the run is
    diverged (NaN from then on), no state reset, no MUJOCO_LOG.TXT written."""
    monkeypatch.chdir(tmp_path)
    case = make_case("free_top", omega0=(1.0, 500.0, 1.0), t_final=5.0, sample_interval=0.05)
    prepared, outcome = run(case, Settings("euler", dt=0.05))
    assert not outcome.trajectory.is_finite()
    assert 0.0 < outcome.trajectory.first_nonfinite_time() < 5.0
    assert "unstable" in outcome.info["message"]
    assert list(tmp_path.iterdir()) == []


def test_dt_must_divide_the_sample_interval():
    case = make_case("free_top")
    with pytest.raises(ValueError, match="does not divide"):
        ADAPTER.check(case.scene, case.times, Settings("rk4", dt=3e-3))


def test_mjcf_is_plain_text_without_defaults():
    text = ADAPTER.describe(make_case("pivoted_rod").scene, Settings("rk4", dt=1e-3))
    assert "<freejoint" not in text and 'type="hinge"' in text and 'gravity="disable"' in text
    assert "<geom" not in text and 'damping="0"' in text


def test_a_weld_to_the_world_as_an_equality_constraint_holds_its_body_where_the_tree_puts_it():
    """A plate welded to the world at a turned pose, a rod hinged under it: with ``welds=equality`` the weld is
    a constraint whose first body is MuJoCo's world frame (it raised KeyError 'world' before), and the motion
    is the tree's to the constraint's softness (``CHAIN_WELD_TOL``: the same softness, time constant 2 dt;
    measured 2.8e-8 m and 7.8e-8 rad at rk4 dt 1e-3 over 0.5 s)."""
    from dalembert.scene import Body, Joint, Scene

    plate, rod = Body.box("plate", 1.0, (0.2, 0.2, 0.05)), Body.cylinder("rod", 0.5, 0.6, 0.02, axis=2)
    scene = Scene("welded_plate", (plate, rod),
                  (Joint("weld", "world", "plate", parent_point=(0.1, 0.0, 1.0),
                         parent_quat=spatial.quat_exp([0.2, 0.0, 0.3])),
                   Joint("revolute", "plate", "rod", (0.7,), (0.0,), axis=(0.0, 1.0, 0.0),
                         parent_point=(0.0, 0.0, -0.05), child_point=(0.0, 0.0, 0.3))),
                  (0.0, 0.0, -9.81))
    times = np.linspace(0.0, 0.5, 51)
    adapter = get_adapter("mujoco")
    tree, held = (adapter.run(adapter.prepare(scene, times, Settings("rk4", dt=1e-3, options={"welds": w}))).trajectory
                  for w in ("tree", "equality"))
    e = trajectory_errors(held, tree)
    assert e["position"][0] < CHAIN_WELD_TOL and e["orientation"][0] < CHAIN_WELD_TOL, e
