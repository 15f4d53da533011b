"""Drake adapter against the closed forms, convergence orders and the reference solver."""

import numpy as np
import pytest

from dalembert import Settings, make_case, spatial
from dalembert.adapters import get_adapter
from dalembert.errors import trajectory_errors
from dalembert.reference import simulate
from dalembert.scene import Body, Joint, Scene
from bounds import (BOX_COM_TOL, BOX_ORIENTATION_TOL, CROSS_CHECK_TOL, ORDER_SLACK, ROD_ANGLE_TOL,
                    ROD_REACTION_TOL, TOP_ORIENTATION_TOL)
from scenes import chain_case, free_body_world_loads_case
from installed import needs

pytestmark = needs("pydrake")  # CI installs it (dalembert[drake]): this never skips there

ADAPTER = get_adapter("drake")

# Observed orders on the top over 2 s, log2 of the error ratio between the two steps given: the
# schemes' nominal orders (Drake's documentation); the steps are chosen where the truncation error
# is far above roundoff (rk5: 2.8e-10 and 8.9e-12 rad at 1e-2 and 5e-3) and the error constant settled.
ORDERS = [("explicit-euler", 1, 2e-3, 1e-3), ("semi-explicit-euler", 1, 2e-3, 1e-3), ("rk2", 2, 1e-2, 5e-3),
          ("rk3", 3, 1e-2, 5e-3), ("bs3", 3, 1e-2, 5e-3), ("rk5", 5, 1e-2, 5e-3), ("implicit-euler", 1, 2e-3, 1e-3),
          ("velocity-implicit-euler", 1, 2e-3, 1e-3), ("radau1", 1, 2e-3, 1e-3), ("radau3", 3, 1e-2, 5e-3)]
# Error control: rk3-adaptive on the top over 20 s, the error falls with the target accuracy
# (measured 6.1e-6 and 5.6e-9 rad at 1e-6 and 1e-9, sampled from Drake's dense output: a factor 1090; 5.8e-6
# and 6.1e-9 when every step ended at a sample). A factor of 100 per 1000 in accuracy leaves room for the
# controller's step choices (not proportional by contract). (rk5-adaptive, 8.8e-6 and 9.8e-9 rad, follows it too
# now that its steps are no longer capped at the sample interval: tests/test_adaptive_tolerance.py.)
ACCURACY_GAIN_PER_1000 = 100.0


def run(case, settings):
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    return prepared, ADAPTER.run(prepared)


def errors(case, settings):
    return trajectory_errors(run(case, settings)[1].trajectory, case.exact(case.times))


def test_rk5_matches_the_closed_forms():
    """Drake's fifth-order Runge-Kutta at a fixed dt = 1e-3 on every canonical case (bounds.py)."""
    s = Settings("rk5", dt=1e-3)
    rod = errors(make_case("pivoted_rod"), s)
    assert rod["joint"][0] < ROD_ANGLE_TOL and rod["reaction_force"][0] < ROD_REACTION_TOL, rod
    assert errors(make_case("free_top"), s)["orientation"][0] < TOP_ORIENTATION_TOL
    intermediate = make_case("free_top_intermediate")
    assert errors(intermediate, s)["orientation"][0] < intermediate.tolerances["orientation"].value
    box = errors(make_case("particle_box"), s)
    assert box["position"][0] < BOX_COM_TOL and box["orientation"][0] < BOX_ORIENTATION_TOL, box


@pytest.mark.parametrize("integrator,order,coarse,fine", ORDERS)
def test_each_integrator_converges_at_its_order_on_the_top(integrator, order, coarse, fine):
    top = make_case("free_top", t_final=2.0)
    e_coarse, e_fine = (errors(top, Settings(integrator, dt=dt))["orientation"][0] for dt in (coarse, fine))
    assert np.log2(e_coarse / e_fine) / np.log2(coarse / fine) == pytest.approx(order, abs=ORDER_SLACK)


def test_discrete_mode_is_first_order_on_the_rod():
    """The plant's discrete update (semi-implicit Euler in effect) on phi'' = const: its error is
    alpha h t / 2, exactly proportional to the step."""
    rod = make_case("pivoted_rod")
    coarse, fine = (errors(rod, Settings("discrete", dt=dt))["joint"][0] for dt in (1e-2, 1e-3))
    assert coarse / fine == pytest.approx(10.0, rel=0.01)


def test_discrete_samples_do_not_depend_on_the_roundoff_in_their_times():
    """linspace's 0.15000000000000002 and 0.30000000000000004 (every 0.05 s) and the same instants
    sampled every 1e-3 s: the discrete plant has run the same updates at both (before the stepping
    took each sample half a step early, the first ran one more: 9e-4 and 1.8e-3 rad apart)."""
    rod = make_case("pivoted_rod")
    coarse, fine = np.linspace(0.0, 0.5, 11), np.linspace(0.0, 0.5, 501)
    q = [ADAPTER.run(ADAPTER.prepare(rod.scene, t, Settings("discrete", dt=1e-3))).trajectory.joints["rod"].q[:, 0]
         for t in (coarse, fine)]
    assert np.array_equal(q[0], q[1][::50])


def test_error_control_follows_the_target_accuracy():
    top = make_case("free_top")
    loose, tight = (errors(top, Settings("rk3-adaptive", rtol=r))["orientation"][0] for r in (1e-6, 1e-9))
    assert tight < top.tolerances["orientation"].value and loose / tight > ACCURACY_GAIN_PER_1000


def test_world_frame_angular_velocity_in_and_out():
    """Drake's floating joint carries w in world axes: the adapter converts the scene's body-frame
    w0 on the way in and reads world w out, exactly at t = 0 and along the closed form."""
    case = make_case("free_top_intermediate", t_final=1.0)
    prepared, outcome = run(case, Settings("rk5", dt=1e-3))
    R0 = spatial.quat_to_matrix(case.scene.joints[0].q0[3:])
    assert np.array_equal(prepared.v0[:3], R0 @ np.array(case.scene.joints[0].v0[3:]))
    traj, exact = outcome.trajectory, case.exact(case.times)
    w_W = traj.bodies["top"].angular_velocity
    assert np.max(np.abs(w_W - exact.bodies["top"].angular_velocity)) < case.tolerances["angular_velocity"].value
    # the scene's free-joint coordinates: w in body axes
    w_B = spatial.world_to_body(traj.bodies["top"].quaternion, w_W)
    assert np.allclose(traj.joints["top"].v[:, 3:], w_B, rtol=0, atol=1e-12)


def test_audit_proves_only_the_scene_physics():
    for name in ("pivoted_rod", "free_top", "particle_box"):
        case = make_case(name, t_final=0.1)
        prepared, outcome = run(case, Settings("rk3", dt=1e-2))
        audit = ADAPTER.audit(prepared, outcome)
        assert audit["gravity"] == case.scene.gravity
        assert audit["collision_geometries"] == 0 and audit["actuators"] == 0 and audit["constraints"] == 0
        assert audit["max_joint_damping"] == 0.0 and audit["finite_limits"] == 0
        assert audit["force_elements"] == 1  # the gravity field alone (zero where the scene has none)
        assert audit["mode"] == "continuous" and audit["integrator"] == "runge_kutta3"
        assert ("body_poses" in audit["load_path"]) == any(ld.frame == "body" for ld in case.scene.loads)
        # three stages a step, each evaluating the follower force from that stage's pose
        assert (audit["load_evaluations"] >= 3 * 10) == bool(case.scene.loads)
    case = make_case("pivoted_rod", t_final=0.1)
    prepared, outcome = run(case, Settings("discrete", dt=1e-2))
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["mode"] == "discrete" and audit["time_step"] == 1e-2


def test_ball_joint_runs_through_its_roll_pitch_yaw_singularity():
    """Drake's ball joint is roll-pitch-yaw, singular at +-90 deg pitch, where Drake stops. The heavy top
    (spinning about a horizontal axis) reached it after 10 ms and a start at 90 deg pitch is on it;
    re-charted (``dalembert.adapters.drake.charts``), both run to their truths: the closed form, and the
    reference at tight tolerance."""
    case = make_case("heavy_top", t_final=0.5)
    _, outcome = run(case, Settings("rk5", dt=1e-3))
    e = trajectory_errors(outcome.trajectory, case.exact(case.times))
    assert e["orientation"][0] < case.tolerances["orientation"].value  # measured 1.2e-9 rad (tolerance 1e-6)
    assert e["reaction_force"][0] < case.tolerances["reaction_force"].value
    body = Body("b", 1.0, np.diag([0.1, 0.2, 0.3]))
    q0 = spatial.quat_from_axis_angle([0, 1, 0], np.pi / 2)  # body x along -z: pitch 90 deg in the scene's frames
    scene = Scene("locked", [body], [Joint("ball", "world", "b", q0=q0, v0=[0.5, 3.0, 1.0],
                                           child_point=[0.0, 0.0, 0.5])], gravity=[0, 0, -9.81])
    assert ADAPTER.unsupported(scene, Settings("rk5", dt=1e-3)) is None
    times = np.linspace(0.0, 2.0, 21)
    ref = simulate(scene, times, Settings("dop853", rtol=1e-12, atol=1e-12))[0]
    prepared = ADAPTER.prepare(scene, times, Settings("rk5", dt=1e-3))
    outcome = ADAPTER.run(prepared)
    assert outcome.info["ball_recharts"] >= 1
    e = trajectory_errors(outcome.trajectory, ref)
    for q in ("position", "orientation", "velocity", "angular_velocity", "reaction_force"):
        assert e[q][0] < CROSS_CHECK_TOL, (q, e[q])
    assert "re-set" in ADAPTER.audit(prepared, outcome)["ball_joint_charts"]


def test_divergence_is_data():
    """Explicit Euler at 500 rad/s with 5 rad per step blows up: NaN from then on, no exception."""
    case = make_case("free_top_fast_spin", spin=500.0, t_final=2.0)
    _, outcome = run(case, Settings("explicit-euler", dt=1e-2))
    assert not outcome.trajectory.is_finite()
    assert 0.0 < outcome.trajectory.first_nonfinite_time() <= 2.0


@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case])
def test_every_joint_kind_frame_and_load_against_the_reference(make):
    case = make()
    ref = simulate(case.scene, case.times, Settings("dop853", rtol=1e-12, atol=1e-12,
                                                    options={"formulation": "kane"}))[0]
    dr = run(case, Settings("rk5", dt=1e-3))[1].trajectory
    e = trajectory_errors(dr, ref)
    for q in ("position", "orientation", "velocity", "angular_velocity", "reaction_force"):
        if q in e:
            assert e[q][0] < CROSS_CHECK_TOL, (q, e[q])
    for name, j in ref.joints.items():
        if j.q.shape[1] == 0:  # a weld
            continue
        assert np.max(np.abs(dr.joints[name].q - j.q)) < CROSS_CHECK_TOL, name
        assert np.max(np.abs(dr.joints[name].v - j.v)) < CROSS_CHECK_TOL, name


def test_show_model_prints_the_plant():
    text = ADAPTER.describe(make_case("pivoted_rod").scene, Settings("rk3", dt=1e-3))
    assert "MultibodyPlant: continuous" in text and "revolute" in text and "gravity = [0.0, 0.0, 0.0]" in text
    assert "0 collision geometries" in text and "SceneLoads" in text
    assert "quaternion_floating" in ADAPTER.describe(make_case("free_top").scene, Settings("discrete", dt=1e-3))
