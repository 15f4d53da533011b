"""Prismatic joints in the reference solver (Kane, ``reference.generalized``) against independent truths:
the inclined slider under gravity (exact for any second-order method, with its reaction), the slider on a
spring (the oscillator's closed form), the bead on a spinning rod (its exact first integrals, the time as a
quadrature of them, and the rigid-hub limit ``r'' = w^2 r``), the slider on a swinging rod against
Lagrange's equations written by hand, and a slider-crank (a loop closed over a prismatic joint) against
its closed-form kinematics."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from dalembert import closure, invariants, spatial
from dalembert.adapters.reference import ReferenceAdapter
from dalembert.reference import simulate
from dalembert.reference.generalized import Kane
from dalembert.reference.planar import why_not
from dalembert.scene import Body, Joint, Loop, Scene, Spring
from dalembert.settings import Settings
from test_springs import DAMPING, MASS, ORDER_RATIO, POSITION_TOL, REST, STEPS, STIFFNESS, STRETCH, _damped_stretch

G = np.array([0.0, 0.0, -9.81])  # m/s^2
TIGHT = Settings("dop853", rtol=1e-12, atol=1e-12)  # the reference's truth tolerances (integrators.DOP853)
# RK4 integrates a motion quadratic in time exactly: what is left is the roundoff of ~100 steps on
# metre-sized coordinates (measured 4e-16 m, 9e-16 N on the inclined slider; 5e-16 m in the joints' residuals).
EXACT_TOL = 1e-12
# A first integral (energy, angular momentum) over 2 s at DOP853's 1e-12 tolerances: measured relative
# drifts 5e-13 (the bead's energy), 1.1e-11 (the swinging slider's), 3.4e-11 (the bead's L_z); a Coriolis
# term of half its size moves the bead's at O(1e-2) within the first second.
INTEGRAL_TOL = 2e-10
# The bead's time from the quadrature of its first integrals (scipy quad at 1e-13) against the samples
# of the DOP853 run at 1e-12: measured 3.8e-12 s.
QUADRATURE_TOL = 1e-9
# Kane's accelerations against Lagrange's at random states: two algebras of the same equations, so
# roundoff only (measured 4.5e-16 relative to the largest).
ALGEBRA_TOL = 1e-11


def _rotation_quat(axis, angle):
    """Unit quaternion (w, x, y, z) of the rotation by ``angle`` (rad) about ``axis``."""
    return tuple(spatial.matrix_to_quat(spatial.so3_exp(np.asarray(axis, float) / np.linalg.norm(axis) * angle)))


# ---------------------------------------------------------------- the inclined slider
SLIDER_AXIS = (1.0, -2.0, 2.0)  # in the joint frame, not unit: |axis| = 3
SLIDER_QUAT = _rotation_quat((0.3, 1.0, -0.5), 0.8)  # the parent joint frame, turned from the world's
SLIDER_POINT = (0.2, -0.1, 0.4)  # the parent joint point, world (m)
SLIDER_CHILD_POINT = (0.05, 0.0, -0.1)  # the child joint point, body frame (m): the COM is off the axis


def _inclined_slider(d0=0.3, v0=-0.7):
    box = Body.box("box", 2.5, (0.2, 0.3, 0.4))
    joint = Joint("prismatic", "world", "box", (d0,), (v0,), axis=SLIDER_AXIS, parent_point=SLIDER_POINT,
                  parent_quat=SLIDER_QUAT, child_point=SLIDER_CHILD_POINT, child_quat=_rotation_quat((1, 1, 0), 0.4))
    return Scene("inclined_slider", [box], [joint], tuple(G))


def test_the_inclined_slider_falls_along_its_axis_exactly_and_the_joint_holds_the_rest_of_its_weight():
    """d(t) = d0 + v0 t + (g . a) t^2 / 2; the joint's force ON the box is m (a (g . a) - g): the part of
    the weight normal to the axis, reversed (a frictionless slide)."""
    d0, v0 = 0.3, -0.7
    scene = _inclined_slider(d0, v0)
    a_W = spatial.quat_to_matrix(SLIDER_QUAT) @ (np.array(SLIDER_AXIS) / 3.0)
    times = np.linspace(0.0, 1.0, 11)
    traj = simulate(scene, times, Settings("rk4", dt=1e-2, options={"formulation": "kane"}))[0]
    d = d0 + v0 * times + 0.5 * (G @ a_W) * times**2
    np.testing.assert_allclose(traj.joints["box"].q[:, 0], d, rtol=0, atol=EXACT_TOL)
    np.testing.assert_allclose(traj.joints["box"].v[:, 0], v0 + (G @ a_W) * times, rtol=0, atol=EXACT_TOL)
    box = traj.bodies["box"]
    R = box.rotation_matrix
    p_expected = np.array(SLIDER_POINT) + d[:, None] * a_W - R @ np.array(SLIDER_CHILD_POINT)
    np.testing.assert_allclose(box.position, p_expected, rtol=0, atol=EXACT_TOL)
    np.testing.assert_allclose(box.angular_velocity, 0.0, rtol=0, atol=EXACT_TOL)
    np.testing.assert_allclose(R, np.broadcast_to(R[0], R.shape), rtol=0, atol=EXACT_TOL)  # it does not turn
    reaction = 2.5 * (a_W * (G @ a_W) - G)
    np.testing.assert_allclose(traj.extras["reaction_force:box"], np.broadcast_to(reaction, (11, 3)),
                               rtol=0, atol=EXACT_TOL)
    assert abs(reaction @ a_W) < EXACT_TOL  # (normal to the axis, as a frictionless slide's must be)
    assert np.max(invariants.joint_residual(scene, traj)) < EXACT_TOL


def test_the_reference_adapter_builds_prismatic_joints_and_the_planar_formulation_refuses_them():
    scene = _inclined_slider()
    assert "joint:prismatic" in scene.effects
    assert ReferenceAdapter().unsupported(scene, Settings("rk4", dt=1e-2)) is None
    assert why_not(scene) == "the planar formulation takes revolute joints only"
    assert ReferenceAdapter().unsupported(scene, Settings("rk4", dt=1e-2, options={"formulation": "planar"})) \
        == "the planar formulation takes revolute joints only"


def test_the_joint_residual_sees_a_slider_pushed_off_its_axis_but_not_its_slide():
    scene = _inclined_slider()
    times = np.linspace(0.0, 0.2, 3)
    traj = simulate(scene, times, Settings("rk4", dt=1e-2))[0]
    a_W = spatial.quat_to_matrix(SLIDER_QUAT) @ (np.array(SLIDER_AXIS) / 3.0)
    normal = np.cross(a_W, [0.0, 0.0, 1.0])
    normal /= np.linalg.norm(normal)
    traj.bodies["box"].position[:] += 1e-3 * normal
    np.testing.assert_allclose(invariants.joint_residual(scene, traj), 1e-3, rtol=1e-9)


# ---------------------------------------------------------------- the slider on a spring
@pytest.mark.parametrize("damping", [0.0, DAMPING])
def test_the_slider_on_a_spring_along_its_axis_is_the_oscillator(damping):
    """A box on the inclined axis, a spring-damper from the world point of the axis to its COM: along the
    axis, m x'' + c x' + k (x - l0) = m (g . a), the oscillator of ``test_springs`` about x_eq = l0 + m (g . a) / k
    (its closed form, ``_damped_stretch``), converging at fourth order under RK4."""
    R_WJ = spatial.quat_to_matrix(SLIDER_QUAT)
    a_W = R_WJ @ (np.array(SLIDER_AXIS) / 3.0)
    x_eq = REST + MASS * (G @ a_W) / STIFFNESS
    scene = Scene("slider_spring", [Body.box("b", MASS, (0.1, 0.2, 0.3))],
                  [Joint("prismatic", "world", "b", (x_eq + STRETCH,), (0.0,), axis=SLIDER_AXIS,
                         parent_point=SLIDER_POINT, parent_quat=SLIDER_QUAT, child_quat=SLIDER_QUAT)],
                  tuple(G), springs=[Spring("world", "b", point_a=SLIDER_POINT, stiffness=STIFFNESS, damping=damping,
                                            rest_length=REST)])
    times = np.linspace(0.0, 2.0, 201)
    exact = x_eq + _damped_stretch(times, damping)
    errors = []
    for dt in STEPS:
        traj = simulate(scene, times, Settings("rk4", dt=dt))[0]
        errors.append(np.abs(traj.joints["b"].q[:, 0] - exact).max())
    assert ORDER_RATIO[0] < errors[0] / errors[1] < ORDER_RATIO[1], errors
    assert errors[1] < POSITION_TOL
    if damping:
        assert invariants.drift("energy_balance", scene, traj) < 1e-6  # test_springs.BALANCE_TOL's reason


# ---------------------------------------------------------------- the bead on a spinning rod
HUB_RATE = 2.0  # rad/s
BEAD_MASS = 0.5  # kg
BEAD_R0, BEAD_V0 = 0.2, 0.3  # m, m/s: moving outward (no turning point on the way: the quadrature is regular)


def _bead_on_a_rod(hub_inertia_scale=1.0):
    """A hub turning freely about the world z (its parent joint point raised 0.1 m, its axis given as
    (0, 0, 2)) and a bead sliding along the hub's x axis, 0.25 m above the hub's COM; gravity along -z
    does no work on either."""
    hub = Body("hub", 3.0, np.diag([0.2, 0.3, 0.4]) * hub_inertia_scale)
    bead = Body.box("bead", BEAD_MASS, (0.04, 0.02, 0.06))
    return Scene("bead_on_rod", [hub, bead],
                 [Joint("revolute", "world", "hub", (0.4,), (HUB_RATE,), axis=(0, 0, 2), parent_point=(0, 0, 0.1)),
                  Joint("prismatic", "hub", "bead", (BEAD_R0,), (BEAD_V0,), axis=(3, 0, 0), parent_point=(0, 0, 0.25))],
                 tuple(G))


def test_the_bead_on_a_spinning_rod_keeps_its_energy_and_angular_momentum_about_the_spin_axis():
    scene = _bead_on_a_rod()
    times = np.linspace(0.0, 2.0, 101)
    traj = simulate(scene, times, TIGHT)[0]
    assert invariants.drift("energy", scene, traj) < INTEGRAL_TOL
    L_z = invariants.angular_momentum_about(scene, traj, (0.0, 0.0, 0.0))[:, 2]
    assert np.abs(L_z - L_z[0]).max() / abs(L_z[0]) < INTEGRAL_TOL
    r = traj.joints["bead"].q[:, 0]
    assert r[-1] > 2.0 * BEAD_R0  # it does slide out (the invariants are not those of a bead at rest)
    assert np.max(invariants.joint_residual(scene, traj)) < EXACT_TOL


def test_the_bead_reaches_each_radius_at_the_time_its_first_integrals_give():
    """With I the hub's and the bead's moments about z and m the bead's mass, L = (I + m r^2) w and
    2E = (I + m r^2) w^2 + m r'^2 are constant, so r' = sqrt((2E - L^2 / (I + m r^2)) / m) and the time
    to reach r is the quadrature of dr / r' from r0: exact, and nothing of Kane's in it."""
    scene = _bead_on_a_rod()
    times = np.linspace(0.0, 1.0, 11)
    r = simulate(scene, times, TIGHT)[0].joints["bead"].q[:, 0]
    I = scene.body("hub").inertia_matrix[2, 2] + scene.body("bead").inertia_matrix[2, 2]
    m = BEAD_MASS
    L = (I + m * BEAD_R0**2) * HUB_RATE
    two_E = (I + m * BEAD_R0**2) * HUB_RATE**2 + m * BEAD_V0**2

    def dt_dr(x):
        return 1.0 / np.sqrt((two_E - L**2 / (I + m * x**2)) / m)

    t_of_r = np.array([quad(dt_dr, BEAD_R0, x, epsabs=1e-13, epsrel=1e-13)[0] for x in r])
    np.testing.assert_allclose(t_of_r, times, rtol=0, atol=QUADRATURE_TOL)


def test_on_a_hub_of_huge_inertia_the_bead_follows_cosh():
    """The hub's rate held: r'' = w^2 r, r = r0 cosh(w t) + (r0' / w) sinh(w t). With the hub's moment I,
    w changes by w m (r^2 - r0^2) / I at most, and r by about r w^2 t^2 / 2 times that fraction."""
    scale = 1e9
    scene = _bead_on_a_rod(scale)
    times = np.linspace(0.0, 1.0, 11)
    r = simulate(scene, times, TIGHT)[0].joints["bead"].q[:, 0]
    exact = BEAD_R0 * np.cosh(HUB_RATE * times) + BEAD_V0 / HUB_RATE * np.sinh(HUB_RATE * times)
    I = 0.4 * scale
    bound = exact.max() * (HUB_RATE * times[-1]) ** 2 / 2 * BEAD_MASS * exact.max() ** 2 / I  # 5.4e-9 m
    assert np.abs(r - exact).max() < bound + 1e-10  # + the integrator's own 1e-12 tolerance, with room (5.8e-10 m)


# ---------------------------------------------------------------- the slider on a swinging rod (Lagrange)
ROD_MASS, ROD_HALF = 1.2, 0.5  # kg, m: a 1-m rod pivoted at its top end
SLIDE_MASS, SPRING_K, SPRING_L0 = 0.7, 40.0, 0.6  # kg, N/m, m: a spring from the pivot pulls the slider


def _slider_on_a_swinging_rod(theta0=0.5, theta_dot0=-0.4, r0=0.45, r_dot0=0.2):
    """A rod hanging from the world origin by a revolute about y (its top end), a slider on a prismatic
    joint along the rod (axis given as (0, 0, -2) from the pivot, in the rod's frame), and a spring from the
    pivot to the slider's COM (along the rod: it exerts no moment about the pivot)."""
    rod = Body.box("rod", ROD_MASS, (0.03, 0.03, 2 * ROD_HALF))
    slide = Body.box("slide", SLIDE_MASS, (0.08, 0.06, 0.05))
    return Scene("swinging_slider", [rod, slide],
                 [Joint("revolute", "world", "rod", (theta0,), (theta_dot0,), axis=(0, 1, 0), child_point=(0, 0, ROD_HALF)),
                  Joint("prismatic", "rod", "slide", (r0,), (r_dot0,), axis=(0, 0, -2), parent_point=(0, 0, ROD_HALF))],
                 tuple(G), springs=[Spring("world", "slide", stiffness=SPRING_K, rest_length=SPRING_L0)])


def _lagrange_accelerations(scene, theta, r, theta_dot, r_dot):
    """theta'', r'' from Lagrange's equations of the swinging slider, written by hand.

    The slider's COM is at r e(theta), e = (-sin, 0, -cos), the rod's at ROD_HALF e, with
    T = (I1 + I2 + m2 r^2) theta'^2 / 2 + m2 r'^2 / 2 (I1: the rod about the pivot, I2: the slider about its
    COM, both about y) and V = -(m1 c + m2 r) g cos(theta) + k (r - l0)^2 / 2:

        (I1 + I2 + m2 r^2) theta'' + 2 m2 r r' theta' + (m1 c + m2 r) g sin(theta) = 0
        m2 r'' - m2 r theta'^2 - m2 g cos(theta) + k (r - l0) = 0
    """
    g = -G[2]
    I1 = scene.body("rod").inertia_matrix[1, 1] + ROD_MASS * ROD_HALF**2
    I2 = scene.body("slide").inertia_matrix[1, 1]
    m2 = SLIDE_MASS
    theta_dd = -(2 * m2 * r * r_dot * theta_dot + (ROD_MASS * ROD_HALF + m2 * r) * g * np.sin(theta)) / (I1 + I2 + m2 * r**2)
    r_dd = r * theta_dot**2 + g * np.cos(theta) - SPRING_K * (r - SPRING_L0) / m2
    return np.array([theta_dd, r_dd])


def test_kane_and_lagranges_equations_agree_on_the_slider_on_a_swinging_rod():
    rng = np.random.default_rng(17)
    for _ in range(20):
        theta, r, theta_dot, r_dot = rng.uniform(-2.5, 2.5), rng.uniform(0.1, 1.0), rng.uniform(-3, 3), rng.uniform(-2, 2)
        scene = _slider_on_a_swinging_rod(theta, theta_dot, r, r_dot)
        kane = Kane(scene)
        got = kane.acceleration(0.0, kane.q0, kane.v0)
        expected = _lagrange_accelerations(scene, theta, r, theta_dot, r_dot)
        np.testing.assert_allclose(got, expected, rtol=ALGEBRA_TOL, atol=ALGEBRA_TOL * np.abs(expected).max())


def test_the_swinging_slider_keeps_its_energy_with_the_spring_and_its_rod_holds():
    scene = _slider_on_a_swinging_rod()
    times = np.linspace(0.0, 2.0, 101)
    traj = simulate(scene, times, TIGHT)[0]
    assert invariants.drift("energy", scene, traj) < INTEGRAL_TOL
    assert np.max(invariants.joint_residual(scene, traj)) < EXACT_TOL
    # the slider's COM stays on the rod's line through the pivot
    e = traj.bodies["rod"].position / ROD_HALF  # the rod's unit direction from the pivot
    r = traj.joints["slide"].q[:, 0]
    np.testing.assert_allclose(traj.bodies["slide"].position, r[:, None] * e, rtol=0, atol=EXACT_TOL)


# ---------------------------------------------------------------- a loop over a prismatic joint
CRANK, ROD = 0.1, 0.3  # m: the slider-crank's crank and connecting rod
CRANK_STEP = 2.5e-3  # s: RK4's step on the slider-crank (each evaluation projects onto the loop: costly)
# RK4 at that step keeps the slider-crank's energy to 4.8e-6 relative over 0.35 s (measured; 1.1e-4 at twice the
# step, 7e-10 with DOP853 at 1e-9): a wrong slide velocity or Coriolis term moves it at O(1).
CRANK_ENERGY_TOL = 2e-5


def _slider_crank(phi0=2.5, phi_dot0=15.0):
    """A crank (revolute about z at the world origin), a connecting rod (revolute about z at the crank's
    tip) and a slider on a prismatic joint along the world x, the rod's far end pinned to the slider by a
    revolute loop about z. The rod's initial angle and the slider's position and rates follow from the
    loop's closed form, x = a cos(phi) + sqrt(b^2 - a^2 sin^2(phi))."""
    a, b = CRANK, ROD
    beta = np.arcsin(a * np.sin(phi0) / b)  # the rod's angle below the x axis
    x = a * np.cos(phi0) + b * np.cos(beta)
    beta_dot = a * np.cos(phi0) * phi_dot0 / (b * np.cos(beta))
    x_dot = -a * np.sin(phi0) * phi_dot0 - b * np.sin(beta) * beta_dot
    crank = Body.box("crank", 0.5, (a, 0.02, 0.02))
    rod = Body.box("rod", 0.8, (b, 0.02, 0.02))
    slider = Body.box("slider", 1.5, (0.06, 0.04, 0.04))
    return Scene("slider_crank", [crank, rod, slider],
                 [Joint("revolute", "world", "crank", (phi0,), (phi_dot0,), axis=(0, 0, 1), child_point=(-a / 2, 0, 0)),
                  Joint("revolute", "crank", "rod", (-phi0 - beta,), (-phi_dot0 - beta_dot,), axis=(0, 0, 1),
                        parent_point=(a / 2, 0, 0), child_point=(-b / 2, 0, 0)),
                  Joint("prismatic", "world", "slider", (x,), (x_dot,), axis=(1, 0, 0))],
                 (0.0, -9.81, 0.0), loops=[Loop("revolute", "rod", "slider", point_a=(b / 2, 0, 0), axis=(0, 0, 1))])


def test_a_slider_crank_closed_over_its_prismatic_joint_follows_its_closed_form_kinematics():
    """The loop is projected onto its manifold after every step, so the slider's x must follow the crank's
    angle to roundoff whatever the integrator's error; that error shows in the energy only."""
    scene = _slider_crank()
    summary = closure.summary(scene)
    assert summary.dof == 1 and summary.position_residual < EXACT_TOL and summary.velocity_residual < EXACT_TOL
    times = np.linspace(0.0, 0.35, 15)
    traj = simulate(scene, times, Settings("rk4", dt=CRANK_STEP))[0]
    phi = traj.joints["crank"].q[:, 0]
    x = CRANK * np.cos(phi) + np.sqrt(ROD**2 - CRANK**2 * np.sin(phi) ** 2)
    np.testing.assert_allclose(traj.joints["slider"].q[:, 0], x, rtol=0, atol=EXACT_TOL)
    assert phi.min() < np.pi and phi.max() > 2 * np.pi  # through both dead centres (x = b - a, then b + a)
    assert invariants.drift("energy", scene, traj) < CRANK_ENERGY_TOL
    assert np.max(invariants.loop_residual(scene, traj)) < EXACT_TOL
