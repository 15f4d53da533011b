"""PyBullet adapter (PyBullet 3.2.7): exact truths of its one integrator, semi-implicit Euler, and MuJoCo's
semi-implicit Euler as the cross-check (the same update on the same state: the two agree to roundoff on every
joint kind, frame and load); the audit that PyBullet's defaults are off, and what they do when kept."""

import os
import subprocess
import sys

import numpy as np
import pytest
from installed import needs

pytestmark = needs("pybullet")  # dalembert[pybullet]

from dalembert import Settings, invariants, make_case  # noqa: E402
from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.errors import trajectory_errors  # noqa: E402
from dalembert.reference import simulate  # noqa: E402
from dalembert.scene import Body, ContactPair, Geom, Joint, Plane, Scene  # noqa: E402
from bounds import ORDER_SLACK, ROD_ANGLE_TOL  # noqa: E402
from scenes import chain_case, free_body_world_loads_case  # noqa: E402
from test_mujoco_prismatic import (BEAD_TIMES, G_W, SLIDER_DT, SLIDER_MASS, SLIDER_ROUNDOFF, SLIDER_TIMES,  # noqa: E402
                                   SLIDER_V0, bead_on_rod, slider, slider_axis_W, slider_exact)

ADAPTER = get_adapter("pybullet")
MUJOCO = get_adapter("mujoco")

# PyBullet against MuJoCo, both semi-implicit Euler at dt = 1e-3 (velocities from the state's accelerations,
# then positions from the new velocities): the same arithmetic up to the order of sums; measured 8e-15 to
# 3e-14 on the chain scene, the free body under world loads and the bead on the rod, 1e-12 on the kovalevskaya
# top. A frame, sign or load path wrong is O(1e-3) or more (one step's worth).
CROSS_ENGINE_TOL = 1e-11
# Observed order of semi-implicit Euler, log2 of the error ratio between the two steps: on the free top over
# 1 s at 2e-3 and 1e-3 s; on the heavy top (150 rad/s: over 1 s the error is 3 rad down to 1e-4 s) over its first
# 0.1 s at 2e-4 and 1e-4 s (measured 1.05).
ORDERS = {"free_top": (1.0, 2e-3, 1e-3), "heavy_top": (0.1, 2e-4, 1e-4)}
# The principal moments PyBullet holds against numpy's eigenvalues of the scene's tensor: the adapter's
# eigen-solve and numpy's, a few ulps apart.
MOMENTS_REL_TOL = 1e-12
# The probe of velocity-odd forces (audit.velocity_odd_acceleration) with nothing damping: roundoff of
# (v + h a) - v, a few ulps of the velocities (up to 150 rad/s on the heavy top) over h = 1e-3 s:
# 150 * 2.2e-16 / 1e-3 = 3.3e-11 (measured 0 on the tops, 5.6e-14 on the pendulum).
ODD_ACCELERATION_ROUNDOFF = 1e-10
# The free top over 20 s at dt = 1e-3 with defaults=scene: semi-implicit Euler's own energy drift (measured
# 1.3e-4); with PyBullet's defaults its damping takes 98.6 % of the energy (measured 0.9857).
EULER_TOP_DRIFT = 1e-3
ENGINE_DEFAULTS_ENERGY_LOSS = 0.98
# Hard contact with friction, the sphere's COM and angular velocity against the closed forms at dt = 1e-3: the
# impulses give the contact's exact velocity constraint each step; roundoff of 1000 steps on ~1 m/s and ~10 rad/s
# (measured 9e-14 and 6e-14 m/s, rad/s).
CONTACT_VELOCITY_ROUNDOFF = 1e-11
# PyBullet's default clamp on joint rates (btMultiBody's maxCoordinateVelocity), rad/s or m/s.
DEFAULT_RATE_CLAMP = 100.0


def run(scene, times, dt, engine=ADAPTER, **options):
    """``(prepared, outcome)`` of ``engine`` on ``scene`` at ``times`` with semi-implicit Euler at ``dt``."""
    prepared = engine.prepare(scene, times, Settings("euler", dt=dt, options=options))
    return prepared, engine.run(prepared)


def test_the_import_prints_nothing():
    """PyBullet's C initializer writes its build time to fd 2; ``model.engine`` silences it (fails with a plain
    ``import pybullet``, which prints "pybullet build time: ...")."""
    code = "from dalembert.adapters.pybullet.model import engine; engine(); print('', end='')"
    done = subprocess.run([sys.executable, "-P", "-c", code], capture_output=True, text=True, env=os.environ.copy())
    assert done.returncode == 0, done.stderr
    assert (done.stdout, done.stderr) == ("", "")


def test_without_pybullet_the_engine_is_not_installed(monkeypatch):
    """``version`` raises ImportError (``dalembert engines`` then says "not installed")."""
    monkeypatch.setitem(sys.modules, "pybullet", None)  # what ``import pybullet`` finds when it is missing
    with pytest.raises(ImportError):
        ADAPTER.version()


@pytest.mark.parametrize("make", [chain_case, free_body_world_loads_case,
                                  lambda: make_case("kovalevskaya_top", t_final=1.0),
                                  lambda: make_case("particle_box_welded", t_final=0.5)],
                         ids=["chain", "free_world_loads", "kovalevskaya", "welded_box"])
def test_every_joint_kind_frame_and_load_is_mujocos_semi_implicit_euler(make):
    """Ball, weld, revolute and free joints, full inertia tensors (PyBullet's inertial frames turned off the
    body frames), turned and offset joint frames, follower and world forces and torques: MuJoCo's Euler on
    the same scene, to roundoff."""
    case = make()
    pb = run(case.scene, case.times, 1e-3)[1].trajectory
    mj = run(case.scene, case.times, 1e-3, engine=MUJOCO)[1].trajectory
    e = trajectory_errors(pb, mj)
    for q in ("position", "orientation", "velocity", "angular_velocity", "joint"):
        if q in e:
            assert e[q][0] < CROSS_ENGINE_TOL, (q, e[q])
    for name, j in mj.joints.items():
        assert np.abs(pb.joints[name].q - j.q).max() < CROSS_ENGINE_TOL
        assert np.abs(pb.joints[name].v - j.v).max() < CROSS_ENGINE_TOL


def test_the_follower_force_turns_with_the_rod_at_each_step():
    """The pivoted rod: a constant torque about the pivot, which semi-implicit Euler integrates to
    ``phi + alpha h t / 2`` and ``rate`` exactly. PyBullet's cached link pose is one step stale; without the
    adapter's refresh the rate is 1.4e-4 rad/s off at dt = 1e-3."""
    case, h = make_case("pivoted_rod"), 1e-3
    traj = run(case.scene, case.times, h)[1].trajectory
    exact = case.exact(case.times).joints["rod"]
    t = case.times
    alpha = (exact.v[-1, 0] - exact.v[0, 0]) / t[-1]
    assert np.abs(traj.joints["rod"].v[:, 0] - exact.v[:, 0]).max() < ROD_ANGLE_TOL
    assert np.abs(traj.joints["rod"].q[:, 0] - (exact.q[:, 0] + alpha * h * t / 2)).max() < ROD_ANGLE_TOL


def test_the_inclined_slider_slides_and_pushes_back_exactly():
    """A prismatic joint with turned and offset joint frames under gravity: the slide is semi-implicit
    Euler's closed form, the rate exact, and the reaction ``m (g . a) a - m g`` (one link: the joint sensor's
    own report, right here)."""
    traj, audit = _run_with_audit(slider(), SLIDER_TIMES, SLIDER_DT)
    a_W, t = slider_axis_W(), SLIDER_TIMES
    assert np.abs(traj.joints["b"].q[:, 0] - slider_exact(t, "euler", SLIDER_DT)).max() < SLIDER_ROUNDOFF
    assert np.abs(traj.joints["b"].v[:, 0] - (SLIDER_V0 + (G_W @ a_W) * t)).max() < SLIDER_ROUNDOFF
    reaction = SLIDER_MASS * (G_W @ a_W) * a_W - SLIDER_MASS * G_W
    assert np.abs(traj.extras["reaction_force:b"] - reaction).max() < SLIDER_ROUNDOFF
    assert audit["joints"]["b"]["type"] == "prismatic" and not audit["joints"]["b"]["limited"]


@pytest.mark.parametrize("name", ["free_top", "heavy_top"])
def test_semi_implicit_euler_is_first_order(name):
    t_final, *steps = ORDERS[name]
    case = make_case(name, t_final=t_final)
    coarse, fine = (trajectory_errors(run(case.scene, case.times, dt)[1].trajectory,
                                      case.exact(case.times))["orientation"][0] for dt in steps)
    assert np.log2(coarse / fine) / np.log2(steps[0] / steps[1]) == pytest.approx(1.0, abs=ORDER_SLACK)


def test_reactions_are_the_joint_sensors_own_right_on_a_hinge_wrong_beyond():
    """The reaction is PyBullet's joint force sensor, turned to world axes, not a value the adapter computes:
    on the pendulum's one hinge it is MuJoCo's to roundoff. On the bead sliding along a spinning rod it is
    not (a finding on PyBullet 3.2.7, which the reports show): at t = 0 its centripetal part is 5/3 of the
    reference's (0.176 N where Kane's multipliers give 0.105 N), on the hub's hinge and on the bead's slide
    alike, while MuJoCo has the reference's."""
    case = make_case("pendulum")
    pb = run(case.scene, case.times, 1e-3)[1].trajectory.extras["reaction_force:rod"]
    mj = run(case.scene, case.times, 1e-3, engine=MUJOCO)[1].trajectory.extras["reaction_force:rod"]
    assert np.abs(pb - mj).max() < CROSS_ENGINE_TOL * np.abs(mj).max()
    scene = bead_on_rod()
    ref = simulate(scene, BEAD_TIMES[:2], Settings("dop853", rtol=1e-12, atol=1e-12,
                                                   options={"formulation": "kane"}))[0]
    pb = run(scene, BEAD_TIMES[:2], 1e-3)[1].trajectory
    for body in ("hub", "bead"):
        exact = ref.extras[f"reaction_force:{body}"][0]
        reported = pb.extras[f"reaction_force:{body}"][0]
        assert reported[2] == pytest.approx(exact[2], rel=1e-12)  # the weights: right
        assert np.linalg.norm(reported[:2]) / np.linalg.norm(exact[:2]) == pytest.approx(5.0 / 3.0, rel=1e-3)


def _run_with_audit(scene, times, dt, **options):
    prepared, outcome = run(scene, times, dt, **options)
    return outcome.trajectory, ADAPTER.audit(prepared, outcome)


@pytest.mark.parametrize("make", [lambda: make_case("pendulum", t_final=0.1), lambda: make_case("free_top", t_final=0.1),
                                  lambda: make_case("heavy_top", t_final=0.1), lambda: chain_case(t_final=0.1)],
                         ids=["pendulum", "free_top", "heavy_top", "chain"])
def test_the_audit_reads_back_only_the_scenes_physics(make):
    case = make()
    traj, audit = _run_with_audit(case.scene, case.times, 1e-3)
    assert audit["gravity"] == case.scene.gravity and audit["time_step"] == 1e-3 and audit["sub_steps"] == 0
    assert audit["collision_shapes"] == 0 and audit["contacts"] == 0 and audit["constraints"] == 0
    assert audit["velocity_odd_acceleration"] < ODD_ACCELERATION_ROUNDOFF  # no damping, no motor
    assert audit["max_motor_force"] == 0.0
    for name, joint in audit["joints"].items():
        assert joint["damping"] == 0.0 and joint["friction"] == 0.0 and not joint["limited"], (name, joint)
    for b in case.scene.bodies:
        assert audit["bodies"][b.name]["mass"] == b.mass
        assert sorted(audit["bodies"][b.name]["principal_moments"]) == pytest.approx(
            np.linalg.eigvalsh(b.inertia_matrix), rel=MOMENTS_REL_TOL)
    kinds = {j.child: j.kind for j in case.scene.joints}
    assert {n: j["type"] for n, j in audit["joints"].items()} == {
        n: {"revolute": "revolute", "ball": "spherical", "weld": "fixed"}[k] for n, k in kinds.items() if k != "free"}


def test_pybullets_defaults_damp_the_top_and_hold_the_joints():
    """``defaults=engine`` keeps PyBullet's damping, joint motors, rate clamp and sleeping: the free top loses
    98.6 % of its energy in 20 s (semi-implicit Euler alone: 1.3e-4), and the pendulum's and the heavy top's
    motors hold them still; the audit's probe sees both."""
    case = make_case("free_top", t_final=20.0)
    drift = {}
    for defaults in ("scene", "engine"):
        traj, audit = _run_with_audit(case.scene, case.times, 1e-3, defaults=defaults)
        drift[defaults] = invariants.drift("energy", case.scene, traj)
        assert audit["defaults"] == defaults
    assert drift["scene"] < EULER_TOP_DRIFT and drift["engine"] > ENGINE_DEFAULTS_ENERGY_LOSS, drift
    assert audit["velocity_odd_acceleration"] > 1.0  # 0.04 linear + 0.04 |v| quadratic, on rates of ~1
    for name in ("pendulum", "heavy_top"):
        case = make_case(name, t_final=0.1)
        traj, audit = _run_with_audit(case.scene, case.times, 1e-3, defaults="engine")
        assert traj.is_still() and audit["max_motor_force"] > 0.0, name


def test_joint_rates_pass_pybullets_default_clamp():
    """The violent rod reaches ~300 rad/s in 1 s; PyBullet's default clamp would hold it at 100 rad/s."""
    case = make_case("pivoted_rod_violent", t_final=1.0)
    traj = run(case.scene, case.times, 1e-4)[1].trajectory
    exact = case.exact(case.times).joints["rod"].v[:, 0]
    assert exact[-1] > 2 * DEFAULT_RATE_CLAMP
    assert traj.joints["rod"].v[-1, 0] == pytest.approx(exact[-1], rel=1e-3)


def test_a_blow_up_is_nan_from_there_on_not_an_exception():
    """The heavy top (150 rad/s) at dt = 2e-3: semi-implicit Euler blows up (at 1.18 s); PyBullet steps on through
    it, and the run is NaN from the first non-finite sample, with the time in its message (with a finite rate
    clamp the blow-up would be held at the clamp, finite)."""
    case = make_case("heavy_top", t_final=2.0)
    outcome = run(case.scene, case.times, 2e-3)[1]
    t_bad = outcome.trajectory.first_nonfinite_time()
    assert t_bad is not None and f"t = {t_bad:g} s" in outcome.info["message"]
    after = case.times >= t_bad
    assert np.isnan(outcome.trajectory.bodies["top"].position[after]).all()
    assert np.isfinite(outcome.trajectory.bodies["top"].position[~after]).all()
    assert outcome.n_steps < int(round(case.t_final / 2e-3))


@pytest.mark.parametrize("name,effect,why", [("four_bar", "loop:revolute", "createConstraint"),
                                             ("flyball_governor", "spring_damper", "no spring-damper element")])
def test_loops_and_springs_are_refused_with_the_reason(name, effect, why):
    case = make_case(name)
    reason = ADAPTER.unsupported(case.scene, Settings("euler", dt=1e-3))
    assert effect in reason and why in reason, reason


def test_contact_it_cannot_map_is_refused_with_the_reason():
    """A geom on a jointed body (a link), and pairs whose coefficients Bullet's product rule cannot give."""
    case = make_case("ball_slide_to_roll")
    scene = case.scene
    pendulum = make_case("pendulum").scene
    on_link = Scene("on_link", pendulum.bodies, pendulum.joints, pendulum.gravity,
                    geoms=[Geom("rod", "sphere", (0.1,), name="tip")], planes=[Plane("ground", point=(0.0, 0.0, -5.0))],
                    contacts=[ContactPair("tip", "ground", 0.1)])
    assert "jointed bodies" in ADAPTER.unsupported(on_link, Settings("euler", dt=1e-3))
    balls = [Body("ball%d" % i, 1.0, np.eye(3) * 0.004) for i in range(3)]
    free = [Joint("free", "world", b.name, q0=(float(i), 0.0, 0.0, 1.0, 0.0, 0.0, 0.0), v0=(0.0,) * 6)
            for i, b in enumerate(balls)]
    geoms = [Geom(b.name, "sphere", (0.1,), name=f"g{i}") for i, b in enumerate(balls)]
    chain = [ContactPair("g0", "g1", 0.1), ContactPair("g1", "g2", 0.2)]
    assert ADAPTER.unsupported(Scene("two", balls, free, (0.0, 0.0, 0.0), geoms=geoms, contacts=chain),
                               Settings("euler", dt=1e-3)) is None  # g0 0.1, g1 1, g2 0.2
    three = Scene("three", balls, free, (0.0, 0.0, 0.0), geoms=geoms, contacts=[*chain, ContactPair("g0", "g2", 0.3)])
    assert "product" in ADAPTER.unsupported(three, Settings("euler", dt=1e-3))


@pytest.mark.parametrize("name", ["ball_slide_to_roll", "ball_rolling_incline"])
def test_hard_contact_with_friction_gives_the_closed_form_velocity(name):
    """A sphere sliding into rolling on the ground, and rolling down a slope: PyBullet's impulses keep the contact
    closed and the Coulomb cone exact, the COM velocity the closed form's to roundoff (its position carries
    semi-implicit Euler's first-order error); the audit reads back the pair's friction and nothing else on it."""
    case = make_case(name)
    traj, audit = _run_with_audit(case.scene, case.times, 1e-3)
    e = trajectory_errors(traj, case.exact(case.times))
    assert e["velocity"][0] < CONTACT_VELOCITY_ROUNDOFF and e["angular_velocity"][0] < CONTACT_VELOCITY_ROUNDOFF, e
    (pair,) = case.scene.contacts
    assert audit["contact_pairs"][pair.name]["friction"] == pair.friction
    assert audit["contact_pairs"][pair.name]["restitution"] == 0.0
    for obj in audit["contact_objects"].values():
        assert obj["rolling_friction"] == 0.0 and obj["spinning_friction"] == 0.0
    assert audit["collision_shapes"] == 2


def test_a_repeated_contact_run_is_the_first():
    """Bullet's contact manifolds outlive a reset of the bodies' states; the adapter rebuilds a contact scene's
    world before each run (without it the second run of the block differs from the first from its first step)."""
    case = make_case("block_on_incline", t_final=0.2)
    prepared = ADAPTER.prepare(case.scene, case.times, Settings("euler", dt=1e-2))
    first, second = (ADAPTER.run(prepared).trajectory.bodies["box"] for _ in range(2))
    assert np.array_equal(first.position, second.position) and np.array_equal(first.quaternion, second.quaternion)


def test_the_solver_iterations_reach_the_engine():
    """Option ``solver_iterations`` as PyBullet reports it back (its default 50 otherwise)."""
    case = make_case("block_on_incline", t_final=0.1)
    assert _run_with_audit(case.scene, case.times, 1e-2)[1]["solver_iterations"] == 50
    audit = _run_with_audit(case.scene, case.times, 1e-2, solver_iterations="7", solver="pgs")[1]
    assert audit["solver_iterations"] == 7 and audit["solver"] == "CONSTRAINT_SOLVER_LCP_PGS"


def test_only_the_named_pairs_collide():
    """The two spheres of sphere_collision without their pair pass through each other untouched."""
    case = make_case("sphere_collision")
    scene = case.scene
    apart = Scene("apart", scene.bodies, scene.joints, scene.gravity, geoms=scene.geoms)
    traj = run(apart, case.times, 1e-3)[1].trajectory
    for j in scene.joints:
        assert np.array_equal(traj.bodies[j.child].velocity[-1], j.v0[:3])


def test_finding_restitution_fades_as_the_step_shrinks():
    """PyBullet 3.2.7's hard contact starts before the touch (a contact point within its breaking threshold
    limits the approach to the gap per step) and applies restitution only to what is left of the approach at the
    touch: the ball dropped with e = 0.5 leaves the ground at 0.475 of its impact speed at dt = 1e-3 and does not
    bounce at all at dt = 1e-4 (measured: 1e-6 m/s after it). The harness shows it (bouncing_ball's apexes)."""
    case = make_case("bouncing_ball", t_final=0.6)
    rebound = {}
    for dt in (1e-3, 1e-4):
        vz = run(case.scene, case.times, dt)[1].trajectory.bodies["ball"].velocity[:, 2]
        rebound[dt] = vz.max() / -vz.min()
    assert rebound[1e-3] == pytest.approx(0.475, abs=0.01) and rebound[1e-4] < 1e-3, rebound


def test_describe_reads_the_built_multibodies():
    case = chain_case()
    text = ADAPTER.describe(case.scene, Settings("euler", dt=1e-3))
    assert text.count("\n") == 1 + 3 + 1  # the header, the fixed base, the three links
    assert "gravity [0.0, 0.0, -9.81]" in text and "mass 2.0" in text


def test_a_branching_tree_keeps_each_links_mass_and_a_tree_beyond_pybullets_links_is_refused():
    """PyBullet numbers a multibody's links depth-first whatever order they are passed in: Solo12's four legs
    (three links each, passed breadth-first before) came back with masses swapped between legs, which
    ``prepare``'s mass check refuses; passed depth-first, every link is the scene's. A tree of more links than
    one multibody holds (``MAX_LINKS``) is refused before anything is built."""
    from dalembert.adapters.pybullet.adapter import MAX_LINKS

    adapter = get_adapter("pybullet")
    case = make_case("robot_free_fall")
    settings = Settings("euler", dt=1e-3)
    assert adapter.unsupported(case.scene, settings) is None
    adapter.prepare(case.scene, case.times[:3], settings)  # raises when a link's mass is another's
    assert adapter.unsupported(make_case("chain", n=MAX_LINKS).scene, settings) is None
    why = adapter.unsupported(make_case("chain", n=MAX_LINKS + 1).scene, settings)
    assert f"a tree of {MAX_LINKS + 1} links" in why and f"at most {MAX_LINKS}" in why
