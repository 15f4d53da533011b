"""Drake closes loops (``dalembert.adapters.drake.loops``): SAP constraints in the discrete plant,
against the parallelogram four-bar's closed form and the reference solver; its continuous
integrators declare loops unsupported."""

import numpy as np
import pytest

from dalembert import invariants, spatial
from dalembert.adapters import get_adapter
from dalembert.cases.four_bar import four_bar, parallelogram_pendulum  # the one import of the four-bar module
from dalembert.reference import simulate
from dalembert.reference.closed_form import RigidPendulum
from dalembert.scene import Body, Joint, Load, Loop, Scene
from dalembert.settings import Settings
from installed import needs

pytestmark = needs("pydrake")

ADAPTER = get_adapter("drake")

# The four-bar over its default 0.5 s (the flat singular position at t = 0.23 s), discrete SAP,
# crank angle against the closed form, measured: 3.36e-4 rad at dt = 1e-2, 3.07e-6 at 1e-3,
# 2.08e-7 at 1e-4. The plant's update is semi-implicit Euler, whose positions are those of
# leapfrog with the first velocity off by half a step of the initial acceleration, zero here (the
# crank starts vertical, no gravity torque): second order at first (the 1e-2 -> 1e-3 factor of 110);
# below 1e-3 a floor of SAP's own (its stopping test is relative to the whole momentum, 1e-6 in
# Drake's SapSolverParameters, not exposed in pydrake) takes over: factor 15.
# A decade of dt must buy at least a decade of accuracy (first order at worst):
DECADE_GAIN = 10.0
# and the finest step must reach this (3x the 2.08e-7 measured: the floor is the solver's, not ours).
FINE_ANGLE_TOL = 6e-7
# The loop's gap is relaxed over one step (SAP's near-rigid regime): it falls as dt^2. Measured (m,
# or the sine of the axis tilt, the largest over the samples): the four-bar's revolute 0.13 dt^2 at
# dt = 1e-2, 0.021 dt^2 at 1e-3 and 1e-4; the ball to the world 0.39 / 0.060 dt^2 and the distance
# 0.045 / 0.024 dt^2 at 1e-2 / 1e-3; the tilted hinge 1.0 / 1.3 dt^2. 4 dt^2 (1/s^2 times m or 1)
# leaves room and fails for a soft or lost constraint (a gap that does not fall as dt^2: at 1e-3 the
# bound is 4e-6).
GAP_PER_DT2 = 4.0
# A ball loop (and a distance loop) to the world over 0.3 s (past the flat position at 0.23 s)
# against the reference (RK4 at 1e-3: within 7.8e-13 rad of the closed form on the ball chain, a
# parallelogram too): measured 4.8e-4 / 6.4e-6 rad (ball) and 2.8e-4 / 2.8e-6 (distance) at
# dt = 1e-2 / 1e-3, the largest joint-angle error; 3x for the machine.
REFERENCE_ANGLE_TOL = {1e-2: 1.5e-3, 1e-3: 2e-5}
# Loop reactions (``loops.LoopForces``: the constraints' generalized force in Drake's step, resolved on the
# loop's rows), relative to the largest true reaction. They follow the step at first order, but for the
# samples near the flat singular position (t = 0.2376 s), where the loop's Jacobian nearly loses the
# bars' direction and SAP's near-rigid force in it is not the rigid one (measured 0.25 at dt = 1e-3 on
# the sample at 0.24 s, 4.4e-4 at 1e-4). Measured on the four-bar against its closed form: 4.8e-4 at
# dt = 1e-3 beyond FLAT_WINDOW of the flat instant, 4.4e-4 at 1e-4 everywhere; to the world against the
# reference at 1e-3 beyond the window: ball 1.4e-3, distance 3.4e-4. ~3x the largest, for the machine:
REACTION_TOL = 4e-3
FLAT_TIME = 0.23758016402411217  # s: the closed form's crank angle reaches pi (brentq on RigidPendulum.angle)
FLAT_WINDOW = 0.02  # s: the two samples on either side of it


def _reaction_errors(traj, truth, name):
    """Per sample, the error of ``reaction_force:<name>`` relative to the truth's largest reaction."""
    scale = max(np.abs(f).max() for k, f in truth.extras.items() if k.startswith("reaction_force:"))
    key = f"reaction_force:{name}"
    return np.linalg.norm(traj.extras[key] - truth.extras[key], axis=1) / scale


def _crank_errors(case, dts):
    m, d, I, g, theta0, rate0 = parallelogram_pendulum()
    exact = RigidPendulum(m, d, I, g, theta0, rate0).angle(case.times) - np.pi / 2
    truth = case.exact(case.times)
    out = []
    for dt in dts:
        traj = ADAPTER.run(ADAPTER.prepare(case.scene, case.times, Settings("discrete", dt=dt))).trajectory
        crank, rocker = traj.joints["crank"].q[:, 0], traj.joints["rocker"].q[:, 0]
        out.append((np.abs(crank - exact).max(), np.abs(rocker - exact).max(),
                    invariants.loop_residual(case.scene, traj, "position").max(), _reaction_errors(traj, truth, "C")))
    return out


def test_discrete_four_bar_converges_to_the_closed_form_and_keeps_its_loop_closed():
    case = four_bar()
    dts = (1e-2, 1e-3, 1e-4)
    errs = _crank_errors(case, dts)
    crank = [e[0] for e in errs]
    assert crank[0] / crank[1] > DECADE_GAIN and crank[1] / crank[2] > DECADE_GAIN, crank
    assert crank[2] < FINE_ANGLE_TOL
    for dt, (c, r, gap, _) in zip(dts, errs):
        assert abs(r - c) < 0.1 * c  # the rocker turns with the crank: the parallelogram branch
        assert gap < GAP_PER_DT2 * dt**2, (dt, gap)
    far = np.abs(case.times - FLAT_TIME) > FLAT_WINDOW
    assert errs[1][3][far].max() < REACTION_TOL and errs[2][3].max() < REACTION_TOL


def _world_loop_scene(kind):
    """The four-bar closed at the ground pivot D by a loop to the world: ``ball`` (a chain
    world-crank-coupler-rocker, the rocker's end held at D) or ``distance`` (no rocker: a massless
    rod D-C, the loop's length)."""
    base = four_bar().scene
    crank, coupler, _ = base.joints
    if kind == "ball":
        rocker = Joint("revolute", "coupler", "rocker", q0=crank.q0, v0=crank.v0, axis=[0, 0, 1],
                       parent_point=[0.5, 0, 0], child_point=[0.5, 0, 0])
        return Scene("four_bar_ball_chain", base.bodies, [crank, coupler, rocker], base.gravity,
                     loops=[Loop("ball", "world", "rocker", point_a=[1.0, 0, 0], point_b=[-0.5, 0, 0], name="D")])
    return Scene("four_bar_distance", base.bodies[:2], [crank, coupler], base.gravity,
                 loops=[Loop("distance", "world", "coupler", point_a=[1.0, 0, 0], point_b=[0.5, 0, 0], length=1.0,
                             name="DC")])


@pytest.mark.parametrize("kind", ["ball", "distance"])
def test_a_loop_to_the_world_matches_the_reference(kind):
    """Loops to the world go through the anchor body welded to it (Drake 1.51 crashes on the world
    body in a constraint); the truth is the reference's Kane-plus-multipliers solver."""
    scene = _world_loop_scene(kind)
    times = np.linspace(0.0, 0.3, 31)
    ref = simulate(scene, times, Settings("rk4", dt=1e-3))[0]
    for dt, tol in REFERENCE_ANGLE_TOL.items():
        prepared = ADAPTER.prepare(scene, times, Settings("discrete", dt=dt))
        outcome = ADAPTER.run(prepared)
        traj = outcome.trajectory
        err = max(np.abs(traj.joints[j.child].q - ref.joints[j.child].q).max() for j in scene.joints)
        assert err < tol, (dt, err)
        assert invariants.loop_residual(scene, traj, "position").max() < GAP_PER_DT2 * dt**2
    far = np.abs(times - FLAT_TIME) > FLAT_WINDOW  # the chains move as the parallelogram does
    assert _reaction_errors(traj, ref, scene.loops[0].name)[far].max() < REACTION_TOL  # at dt = 1e-3
    audit = ADAPTER.audit(prepared, outcome)
    assert "welded to the world" in audit["loop_world_anchor"]
    assert audit["loop_constraints"] == 1 and kind in audit["loops"][scene.loops[0].name]


# A rod on a free joint held to the world by a revolute loop whose axis is tilted (Ja turned 0.6 rad
# about x, Jb 0.4 rad about y in the rod): a hinge in space, where a revolute loop and a ball loop
# differ (on the planar four-bar they cannot), against the same hinge as a tree joint in the
# reference (RK4 at 1e-3). Measured, dt = 1e-2 / 1e-3: the quaternion 9.7e-3 / 9.6e-4 (first order, the
# start not at rest); the hinge's reaction 4.6e-2 / 1.3e-3 of the largest, but for the sample at t = 0:
# 0.199 at every dt. There the step starts exactly on the constraint, and SAP's constraint on the
# velocity, J(q_n) v_n+1, has no velocity-product term (the points' relative centripetal acceleration:
# zero on the parallelogram, whose coupler translates); from the second step on the O(dt) constraint
# velocity the step leaves carries it (checked: the shortfall is the velocity-product share of the rigid
# force, -(J M^-1 J^T)^+ Jdot v, to 1e-2 N; adapters/drake/loops.py). The force Drake applies in its first
# step is that much off the rigid one, and the read-back reports it.
HINGE_GAIN = 8.0  # a decade of dt buys 10x in the attitude; room for the constant
HINGE_QUAT_TOL, HINGE_REACTION_TOL = 3e-3, 4e-3  # at dt = 1e-3: 3x the measured
FIRST_STEP_REACTION = (0.1, 0.3)  # measured 0.199 at dt = 1e-2 and 1e-3: the first step's missing term


def _tilted_hinge():
    """``(tree, loop)``: the rod on a tilted revolute joint, and the same rod on a free joint closed to the
    world by a revolute loop, started in the same state."""
    rod = Body.cylinder("rod", 1.0, 1.0, 0.05, axis=0)
    q_a, q_b = [np.cos(0.3), np.sin(0.3), 0, 0], [np.cos(0.2), 0, np.sin(0.2), 0]
    gravity = [0.0, 0.0, -9.81]
    tree = Scene("hinge_tree", [rod], [Joint("revolute", "world", "rod", q0=[0.7], v0=[2.0], axis=[0, 0, 1],
                                             parent_quat=q_a, child_point=[-0.5, 0, 0], child_quat=q_b)], gravity)
    start = simulate(tree, np.array([0.0, 1e-3]), Settings("rk4", dt=1e-3))[0].bodies["rod"]
    R_WB = spatial.quat_to_matrix(start.quaternion[0])
    free = Joint("free", "world", "rod", q0=[*start.position[0], *start.quaternion[0]],
                 v0=[*start.velocity[0], *(R_WB.T @ start.angular_velocity[0])])
    loop = Scene("hinge_loop", [rod], [free], gravity,
                 loops=[Loop("revolute", "world", "rod", point_a=[0, 0, 0], quat_a=q_a, point_b=[-0.5, 0, 0],
                             quat_b=q_b, axis=[0, 0, 1], name="H")])
    return tree, loop


def test_a_revolute_loop_in_space_is_the_hinge_it_stands_for():
    tree, loop = _tilted_hinge()
    times = np.linspace(0.0, 0.5, 51)
    ref = simulate(tree, times, Settings("rk4", dt=1e-3))[0]
    scale = np.abs(ref.extras["reaction_force:rod"]).max()
    quat, reaction = [], []
    for dt in (1e-2, 1e-3):
        traj = ADAPTER.run(ADAPTER.prepare(loop, times, Settings("discrete", dt=dt))).trajectory
        quat.append(np.abs(traj.bodies["rod"].quaternion - ref.bodies["rod"].quaternion).max())
        miss = traj.extras["reaction_force:H"] - ref.extras["reaction_force:rod"]
        reaction.append(np.linalg.norm(miss, axis=1) / scale)
        assert invariants.loop_residual(loop, traj, "position").max() < GAP_PER_DT2 * dt**2
    assert quat[0] / quat[1] > HINGE_GAIN and quat[1] < HINGE_QUAT_TOL, quat
    assert reaction[1][1:].max() < HINGE_REACTION_TOL
    assert all(FIRST_STEP_REACTION[0] < r[0] < FIRST_STEP_REACTION[1] for r in reaction)


# The ball chain with a world force on the coupler and a follower force on the crank, over 0.2 s (short of
# the flat position), against the reference: the gravity torque is no longer zero at the start, so the
# discrete step is first order in the angles too. Measured at dt = 1e-2 / 1e-3: angles 2.1e-3 / 1.9e-4
# rad, reaction at D 2.0e-2 / 2.0e-3 (relative): a decade of dt buys 10x; 8x leaves room, and a load
# missing from the reaction's balance would not converge at all.
FIRST_ORDER_GAIN = 8.0
LOADED_ANGLE_TOL, LOADED_REACTION_TOL = 6e-4, 6e-3  # at dt = 1e-3: 3x the measured


def test_loads_on_a_closed_loop_match_the_reference_at_first_order():
    b = _world_loop_scene("ball")
    scene = Scene("four_bar_ball_chain_loaded", b.bodies, b.joints, b.gravity, loops=b.loops,
                  loads=[Load("coupler", "force", [3.0, 0, 2.0], "world", point=[0.2, 0, 0]),
                         Load("crank", "force", [0, 0, -4.0], "body", point=[0.3, 0, 0])])
    times = np.linspace(0.0, 0.2, 21)
    ref = simulate(scene, times, Settings("rk4", dt=1e-3))[0]
    angle, reaction = [], []
    for dt in (1e-2, 1e-3):
        traj = ADAPTER.run(ADAPTER.prepare(scene, times, Settings("discrete", dt=dt))).trajectory
        angle.append(max(np.abs(traj.joints[j.child].q - ref.joints[j.child].q).max() for j in scene.joints))
        reaction.append(_reaction_errors(traj, ref, "D").max())
    assert angle[0] / angle[1] > FIRST_ORDER_GAIN and reaction[0] / reaction[1] > FIRST_ORDER_GAIN, (angle, reaction)
    assert angle[1] < LOADED_ANGLE_TOL and reaction[1] < LOADED_REACTION_TOL


def test_continuous_integrators_declare_loops_unsupported_and_discrete_runs_them():
    scene = four_bar().scene
    assert {"loop:ball", "loop:revolute", "loop:distance"} <= ADAPTER.effects
    for name in ADAPTER.integrators:
        s = Settings(name, dt=1e-3) if ADAPTER.integrators[name].fixed_step else Settings(name, rtol=1e-6)
        reason = ADAPTER.unsupported(scene, s)
        if name == "discrete":
            assert reason is None
        else:
            assert "loop:revolute" in reason and "Continuous time does not support constraints" in reason, name


def test_audit_says_how_the_revolute_loop_is_closed():
    case = four_bar(t_final=0.1)
    prepared = ADAPTER.prepare(case.scene, case.times, Settings("discrete", dt=1e-3))
    outcome = ADAPTER.run(prepared)
    audit = ADAPTER.audit(prepared, outcome)
    assert audit["loop_constraints"] == 2  # two ball constraints along the axis
    assert "0.5 m along the axis" in audit["loops"]["C"]  # the lever: the loop point's distance from the COMs
    assert "near-rigid" in audit["loop_stiffness"] and "beta = 0.1" in audit["loop_stiffness"]
    assert "minimum-norm" in audit["loop_reactions"]
