"""DART adapter against the closed forms, MuJoCo's semi-implicit Euler and the reference solver.

DART 6.20 has one integrator, semi-implicit Euler (``World.step``), the same update as MuJoCo's ``euler``
(``v += h a(q, v)``, then ``q`` from the new ``v``): on the same scene the two engines agree to roundoff, which
checks every frame, coordinate and load conversion of the adapter far more tightly than a first-order method's
truncation error against the reference could. The truncation error is checked too: exactly its closed form
where the acceleration is constant, and first order against the reference elsewhere.
"""

import subprocess
import sys

import numpy as np
import pytest

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter
from dalembert.errors import trajectory_errors
from dalembert.reference import simulate
from dalembert.scene import Body, Joint, Scene
from bounds import ORDER_SLACK
from scenes import cart_pendulum, chain_case, free_body_world_loads_case
from installed import needs

pytestmark = needs("dartpy")  # the optional extra dalembert[dart]

ADAPTER = get_adapter("dart")

# DART against MuJoCo's ``euler`` at one dt over 1000 steps: the same semi-implicit Euler update, computed by two
# libraries in different orders (DART's articulated-body recursion, MuJoCo's factorized mass matrix), so they
# differ by roundoff only; measured at most 3.8e-14 (rad, m, m/s, rad/s, N) on the chain of every joint kind and
# load, the free body with world loads and the heavy top. A frame or sign mistake gives O(1e-3) or more.
SAME_SCHEME_TOL = 1e-11
# The pivoted rod's angle under a constant angular acceleration alpha: semi-implicit Euler's error is exactly
# alpha h t / 2 (v_n = alpha n h, q_n = alpha h^2 n (n + 1) / 2), so it scales with h exactly but for roundoff
# (measured: the ratio between dt = 1e-2 and 1e-3 is 10 to 1e-9 relative).
EXACT_RATIO_REL_TOL = 1e-6
# The chain and the world-loaded free body against the reference at dt = 1e-3 over 1 s: semi-implicit Euler's
# first-order truncation, measured at most 6.2e-3 (rad/s, the chain's angular velocity); halved by halving dt.
FIRST_ORDER_TOL = 2e-2


def run(case, settings):
    prepared = ADAPTER.prepare(case.scene, case.times, settings)
    return prepared, ADAPTER.run(prepared)


def errors(case, settings, truth=None):
    truth = truth if truth is not None else case.exact(case.times)
    return trajectory_errors(run(case, settings)[1].trajectory, truth)


def test_importing_dart_prints_nothing():
    """dartpy 6.20 prints nothing when imported (unlike PyBullet): checked on both streams of a fresh process."""
    out = subprocess.run([sys.executable, "-c", "import dartpy; from dalembert.adapters import get_adapter; "
                          "get_adapter('dart').load()"], capture_output=True, text=True, check=True)
    assert out.stdout == "" and out.stderr == ""


@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case,
                                  lambda: make_case("heavy_top", t_final=0.2)])
def test_dart_is_mujoco_s_semi_implicit_euler_to_roundoff(make):
    """Ball, weld and revolute joints with rotated and offset joint frames, full inertia tensors, follower and
    world forces and torques, a free body with world loads, a fast heavy top: DART and MuJoCo ``euler`` at
    dt = 1e-3 agree on every body state, joint coordinate and joint reaction (``SAME_SCHEME_TOL``)."""
    case = make()
    s = Settings("euler", dt=1e-3)
    mujoco = get_adapter("mujoco")
    ours = run(case, s)[1].trajectory
    theirs = mujoco.run(mujoco.prepare(case.scene, case.times, s)).trajectory
    e = trajectory_errors(ours, theirs)
    for q in ("position", "orientation", "velocity", "angular_velocity", "joint", "reaction_force"):
        if q in e:
            assert e[q][0] < SAME_SCHEME_TOL, (q, e[q][0])
    for name, j in theirs.joints.items():
        if j.q.shape[1] in (1, 3):  # revolute, prismatic; a ball's velocity (a quaternion's sign is a choice)
            assert np.abs(ours.joints[name].v - j.v).max() < SAME_SCHEME_TOL, name


@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case])
def test_every_joint_kind_frame_and_load_is_first_order_against_the_reference(make):
    case = make()
    ref = simulate(case.scene, case.times, Settings("dop853", rtol=1e-12, atol=1e-12,
                                                    options={"formulation": "kane"}))[0]
    coarse, fine = (errors(case, Settings("euler", dt=dt), ref) for dt in (1e-3, 5e-4))
    for q in ("position", "orientation", "velocity", "angular_velocity", "reaction_force"):
        if q in coarse and coarse[q][0] > 1e-10:  # the free body's velocity is exact: a constant force
            assert coarse[q][0] < FIRST_ORDER_TOL, (q, coarse[q][0])
            assert np.log2(coarse[q][0] / fine[q][0]) == pytest.approx(1.0, abs=ORDER_SLACK), q


def test_the_rod_s_error_is_semi_implicit_euler_s_closed_form():
    """The pivoted rod (a follower force at its tip, no gravity) turns at a constant angular acceleration: the
    angle's error is alpha h t / 2, ten times smaller at a ten times smaller step; the pivot's reaction follows."""
    rod = make_case("pivoted_rod")
    coarse, fine = (errors(rod, Settings("euler", dt=dt)) for dt in (1e-2, 1e-3))
    assert coarse["joint"][1] / fine["joint"][1] == pytest.approx(10.0, rel=EXACT_RATIO_REL_TOL)
    assert coarse["reaction_force"][0] / fine["reaction_force"][0] == pytest.approx(10.0, rel=1e-3)


def test_the_box_falls_with_semi_implicit_euler_s_lag():
    """The particle box's COM falls at g: semi-implicit Euler puts it g h t / 2 low at t, exactly."""
    box = make_case("particle_box")
    h = 1e-3
    e = errors(box, Settings("euler", dt=h))
    g = np.linalg.norm(box.scene.gravity)
    assert e["position"][1] == pytest.approx(g * h * box.t_final / 2, rel=EXACT_RATIO_REL_TOL)
    assert e["velocity"][0] < 1e-9  # v_n = g n h: exact but for roundoff


def test_the_top_converges_at_first_order():
    top = make_case("free_top", t_final=2.0)
    coarse, fine = (errors(top, Settings("euler", dt=dt))["orientation"][0] for dt in (2e-3, 1e-3))
    assert np.log2(coarse / fine) == pytest.approx(1.0, abs=ORDER_SLACK)


def test_prismatic_joint_is_mujoco_s_slide_to_roundoff_and_first_order_to_the_reference():
    scene, times = cart_pendulum(), np.linspace(0.0, 1.0, 101)
    s = Settings("euler", dt=1e-3)
    ours = ADAPTER.run(ADAPTER.prepare(scene, times, s)).trajectory
    mujoco = get_adapter("mujoco")
    e = trajectory_errors(ours, mujoco.run(mujoco.prepare(scene, times, s)).trajectory)
    assert max(v[0] for v in e.values()) < SAME_SCHEME_TOL, e
    ref = simulate(scene, times, Settings("dop853", rtol=1e-12, atol=1e-12))[0]
    assert np.abs(ours.joints["cart"].q - ref.joints["cart"].q).max() < FIRST_ORDER_TOL


def test_audit_reads_back_that_nothing_else_is_simulated():
    case = make_case("chain", t_final=0.1)
    prepared, outcome = run(case, Settings("euler", dt=1e-2))
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["gravity"] == case.scene.gravity and audit["timestep"] == 1e-2
    assert audit["deactivation"]["enabled"] is False
    # contact: DART's flag stays on (dartpy cannot set it), but there is nothing to collide
    assert audit["shapes"] == audit["collision_shape_frames"] == 0
    assert audit["constraints"] == 0 and not audit["self_collision"]
    assert not audit["limits_enforced"]
    assert audit["max_damping"] == audit["max_spring_stiffness"] == audit["max_coulomb_friction"] == 0.0
    assert {j["type"] for j in audit["joints"].values()} == {"RevoluteJoint"}
    assert all(j["actuator"] == "FORCE" for j in audit["joints"].values())
    for b in case.scene.bodies:
        assert audit["bodies"][b.name]["mass"] == b.mass and audit["bodies"][b.name]["com"] == [0.0, 0.0, 0.0]


def test_engine_defaults_are_read_back_and_leave_a_scene_without_contact_alone():
    """``defaults=engine`` keeps DART's fresh world: deactivation (sleeping) on, with its thresholds. DART 6.20 puts to sleep only bodies resting in a contact island, so with no shapes (a scene without
    contact) the motion is bit for bit that of ``defaults=scene``, even for a body slower than every threshold."""
    body = Body("b", 1.0, np.diag([0.1, 0.2, 0.3]))
    slow = Scene("slow", (body,), (Joint("free", "world", "b", (0, 0, 0, 1, 0, 0, 0), (0.005, 0, 0, 0, 0, 0.01)),),
                 (0.0, 0.0, 0.0))
    times = np.linspace(0.0, 2.0, 21)
    trajectories = {}
    for defaults in ("scene", "engine"):
        s = Settings("euler", dt=1e-3, options={"defaults": defaults})
        prepared = ADAPTER.prepare(slow, times, s)
        outcome = ADAPTER.run(prepared)
        audit = ADAPTER.audit(prepared, outcome)
        assert audit["defaults"] == defaults
        assert audit["deactivation"]["enabled"] is (defaults == "engine")
        assert audit["deactivation"]["linear_speed_threshold"] == 0.01  # DART's own, read back either way
        trajectories[defaults] = outcome.trajectory.bodies["b"]
    assert np.array_equal(trajectories["scene"].position, trajectories["engine"].position)
    assert trajectories["engine"].position[-1, 0] == pytest.approx(0.01, rel=1e-12)  # still moving at 5 mm/s


def test_a_blow_up_dart_hides_is_nan_and_prints_nothing(capfd):
    """DART replaces a non-finite acceleration with zero and steps on, warning on the console: the adapter reads
    the warning as DART's own detection of the blow-up (NaN from that sample on, its message kept) and nothing
    reaches the console."""
    case = make_case("free_top_fast_spin", t_final=5.0)  # 50 rad/s, 0.5 rad per step: measured, flagged at 2.57 s
    _, outcome = run(case, Settings("euler", dt=1e-2))
    assert not outcome.trajectory.is_finite() and 0.0 < outcome.trajectory.first_nonfinite_time() < 5.0
    assert "Non-finite" in outcome.info["message"] and "\x1b" not in outcome.info["message"]
    captured = capfd.readouterr()
    assert captured.out == "" and captured.err == ""


@pytest.mark.parametrize("case,words", [("flyball_governor", "two points")])
def test_what_dart_does_not_run_is_refused_with_the_reason(case, words):
    c = make_case(case)
    reason = ADAPTER.unsupported(c.scene, Settings("euler", dt=1e-3))
    assert reason.startswith("dart adapter cannot represent") and words in reason


def test_options_are_checked_before_anything_runs():
    case = make_case("pendulum")
    with pytest.raises(ValueError, match="options.defaults: unknown 'dart'"):
        ADAPTER.check(case.scene, case.times, Settings("euler", dt=1e-3, options={"defaults": "dart"}))
    with pytest.raises(ValueError, match="dt"):
        ADAPTER.check(case.scene, case.times, Settings("euler", dt=3e-3))


def test_show_model_describes_the_world():
    text = ADAPTER.describe(make_case("pendulum").scene, Settings("euler", dt=1e-3))
    assert "RevoluteJoint" in text and "defaults=scene" in text and "time step 0.001" in text


def test_a_star_of_welds_is_mujoco_s_nested_bodies_to_roundoff():
    """The welded particle box (26 bodies welded to a free centre): DART's WeldJoint, like MuJoCo's nested bodies
    (``welds=tree``), adds no constraint, so the two semi-implicit Eulers agree to roundoff on all 27 bodies."""
    case = make_case("particle_box_welded", t_final=0.5)
    s = Settings("euler", dt=1e-3)
    mujoco = get_adapter("mujoco")
    e = trajectory_errors(run(case, s)[1].trajectory, mujoco.run(mujoco.prepare(case.scene, case.times, s)).trajectory)
    for q in ("position", "orientation", "velocity", "angular_velocity"):
        assert e[q][0] < SAME_SCHEME_TOL, (q, e[q][0])
