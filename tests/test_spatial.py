"""Conversions in dalembert.spatial, against definitions and each other."""

import numpy as np
import pytest

from dalembert import spatial

ROUNDOFF = 1e-14  # a few ulps of 1 after a handful of products


@pytest.fixture
def rng():
    return np.random.default_rng(7)


def random_quats(rng, n):
    q = rng.normal(size=(n, 4))
    return spatial.quat_normalize(q)


def test_matrix_round_trip_every_branch(rng):
    q = random_quats(rng, 500)
    # include the four Shepperd branches explicitly: identity and 180-degree turns
    q = np.vstack([q, np.eye(4)])
    back = spatial.matrix_to_quat(spatial.quat_to_matrix(q))
    assert np.max(spatial.rotation_angle(q, back)) < ROUNDOFF
    R = spatial.quat_to_matrix(q)
    assert np.max(np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3))) < ROUNDOFF
    assert np.allclose(np.linalg.det(R), 1.0, atol=ROUNDOFF)


def test_single_and_stacked_paths_agree(rng):
    q1, q2 = random_quats(rng, 2)
    w = rng.normal(size=3)
    assert np.allclose(spatial.quat_multiply(q1, q2), spatial.quat_multiply(q1[None], q2[None])[0], atol=0, rtol=0)
    assert np.array_equal(spatial.quat_to_matrix(q1), spatial.quat_to_matrix(q1[None])[0])
    assert np.allclose(spatial.quat_exp(w), spatial.quat_exp(w[None])[0], atol=ROUNDOFF)
    assert np.allclose(spatial.so3_exp(w), spatial.so3_exp(w[None])[0], atol=ROUNDOFF)
    assert np.allclose(spatial.cross(w, q1[1:]), np.cross(w, q1[1:]), atol=ROUNDOFF)


def test_single_vector_paths_are_bit_for_bit_numpy_s(rng):
    """The single-vector paths compute in Python floats (``spatial.skew``): the same IEEE operations as the
    stacked paths' numpy arrays, so the same bits, over magnitudes from 1e-150 to 1e150 and through
    overflow, infinities and NaN (the reference's truths and every stored figure rest on this)."""
    a, b = (rng.normal(size=(2000, 4)) * 10.0 ** rng.uniform(-150, 150, size=(2000, 4)) for _ in range(2))
    a[::97, 1], b[::89, 2], a[::83, 3] = np.inf, np.nan, -np.inf
    with np.errstate(all="ignore"):
        for x, y in zip(a, b):
            assert np.array_equal(spatial.cross(x[1:], y[1:]), np.cross(x[1:], y[1:]), equal_nan=True)
            assert np.array_equal(spatial.skew(x[1:]), spatial.skew(x[None, 1:])[0], equal_nan=True)
            assert np.array_equal(spatial.quat_to_matrix(x), spatial.quat_to_matrix(x[None])[0], equal_nan=True)
            assert np.array_equal(spatial.quat_multiply(x, y), spatial.quat_multiply(x[None], y[None])[0],
                                  equal_nan=True)


def test_hamilton_product_composes_rotations(rng):
    q1, q2 = random_quats(rng, 2)
    R12 = spatial.quat_to_matrix(q1) @ spatial.quat_to_matrix(q2)
    assert np.allclose(spatial.quat_to_matrix(spatial.quat_multiply(q1, q2)), R12, atol=ROUNDOFF)


def test_exp_maps_agree_and_rotate_about_the_axis(rng):
    for theta in (rng.normal(size=3), np.array([1e-6, -2e-6, 3e-7]), np.array([0.0, 0.0, np.pi])):
        R = spatial.so3_exp(theta)
        assert np.allclose(spatial.quat_to_matrix(spatial.quat_exp(theta)), R, atol=ROUNDOFF)
        assert np.allclose(R @ theta, theta, atol=ROUNDOFF)  # the axis is fixed
    # rotation by pi/2 about z sends x to y
    assert np.allclose(spatial.quat_rotate(spatial.quat_from_axis_angle([0, 0, 1], np.pi / 2), [1, 0, 0]),
                       [0, 1, 0], atol=ROUNDOFF)


def test_dexpinv_inverts_the_tangent_of_exp(rng):
    """d/dt exp(theta(t)) = exp(theta) skew(w) with theta' = dexpinv(theta, w): check by finite differences."""
    for theta in (rng.normal(size=3), 1e-5 * rng.normal(size=3)):
        w = rng.normal(size=3)
        dtheta = spatial.so3_dexpinv(theta, w)
        h = 1e-6
        dR = (spatial.so3_exp(theta + h * dtheta) - spatial.so3_exp(theta - h * dtheta)) / (2 * h)
        expected = spatial.so3_exp(theta) @ spatial.skew(w)
        assert np.allclose(dR, expected, atol=1e-8)  # central difference error ~h^2


def test_rotation_angle_is_geodesic_and_precise_for_small_angles():
    for angle in (1e-12, 1e-6, 0.3, 3.0):
        q = spatial.quat_from_axis_angle([1, 2, 3], angle)
        assert spatial.rotation_angle(spatial.IDENTITY_QUAT, q) == pytest.approx(angle, rel=1e-12)
        assert spatial.rotation_angle(-q, q) < 1e-15  # sign-blind


def test_body_world_round_trip(rng):
    q = random_quats(rng, 10)
    v = rng.normal(size=(10, 3))
    assert np.allclose(spatial.world_to_body(q, spatial.body_to_world(q, v)), v, atol=ROUNDOFF)


def test_quaternion_derivative_matches_body_angular_velocity(rng):
    q = random_quats(rng, 1)[0]
    w_B = rng.normal(size=3)
    h = 1e-6
    qd = spatial.quat_derivative(q, w_B)
    dR = (spatial.quat_to_matrix(q + h * qd) - spatial.quat_to_matrix(q - h * qd)) / (2 * h)
    assert np.allclose(dR, spatial.quat_to_matrix(q) @ spatial.skew(w_B), atol=1e-8)


def test_euler_zxz_matches_composition():
    phi, th, psi = 0.3, 1.1, -2.0
    Rz = lambda a: spatial.so3_exp([0, 0, a])  # noqa: E731
    Rx = lambda a: spatial.so3_exp([a, 0, 0])  # noqa: E731
    assert np.allclose(spatial.matrix_from_euler_zxz(phi, th, psi), Rz(phi) @ Rx(th) @ Rz(psi), atol=ROUNDOFF)


def test_scalar_last_round_trip(rng):
    q = random_quats(rng, 5)
    assert np.array_equal(spatial.xyzw_to_wxyz(spatial.wxyz_to_xyzw(q)), q)
    assert np.array_equal(spatial.wxyz_to_xyzw(q)[:, 3], q[:, 0])


def test_initial_body_states_match_kanes_kinematics():
    """Forward kinematics for redundant-coordinate engines against the reference's Kane kinematics."""
    from dalembert.reference.generalized import Kane
    from scenes import chain_case

    scene = chain_case().scene
    kane = Kane(scene)
    expected = kane.kinematics(kane.q0, kane.v0)
    for name, got in spatial.initial_body_states(scene).items():
        for key in ("R", "p", "v", "w"):
            np.testing.assert_allclose(got[key], expected[name][key], rtol=0, atol=1e-14, err_msg=f"{name} {key}")


def test_initial_body_states_of_a_bead_sliding_on_a_spinning_rod():
    """A prismatic joint on a revolute hub: the bead at r along the rod turned by theta, its velocity the
    slide plus the hub's rotation, v = r' e_r + omega r e_theta (polar coordinates, exact)."""
    from dalembert.scene import Body, Joint, Scene

    theta, omega, r, r_dot, h = 0.7, 2.0, 0.3, -0.5, 0.25
    scene = Scene("bead", (Body.box("hub", 1.0, (0.1, 0.1, 0.1)), Body.box("bead", 0.2, (0.02, 0.02, 0.02))),
                  (Joint("revolute", "world", "hub", (theta,), (omega,), axis=(0, 0, 2)),
                   Joint("prismatic", "hub", "bead", (r,), (r_dot,), axis=(3, 0, 0), parent_point=(0, 0, h))),
                  gravity=(0, 0, -9.81))
    e_r, e_t = np.array([np.cos(theta), np.sin(theta), 0.0]), np.array([-np.sin(theta), np.cos(theta), 0.0])
    bead = spatial.initial_body_states(scene)["bead"]
    np.testing.assert_allclose(bead["p"], r * e_r + [0, 0, h], rtol=0, atol=ROUNDOFF)
    np.testing.assert_allclose(bead["v"], r_dot * e_r + omega * r * e_t, rtol=0, atol=ROUNDOFF)
    np.testing.assert_allclose(bead["w"], [0, 0, omega], rtol=0, atol=ROUNDOFF)
    np.testing.assert_allclose(bead["R"], spatial.so3_exp(np.array([0, 0, theta])), rtol=0, atol=ROUNDOFF)


def test_so3_exp_of_a_blown_up_angle_is_nan_not_an_exception():
    """A run that blew up to finite but huge angles (1.9e202 rad: seen on a stiff case at too large a step) reads
    back as NaN, the harness's mark of a divergence, in both the single and the batched path."""
    huge = np.array([0.0, 0.0, 1.9e202])
    assert np.all(np.isnan(spatial.so3_exp(huge)))
    with np.errstate(invalid="ignore", over="ignore"):
        assert np.all(np.isnan(spatial.so3_exp(huge[None])))
