"""Exudyn's spring-dampers (``Scene.springs`` as ``ObjectConnectorSpringDamper``, adapters/exudyn/springs.py):
the single-body oscillators against their closed forms with every fixed-step solver at its own order, the
off-centre spring on a tumbling box and a hinged pair held by two springs (markers on kinematic-tree links,
and on rigid bodies with redundant joints) against the reference solver, Andrews' squeezer against the
published Test Set solution, and the audit, which reads each spring back from the system that ran.

Numbers measured with Exudyn 1.13.6.
"""

import numpy as np
import pytest

from dalembert.adapters import get_adapter
from dalembert.adapters.exudyn.model import build
from dalembert.adapters.exudyn.springs import ELEMENT, passive_effects, read_springs, unexpected_passive
from dalembert.case import make_case
from dalembert.cases.andrews_squeezer import ANGLES, REFERENCE_ANGLES, REFERENCE_T
from dalembert.reference import simulate
from dalembert.scene import Body, Joint, Scene, Spring
from dalembert.settings import Settings
from bounds import ORDER_SLACK
from test_springs import DAMPING, GRAVITY, MASS, REST, STIFFNESS, TIMES, _damped_stretch, _oscillator

exudyn = pytest.importorskip("exudyn")  # CI installs it: this never skips there

ADAPTER = get_adapter("exudyn")
# The truth where no closed form exists: the reference's Kane formulation, DOP853 at 1e-12 (its own error on
# these 1-2 s motions ~1e-11, below every bound here).
TRUTH = Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "kane"})
STEPS = (1e-2, 5e-3)  # s: both divide the oscillators' 0.01-s sample interval
# Each fixed-step solver's order and its largest error on the two oscillators (undamped, and damped under
# gravity) at dt = 5e-3 over 2 s, measured (m): the bound is twice that; the order is checked by halving the step.
ORDERS = {"explicit-midpoint": (2, 2.48e-4), "generalized-alpha": (2, 1.25e-4), "trapezoidal-index2": (2, 1.24e-4),
          "rk33": (3, 1.85e-6), "rk44": (4, 7.75e-9), "rk67": (6, 3.77e-13)}
MARGIN = 2.0  # the bounds above: twice the measured error; a wrong force, sign or rest length is O(STRETCH)
# Exudyn's velocity-verlet takes the step-end acceleration at the half-step velocity, f(q_n+1, v_n+1/2)
# (readback.STALE_ACCELERATIONS): second order without a damper (measured 2.47e-4, 6.18e-5 m at dt = 1e-2,
# 5e-3), first with one, whose force is then an O(dt) step late (measured 2.79e-3, 1.37e-3 m).
VERLET_UNDAMPED, VERLET_DAMPED = (2, 6.18e-5), (1, 1.37e-3)
# dopri5 at rtol = atol = 1e-9: its steps are capped by the 0.01-s samples (sampling.solve_per_sample), and the
# error is the capped step's (measured 2.4e-10 m undamped, 9.7e-11 m damped; the same at rtol 1e-6).
DOPRI5_TOL = 1e-9
# The tumbling box (off-centre, damped spring under gravity) against the reference: rk67 at dt = 5e-3, measured
# 1.8e-11 m and 2.9e-8 rad/s (sixth order: 1.4e-9 m, 2.1e-6 rad/s at 1e-2); a lever wrong by its own length
# or taken about the wrong point makes them O(1).
BOX_POSITION_TOL = 1e-10  # m: 5x the measured error
BOX_RATE_TOL = 1e-7  # rad/s: 3.4x the measured error
# The hinged pair against the reference (kinematic-tree markers, rk67 at dt = 5e-3): measured 2.0e-11 m,
# 5.1e-10 rad/s and 6.2e-11 relative on the joint reactions, which subtract the springs' forces on each link.
PAIR_TREE_TOL = 1e-9  # m, rad/s and relative: 2x the largest measured (the rate's), 16x and 50x the others
# The pair with redundant joints on Euler-parameter nodes and trapezoidal-index2 at dt = 5e-4 (second order):
# measured 1.9e-6 m, 3.2e-5 rad/s, reactions 1.3e-5 relative (4x smaller than at 1e-3). Euler-parameter nodes:
# rotation-vector nodes report the reactions short of their centripetal part (audit.ROTVEC_LG_REACTION),
# and generalized-alpha's multipliers carry a start-up transient (test_exudyn_loops.START_UP).
PAIR_REDUNDANT_POSITION_TOL, PAIR_REDUNDANT_RATE_TOL, PAIR_REDUNDANT_REACTION_TOL = 5e-6, 1e-4, 3e-5  # 2.5-3x
PAIR_STEPS = (1e-3, 5e-4)
# Andrews' squeezer against the published angles at t = 0.03 s (the Test Set's PSIDE solution, within 1.4e-9 rad
# of the case's truth: tests/test_andrews_squeezer.py), second order, measured at dt = 1e-4, 1e-5, 5e-6:
# generalized-alpha on the kinematic tree 8.32e-3, 8.30e-5, 2.08e-5 rad; trapezoidal-index2 with redundant
# joints on Euler-parameter nodes 1.12e-3, 1.09e-5, 2.66e-6 rad. The test runs 1e-4 and 5e-5.
SQUEEZER_STEPS = (1e-4, 5e-5)
SQUEEZER_ANGLE_TOL = 5e-3  # rad at dt = 5e-5: 2.4x the 2.08e-3 that generalized-alpha's 8.32e-3 at 1e-4 gives


def _run(scene, times, integrator, dt=None, **options):
    settings = Settings(integrator, dt=dt, options=options) if dt else Settings(integrator, rtol=1e-9, atol=1e-9)
    prepared = ADAPTER.prepare(scene, times, settings)
    assert ADAPTER.unsupported(scene, settings) is None
    outcome = ADAPTER.run(prepared)
    return outcome.trajectory, ADAPTER.audit(prepared, outcome)


def _oscillator_error(damping, gravity, integrator, dt=None):
    scene = _oscillator(damping, gravity)
    exact_z = -(REST + MASS * gravity / STIFFNESS + _damped_stretch(TIMES, damping))
    traj, audit = _run(scene, TIMES, integrator, dt)
    assert np.abs(traj.bodies["b"].position[:, :2]).max() == 0.0  # the force stays on the line
    assert audit["springs"]["spring_world_b"]["mismatches"] == [] and audit["passive_extra"] == []
    return np.abs(traj.bodies["b"].position[:, 2] - exact_z).max()


def _assert_order(errors, order):
    observed = np.log2(errors[0] / errors[1])
    assert abs(observed - order) < ORDER_SLACK, (errors, observed)


@pytest.mark.parametrize("damping,gravity", [(0.0, 0.0), (DAMPING, GRAVITY)])
@pytest.mark.parametrize("integrator", sorted(ORDERS))
def test_oscillator_converges_to_its_closed_form_at_the_solvers_order(integrator, damping, gravity):
    order, measured = ORDERS[integrator]
    errors = [_oscillator_error(damping, gravity, integrator, dt) for dt in STEPS]
    _assert_order(errors, order)
    assert errors[1] < MARGIN * measured


@pytest.mark.parametrize("damping,gravity,expected", [(0.0, 0.0, VERLET_UNDAMPED), (DAMPING, GRAVITY, VERLET_DAMPED)])
def test_velocity_verlet_is_first_order_with_a_damper(damping, gravity, expected):
    order, measured = expected
    errors = [_oscillator_error(damping, gravity, "velocity-verlet", dt) for dt in STEPS]
    _assert_order(errors, order)
    assert errors[1] < MARGIN * measured


@pytest.mark.parametrize("damping,gravity", [(0.0, 0.0), (DAMPING, GRAVITY)])
def test_adaptive_dopri5_meets_the_closed_form(damping, gravity):
    assert _oscillator_error(damping, gravity, "dopri5") < DOPRI5_TOL


@pytest.fixture(scope="module")
def tumbling_box():
    scene = _oscillator(DAMPING, GRAVITY, point_b=(0.05, 0.1, 0.15), w0=(1.0, -2.0, 3.0))
    return scene, simulate(scene, TIMES, TRUTH)[0]


def test_off_centre_spring_on_a_tumbling_box_matches_the_reference(tumbling_box):
    scene, truth = tumbling_box
    traj, audit = _run(scene, TIMES, "rk67", STEPS[1])
    assert np.abs(traj.bodies["b"].position - truth.bodies["b"].position).max() < BOX_POSITION_TOL
    assert np.abs(traj.bodies["b"].angular_velocity - truth.bodies["b"].angular_velocity).max() < BOX_RATE_TOL
    spring = audit["springs"]["spring_world_b"]
    assert spring["point_b"] == pytest.approx([0.05, 0.1, 0.15], abs=1e-15) and spring["mismatches"] == []


def hinged_pair():
    """Two 0.6-m rods hanging from the world by revolute joints about x and then y (a spatial chain, under
    gravity), held by a damped spring from a world point to an off-axis point of the lower rod and by a second
    one between the two rods, joined at off-axis points (link to link)."""
    length = 0.6
    bodies = [Body.cylinder("l0", 1.0, length, 0.02, axis=2), Body.cylinder("l1", 0.7, length, 0.02, axis=2)]
    joints = [Joint("revolute", "world", "l0", q0=[0.4], v0=[1.0], axis=[1, 0, 0], child_point=[0, 0, length / 2]),
              Joint("revolute", "l0", "l1", q0=[-0.3], v0=[0.5], axis=[0, 1, 0], parent_point=[0, 0, -length / 2],
                    child_point=[0, 0, length / 2])]
    springs = [Spring("world", "l1", point_a=(0.3, 0.2, -0.2), point_b=(0.02, 0.0, -0.25), stiffness=40.0,
                      damping=0.5, rest_length=0.3, name="anchor"),
               Spring("l0", "l1", point_a=(0.0, 0.02, 0.1), point_b=(0.0, -0.02, 0.1), stiffness=20.0, damping=0.2,
                      rest_length=0.5, name="between")]
    return Scene("hinged_pair", bodies, joints, [0.0, 0.0, -9.81], springs=springs)


PAIR_TIMES = np.linspace(0.0, 1.0, 101)


@pytest.fixture(scope="module")
def pair():
    scene = hinged_pair()
    return scene, simulate(scene, PAIR_TIMES, TRUTH)[0]


def _pair_errors(traj, truth):
    """Largest position (m), angular velocity (rad/s) and joint reaction error relative to its largest."""
    position = max(np.abs(traj.bodies[b].position - truth.bodies[b].position).max() for b in truth.bodies)
    rate = max(np.abs(traj.bodies[b].angular_velocity - truth.bodies[b].angular_velocity).max() for b in truth.bodies)
    reaction = max(np.abs(traj.extras[f"reaction_force:{b}"] - truth.extras[f"reaction_force:{b}"]).max()
                   / np.abs(truth.extras[f"reaction_force:{b}"]).max() for b in truth.bodies)
    return position, rate, reaction


def _assert_pair_audit(scene, audit):
    for sp in scene.springs:
        got = audit["springs"][sp.name]
        assert got["mismatches"] == [], got
        assert (got["element"], got["body_a"], got["body_b"]) == (ELEMENT, sp.body_a, sp.body_b)
        assert (got["stiffness"], got["damping"], got["rest_length"]) == (sp.stiffness, sp.damping, sp.rest_length)
        assert (got["preload"], got["velocity_offset"], got["user_function"]) == (0.0, 0.0, False)
    assert audit["passive"]["objects"][ELEMENT] == 2 and audit["passive_extra"] == []


def test_springs_on_kinematic_tree_links_match_the_reference(pair):
    scene, truth = pair
    traj, audit = _run(scene, PAIR_TIMES, "rk67", STEPS[1])
    assert max(_pair_errors(traj, truth)) < PAIR_TREE_TOL
    _assert_pair_audit(scene, audit)
    passive = audit["passive"]
    assert passive["objects"]["ObjectKinematicTree"] == 1
    assert (passive["tree_joint_stiffness"], passive["tree_joint_damping"], passive["tree_joint_forces"]) == (0, 0, 0)


def test_springs_on_rigid_bodies_with_redundant_joints_match_the_reference(pair):
    scene, truth = pair
    errors = []
    for dt in PAIR_STEPS:
        traj, audit = _run(scene, PAIR_TIMES, "trapezoidal-index2", dt, joints="redundant", node="ep")
        errors.append(_pair_errors(traj, truth))
    _assert_order([e[0] for e in errors], 2)
    position, rate, reaction = errors[1]
    assert position < PAIR_REDUNDANT_POSITION_TOL and rate < PAIR_REDUNDANT_RATE_TOL
    assert reaction < PAIR_REDUNDANT_REACTION_TOL
    _assert_pair_audit(scene, audit)
    assert audit["passive"]["objects"]["ObjectRigidBody"] == 2 and "ObjectKinematicTree" not in audit["passive"]["objects"]


@pytest.mark.parametrize("joints", ["minimal", "redundant"])
def test_the_audit_reads_what_exudyn_holds_and_catches_what_the_scene_lacks(joints):
    """The read-back is Exudyn's, not the scene's: a stiffness changed in the built system, a tree joint damper
    or a load switched on are each reported."""
    scene = hinged_pair()
    built = build(scene, Settings("generalized-alpha", dt=1e-3, options={"joints": joints, "node": "ep"}))
    mbs = built.mbs
    assert all(s["mismatches"] == [] for s in built.spring_readout.values())
    rigid = sum(owner != "world" for owner in built.owners.values())
    assert unexpected_passive(passive_effects(mbs), scene, rigid) == []
    mbs.SetObjectParameter(built.springs["anchor"]["object"], "stiffness", 41.0)
    mismatches = read_springs(mbs, scene, built)["anchor"]["mismatches"]
    assert mismatches[0] == "stiffness: engine 41.0, scene 40.0"
    assert any(m.startswith("initial_tension: engine") for m in mismatches)  # Exudyn's own force, read back
    from exudyn.itemInterface import LoadForceVector, MarkerBodyRigid, MarkerKinematicTreeRigid

    if joints == "minimal":
        tree = next(i for i in range(mbs.systemData.NumberOfObjects())
                    if mbs.GetObject(i)["objectType"] == "KinematicTree")
        mbs.SetObjectParameter(tree, "jointDControlVector", [0.0, 0.3])
        marker = mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=tree, linkNumber=0))
    else:
        marker = mbs.AddMarker(MarkerBodyRigid(bodyNumber=next(iter(built.owners))))
    mbs.AddLoad(LoadForceVector(markerNumber=marker, loadVector=[1.0, 0.0, 0.0]))
    found = unexpected_passive(passive_effects(mbs), scene, rigid)
    assert "1 LoadForceVector(s) for 0" in found
    assert ("tree_joint_damping 0.3" in found) == (joints == "minimal")


@pytest.mark.parametrize("integrator,options", [("generalized-alpha", {}),
                                                ("trapezoidal-index2", {"joints": "redundant", "node": "ep"})])
def test_andrews_squeezer_reaches_the_published_angles_at_second_order(integrator, options):
    case = make_case("andrews_squeezer")
    assert case.times[-1] == REFERENCE_T
    published = np.array(list(REFERENCE_ANGLES.values()))
    errors = []
    for dt in SQUEEZER_STEPS:
        traj, audit = _run(case.scene, case.times, integrator, dt, **options)
        errors.append(np.abs(np.array([traj.joints[b].q[-1, 0] for b in ANGLES.values()]) - published).max())
    _assert_order(errors, 2)
    assert errors[1] < SQUEEZER_ANGLE_TOL
    assert audit["springs"]["spring_DC"]["mismatches"] == [] and audit["passive_extra"] == []


def test_explicit_solvers_still_refuse_the_squeezers_loops_not_its_spring():
    scene = make_case("andrews_squeezer").scene
    reason = ADAPTER.unsupported(scene, Settings("rk44", dt=1e-5))
    assert reason.startswith("loop closures with an explicit integrator") and "spring" not in reason
    # without its loops the same mechanism (an open tree with the spring and the motor) runs explicitly
    tree = Scene("squeezer_tree", scene.bodies, scene.joints, scene.gravity, loads=scene.loads, springs=scene.springs)
    assert ADAPTER.unsupported(tree, Settings("rk44", dt=1e-5)) is None
