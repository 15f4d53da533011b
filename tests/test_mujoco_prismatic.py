"""MuJoCo and MJX build prismatic joints as slide joints (``adapters/mujoco/mjcf.py``): exact truths only.

* A box on an inclined slider under gravity (turned joint frames, offset joint points): a constant
  acceleration ``g . a_W`` along the axis, which RK4 integrates exactly and the first-order integrators
  by their own closed form; the reaction ``m (g . a_W) a_W - m g`` at every sample; the MJCF's slide joint
  and the compiled model's (the audit) along the scene's axis, with nothing else on it.
* The slider on a spring-damper along its axis: ``test_springs``' oscillator closed forms, at each
  integrator's order; the reaction ``-m g_perp`` (the spring's force is along the axis).
* A bead on a spinning rod (a free hub on a revolute joint, the bead sliding along a rod off the hub's
  axis): no closed form, but the energy and the angular momentum about the hub's axis are conserved, and
  the frictionless slide exerts no force along its axis; and the whole motion against the reference (Kane).
* Two of the reference's scenes (tests/test_prismatic.py): the slider on a swinging rod, against it; the
  slider-crank closed over its prismatic joint, against its closed-form kinematics.
* MJX (one compile, ``long``): the slider and the bead in one model, in float64.
"""

import numpy as np
import pytest
from installed import needs

pytestmark = needs("mujoco")

from dalembert import Settings, invariants, spatial  # noqa: E402
from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.errors import trajectory_errors  # noqa: E402
from dalembert.reference import simulate  # noqa: E402
from dalembert.scene import Body, Joint, Scene, Spring  # noqa: E402
from engine_runs import run_with_audit  # noqa: E402
from test_mujoco_springs import FIRST_ORDER_POSITION_TOL, FIRST_ORDER_RATIO  # noqa: E402
from test_springs import (DAMPING, MASS, ORDER_RATIO, POSITION_TOL, REST, STIFFNESS, STRETCH, TIMES,  # noqa: E402
                          _damped_stretch)

INTEGRATORS = ("euler", "rk4", "implicit", "implicitfast", "discrete")
G_W = np.array([0.0, 0.0, -9.81])  # m/s^2
# The inclined slider: joint frames turned and offset, so that a frame or axis mixed up shows.
SLIDER_AXIS = (1.0, 0.0, 2.0)  # in the parent joint frame, not unit
SLIDER_PARENT_QUAT = tuple(spatial.matrix_to_quat(spatial.so3_exp(np.array([0.3, -0.2, 0.5]))))
SLIDER_CHILD_QUAT = tuple(spatial.matrix_to_quat(spatial.so3_exp(np.array([-0.1, 0.4, 0.2]))))
SLIDER_MASS, SLIDER_D0, SLIDER_V0 = 1.5, 0.2, 0.7  # kg, m, m/s
SLIDER_TIMES = np.linspace(0.0, 1.0, 101)
SLIDER_DT = 1e-2  # s: the closed forms below hold at any step
# Under a constant acceleration every integrator's update is exact polynomial arithmetic: the slide and the
# reaction agree with their closed forms up to a few roundings of ~1 m and ~10 N (measured 5e-15 and 6e-15).
SLIDER_ROUNDOFF = 1e-13
# The discrete integrator is implicit in the spring's stiffness, which damps the oscillation numerically: per
# step the amplitude falls by (1 + h^2 w^2)^(-1/2), i.e. by exp(-h w^2 t / 2) over t; with w^2 = 25 /s^2,
# h = 5e-3 s, t = 2 s: 0.3 m (1 - e^-0.125) = 3.5e-2 m (measured 3.3e-2 undamped, 1.3e-2 damped).
DISCRETE_POSITION_TOL = 4e-2
# The bead on the rod, RK4 over 1 s: energy and L_z drift fall 16-fold per halved step (measured 16.1, 16.0)
# to 6.3e-12 and 2.7e-11 relative at dt = 5e-3; a slide frame or rate wrong by O(1) breaks them at O(1).
BEAD_STEPS = (1e-2, 5e-3)
BEAD_DRIFT_TOL = 1e-10
BEAD_TIMES = np.linspace(0.0, 1.0, 101)
# The frictionless slide's force along its own axis, and the read-back bead position against the slide
# and the hub's angle: roundoff of ~1 N and ~0.5 m (measured ~1e-15).
BEAD_ROUNDOFF = 1e-13
# The bead, MuJoCo RK4 at dt = 5e-3 against the reference (Kane, DOP853 at rtol 1e-12, itself ~3e-10 from its
# rtol-1e-10 run): measured 2.3e-11 rad (hub angle), 1.1e-11 m, 2.5e-11 rad/s, 1.7e-11 m/s, 2.2e-12 N, 16-fold
# under the 3.6e-10 rad at dt = 1e-2 (fourth order); a slide frame, rate or Coriolis term wrong would be O(1e-2).
BEAD_REFERENCE_TOL = 1e-10
# The reference's slider on a swinging rod (tests/test_prismatic.py: a spring along the rod, gravity across it),
# MuJoCo RK4 at dt = 5e-3 over 2 s against the reference's DOP853 at 1e-12: measured 5.5e-8 m, 4.5e-8 rad,
# 4.1e-7 m/s, 2.8e-7 N, 16-fold under dt = 1e-2 (8.9e-7 m, 6.5e-6 m/s): fourth order; 3.6x the largest.
SWING_REFERENCE_TOL = 1.5e-6
# The slider-crank closed over its prismatic joint by a revolute loop (two connects, MuJoCo's soft equality),
# RK4 at dt = 1e-3 over 0.35 s through both dead centres: the slide off its closed-form kinematics by the loop's
# softness, measured 2.0e-6 m (2.0e-8 at dt = 1e-4: as dt^2, the time constant's two steps); 5x.
CRANK_KINEMATICS_TOL = 1e-5
# MJX against MuJoCo C, the same RK4 on the same model in float64 over 100 steps: the two libraries' arithmetic
# in different orders; at most a few hundred roundings of ~1 (measured 2.2e-16 in the hinge's and slide's q and v).
MJX_PARITY_TOL = 1e-12


def slider():
    """A box on an inclined prismatic joint to the world, both joint frames turned, the points offset."""
    return Scene("inclined_slider", [Body.box("b", SLIDER_MASS, (0.1, 0.2, 0.3))],
                 [Joint("prismatic", "world", "b", (SLIDER_D0,), (SLIDER_V0,), axis=SLIDER_AXIS,
                        parent_point=(0.1, -0.2, 0.3), parent_quat=SLIDER_PARENT_QUAT,
                        child_point=(0.05, 0.02, -0.03), child_quat=SLIDER_CHILD_QUAT)], tuple(G_W))


def slider_axis_W():
    """The slider's unit axis in world (the parent joint frame is fixed): (3,)."""
    return spatial.quat_to_matrix(np.array(SLIDER_PARENT_QUAT)) @ (np.array(SLIDER_AXIS) / np.linalg.norm(SLIDER_AXIS))


def slider_exact(t, integrator, h):
    """The slide (m) at times ``t`` (s) under the constant acceleration ``alpha = g . a_W``: exactly
    ``d0 + v0 t + alpha t^2 / 2`` for RK4 (exact on a quadratic); the semi-implicit Euler update
    (v += h alpha, then d += h v) adds ``alpha h t / 2``, and so do the implicit ones (no force depends
    on the velocity here)."""
    alpha = G_W @ slider_axis_W()
    lag = 0.0 if integrator == "rk4" else alpha * h * t / 2
    return SLIDER_D0 + SLIDER_V0 * t + alpha * t**2 / 2 + lag


def spring_slider(damping):
    """A box on a prismatic joint at the world origin along ``u`` (world, downhill), on a spring-damper from
    the origin to its COM: the stretch beyond the sagged equilibrium ``REST + m (g . u) / k`` starts at
    ``STRETCH`` from rest."""
    u = np.array([1.0, 2.0, -2.0]) / 3.0
    s_eq = REST + MASS * (G_W @ u) / STIFFNESS
    scene = Scene("spring_slider", [Body.box("b", MASS, (0.1, 0.2, 0.3))],
                  [Joint("prismatic", "world", "b", (s_eq + STRETCH,), (0.0,), axis=tuple(3.0 * u))], tuple(G_W),
                  springs=[Spring("world", "b", stiffness=STIFFNESS, damping=damping, rest_length=REST)])
    return scene, u, s_eq


BEAD_POINT = (0.0, 0.05, 0.1)  # m: the rod along the hub's x, off its axis by 5 cm and 10 cm up


def bead_on_rod():
    """A hub free to turn about the world z (a box, 1 kg) and a bead (0.2 kg) sliding on a rod along the hub's
    x through ``BEAD_POINT``, flung outwards by the spin; gravity along -z does no work on the motion."""
    return Scene("bead_on_rod", (Body.box("hub", 1.0, (0.4, 0.1, 0.1)), Body.box("bead", 0.2, (0.02, 0.03, 0.04))),
                 (Joint("revolute", "world", "hub", (0.3,), (2.0,), axis=(0, 0, 1)),
                  Joint("prismatic", "hub", "bead", (0.1,), (0.2,), axis=(1, 0, 0), parent_point=BEAD_POINT)),
                 tuple(G_W))


def test_mujoco_and_mjx_declare_prismatic_joints():
    for engine in ("mujoco", "mjx"):
        adapter = get_adapter(engine)
        assert {"joint:prismatic"} <= adapter.effects
        assert adapter.unsupported(slider(), Settings("rk4", dt=SLIDER_DT)) is None


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_the_inclined_slider_slides_and_pushes_back_exactly(integrator):
    scene = slider()
    traj, audit = run_with_audit(scene, SLIDER_TIMES, integrator, SLIDER_DT)
    a_W, t = slider_axis_W(), SLIDER_TIMES
    d = slider_exact(t, integrator, SLIDER_DT)
    assert np.abs(traj.joints["b"].q[:, 0] - d).max() < SLIDER_ROUNDOFF
    # the rate is exact for every integrator (v += h alpha at each step)
    assert np.abs(traj.joints["b"].v[:, 0] - (SLIDER_V0 + (G_W @ a_W) * t)).max() < SLIDER_ROUNDOFF
    p0 = spatial.initial_body_states(scene)["b"]["p"]
    assert np.abs(traj.bodies["b"].position - (p0 + np.outer(d - SLIDER_D0, a_W))).max() < SLIDER_ROUNDOFF
    assert np.abs(traj.bodies["b"].quaternion - traj.bodies["b"].quaternion[0]).max() == 0.0
    reaction = SLIDER_MASS * (G_W @ a_W) * a_W - SLIDER_MASS * G_W  # m x'' - m g: perpendicular to the axis
    assert np.abs(traj.extras["reaction_force:b"] - reaction).max() < SLIDER_ROUNDOFF
    # the compiled model's slide joint, read back: along the scene's axis, nothing on it but the slide
    assert audit["joints"] == {"b": {"type": "slide", "axis_W": pytest.approx(list(a_W), rel=0, abs=1e-15),
                                     "limited": False, "stiffness": 0.0, "damping": 0.0, "armature": 0.0,
                                     "frictionloss": 0.0}}


def test_the_mjcf_writes_a_slide_joint_along_the_scenes_axis_in_the_child_frame():
    import xml.etree.ElementTree as ET

    from dalembert.adapters.mujoco.mjcf import mjcf

    root = ET.fromstring(mjcf(slider(), Settings("rk4", dt=SLIDER_DT)))
    (joint,) = root.iter("joint")
    assert joint.get("type") == "slide" and joint.get("limited") == "false"
    assert [float(x) for x in joint.get("axis").split()] == list(SLIDER_AXIS)
    assert all(float(joint.get(k)) == 0.0 for k in ("damping", "armature", "stiffness", "frictionloss"))


def _spring_errors(integrator, damping):
    """Largest slide error (m) against the closed form at each of ``STEPS``, and the largest reaction error (N)."""
    scene, u, s_eq = spring_slider(damping)
    exact = s_eq + _damped_stretch(TIMES, damping)
    reaction = -MASS * (G_W - (G_W @ u) * u)  # the spring pulls along the axis: the joint holds gravity's rest
    errors, reaction_error = [], 0.0
    for dt in (1e-2, 5e-3):
        traj, _ = run_with_audit(scene, TIMES, integrator, dt)
        errors.append(np.abs(traj.joints["b"].q[:, 0] - exact).max())
        reaction_error = max(reaction_error, np.abs(traj.extras["reaction_force:b"] - reaction).max())
    return errors, reaction_error


@pytest.mark.parametrize("damping", [0.0, DAMPING])
def test_rk4_slider_on_a_spring_converges_at_fourth_order_to_the_oscillator(damping):
    e, reaction_error = _spring_errors("rk4", damping)
    assert ORDER_RATIO[0] < e[0] / e[1] < ORDER_RATIO[1], e
    assert e[1] < POSITION_TOL and reaction_error < SLIDER_ROUNDOFF


@pytest.mark.parametrize("integrator", ["euler", "implicit", "implicitfast", "discrete"])
def test_first_order_slider_on_a_damped_spring_converges_and_its_reaction_is_exact(integrator):
    """The reaction is read from the sampled state's dynamics, whatever the integrator (the discrete
    integrator's own ``mj_forward`` would give its step's implicit acceleration: ``readback._state_dynamics``)."""
    for damping in (0.0, DAMPING):
        e, reaction_error = _spring_errors(integrator, damping)
        assert FIRST_ORDER_RATIO[0] < e[0] / e[1] < FIRST_ORDER_RATIO[1], e
        assert e[1] < (DISCRETE_POSITION_TOL if integrator == "discrete" else FIRST_ORDER_POSITION_TOL), e
        assert reaction_error < SLIDER_ROUNDOFF


def _bead_checks(scene, traj):
    """The slide read back as the bead's place on the rod, and the frictionless slide's axial force (both
    exact at any step): largest errors (m, N)."""
    R_WH = spatial.quat_to_matrix(traj.bodies["hub"].quaternion)
    x_W = R_WH[:, :, 0]  # the rod's axis, the hub's x
    d = traj.joints["bead"].q[:, 0]
    place = np.abs(traj.bodies["bead"].position - np.einsum("nij,j->ni", R_WH, BEAD_POINT) - d[:, None] * x_W).max()
    axial = np.abs(np.einsum("ni,ni->n", traj.extras["reaction_force:bead"], x_W)).max()
    return place, axial


def test_bead_on_a_spinning_rod_keeps_its_energy_and_angular_momentum_about_the_axis():
    scene = bead_on_rod()
    drifts = []
    for dt in BEAD_STEPS:
        traj, audit = run_with_audit(scene, BEAD_TIMES, "rk4", dt)
        L_z = invariants.angular_momentum_about(scene, traj, (0.0, 0.0, 0.0))[:, 2]
        drifts.append((invariants.drift("energy", scene, traj), np.abs(L_z - L_z[0]).max() / abs(L_z[0])))
        place, axial = _bead_checks(scene, traj)
        assert place < BEAD_ROUNDOFF and axial < BEAD_ROUNDOFF
        assert invariants.joint_residual(scene, traj).max() < BEAD_ROUNDOFF  # the slide off its axis: none
    assert traj.joints["bead"].q[-1, 0] > 0.4  # flung out from 0.1 m: the slide moved
    for coarse, fine in zip(*drifts):
        assert ORDER_RATIO[0] < coarse / fine < ORDER_RATIO[1], drifts
        assert fine < BEAD_DRIFT_TOL, drifts
    assert audit["joints"]["bead"]["type"] == "slide" and audit["joints"]["hub"]["type"] == "hinge"


def test_bead_on_a_spinning_rod_follows_the_reference():
    scene = bead_on_rod()
    ref = simulate(scene, BEAD_TIMES, Settings("dop853", rtol=1e-12, atol=1e-12, options={"formulation": "kane"}))[0]
    traj, _ = run_with_audit(scene, BEAD_TIMES, "rk4", BEAD_STEPS[1])
    e = trajectory_errors(traj, ref)
    for q in ("position", "orientation", "velocity", "angular_velocity", "joint", "reaction_force"):
        assert e[q][0] < BEAD_REFERENCE_TOL, (q, e[q])
    for name in ("hub", "bead"):
        assert np.abs(traj.joints[name].q - ref.joints[name].q).max() < BEAD_REFERENCE_TOL
        assert np.abs(traj.joints[name].v - ref.joints[name].v).max() < BEAD_REFERENCE_TOL


def test_the_references_slider_on_a_swinging_rod_and_slider_crank():
    """Two of the reference's prismatic scenes (tests/test_prismatic.py): a slide on a moving parent with a
    spring, against the reference; a slide closed into a loop, against its closed-form kinematics."""
    from test_prismatic import CRANK, ROD, _slider_crank, _slider_on_a_swinging_rod

    scene, times = _slider_on_a_swinging_rod(), np.linspace(0.0, 2.0, 201)
    ref = simulate(scene, times, Settings("dop853", rtol=1e-12, atol=1e-12))[0]
    e = trajectory_errors(run_with_audit(scene, times, "rk4", 5e-3)[0], ref)
    for q in ("position", "orientation", "velocity", "angular_velocity", "joint", "reaction_force"):
        assert e[q][0] < SWING_REFERENCE_TOL, (q, e[q])
    crank = _slider_crank()
    traj, audit = run_with_audit(crank, np.linspace(0.0, 0.35, 15), "rk4", 1e-3)
    phi = traj.joints["crank"].q[:, 0]
    assert phi.min() < np.pi and phi.max() > 2 * np.pi  # through both dead centres
    x = CRANK * np.cos(phi) + np.sqrt(ROD**2 - CRANK**2 * np.sin(phi) ** 2)
    assert np.abs(traj.joints["slider"].q[:, 0] - x).max() < CRANK_KINEMATICS_TOL
    assert audit["loop_constraints"] == {crank.loops[0].name: "connect", f"{crank.loops[0].name}:axis": "connect"}


@pytest.mark.long
def test_mjx_slides_like_mujoco_c():
    """One compile (rk4, float64, dt = 1e-2): the slider and the bead in one model. The slider's constant
    acceleration is integrated exactly, its reaction exact; the bead follows MuJoCo C's (the same RK4 on the
    same model: hinge and slide coordinates are plain vectors, which MJX's RK4 integrates as MuJoCo C's)."""
    pytest.importorskip("mujoco.mjx")
    a, b = slider(), bead_on_rod()
    scene = Scene("slider_and_bead", a.bodies + b.bodies, a.joints + b.joints, tuple(G_W))
    traj, audit = run_with_audit(scene, SLIDER_TIMES, "rk4", SLIDER_DT, engine="mjx", precision="float64")
    c, _ = run_with_audit(scene, SLIDER_TIMES, "rk4", SLIDER_DT)
    a_W = slider_axis_W()
    assert np.abs(traj.joints["b"].q[:, 0] - slider_exact(SLIDER_TIMES, "rk4", SLIDER_DT)).max() < SLIDER_ROUNDOFF
    reaction = SLIDER_MASS * (G_W @ a_W) * a_W - SLIDER_MASS * G_W
    assert np.abs(traj.extras["reaction_force:b"] - reaction).max() < SLIDER_ROUNDOFF
    for name in ("hub", "bead"):
        assert np.abs(traj.joints[name].q - c.joints[name].q).max() < MJX_PARITY_TOL
        assert np.abs(traj.joints[name].v - c.joints[name].v).max() < MJX_PARITY_TOL
    assert max(_bead_checks(scene, traj)) < BEAD_ROUNDOFF
    assert audit["joints"]["b"]["type"] == "slide" and audit["precision"] == "float64"

