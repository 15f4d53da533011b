"""Each closed form against an independent computation.

The torque-free top is checked against a Taylor-series integration in 40-digit
arithmetic (tests/taylor.py): no formula in common with the elliptic-function
solution, and precise enough to resolve 1e-11 rad near the separatrix, where
any double-precision integrator stalls at ~1e-8 rad.
"""

import numpy as np
import pytest

from dalembert import Settings, invariants, spatial
from dalembert.scene import Body, mass_properties
from dalembert.reference import simulate
from dalembert.reference.closed_form import Ballistic, FollowerForceRod, LagrangeTop, RigidPendulum, TorqueFreeTop
from taylor import integrate_body_on_pivot, integrate_pendulum, integrate_top

# rad over 20 s against the 40-digit integration. A closed form exact up to roundoff is off by
# some ulps of the ~100 rad it turns (measured at most 5.3e-14 rad, on the separatrix); and it
# must resolve 1000x below the roundoff floor of double-precision integrators near the
# separatrix (1e-8 to 1e-7 rad at 20 s, reference/roundoff.py) to serve as their truth.
ATTITUDE_TOL = 1e-11
RATE_TOL = 1e-12  # rad/s at spins of ~5 rad/s: a few hundred ulps (measured at most 1.8e-14)
# relative: energy and world angular momentum are exact invariants, and the closed form's w(t) and
# R(t) give them to a few ulps at every instant (measured at most 6.7e-16)
INVARIANT_TOL = 1e-12
# The rod and the falling box by Kane's equations (DOP853 at rtol = atol = 1e-13) over 2 s: 100x
# that tolerance, for the global error local control lets accumulate (measured at most 2.0e-12 rad,
# the box's attitude; 1e-14 on the rod and the fall).
KANE_TOL = 1e-11

TOPS = {
    "stable spin near the largest axis": ((1.0, 2.0, 3.0), (0.1, 0.0, 5.0), 20.0),
    "1e-3 rad/s off the intermediate axis": ((1.0, 2.0, 3.0), (1e-3, 5.0, 1e-3), 20.0),
    "exactly on the separatrix (M^2 = 2 E I2)": ((2.0, 3.0, 6.0), (3.0, 0.5, 1.0), 20.0),
    "particle box, circulating about the smallest axis": ((65 / 3, 50 / 3, 25 / 3), (0.0, 1.0, 1.0), 20.0),
    "axisymmetric (I1 = I2)": ((1.0, 1.0, 2.0), (0.3, 0.2, 1.0), 10.0),
}


@pytest.mark.parametrize("label", TOPS)
def test_top_against_40_digit_taylor_integration(label):
    moments, w0, t_final = TOPS[label]
    t = np.linspace(0.0, t_final, 11)
    top = TorqueFreeTop(np.diag(moments), np.array(w0))
    q_ref, w_ref = integrate_top(moments, w0, spatial.IDENTITY_QUAT, t)
    assert np.max(spatial.rotation_angle(top.quaternion(t), q_ref)) < ATTITUDE_TOL
    assert np.max(np.abs(top.angular_velocity_body(t) - w_ref)) < RATE_TOL


def test_separatrix_case_is_exactly_on_it():
    top = TorqueFreeTop(np.diag([2.0, 3.0, 6.0]), np.array([3.0, 0.5, 1.0]))
    assert top.m1 == 0.0 and top.regime == "elliptic"


def test_intermediate_start_flips():
    """The spin about the intermediate axis reverses (that axis is unstable: Landau & Lifshitz,
    Mechanics, section 37)."""
    top = TorqueFreeTop(np.diag([1.0, 2.0, 3.0]), np.array([1e-3, 5.0, 1e-3]))
    w2 = top.angular_velocity_body(np.linspace(0, 20, 2001))[:, 1]
    assert w2.min() < -4.9 and w2.max() > 4.9


def test_top_invariants_constant():
    t = np.linspace(0.0, 20.0, 2001)
    for moments, w0, _ in TOPS.values():
        top = TorqueFreeTop(np.diag(moments), np.array(w0))
        R = top.rotation(t)
        w_B = top.angular_velocity_body(t)
        E = 0.5 * np.einsum("ni,i,ni->n", w_B, np.array(moments), w_B)
        L_W = np.einsum("nij,nj->ni", R, np.array(moments) * w_B)
        assert np.max(np.abs(E / top.kinetic_energy() - 1.0)) < INVARIANT_TOL
        L0 = top.angular_momentum_world()
        assert np.max(np.linalg.norm(L_W - L0, axis=1)) < INVARIANT_TOL * np.linalg.norm(L0)


def test_top_with_full_inertia_tensor_and_initial_attitude():
    """A body whose frame is not principal, starting rotated: the same motion as the
    principal-axis body, seen through the fixed rotation R_BP (and checked against
    the reference solver at tight tolerance, a second formulation)."""
    R_BP = spatial.so3_exp([0.4, -0.3, 0.8])
    D = np.diag([1.0, 2.0, 3.0])
    w_P = np.array([0.2, 3.0, 0.5])
    q0_WP = spatial.quat_exp([0.1, 0.2, -0.3])
    principal = TorqueFreeTop(D, w_P, q0_WP)
    R_WB0 = spatial.quat_to_matrix(q0_WP) @ R_BP.T
    body = TorqueFreeTop(R_BP @ D @ R_BP.T, R_BP @ w_P, spatial.matrix_to_quat(R_WB0))
    t = np.linspace(0, 10, 101)
    assert np.max(np.abs(body.rotation(t) - principal.rotation(t) @ R_BP.T)) < 1e-12
    assert np.max(np.abs(body.angular_velocity_world(t) - principal.angular_velocity_world(t))) < 1e-12


def test_uniform_rotations_are_elementary():
    t = np.linspace(0, 3, 31)
    sphere = TorqueFreeTop(2.0 * np.eye(3), np.array([0.3, -0.4, 1.2]))
    assert sphere.regime == "uniform"
    expected = spatial.so3_exp(t[:, None] * np.array([0.3, -0.4, 1.2]))
    assert np.max(np.abs(sphere.rotation(t) - expected)) < 1e-14
    spin = TorqueFreeTop(np.diag([1.0, 2.0, 3.0]), np.array([0.0, 0.0, 5.0]))
    angle = spatial.rotation_angle(spin.quaternion(t), spatial.quat_from_axis_angle([0, 0, 1], 5.0 * t))
    assert np.max(angle) < 1e-14


def test_rod_reduces_to_the_thin_rod_formula():
    """d'Alembert's principle for a thin rod: phi'' m l^2/3 = l F  =>  phi = 3F/(2 m l) t^2; 12 rad at 2 s for
    l = m = 1, F = 2."""
    rod = FollowerForceRod(mass=1.0, length=1.0, inertia_pivot=1.0 / 3.0, force=2.0)
    assert rod.angle(2.0) == pytest.approx(12.0, rel=1e-15)
    assert rod.angle(0.7) == pytest.approx(3 * 2.0 / 2 * 0.7**2, rel=1e-15)


def test_rod_reaction_elementary_values():
    """At rest the pivot pushes with m (l/2) phi'' - F = F/2 along the force; later
    the centripetal part -m (l/2) phi'^2 dominates along the rod."""
    rod = FollowerForceRod(mass=1.0, length=1.0, inertia_pivot=1.0 / 3.0, force=2.0)
    assert np.allclose(rod.reaction_force(np.array([0.0]))[0], [0.0, 1.0, 0.0], atol=1e-15)
    t = np.array([2.0])
    phi, w = rod.angle(t)[0], rod.rate(t)[0]
    r_hat, t_hat = np.array([np.cos(phi), np.sin(phi), 0]), np.array([-np.sin(phi), np.cos(phi), 0])
    expected = -0.5 * w**2 * r_hat + (0.5 * rod.angular_acceleration - 2.0) * t_hat
    assert np.allclose(rod.reaction_force(t)[0], expected, atol=1e-13)


def test_rod_kinetic_energy_equals_work_of_the_follower_force():
    rod = FollowerForceRod(mass=1.0, length=1.0, inertia_pivot=1.0 / 3.0 + 2.5e-5, force=2.0)
    t = np.linspace(0, 2, 21)
    assert np.allclose(rod.kinetic_energy(t), rod.work(t), rtol=1e-14, atol=0)


def test_rod_and_ballistic_against_the_reference_solver():
    """Second formulation: Kane's equations at tight tolerance reproduce the rod,
    its pivot reaction, and the parabola of the falling box."""
    from dalembert import make_case
    from dalembert.errors import trajectory_errors

    for name, quantities in (("pivoted_rod", ("joint", "reaction_force")), ("particle_box", ("position", "orientation"))):
        case = make_case(name, t_final=2.0)
        traj = simulate(case.scene, case.times, Settings("dop853", rtol=1e-13, atol=1e-13,
                                                         options={"formulation": "kane"}))[0]
        errors = trajectory_errors(traj, case.exact(case.times))
        for q in quantities:
            assert errors[q][0] < KANE_TOL, (name, q, errors[q])


def test_ballistic_parabola():
    com = Ballistic((1.0, 2.0, 3.0), (0.5, 0.0, 4.0), (0.0, 0.0, -9.8))
    assert np.allclose(com.position([2.0]), [[2.0, 2.0, 3.0 + 8.0 - 19.6]], atol=1e-14)
    assert np.allclose(com.velocity([2.0]), [[0.5, 0.0, 4.0 - 19.6]], atol=1e-14)


def test_three_particle_inertia():
    """The inertia tensor of unit masses at (0,0,0), (1,0,0), (0,1,0), worked by hand."""
    mass, com, A = mass_properties([1, 1, 1], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    assert mass == 3.0 and np.allclose(com, [1 / 3, 1 / 3, 0], atol=1e-16)
    assert np.allclose(A, [[2 / 3, 1 / 3, 0], [1 / 3, 2 / 3, 0], [0, 0, 4 / 3]], atol=1e-15)
    assert np.allclose(np.linalg.eigvalsh(A), [1 / 3, 1.0, 4 / 3], atol=1e-15)


def test_27_particle_box_inertia():
    from dalembert import make_case

    body = make_case("particle_box").scene.body("box")
    assert body.mass == pytest.approx(10.0, rel=1e-15)
    assert np.allclose(body.inertia_matrix, np.diag([65 / 3, 50 / 3, 25 / 3]), atol=1e-13)
    assert len(body.particles) == 27


def test_body_solids():
    rod = Body.cylinder("r", 2.0, 1.0, 0.1, axis=0)
    assert np.allclose(np.diag(rod.inertia_matrix), [0.01, 2 * (0.03 + 1) / 12, 2 * (0.03 + 1) / 12])
    box = Body.box("b", 12.0, (1.0, 2.0, 3.0))
    assert np.allclose(np.diag(box.inertia_matrix), [13.0, 10.0, 5.0])


# ------------------------------------------------------------------ the physical pendulum
# rad over 10 s against the 40-digit Taylor integration (issue bound). Exact up to roundoff, the closed
# form is off by some ulps of the phase w0 t ~ 40 rad (measured at most 1.2e-13 rad, a hair from the
# separatrix, where the motion amplifies the rounding of the initial data).
PENDULUM_ANGLE_TOL = 1e-12
PENDULUM_RATE_TOL = 1e-11  # rad/s at rates up to ~8 rad/s: as above, times the rate (measured at most 4.6e-13)
# The uniform rod of the pendulum case: m = 1 kg, l = 1 m, r = 0.01 m (I_O = m l^2/3 + m r^2/4)
ROD = dict(mass=1.0, com_distance=0.5, inertia_pivot=1.0 / 3.0 + 2.5e-5, gravity=9.81)
PENDULUMS = {
    "libration from rest at 1 rad (the pendulum case)": (1.0, 0.0),
    "from the horizontal (IFToMM A01)": (np.pi / 2, 0.0),
    "from rest at 3.1 rad": (3.1, 0.0),
    "1e-6 rad below the top": (np.pi - 1e-6, 0.0),
    "moving and displaced": (0.3, -2.0),
    "over the top": (0.3, 8.0),
    "over the top backwards": (1.0, -9.0),
}


@pytest.mark.parametrize("label", PENDULUMS)
def test_pendulum_against_40_digit_taylor_integration(label):
    theta0, rate0 = PENDULUMS[label]
    p = RigidPendulum(**ROD, theta0=theta0, rate0=rate0)
    t = np.linspace(0.0, 10.0, 11)
    theta, rate = integrate_pendulum(p.natural_frequency, theta0, rate0, t)
    assert p.regime == ("rotation" if abs(rate0) > 7 else "libration")
    assert np.max(np.abs(p.angle(t) - theta)) < PENDULUM_ANGLE_TOL
    assert np.max(np.abs(p.rate(t) - rate)) < PENDULUM_RATE_TOL


def test_pendulum_separatrix_is_the_gudermannian():
    """From the bottom at exactly the rate that reaches the top, 2 w0: theta = 4 atan(exp(w0 t)) - pi
    (Whittaker, section 44), approaching pi forever; regime 'separatrix'."""
    p = RigidPendulum(1.0, 1.0, 1.0, 4.0, 0.0, 4.0)  # w0 = 2 rad/s, rate0 = 2 w0
    t = np.linspace(0.0, 5.0, 51)
    assert p.regime == "separatrix"
    assert np.max(np.abs(p.angle(t) - (4.0 * np.arctan(np.exp(2.0 * t)) - np.pi))) < 1e-14


def test_pendulum_small_amplitude_period_and_bottom_reaction():
    """Small swings have period 2 pi / w0 (to the amplitude squared, A&S 17.3.11: K = pi/2 (1 + k^2/4 +
    ...)); a point mass released from the horizontal pulls on the pivot with 3 m g at the bottom
    (energy: v^2 = 2 g L, so m v^2 / L + m g = 3 m g)."""
    small = RigidPendulum(1.0, 1.0, 1.0, 9.81, 1e-4, 0.0)
    assert small.period == pytest.approx(2 * np.pi / small.natural_frequency, rel=1e-8)
    p = RigidPendulum(1.0, 1.0, 1.0, 9.81, np.pi / 2, 0.0)
    bottom = np.array([p.period / 4])
    assert abs(p.angle(bottom)[0]) < 1e-13
    assert np.allclose(p.reaction_force(bottom)[0], [0.0, 0.0, 3 * 9.81], atol=1e-12)


# ------------------------------------------------------------------ the heavy (Lagrange) top
# rad against the 40-digit Taylor integration of the Euler-Poisson equations (issue bound); the closed
# form is exact up to roundoff (measured at most 1.2e-14 rad, through the benchmark's passage within
# 7e-7 rad of the downward vertical).
HEAVY_TOP_ATTITUDE_TOL = 1e-11
HEAVY_TOP_RATE_TOL = 1e-10  # rad/s at 150 rad/s: the attitude bound times the rate (measured at most 7.5e-14)
# The benchmark top (Terze, Mueller, Zlatar 2016): 15 kg, COM 1 m along body y, inertia about the COM
# diag(0.234375, 0.46875, 0.234375); in the closed form's top frame T (axis 3 = body y): R_BT.
BENCHMARK = dict(mgl=15.0 * 9.81 * 1.0, A=0.234375 + 15.0, C=0.46875)
R_BT = np.column_stack([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
HEAVY_TOPS = {
    "the benchmark over its 0.2 s": (BENCHMARK, np.eye(3), (0.0, 150.0, -4.61538), 0.2, 5),
    "the benchmark through its passage near the vertical (0.37 s)": (BENCHMARK, np.eye(3), (0.0, 150.0, -4.61538),
                                                                     0.5, 6),
    "slow and strongly nutating (the heavy_top_nutating case)": (BENCHMARK, spatial.so3_exp([0.5, 0.0, 0.0]),
                                                                 (0.0, 20.0, 0.0), 3.0, 7),
    "tilted, every rate non-zero": (dict(mgl=2.0, A=1.5, C=0.8), spatial.so3_exp([0.3, -0.2, 0.4]),
                                    (1.0, 6.0, -2.0), 3.0, 7),
    # A, C, w3 chosen so that a = C w3 / A = 2 is exact and b = -a: the axis goes exactly through the
    # downward vertical (b + a = 0), where the Euler angles flip
    "exactly through the downward vertical (at 1.06 s)": (dict(mgl=4.0, A=16.0, C=0.5), np.eye(3), (0.0, 64.0, -2.0),
                                                          1.2, 7),
}


@pytest.mark.parametrize("label", HEAVY_TOPS)
def test_heavy_top_against_40_digit_taylor_integration(label):
    data, R0_WB, w0_B, t_final, samples = HEAVY_TOPS[label]
    w0_T = R_BT.T @ np.array(w0_B)
    top = LagrangeTop(data["mgl"], data["A"], data["C"], R0_WB @ R_BT, w0_T)
    t = np.linspace(0.0, t_final, samples)
    q_ref, w_ref, gamma = integrate_body_on_pivot(np.diag([data["A"], data["A"], data["C"]]), [0, 0, data["mgl"]],
                                                  [0, 0, 1], w0_T, spatial.matrix_to_quat(R0_WB @ R_BT), t,
                                                  1.2 * np.linalg.norm(w0_B))
    assert np.max(spatial.rotation_angle(top.quaternion(t), q_ref)) < HEAVY_TOP_ATTITUDE_TOL
    assert np.max(np.abs(top.angular_velocity_top(t) - w_ref)) < HEAVY_TOP_RATE_TOL
    assert np.max(np.abs(top.cos_theta(t) - gamma[:, 2])) < HEAVY_TOP_ATTITUDE_TOL  # T3 . up


def test_heavy_top_against_exudyns_converged_benchmark_values():
    """Exudyn's test model of the benchmark (TestModels/explicitLieGroupIntegratorTest.py, J. Gerstmayr,
    2020) quotes the world y angular velocity 149.8473939540758 rad/s at 0.01 s ("converged to 14
    digits") and -106.16380414 rad/s at 2 s (its RK67 at dt 5e-5, 2e-5 and 1e-5 spread over 2.1e-9)."""
    top = LagrangeTop(BENCHMARK["mgl"], BENCHMARK["A"], BENCHMARK["C"], R_BT, R_BT.T @ np.array([0.0, 150.0, -4.61538]))
    w = top.angular_velocity_world(np.array([0.01, 2.0]))[:, 1]
    assert abs(w[0] - 149.8473939540758) < 1e-11  # 14 digits of 150
    assert abs(w[1] - (-106.16380414217615)) < 5e-9  # their spread at 2 s, doubled


def test_heavy_top_steady_precession_is_uniform():
    """Started at the precession rate that balances gravity (Goldstein 5.7: m g l = phi' (C w3 - A phi' cos)
    at theta' = 0), the axis keeps its height and precesses uniformly."""
    A, C, mgl, w3, theta = 1.5, 0.8, 2.0, 10.0, 1.0
    u = np.cos(theta)
    phi_rate = (C * w3 - np.sqrt((C * w3) ** 2 - 4 * A * u * mgl)) / (2 * A * u)  # the slow root
    R0 = spatial.so3_exp([theta, 0.0, 0.0])  # T3 tilted by theta from up (z), nodal line along x
    w0_T = R0.T @ np.array([0.0, 0.0, phi_rate]) + np.array([0.0, 0.0, w3 - phi_rate * u])
    top = LagrangeTop(mgl, A, C, R0, w0_T)
    t = np.linspace(0.0, 5.0, 51)
    assert np.max(np.abs(top.cos_theta(t) - u)) < 1e-12
    e3 = top.rotation(t)[:, :, 2]  # the symmetry axis in the world: azimuth phi with e3 = (s sin phi, -s cos phi, c)
    azimuth = np.unwrap(np.arctan2(e3[:, 0], -e3[:, 1]))
    assert np.max(np.abs(azimuth - azimuth[0] - phi_rate * t)) < 1e-11
