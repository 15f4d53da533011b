"""Kane's kinematics (``reference.generalized``, its pass ``reference.tree_pass``) by two routes each: the bodies'
velocities built joint by joint against the Jacobians built from each speed's motion, and the pass over a stack
of states against the pass state by state."""

import math

import numpy as np
import pytest

from dalembert.case import make_case
from dalembert.reference.generalized import Kane
from dalembert.reference.tree_pass import ARRAY_MATH, FLOAT_MATH, Step, forward

# ``v = Jv u`` and ``w = Jw u``: the pass accumulates each body's velocities joint by joint, the Jacobians'
# columns come from each speed's axis and the lever to the body; measured up to 3e-16 of the largest velocity
# over the scenes below (random states) -> roundoff, with a margin.
JACOBIAN_AGREEMENT = 1e-14
# Rodrigues' rotation entries against their series: each a few products and sums of correctly rounded terms.
SMALL_ANGLE_ROUNDOFFS = 4
# One revolute joint, every kind of joint, prismatic and ball joints, welds, a free base under a tree, loops.
SCENES = ["pendulum", "robot_arm", "flyball_governor", "kovalevskaya_top", "particle_box_welded", "robot_free_fall",
          "robot_tree", "andrews_squeezer"]


def _random_state(system, rng):
    return system.q0 + 0.5 * rng.standard_normal(len(system.q0)), system.v0 + rng.standard_normal(system.nv)


@pytest.mark.parametrize("name", SCENES)
def test_the_jacobians_give_the_velocities_of_the_pass(name):
    """Each body's COM velocity and angular velocity from the pass equal its Jacobians times the speeds."""
    system = Kane(make_case(name).scene)
    rng = np.random.default_rng(7)
    for _ in range(3):
        q, u = _random_state(system, rng)
        kin = system.kinematics(q, u)
        scale = max(max(np.abs(kin[b]["v"]).max(), np.abs(kin[b]["w"]).max()) for b in system._names)
        for body in system._names:
            k = kin[body]
            assert np.abs(k["Jv"] @ u - k["v"]).max() <= JACOBIAN_AGREEMENT * scale, (body, "v")
            assert np.abs(k["Jw"] @ u - k["w"]).max() <= JACOBIAN_AGREEMENT * scale, (body, "w")


@pytest.mark.parametrize("name", SCENES)
def test_the_pass_over_a_stack_of_states_is_the_pass_state_by_state(name):
    """The same scalar code on (m,) arrays: numpy's products and sums round as Python's floats do, so the stacked
    pass gives the single one's numbers bit for bit (the sines aside: numpy's may differ from the math module's
    in the last bit, so the check takes them from the same function)."""
    system = Kane(make_case(name).scene)
    rng = np.random.default_rng(11)
    Q, U = zip(*(_random_state(system, rng) for _ in range(4)))
    Q, U = np.array(Q), np.array(U)
    stacked = forward(system._steps, list(Q.T), list(U.T), ARRAY_MATH)
    sin = lambda x: float(np.sin(x))  # noqa: E731 (numpy's sine, one value at a time)
    flat = lambda out: [x for table in out for item in table for vec in item for x in vec]  # noqa: E731
    for i in range(len(Q)):
        single = forward(system._steps, Q[i].tolist(), U[i].tolist(), (sin, FLOAT_MATH[1]))
        for x, y in zip(flat(stacked), flat(single), strict=True):  # every scalar of every body and speed
            assert np.array_equal(np.broadcast_to(x, (len(Q),))[i], y), (name, i)


def test_a_revolute_joint_at_a_small_angle_keeps_every_digit_of_its_rotation():
    """Rodrigues' ``R = I + sin(th) K + (1 - cos(th)) K^2`` about an axis off the coordinate axes (where ``K^2`` has
    off-diagonal terms, the size of ``1 - cos(th)``) at angles down to 1e-9 rad, against its Taylor series summed in
    extended precision: every entry to a few roundoffs of itself (written ``1 - cos(th)``, the term loses its
    digits below ~1e-4 rad, and every one at 1e-8 rad: ``cos`` rounds to 1)."""
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    step = Step("revolute", 0, 0, 0, np.eye(3), np.zeros(3), np.eye(3), np.zeros(3), axis)
    K = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]], dtype=np.longdouble)
    for th in (1e-9, 1e-6, 1e-4, 1e-3):
        (R, *_), = forward([step], [th], [0.0], FLOAT_MATH)[0]
        x = np.longdouble(th)
        sin = sum((-1) ** k * x ** (2 * k + 1) / math.factorial(2 * k + 1) for k in range(6))
        one_minus_cos = sum((-1) ** k * x ** (2 * k + 2) / math.factorial(2 * k + 2) for k in range(6))
        expected = np.eye(3, dtype=np.longdouble) + sin * K + one_minus_cos * (K @ K)
        got = np.array(R, dtype=np.longdouble).reshape(3, 3)
        assert np.all(np.abs(got - expected) <= SMALL_ANGLE_ROUNDOFFS * np.finfo(float).eps * np.abs(expected)), th


def _same(a, b):
    return np.shape(a) == np.shape(b) and np.asarray(a).tobytes() == np.asarray(b).tobytes()


@pytest.mark.parametrize("name", SCENES)
def test_one_positions_pass_serves_the_metric_and_any_speeds_bit_for_bit(name):
    """``positions(q)`` reused (``ClosedLoops``: the projection's last one is the solve's): after it served the mass
    matrix and another state's speeds, ``velocities`` at it are a fresh ``kinematics(q, u)`` to the last bit, for
    one state and for a stack, and it keeps its own entries (its configuration's, whatever the speeds)."""
    system = Kane(make_case(name).scene)
    rng = np.random.default_rng(5)
    Q, U = zip(*(_random_state(system, rng) for _ in range(3)))
    for q, u in [(Q[0], U[0]), (np.array(Q), np.array(U))]:
        pos = system.positions(q)
        kept = {body: dict(pos[body]) for body in system._names}
        system.mass_matrix(pos)
        system.velocities(pos, 2.0 * u + 1.0)
        got, expected = system.velocities(pos, u), system.kinematics(q, u)
        for body in system._names:
            assert set(got[body]) == set(expected[body]), body
            for key, x in expected[body].items():
                assert _same(got[body][key], x), (body, key)
            assert set(pos[body]) == set(kept[body]) == {"R", "p", "Jv", "Jw"}, body
            for key, x in kept[body].items():
                assert _same(pos[body][key], x) and _same(x, expected[body][key]), (body, key)
