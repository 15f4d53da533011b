"""Exudyn's prismatic joints (``PrismaticZ`` links of the kinematic tree; ``ObjectJointGeneric`` leaving the
translation along the axis free, with redundant coordinates) against exact truths: a box sliding down an
inclined axis (its motion quadratic in t, its reaction ``m (a (g . a) - g)``), the same box held by a damped
spring along the axis (the damped oscillator's closed form), a bead on a spinning rod (energy and the angular
momentum about the spin axis conserved; the whole motion and the reactions against the reference's Kane), a
slider-crank closed over its prismatic joint (its closed-form kinematics), ``spatial.joint_coordinates``'s
slide against polar coordinates, and the audit's read-back of each joint from the built system.

Numbers measured with Exudyn 1.13.6.
"""

import numpy as np
import pytest

from dalembert import invariants, spatial
from dalembert.adapters import get_adapter
from dalembert.adapters.exudyn.joints import read_joints
from dalembert.adapters.exudyn.model import build
from dalembert.scene import Body, Joint, Scene, Spring
from dalembert.reference import simulate
from dalembert.settings import Settings
from bounds import ORDER_SLACK
from test_springs import DAMPING, MASS, REST, STIFFNESS, STRETCH, _damped_stretch

exudyn = pytest.importorskip("exudyn")  # CI installs it: this never skips there

ADAPTER = get_adapter("exudyn")
# Double-precision roundoff on the exact quantities below: positions of ~1 m, rates of ~1 m/s and forces of
# ~10 N through a few rotations (~1e-16 relative each) and up to a few hundred steps each adding one rounding.
ROUNDOFF = 1e-12
GRAVITY = np.array([0.0, 0.0, -9.81])  # m/s^2


def _frame(axis, angle):
    return tuple(spatial.quat_from_axis_angle(axis, angle))


# --------------------------------------------------------------------------- spatial.joint_coordinates
def test_joint_coordinates_read_the_slide_of_a_bead_on_a_spinning_rod():
    """The hub turned by theta at omega about z, the rod along the hub's x offset by (0, e, h), the bead's
    joint point at r along it moving at r': in polar coordinates p_Jc = Rz(theta) (r x + (0, e, h)), its
    velocity r' Rz x + omega z x p_Jc (exact); the bead's COM sits at its child_point's lever from there."""
    theta = np.linspace(0.0, 5.0, 7)
    omega, r, r_dot = 2.0 - 0.3 * theta, 0.4 * np.sin(theta) - 0.1, np.cos(theta)
    e, h, c = 0.05, 0.1, np.array([0.01, -0.02, 0.03])
    joint = Joint("prismatic", "hub", "bead", (r[0],), (r_dot[0],), axis=(2, 0, 0), parent_point=(0, e, h),
                  child_point=tuple(c), child_quat=_frame([1, 0, 1], 0.3))
    n, z = len(theta), np.array([0.0, 0.0, 1.0])
    R_WP = spatial.so3_exp(theta[:, None] * z)  # the hub, its COM at the origin
    R_WC = R_WP @ spatial.quat_to_matrix(joint.child_quat).T
    w = omega[:, None] * z
    p_Jc = R_WP @ np.array([0.0, e, h]) + r[:, None] * R_WP[:, :, 0]
    v_Jc = r_dot[:, None] * R_WP[:, :, 0] + np.cross(w, p_Jc)
    lever = R_WC @ c
    q, v = spatial.joint_coordinates(joint, R_WP, R_WC, w, w, p_WP=np.zeros((n, 3)), p_WC=p_Jc - lever,
                                     v_WP_W=np.zeros((n, 3)), v_WC_W=v_Jc - np.cross(w, lever))
    np.testing.assert_allclose(q[:, 0], r, rtol=0, atol=ROUNDOFF)
    np.testing.assert_allclose(v[:, 0], r_dot, rtol=0, atol=ROUNDOFF)
    with pytest.raises(ValueError, match=r"^joint_coordinates\.p_WP: a prismatic joint's slide needs"):
        spatial.joint_coordinates(joint, R_WP, R_WC, w, w)


# --------------------------------------------------------------------------- the inclined slider
SLIDER_MASS = 1.5  # kg
SLIDER_TIMES = np.linspace(0.0, 1.0, 11)


def inclined_slider(springs=False):
    """A box on a prismatic joint to the world whose axis, (1, 2, 0.5) in a joint frame turned 0.6 rad about
    (1, 1, 0), is inclined to gravity; the joint frames sit off both bodies' origins and the child's is turned
    too. With ``springs``: held by a damped spring along the axis from a world point 0.3 m behind the joint
    point (the test_springs oscillator's mass, stiffness, damping and rest length), starting at rest STRETCH
    beyond the sagged equilibrium."""
    parent_quat = _frame([1, 1, 0], 0.6)
    axis = np.array([1.0, 2.0, 0.5])
    a_W = spatial.quat_to_matrix(parent_quat) @ axis / np.linalg.norm(axis)
    parent_point, child_point = np.array([0.1, -0.2, 0.3]), (0.05, 0.02, -0.1)
    mass, q0, v0, spring = SLIDER_MASS, 0.2, 0.3, ()
    if springs:
        behind = 0.3  # m: the spring's world end, on the axis behind the joint point
        mass, v0 = MASS, 0.0
        q0 = REST + MASS * (GRAVITY @ a_W) / STIFFNESS + STRETCH - behind  # the spring's length - behind
        spring = (Spring("world", "b", point_a=tuple(parent_point - behind * a_W), point_b=child_point,
                         stiffness=STIFFNESS, damping=DAMPING, rest_length=REST, name="along"),)
    joint = Joint("prismatic", "world", "b", (q0,), (v0,), axis=tuple(axis), parent_point=tuple(parent_point),
                  parent_quat=parent_quat, child_point=child_point, child_quat=_frame([0, 1, 1], 0.4))
    return Scene("inclined_slider", (Body.box("b", mass, (0.1, 0.2, 0.3)),), (joint,), tuple(GRAVITY),
                 springs=spring), a_W


def _run(scene, times, integrator, dt=None, **options):
    settings = Settings(integrator, dt=dt, options=options) if dt else Settings(integrator, rtol=1e-9, atol=1e-9)
    assert ADAPTER.unsupported(scene, settings) is None
    prepared = ADAPTER.prepare(scene, times, settings)
    outcome = ADAPTER.run(prepared)
    return outcome.trajectory, ADAPTER.audit(prepared, outcome)


FIXED_STEP = ("explicit-euler", "explicit-midpoint", "rk33", "rk44", "rk67", "velocity-verlet", "generalized-alpha",
              "trapezoidal-index2")
REDUNDANT = ({"joints": "redundant"}, {"joints": "redundant", "node": "ep"})
# Generalized-alpha's reaction with redundant joints carries the start-up transient of its multipliers
# (test_exudyn_loops.START_UP), left at Newton's tolerance: measured 2.7e-10 N (rotation-vector nodes) and
# 6.1e-10 N (Euler parameters) of 13.9 N; every other run's reaction is exact to roundoff.
GA_REDUNDANT_REACTION_TOL = 5e-9  # N: 8x the larger
SLIDER_DT = 1e-2  # s


def _slider_truth(a_W, t):
    """The slide d (m), its rate (m/s) and the reaction on the box (N, world, constant) of ``inclined_slider``:
    uniform acceleration g . a along the axis, so the joint supplies m (a (g . a) - g)."""
    g_a = GRAVITY @ a_W
    return 0.2 + 0.3 * t + 0.5 * g_a * t**2, 0.3 + g_a * t, SLIDER_MASS * (a_W * g_a - GRAVITY)


def _assert_slider(scene, a_W, traj, audit, d_error=0.0, reaction_tol=ROUNDOFF):
    d, rate, reaction = _slider_truth(a_W, SLIDER_TIMES)
    j = scene.joint("b")
    np.testing.assert_allclose(traj.joints["b"].q[:, 0], d - d_error, rtol=0, atol=ROUNDOFF)
    np.testing.assert_allclose(traj.joints["b"].v[:, 0], rate, rtol=0, atol=ROUNDOFF)
    # the box keeps its attitude, R_WJp R_BJc^T; its COM is the child joint point minus the turned lever
    R = spatial.quat_to_matrix(j.parent_quat) @ spatial.quat_to_matrix(j.child_quat).T
    p = np.array(j.parent_point) + (d - d_error)[:, None] * a_W - R @ np.array(j.child_point)
    box = traj.bodies["b"]
    np.testing.assert_allclose(box.position, p, rtol=0, atol=ROUNDOFF)
    np.testing.assert_allclose(box.rotation_matrix, np.broadcast_to(R, (len(SLIDER_TIMES), 3, 3)), rtol=0,
                               atol=ROUNDOFF)
    np.testing.assert_allclose(traj.extras["reaction_force:b"], np.broadcast_to(reaction, p.shape), rtol=0,
                               atol=reaction_tol)
    built = audit["joint_readout"]["b"]
    assert built["kind"] == "prismatic" and built["mismatches"] == [], built
    np.testing.assert_allclose(built["axis"], np.array(j.axis) / np.linalg.norm(j.axis), rtol=0, atol=ROUNDOFF)
    assert audit["passive_extra"] == []


def test_the_slider_effect_is_declared():
    assert {"joint:prismatic"} <= ADAPTER.effects
    scene, _ = inclined_slider()
    assert ADAPTER.unsupported(scene, Settings("rk44", dt=SLIDER_DT)) is None


@pytest.mark.parametrize("integrator", FIXED_STEP)
def test_kinematic_tree_slides_down_the_incline_exactly(integrator):
    """Every fixed-step solver on the tree's PrismaticZ link: a motion quadratic in t is exact for every
    method of order >= 2; explicit Euler (first order) lags by exactly g . a t dt / 2 (its slide sums
    dt v_n, v_n exact), a check of the step too."""
    scene, a_W = inclined_slider()
    traj, audit = _run(scene, SLIDER_TIMES, integrator, SLIDER_DT)
    lag = 0.5 * (GRAVITY @ a_W) * SLIDER_TIMES * SLIDER_DT if integrator == "explicit-euler" else 0.0
    _assert_slider(scene, a_W, traj, audit, d_error=lag)
    assert audit["joint_readout"]["b"]["joint_type"] == "PrismaticZ"


@pytest.mark.parametrize("integrator", ["dopri5", "ode23"])
def test_kinematic_tree_slides_down_the_incline_with_adaptive_steps(integrator):
    scene, a_W = inclined_slider()
    _assert_slider(scene, a_W, *_run(scene, SLIDER_TIMES, integrator))


@pytest.mark.parametrize("options", REDUNDANT, ids=["rotvec-lg", "ep"])
@pytest.mark.parametrize("integrator", ["generalized-alpha", "trapezoidal-index2"])
def test_generic_joint_slides_down_the_incline_exactly(integrator, options):
    """Redundant coordinates: the ObjectJointGeneric's free z translation is the axis (the slide read back
    by spatial.joint_coordinates from the bodies), its ForceLocal the reaction."""
    scene, a_W = inclined_slider()
    traj, audit = _run(scene, SLIDER_TIMES, integrator, SLIDER_DT, **options)
    _assert_slider(scene, a_W, traj, audit,
                   reaction_tol=GA_REDUNDANT_REACTION_TOL if integrator == "generalized-alpha" else ROUNDOFF)
    assert audit["joint_readout"]["b"]["joint_type"] == "constrainedAxes [1, 1, 0, 1, 1, 1]"


@pytest.mark.parametrize("integrator", ["rk44", "dopri5"])
def test_explicit_solvers_refuse_generic_joints_and_say_why(integrator):
    scene, _ = inclined_slider()
    settings = Settings(integrator, dt=SLIDER_DT if integrator == "rk44" else None, rtol=1e-9 if integrator ==
                        "dopri5" else None, options={"joints": "redundant"})
    reason = ADAPTER.unsupported(scene, settings)
    assert reason.startswith("Exudyn: explicit integrator detected object which contains constraints")


def test_a_prismatic_joint_on_a_free_body_needs_redundant_joints():
    scene, _ = inclined_slider()
    base = Joint("free", "world", "base", (0, 0, 0, 1, 0, 0, 0), (0,) * 6)
    on_free = Joint("prismatic", "base", "b", (0.0,), (0.0,), axis=(1, 0, 0))
    scene = Scene("on_free", (Body.box("base", 1.0, (0.1, 0.1, 0.1)), Body.box("b", 1.0, (0.1, 0.1, 0.1))),
                  (base, on_free), tuple(GRAVITY))
    reason = ADAPTER.unsupported(scene, Settings("rk44", dt=SLIDER_DT))
    assert reason.startswith("a prismatic joint on a free body: the kinematic tree here has a fixed base")
    assert ADAPTER.unsupported(scene, Settings("generalized-alpha", dt=SLIDER_DT, options={"joints": "redundant"})) is None


@pytest.mark.parametrize("joints", ["minimal", "redundant"])
def test_the_joint_readout_is_exudyns_and_catches_a_wrong_joint(joints):
    """The read-back comes from the built system: a tree joint turned into a revolute one, its axis tilted, or
    a generic joint whose rows leave a rotation free instead, are each reported."""
    scene, _ = inclined_slider()
    built = build(scene, Settings("generalized-alpha", dt=SLIDER_DT, options={"joints": joints}))
    mbs = built.mbs
    assert built.joint_readout["b"]["mismatches"] == []
    if joints == "minimal":
        T = np.asarray(mbs.GetObject(built.tree)["jointTransformations"][0])
        mbs.SetObjectParameter(built.tree, "jointTransformations",
                               exudyn.Matrix3DList([spatial.so3_exp(np.array([0.0, 0.1, 0.0])) @ T]))
        assert read_joints(mbs, scene, built)["b"]["mismatches"][0].startswith("axis: engine")
        mbs.SetObjectParameter(built.tree, "jointTypes", [exudyn.JointType.RevoluteZ])
        assert read_joints(mbs, scene, built)["b"]["mismatches"] == [
            "kind: engine 'revolute' (RevoluteZ), scene 'prismatic'"]
    else:
        mbs.SetObjectParameter(built.joint_objects["b"], "constrainedAxes", [1, 1, 1, 1, 1, 0])
        assert read_joints(mbs, scene, built)["b"]["mismatches"] == [
            "kind: engine 'revolute' (constrainedAxes [1, 1, 1, 1, 1, 0]), scene 'prismatic'"]


# The slider held by a damped spring along the axis against the damped oscillator's closed form over 2 s, the
# error of the slide at dt = 5e-3 measured (m), each solver at its order (checked by halving the step from
# 1e-2); the bound is twice the measured error. A wrong axis, spring end or sign is off by O(STRETCH).
SPRING_ORDERS = {"rk44": (4, 3.49e-9), "rk67": (6, 1.68e-13), "rk33": (3, 7.21e-7), "explicit-midpoint": (2, 1.12e-4),
                 "generalized-alpha": (2, 5.67e-5), "trapezoidal-index2": (2, 5.60e-5)}
SPRING_STEPS = (1e-2, 5e-3)
SPRING_MARGIN = 2.0


def _spring_slide_error(integrator, dt, **options):
    from test_springs import TIMES

    scene, a_W = inclined_slider(springs=True)
    behind = 0.3  # inclined_slider's spring end behind the joint point (m)
    exact = REST + MASS * (GRAVITY @ a_W) / STIFFNESS + _damped_stretch(TIMES, DAMPING) - behind
    traj, audit = _run(scene, TIMES, integrator, dt, **options)
    assert audit["springs"]["along"]["mismatches"] == [] and audit["joint_readout"]["b"]["mismatches"] == []
    return np.abs(traj.joints["b"].q[:, 0] - exact).max()


@pytest.mark.parametrize("integrator", sorted(SPRING_ORDERS))
def test_slider_on_a_spring_converges_to_the_damped_oscillator(integrator):
    order, measured = SPRING_ORDERS[integrator]
    errors = [_spring_slide_error(integrator, dt) for dt in SPRING_STEPS]
    assert abs(np.log2(errors[0] / errors[1]) - order) < ORDER_SLACK, errors
    assert errors[1] < SPRING_MARGIN * measured


@pytest.mark.parametrize("options", REDUNDANT, ids=["rotvec-lg", "ep"])
def test_slider_on_a_spring_with_a_generic_joint(options):
    """Redundant coordinates, trapezoidal-index2: the same error as on the tree (measured 5.598e-5 m)."""
    errors = [_spring_slide_error("trapezoidal-index2", dt, **options) for dt in SPRING_STEPS]
    assert abs(np.log2(errors[0] / errors[1]) - 2) < ORDER_SLACK, errors
    assert errors[1] < SPRING_MARGIN * SPRING_ORDERS["trapezoidal-index2"][1]


# --------------------------------------------------------------------------- the bead on a spinning rod
BEAD_TIMES = np.linspace(0.0, 2.0, 201)


def bead_on_a_spinning_rod():
    """A hub free to turn about the world z (2 rad/s), a rod along its x offset by (0, 0.05, 0.1) from that
    axis, and a bead sliding on it, held by a spring along the rod from the hub (the spring's far end on the
    rod's line behind the axis, so it pulls along the rod only); the bead's joint frame is turned in its body
    and off its COM. Gravity is along z, normal to every motion: the energy (kinetic, the spring's, gravity's
    constant share) and the angular momentum about z are conserved."""
    hub, bead = Body.box("hub", 1.0, (0.4, 0.1, 0.1)), Body.box("bead", 0.2, (0.04, 0.03, 0.02))
    rod, lever = (0.0, 0.05, 0.1), (0.01, 0.0, 0.0)
    joints = (Joint("revolute", "world", "hub", (0.3,), (2.0,), axis=(0, 0, 1)),
              Joint("prismatic", "hub", "bead", (0.1,), (0.3,), axis=(2, 0, 0), parent_point=rod, child_point=lever,
                    child_quat=_frame([1, 0, 1], 0.3)))
    spring = Spring("hub", "bead", point_a=(-0.3, *rod[1:]), point_b=lever, stiffness=5.0, damping=0.0,
                    rest_length=0.35, name="along_rod")
    return Scene("bead_on_a_spinning_rod", (hub, bead), joints, tuple(GRAVITY), springs=(spring,))


def angular_momentum_z(scene, traj):
    """The angular momentum about the world z through the origin, the spin axis (kg m^2/s), shape (n,)."""
    return invariants.angular_momentum(scene, traj)[:, 2]


# The bead's conserved energy (J, of 0.2375) and angular momentum about z (kg m^2/s, of 0.0296): their largest
# change over 2 s, measured at the step given, bounded at twice that; a wrong Coriolis or centripetal term, lever
# or axis changes them by ~1e-3 of their size. Fourth order checked for rk44 by halving the step (the
# momentum's ratio 15.2; the energy's, 26.6, is still short of its asymptote); second order for the others
# (measured ratios 3.2-4.4 from the step given to twice it).
BEAD_RUNS = {  # (integrator, options): (dt, energy change, momentum change, order)
    ("rk44", "minimal"): (5e-3, 1.65e-11, 1.16e-11, 4),
    ("rk67", "minimal"): (1e-2, 8.27e-14, 3.84e-14, None),
    ("generalized-alpha", "minimal"): (5e-4, 3.55e-9, 2.24e-9, 2),
    ("trapezoidal-index2", "redundant"): (5e-4, 8.45e-9, 3.43e-9, 2),
    ("trapezoidal-index2", "redundant-ep"): (5e-4, 1.64e-8, 3.08e-9, 2),
}
BEAD_MARGIN = 2.0
BEAD_OPTIONS = {"minimal": {}, "redundant": {"joints": "redundant"}, "redundant-ep": {"joints": "redundant", "node": "ep"}}


def _bead_changes(integrator, dt, joints):
    scene = bead_on_a_spinning_rod()
    traj, audit = _run(scene, BEAD_TIMES, integrator, dt, **BEAD_OPTIONS[joints])
    assert {c: got["mismatches"] for c, got in audit["joint_readout"].items()} == {"hub": [], "bead": []}
    assert audit["joint_readout"]["hub"]["kind"] == "revolute" and audit["joint_readout"]["bead"]["kind"] == "prismatic"
    energy, momentum = invariants.total_energy(scene, traj), angular_momentum_z(scene, traj)
    return np.abs(energy - energy[0]).max(), np.abs(momentum - momentum[0]).max()


@pytest.mark.parametrize("integrator,joints", sorted(BEAD_RUNS))
def test_bead_on_a_spinning_rod_keeps_its_energy_and_angular_momentum(integrator, joints):
    dt, energy, momentum, order = BEAD_RUNS[(integrator, joints)]
    changes = _bead_changes(integrator, dt, joints)
    assert changes[0] < BEAD_MARGIN * energy and changes[1] < BEAD_MARGIN * momentum, changes
    if order is not None:
        coarse = _bead_changes(integrator, 2.0 * dt, joints)
        assert abs(np.log2(coarse[1] / changes[1]) - order) < ORDER_SLACK, (coarse, changes)


# --------------------------------------------------------------------------- against the reference
# The truth where no closed form exists: the reference's Kane formulation, DOP853 at 1e-12 (its own error on
# this 2-s motion ~1e-11, below every bound here).
TRUTH = Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "kane"})


@pytest.fixture(scope="module")
def bead_truth():
    scene = bead_on_a_spinning_rod()
    return scene, simulate(scene, BEAD_TIMES, TRUTH)[0]


def _bead_errors(traj, truth):
    """The largest error of the bodies' positions (m), angular velocities (rad/s), the joints' coordinates (rad,
    m) and the joint reactions relative to their largest (N / N)."""
    position = max(np.abs(traj.bodies[b].position - truth.bodies[b].position).max() for b in truth.bodies)
    rate = max(np.abs(traj.bodies[b].angular_velocity - truth.bodies[b].angular_velocity).max() for b in truth.bodies)
    joint = max(np.abs(traj.joints[b].q - truth.joints[b].q).max() for b in truth.joints)
    reaction = max(np.abs(traj.extras[f"reaction_force:{b}"] - truth.extras[f"reaction_force:{b}"]).max()
                   / np.abs(truth.extras[f"reaction_force:{b}"]).max() for b in truth.bodies)
    return position, rate, joint, reaction


# The bead against the reference: the tree with rk67 at dt = 1e-2, measured 4.8e-12 m, 2.2e-11 rad/s, 6.0e-12 m
# on the joints and 7.1e-12 relative on the reactions (the reference's own ~1e-11 among them).
BEAD_TREE_TOL = 1e-10  # m, rad/s, m and relative: 4.5x the largest measured
# Redundant joints on Euler-parameter nodes with trapezoidal-index2 (second order; rotation-vector nodes
# report the reactions short of their centripetal part, audit.ROTVEC_LG_REACTION): measured at dt = 1e-3,
# 5e-4: 1.58e-6, 3.95e-7 m; 7.37e-6, 1.83e-6 rad/s; 2.06e-6, 4.88e-7 on the joints; 2.36e-6, 9.7e-7 relative on
# the reactions.
BEAD_REDUNDANT_STEPS = (1e-3, 5e-4)
BEAD_REDUNDANT_TOL = (1e-6, 4e-6, 1e-6, 2e-6)  # m, rad/s, joints, relative: 2-2.5x the measured at 5e-4


def test_bead_on_a_spinning_rod_matches_the_reference_on_the_tree(bead_truth):
    scene, truth = bead_truth
    traj, _ = _run(scene, BEAD_TIMES, "rk67", 1e-2)
    assert max(_bead_errors(traj, truth)) < BEAD_TREE_TOL


def test_bead_on_a_spinning_rod_matches_the_reference_with_generic_joints(bead_truth):
    scene, truth = bead_truth
    errors = [_bead_errors(_run(scene, BEAD_TIMES, "trapezoidal-index2", dt, joints="redundant", node="ep")[0], truth)
              for dt in BEAD_REDUNDANT_STEPS]
    assert abs(np.log2(errors[0][0] / errors[1][0]) - 2) < ORDER_SLACK, errors
    assert all(e < tol for e, tol in zip(errors[1], BEAD_REDUNDANT_TOL)), errors[1]


# The slider-crank of test_prismatic (a loop closed over the prismatic joint, through both dead centres) with
# generalized-alpha at dt = 1e-4, which solves the closure at the position level (index 3): the slider follows
# the crank's closed form x = a cos(phi) + sqrt(b^2 - a^2 sin^2(phi)) to Newton's tolerance (measured 1.1e-16 m
# on the tree, 4.7e-14 m with redundant joints); the energy drifts by the method's own error (measured 9.5e-6
# and 1.2e-5 of the kinetic energy).
CRANK_CLOSURE_TOL = 1e-12  # m: 20x the larger
CRANK_ENERGY_DRIFT = 3e-5  # 2.5x the larger
CRANK_DT = 1e-4


@pytest.mark.parametrize("options", [{}, {"joints": "redundant", "node": "ep"}], ids=["minimal", "redundant-ep"])
def test_a_slider_crank_closed_over_its_prismatic_joint_keeps_its_closed_form(options):
    from test_prismatic import CRANK, ROD, _slider_crank

    scene = _slider_crank()
    traj, audit = _run(scene, np.linspace(0.0, 0.35, 15), "generalized-alpha", CRANK_DT, **options)
    phi = traj.joints["crank"].q[:, 0]
    x = CRANK * np.cos(phi) + np.sqrt(ROD**2 - CRANK**2 * np.sin(phi) ** 2)
    assert phi.min() < np.pi and phi.max() > 2 * np.pi  # through both dead centres
    assert np.abs(traj.joints["slider"].q[:, 0] - x).max() < CRANK_CLOSURE_TOL
    assert invariants.drift("energy", scene, traj) < CRANK_ENERGY_DRIFT
    assert audit["joint_readout"]["slider"]["mismatches"] == []


# --------------------------------------------------------------------------- the flyball governor (IFToMM A05)
# The case's truth (the reference's Kane on Radau at 1e-12, shared with tests/test_flyball_governor.py) over its
# default 2 s. Stiff (decay rates up to 8117 1/s): rk44 diverges at dt = 1e-3 (NaN from 0.01 s), so it runs at
# 2e-4, where its joints are within 9.74e-12 (rad, m; 4.48e-13 at 1e-4: fourth order) and the shaft's and rods'
# reactions within 3.3e-5 and 1.1e-4 N of 203 and 162 N (the dampers' 4e4 N s/m times a 6.9e-9 m/s velocity
# error). The slider's reaction is not compared: the truth's is 4e-15 N (the case's docstring).
FLYBALL_RK44_DT = 2e-4
FLYBALL_RK44_JOINT_TOL = 2e-11  # rad, m: 2x the measured
FLYBALL_RK44_REACTION_TOL = 3e-4  # N: 2.7x the rods' measured
# Generic joints on Euler-parameter nodes, trapezoidal-index2 at 2e-4 and 1e-4 (second order): joints within
# 1.03e-6 and 2.58e-7 (rad, m). (Generalized-alpha with generic joints stops at these steps, its Newton short of
# the adapter's NEWTON_RTOL on these stiff springs; measured: with newton_rtol = newton_atol = 1e-10 it runs
# at 1e-4, within 3.0e-7.)
FLYBALL_GENERIC_STEPS = (2e-4, 1e-4)
FLYBALL_GENERIC_JOINT_TOL = 5e-7  # rad, m: 1.9x the measured at 1e-4


@pytest.fixture(scope="module")
def flyball(shared_dir):
    from dalembert.case import make_case
    from truths import shared_truth

    case = make_case("flyball_governor")
    return case, shared_truth(case, shared_dir)


def _joint_error(traj, truth):
    return max(np.abs(traj.joints[j].q - truth.joints[j].q).max() for j in truth.joints)


def test_flyball_governor_on_the_tree_with_rk44(flyball):
    case, truth = flyball
    traj, audit = _run(case.scene, case.times, "rk44", FLYBALL_RK44_DT)
    assert _joint_error(traj, truth) < FLYBALL_RK44_JOINT_TOL
    for body in ("shaft", "rod1", "rod2"):
        key = f"reaction_force:{body}"
        assert np.abs(traj.extras[key] - truth.extras[key]).max() < FLYBALL_RK44_REACTION_TOL, body
    assert audit["joint_readout"]["slider"]["joint_type"] == "PrismaticZ"
    assert all(got["mismatches"] == [] for got in audit["joint_readout"].values())


def test_flyball_governor_with_generic_joints_at_second_order(flyball):
    case, truth = flyball
    errors = [_joint_error(_run(case.scene, case.times, "trapezoidal-index2", dt, joints="redundant", node="ep")[0],
                           truth) for dt in FLYBALL_GENERIC_STEPS]
    assert abs(np.log2(errors[0] / errors[1]) - 2) < ORDER_SLACK, errors
    assert errors[1] < FLYBALL_GENERIC_JOINT_TOL
