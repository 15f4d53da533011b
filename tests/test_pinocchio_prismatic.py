"""Pinocchio's prismatic joints (``JointModelPrismaticUnaligned``) against exact truths: a box sliding down an
inclined axis (its motion and the joint's reaction in closed form, for every integrator and both loops), the same
slider on a spring-damper (the damped oscillator's closed form of tests/test_springs.py), a bead on a rod that spins
freely about a vertical hub (kinetic energy and the axial angular momentum conserved), a slider-crank closed by a
loop (the slider's closed-form kinematics, energy, and no reaction along the slide); the bead and the slider-crank
against the reference solver's Kane; and the audit's read-back of the built joint."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from installed import needs

pytestmark = needs("pinocchio")

from dalembert import invariants, spatial  # noqa: E402
from dalembert.adapters.registry import get_adapter  # noqa: E402
from dalembert.scene import Body, Joint, Loop, Scene, Spring  # noqa: E402
from dalembert.settings import Settings  # noqa: E402
from test_springs import (DAMPING, GRAVITY, MASS, ORDER_RATIO, POSITION_TOL, REST, STEPS, STIFFNESS,  # noqa: E402
                          STRETCH, TIMES, _damped_stretch)

ADAPTER = get_adapter("pinocchio")
LOOPS = ("native", "python")
FIXED = ("euler", "rk4", "rk4-naive")
ADAPTIVE_TOL = 1e-10  # rtol = atol of the adaptive runs here

# ---------------------------------------------------------------- the inclined slider
SLIDER_MASS = 1.5  # kg
SLIDER_AXIS = (1.0, -2.0, 2.0)  # in the parent joint frame, length 3
SLIDER_D0, SLIDER_V0 = 0.3, 0.7  # m, m/s
SLIDER_G = np.array([0.0, 0.0, -9.81])
SLIDER_TIMES = np.linspace(0.0, 1.0, 11)
SLIDER_DT = 1e-2
# The motion is quadratic in t: RK4 and the adaptive codes integrate it exactly, semi-implicit Euler exactly up to
# its known first-order term (below), so what remains is roundoff over 100 steps on a ~5-m slide and a ~15-N
# reaction (measured <= 1.8e-15 m, 1.8e-15 N); a wrong axis, frame or sign misses by O(1).
SLIDER_ROUNDOFF = 1e-12


def _inclined_slider():
    """A box on a prismatic joint to the world: the joint frame turned and offset, the body frame off the child
    joint frame (point and attitude), so that every frame of the joint enters."""
    q_p = tuple(spatial.quat_normalize(np.array([0.9, 0.2, -0.3, 0.1])))
    q_c = tuple(spatial.quat_normalize(np.array([0.8, -0.1, 0.4, 0.2])))
    joint = Joint("prismatic", "world", "b", (SLIDER_D0,), (SLIDER_V0,), axis=SLIDER_AXIS,
                  parent_point=(0.1, -0.2, 0.5), parent_quat=q_p, child_point=(0.05, 0.02, -0.1), child_quat=q_c)
    scene = Scene("inclined_slider", [Body.box("b", SLIDER_MASS, (0.1, 0.2, 0.3))], [joint], gravity=tuple(SLIDER_G))
    a_W = spatial.quat_to_matrix(q_p) @ (np.array(SLIDER_AXIS) / np.linalg.norm(SLIDER_AXIS))
    return scene, a_W


def _run(scene, times, settings):
    ADAPTER.check(scene, times, settings)
    assert ADAPTER.unsupported(scene, settings) is None
    prepared = ADAPTER.prepare(scene, times, settings)
    return prepared, ADAPTER.run(prepared)


@pytest.mark.parametrize("integrator,loop", [(i, lp) for i in FIXED for lp in LOOPS]
                         + [("rk45", "python"), ("dop853", "python")])  # the adaptive runs have one loop
def test_inclined_slider_slides_and_reacts_exactly(integrator, loop):
    """``d = d0 + v0 t + (g . a) t^2 / 2`` along the world axis ``a`` (semi-implicit Euler adds exactly
    ``(g . a) h t / 2`` to d, nothing to its exact rate: v first, then q with the new v); the COM moves by
    ``(d - d0) a`` without turning; the joint pushes ON the box with ``m (g . a) a - m g``, the part of the weight
    off the axis, reversed."""
    scene, a_W = _inclined_slider()
    settings = (Settings(integrator, dt=SLIDER_DT, options={"loop": loop}) if integrator in FIXED
                else Settings(integrator, rtol=ADAPTIVE_TOL, atol=ADAPTIVE_TOL))
    _, out = _run(scene, SLIDER_TIMES, settings)
    t, g_a = SLIDER_TIMES, float(SLIDER_G @ a_W)
    d = SLIDER_D0 + SLIDER_V0 * t + g_a * t**2 / 2 + (g_a * SLIDER_DT * t / 2 if integrator == "euler" else 0.0)
    d_rate = SLIDER_V0 + g_a * t
    s0 = spatial.initial_body_states(scene)["b"]
    traj = out.trajectory
    b = traj.bodies["b"]
    assert np.abs(traj.joints["b"].q[:, 0] - d).max() < SLIDER_ROUNDOFF
    assert np.abs(traj.joints["b"].v[:, 0] - d_rate).max() < SLIDER_ROUNDOFF
    assert np.abs(b.position - (s0["p"] + np.outer(d - SLIDER_D0, a_W))).max() < SLIDER_ROUNDOFF
    assert np.abs(b.velocity - np.outer(d_rate, a_W)).max() < SLIDER_ROUNDOFF
    assert np.abs(b.angular_velocity).max() < SLIDER_ROUNDOFF
    assert spatial.rotation_angle(b.quaternion, spatial.matrix_to_quat(s0["R"])).max() < SLIDER_ROUNDOFF
    reaction = SLIDER_MASS * (g_a * a_W - SLIDER_G)
    assert np.abs(traj.extras["reaction_force:b"] - reaction).max() < SLIDER_ROUNDOFF
    if integrator in FIXED and loop == "native":
        assert out.info["loop"].startswith("C++"), out.info["loop"]


# ---------------------------------------------------------------- the slider on a spring
# The slide's direction (length 3: tilted, so gravity pulls along it and across it) and the spring's world end, on
# the slide's line: the spring's length is the joint's displacement.
SPRUNG_AXIS = np.array([2.0, 1.0, 2.0])
SPRUNG_ANCHOR = (0.1, 0.2, -0.3)
# The reaction is the weight's part across the slide, reversed, at every instant (the spring and the damper act
# along it): exact but for roundoff on ~20-N forces over 400 steps (measured 7.1e-15 N).
SPRUNG_REACTION_TOL = 1e-12


def _sprung_slider():
    """A box on a prismatic joint from ``SPRUNG_ANCHOR`` along ``SPRUNG_AXIS``, on a spring-damper from the anchor to
    its COM (tests/test_springs.py's constants), starting at rest ``STRETCH`` beyond its sagged equilibrium."""
    u = SPRUNG_AXIS / np.linalg.norm(SPRUNG_AXIS)
    g = np.array([0.0, 0.0, -GRAVITY])
    length_eq = REST + MASS * float(g @ u) / STIFFNESS
    scene = Scene("sprung_slider", [Body.box("b", MASS, (0.1, 0.2, 0.3))],
                  [Joint("prismatic", "world", "b", (length_eq + STRETCH,), (0.0,), axis=tuple(SPRUNG_AXIS),
                         parent_point=SPRUNG_ANCHOR)], gravity=tuple(g),
                  springs=[Spring("world", "b", point_a=SPRUNG_ANCHOR, stiffness=STIFFNESS, damping=DAMPING,
                                  rest_length=REST)])
    return scene, u, g, length_eq


@pytest.mark.parametrize("loop", LOOPS)
def test_slider_on_a_spring_is_the_damped_oscillator(loop):
    """``m l'' = -k (l - l0) - c l' + m g . u`` along the slide: the damped closed form about the sagged equilibrium,
    approached at fourth order by RK4; the joint's reaction never carries the spring's force."""
    scene, u, g, length_eq = _sprung_slider()
    exact = length_eq + _damped_stretch(TIMES, DAMPING)
    errors = []
    for dt in STEPS:
        _, out = _run(scene, TIMES, Settings("rk4", dt=dt, options={"loop": loop}))
        errors.append(np.abs(out.trajectory.joints["b"].q[:, 0] - exact).max())
        reaction = out.trajectory.extras["reaction_force:b"]
        assert np.abs(reaction - (-MASS * (g - (g @ u) * u))).max() < SPRUNG_REACTION_TOL
    assert ORDER_RATIO[0] < errors[0] / errors[1] < ORDER_RATIO[1], errors
    assert errors[1] < POSITION_TOL


# ---------------------------------------------------------------- the bead on a spinning rod
BEAD_TIMES = np.linspace(0.0, 2.0, 201)
BEAD_STEPS = (1e-2, 5e-3)
# RK4 keeps quadratic invariants only to its order: measured (relative, over 2 s, the bead flung from 0.3 to
# 1.6 m) kinetic energy 6.2e-9 / 3.9e-10 and axial angular momentum 2.2e-9 / 1.4e-10 at dt = 1e-2 / 5e-3 (16.0-
# and 16.1-fold); the bounds leave a factor ~3 at the finer step, and the ratio (ORDER_RATIO) pins the fourth
# order. A body state read back in a wrong frame, or a joint's force at a wrong point, breaks them at O(1).
BEAD_ENERGY_TOL = 1e-9
BEAD_MOMENTUM_TOL = 5e-10


def _bead():
    """A hub free to turn about the vertical z axis (revolute to the world); on it, a bead on a prismatic joint
    along the hub's x axis, offset from the hub's axis (0.1 m across, 0.25 m up), its body frame off the joint frame.
    Gravity is along the hub's axis: it does no work on the motion (horizontal) and has no moment about the axis."""
    return Scene("bead_on_a_spinning_rod",
                 (Body.box("hub", 1.0, (0.4, 0.1, 0.1)), Body.box("bead", 0.2, (0.02, 0.03, 0.04))),
                 (Joint("revolute", "world", "hub", (0.7,), (2.0,), axis=(0, 0, 2)),
                  Joint("prismatic", "hub", "bead", (0.3,), (-0.5,), axis=(3, 0, 0), parent_point=(0.0, 0.1, 0.25),
                        child_point=(0.01, 0.02, 0.03),
                        child_quat=tuple(spatial.quat_normalize(np.array([1.0, 0.2, 0.3, 0.1]))))),
                 gravity=(0.0, 0.0, -9.81))


def _axial_momentum(scene, traj):
    """The angular momentum about the hub's axis (the world z axis through the origin), kg m^2/s, shape (n,):
    ``sum_bodies m (x x v)_z + (R I R^T w)_z``, from the trajectory's body states."""
    total = np.zeros(len(traj.t))
    for body in scene.bodies:
        b = traj.bodies[body.name]
        R = spatial.quat_to_matrix(spatial.quat_normalize(b.quaternion))
        spin = np.einsum("nij,jk,nlk,nl->ni", R, body.inertia_matrix, R, b.angular_velocity)
        total += body.mass * np.cross(b.position, b.velocity)[:, 2] + spin[:, 2]
    return total


def test_bead_on_a_spinning_rod_keeps_its_energy_and_axial_momentum():
    scene = _bead()
    drifts = []
    for dt in BEAD_STEPS:
        _, out = _run(scene, BEAD_TIMES, Settings("rk4", dt=dt))
        energy, momentum = invariants.kinetic_energy(scene, out.trajectory), _axial_momentum(scene, out.trajectory)
        drifts.append((np.abs(energy / energy[0] - 1.0).max(), np.abs(momentum / momentum[0] - 1.0).max()))
    (e1, l1), (e2, l2) = drifts
    assert ORDER_RATIO[0] < e1 / e2 < ORDER_RATIO[1] and ORDER_RATIO[0] < l1 / l2 < ORDER_RATIO[1], drifts
    assert e2 < BEAD_ENERGY_TOL and l2 < BEAD_MOMENTUM_TOL


# The bead against the reference solver (Kane, DOP853 at rtol = atol = 1e-12: an independent formulation). Measured,
# largest over 2 s: rk4 at dt = 1e-3 6.1e-12 m, 6.7e-12 rad (and m of slide), 3.9e-11 rad/s, reactions 2.7e-12 of the
# largest (at dt = 5e-3: 4.0e-10 m, 6.1e-10 rad/s, so the truncation at 1e-3 is ~1e-12 and these are the reference's
# own error); Pinocchio's dop853 at 1e-12 the same. 1e-10 in each unit (dalembert.errors): 2.5x the worst.
BEAD_REFERENCE_TOL = 1e-10
BEAD_REFERENCE_RTOL = 1e-12


@pytest.mark.parametrize("settings", [Settings("rk4", dt=1e-3),
                                      Settings("dop853", rtol=BEAD_REFERENCE_RTOL, atol=BEAD_REFERENCE_RTOL)],
                         ids=["rk4", "dop853"])
def test_bead_on_a_spinning_rod_is_the_reference_solution(settings):
    """Every body state, both joints' coordinates and both reactions (the hub's revolute, the bead's slide)."""
    from dalembert.errors import trajectory_errors
    from dalembert.reference import simulate

    scene = _bead()
    ref = simulate(scene, BEAD_TIMES, Settings("dop853", rtol=BEAD_REFERENCE_RTOL, atol=BEAD_REFERENCE_RTOL,
                                               options={"formulation": "kane"}))[0]
    _, out = _run(scene, BEAD_TIMES, settings)
    errors = trajectory_errors(out.trajectory, ref)
    assert {"joint", "reaction_force", "position", "angular_velocity"} <= set(errors)
    for quantity, (largest, _) in errors.items():
        assert largest < BEAD_REFERENCE_TOL, (quantity, largest)


# ---------------------------------------------------------------- the compiled loop
# The compiled and the Python loops do the same arithmetic (no fused multiply-add: native.FLAGS), in a different
# order here and there: measured, relative to the state's size over 2 s at dt = 1e-2, 0 on the bead (bit for bit)
# and <= 7.7e-16 on the sprung slider (the spring's forces).
LOOPS_AGREE_REL = 1e-12


@pytest.mark.parametrize("integrator", FIXED)
@pytest.mark.parametrize("make", [_bead, lambda: _sprung_slider()[0]], ids=["bead", "sprung_slider"])
def test_the_compiled_loop_is_the_python_loop(make, integrator):
    """The stepper is generic over Pinocchio's joint variant (it loads the serialized model): prismatic joints,
    alone or on a revolute hub, with and without a spring, run the same there."""
    scene = make()
    runs = {loop: _run(scene, BEAD_TIMES, Settings(integrator, dt=1e-2, options={"loop": loop}))[1] for loop in LOOPS}
    assert runs["native"].info["loop"].startswith("C++"), runs["native"].info["loop"]
    for name in ("q", "v"):
        for body in runs["python"].trajectory.joints:
            x = getattr(runs["native"].trajectory.joints[body], name)
            y = getattr(runs["python"].trajectory.joints[body], name)
            assert np.abs(x - y).max() <= LOOPS_AGREE_REL * max(1.0, np.abs(y).max()), (body, name)


# ---------------------------------------------------------------- the slider-crank (a loop through a prismatic joint)
CRANK, ROD, OFFSET = 0.1, 0.3, 0.02  # m: crank and connecting-rod lengths, the slide's offset from the crank pivot
CRANK_ANGLE, CRANK_RATE = 0.4, 8.0  # rad, rad/s at t = 0
SLIDER_CRANK_MASS = 1.2  # kg, the slider's
CRANK_G = np.array([0.0, -9.81, 0.0])  # in the mechanism's plane
CRANK_TIMES = np.linspace(0.0, 1.0, 101)
CRANK_STEPS = (1e-3, 5e-4)
# RK4 with constraintDynamics (Baumgarte-corrected, adapters/pinocchio/loops.py) over 1 s (the crank swings back
# through 4 rad): the slide's distance from its closed-form kinematics, measured 4.6e-10 / 2.8e-11 m, and the
# energy's drift 1.3e-8 / 8.5e-10 J (of up to 1.13 J kinetic) at dt = 1e-3 / 5e-4 (16-fold: fourth order); bounds
# a factor ~3 above the finer step's.
CRANK_CLOSURE_TOL = 1e-10  # m
CRANK_ENERGY_TOL = 3e-9  # J
# What the slide and the loop exert on the slider, with its weight, has no component across the slide (it
# moves only along it), and the frictionless slide pushes nothing along itself: exact but for roundoff on
# ~40-N forces (measured <= 2.1e-14 N).
CRANK_FORCE_TOL = 1e-11  # N


def _slider_crank():
    """A crank (revolute to the world about z at the origin), a connecting rod (revolute on the crank's tip), a
    slider (prismatic to the world along x, ``OFFSET`` off the pivot in y); a revolute loop joins the rod's far
    end to the slider. The initial rod angle and the slide's displacement and rates are the closed-form kinematics:
    with ``s = sqrt(ROD^2 - (CRANK sin(theta) - OFFSET)^2)``, ``x = CRANK cos(theta) + s``."""
    th, th_dot = CRANK_ANGLE, CRANK_RATE
    s = np.sqrt(ROD**2 - (CRANK * np.sin(th) - OFFSET) ** 2)
    x = CRANK * np.cos(th) + s
    x_dot = -CRANK * np.sin(th) * th_dot - (CRANK * np.sin(th) - OFFSET) * CRANK * np.cos(th) * th_dot / s
    phi = np.arctan2(OFFSET - CRANK * np.sin(th), x - CRANK * np.cos(th))  # the rod's direction
    phi_dot = -CRANK * np.cos(th) * th_dot / (ROD * np.cos(phi))
    return Scene("slider_crank", (Body.box("crank", 0.5, (CRANK, 0.02, 0.02)), Body.box("rod", 0.8, (ROD, 0.02, 0.02)),
                                  Body.box("slider", SLIDER_CRANK_MASS, (0.05, 0.03, 0.03))),
                 (Joint("revolute", "world", "crank", (th,), (th_dot,), axis=(0, 0, 1), child_point=(-CRANK / 2, 0, 0)),
                  Joint("revolute", "crank", "rod", (phi - th,), (phi_dot - th_dot,), axis=(0, 0, 1),
                        parent_point=(CRANK / 2, 0, 0), child_point=(-ROD / 2, 0, 0)),
                  Joint("prismatic", "world", "slider", (x,), (x_dot,), axis=(1, 0, 0), parent_point=(0, OFFSET, 0))),
                 gravity=tuple(CRANK_G),
                 loops=(Loop("revolute", "rod", "slider", point_a=(ROD / 2, 0, 0), axis=(0, 0, 1)),))


def test_slider_crank_closes_its_loop_through_the_prismatic_joint():
    """pin.constraintDynamics with a prismatic joint in the loop: the slide follows the crank's closed-form
    kinematics, the energy is kept at fourth order, and the slider's forces balance across the slide."""
    scene = _slider_crank()
    closure, energy = [], []
    for dt in CRANK_STEPS:
        prepared, out = _run(scene, CRANK_TIMES, Settings("rk4", dt=dt))
        traj = out.trajectory
        th, x = traj.joints["crank"].q[:, 0], traj.joints["slider"].q[:, 0]
        closure.append(np.abs(x - (CRANK * np.cos(th) + np.sqrt(ROD**2 - (CRANK * np.sin(th) - OFFSET) ** 2))).max())
        e = invariants.total_energy(scene, traj)
        energy.append(np.abs(e - e[0]).max())
    assert prepared.pm.constrained and np.ptp(th) > 3.0  # the loop was solved; the crank swung through 3 rad
    assert closure[1] < CRANK_CLOSURE_TOL and energy[1] < CRANK_ENERGY_TOL, (closure, energy)
    assert ORDER_RATIO[0] < energy[0] / energy[1] < ORDER_RATIO[1], energy
    slide, loop = traj.extras["reaction_force:slider"], traj.extras["reaction_force:loop_rod_slider"]
    assert np.abs(slide[:, 0]).max() < CRANK_FORCE_TOL  # nothing along the frictionless slide
    across = slide + loop + SLIDER_CRANK_MASS * CRANK_G
    assert np.abs(across[:, 1:]).max() < CRANK_FORCE_TOL
    assert np.abs(loop).max() > 10.0  # the loop does carry the rod's push


# The slider-crank over 0.5 s against the reference solver (Kane with its closed-loop solver, DOP853 at 1e-12, 2.8 s
# of the test's time: computed once). Measured, largest over the samples: Pinocchio's dop853 at 1e-12 3.0e-13 m,
# 6.6e-12 rad (and m of slide), 7.7e-11 rad/s, reactions (the loop's included) 1.5e-11 of the largest; its rk4 at
# dt = 5e-4 8.4e-11 m, 1.8e-9 rad, 1.5e-8 rad/s, 4.0e-9 (fourth order: 16x that at 1e-3). Bounds ~4x those.
CRANK_REFERENCE_TIMES = np.linspace(0.0, 0.5, 51)
CRANK_REFERENCE_RTOL = 1e-12
CRANK_REFERENCE_TOL = {"dop853": 3e-10, "rk4": 6e-8}


@functools.lru_cache(maxsize=1)
def _slider_crank_reference():
    from dalembert.reference import simulate

    return simulate(_slider_crank(), CRANK_REFERENCE_TIMES,
                    Settings("dop853", rtol=CRANK_REFERENCE_RTOL, atol=CRANK_REFERENCE_RTOL,
                             options={"formulation": "kane"}))[0]


@pytest.mark.parametrize("settings", [Settings("rk4", dt=5e-4),
                                      Settings("dop853", rtol=CRANK_REFERENCE_RTOL, atol=CRANK_REFERENCE_RTOL)],
                         ids=["rk4", "dop853"])
def test_slider_crank_is_the_reference_solution(settings):
    """Every body state, the joints' coordinates, and every reaction (the slide's and the loop's) against an
    independent solver of the same loop."""
    from dalembert.errors import trajectory_errors

    _, out = _run(_slider_crank(), CRANK_REFERENCE_TIMES, settings)
    errors = trajectory_errors(out.trajectory, _slider_crank_reference())
    assert {"joint", "reaction_force", "position", "angular_velocity"} <= set(errors)
    for quantity, (largest, _) in errors.items():
        assert largest < CRANK_REFERENCE_TOL[settings.integrator], (quantity, largest)


# ---------------------------------------------------------------- the audit and what is refused
def test_the_audit_reads_the_joint_and_its_axis_back_from_the_built_model():
    scene, _ = _inclined_slider()
    prepared, out = _run(scene, SLIDER_TIMES, Settings("rk4", dt=SLIDER_DT))
    audit = ADAPTER.audit(prepared, out)
    assert audit["joints"] == {"b": "JointModelPrismaticUnaligned"}
    np.testing.assert_allclose(audit["joint_axes"]["b"], np.array(SLIDER_AXIS) / 3.0, rtol=0, atol=1e-16)
    assert audit["nq"] == audit["nv"] == 1
    assert "b: prismatic -> pin joint 1 (JointModelPrismaticUnaligned, axis [0.333333333333, -0.666666666667, " \
           "0.666666666667] (joint frame))" in ADAPTER.describe(scene, Settings("rk4", dt=SLIDER_DT))
    assert "joint:prismatic" in ADAPTER.effects


def test_welds_as_constraints_refuse_a_prismatic_joint():
    """With welds as constraints the tree joints' reactions would miss the constraint forces: refused, saying so."""
    scene, _ = _inclined_slider()
    scene = Scene(scene.name, (*scene.bodies, Body.box("w", 0.1, (0.01, 0.01, 0.01))),
                  (*scene.joints, Joint("weld", "b", "w", (), ())), gravity=scene.gravity)
    reason = ADAPTER.unsupported(scene, Settings("rk4", dt=SLIDER_DT, options={"welds": "constraint"}))
    assert reason.startswith("welds=constraint with revolute, prismatic or ball joints")
    assert ADAPTER.unsupported(scene, Settings("rk4", dt=SLIDER_DT)) is None
