"""Loop-closure rows (``dalembert.closure``) as the reference solver evaluates them (``reference.loops``): one state
and a stack of states rounded alike, all loops' Jacobian and bias from one ``G`` as each loop's own rows give them,
and an acceleration without its reactions the same as with them."""

from __future__ import annotations

import numpy as np
import pytest

from dalembert import closure, make_case, spatial
from dalembert.reference.configuration import Block, qdot
from dalembert.reference.loops import ClosedLoops
from dalembert.scene import Loop
from scenes import spatial_chain

# ``ClosedLoops`` sums each row's products with the bodies' Jacobians in one product of all loops' G, where the
# rows' own G_a J_a + G_b J_b sums them loop by loop: the same terms in another order, so roundoff of the largest
# term (measured 2.1e-16 of the largest entry over the scenes and states below).
ASSEMBLY_RTOL = 1e-14


def _states(rng, n=None):
    """Random body states: unit-quaternion attitudes, positions, velocities, angular velocities; one or n."""
    lead = () if n is None else (n,)
    q = spatial.quat_normalize(rng.normal(size=lead + (4,)))
    return dict(R=spatial.quat_to_matrix(q), p=rng.normal(size=lead + (3,)), v=rng.normal(size=lead + (3,)),
                w=rng.normal(size=lead + (3,)))


LOOPS = [Loop("ball", "a", "b", point_a=[0.1, 0.2, 0.3], point_b=[-0.3, 0.0, 0.2]),
         Loop("revolute", "a", "b", point_a=[0.1, 0.0, 0.0], point_b=[0.0, 0.4, 0.0], axis=[1.0, 2.0, 0.5],
              quat_a=tuple(spatial.quat_exp([0.3, -0.2, 0.5])), quat_b=tuple(spatial.quat_exp([-0.1, 0.4, 0.2]))),
         Loop("distance", "a", "b", point_a=[0.2, 0.0, 0.1], point_b=[0.0, -0.1, 0.3], length=0.7)]


@pytest.mark.parametrize("loop", LOOPS, ids=[lp.kind for lp in LOOPS])
def test_rows_of_stacked_states_are_each_states_rows_bit_for_bit(loop):
    """``rows_stacked`` (the read-back's) and ``rows`` (the integrators') write the same terms in the same order
    (``closure.LoopRows``), so that a stacked read-back agrees with one made state by state to the last bit of
    the rows: every kind, to a body and to the world (whose state has no sample axis)."""
    rng = np.random.default_rng(11)
    n = 50
    for A, B in ((_states(rng, n), _states(rng, n)), (_states(rng, n), closure.world_state())):
        stacked = closure.rows_stacked(loop, A, B)
        for k in range(n):
            one = closure.rows(loop, {x: v[k] for x, v in A.items()},
                               {x: (v[k] if np.ndim(v) == np.ndim(A[x]) else v) for x, v in B.items()})
            for field in ("phi", "G_a", "G_b", "gamma", "velocity"):
                assert getattr(stacked, field)[k].tobytes() == getattr(one, field).tobytes(), (loop.kind, field, k)


SCENES = {"andrews_squeezer": lambda: make_case("andrews_squeezer").scene,  # three balls on one body
          "bricard": lambda: make_case("bricard").scene,  # a revolute to the world
          "n_four_bar": lambda: make_case("n_four_bar").scene,  # two revolutes
          "chain_to_an_anchor": lambda: spatial_chain("distance")}  # a distance to the world


@pytest.mark.parametrize("name", SCENES)
def test_all_loops_rows_are_each_loops_own(name):
    """``ClosedLoops.constraints`` (all loops' rows from one ``G`` against the joined bodies' twists) at random
    configurations and speeds: ``phi``, the rows' rates and ``gamma`` are each loop's ``closure.rows``, and
    ``J``, ``b`` are each loop's ``G_a J_a + G_b J_b`` and ``G_a bias_a + G_b bias_b + gamma`` stacked."""
    system = ClosedLoops(SCENES[name]())
    rng = np.random.default_rng(5)
    for _ in range(4):
        q = system.q0 + 0.3 * rng.normal(size=system.q0.shape)
        for b in system.blocks:
            if b.kind == "quat":
                q[b.q] /= np.linalg.norm(q[b.q])
        kin = system.kinematics(q, rng.normal(size=system.nv))
        phi, J, bias, found = system.constraints(kin)
        rows = [closure.rows(loop, kin[loop.body_a], kin[loop.body_b]) for loop in system.loops]
        twist = lambda body: np.concatenate([kin[body]["Jv"], kin[body]["Jw"]])  # noqa: E731
        bias_of = lambda body: np.concatenate([kin[body]["a_bias"], kin[body]["alpha_bias"]])  # noqa: E731
        expected_J = np.vstack([r.G_a @ twist(lp.body_a) + r.G_b @ twist(lp.body_b)
                                for lp, r in zip(system.loops, rows)])
        expected_b = np.concatenate([r.G_a @ bias_of(lp.body_a) + r.G_b @ bias_of(lp.body_b) + r.gamma
                                     for lp, r in zip(system.loops, rows)])
        assert np.array_equal(phi, np.concatenate([r.phi for r in rows]))
        for got, want in zip(found, rows):
            for field in ("phi", "G_a", "G_b", "gamma", "velocity"):
                assert np.array_equal(getattr(got, field), getattr(want, field)), field
        assert np.abs(J - expected_J).max() <= ASSEMBLY_RTOL * np.abs(expected_J).max()
        assert np.abs(bias - expected_b).max() <= ASSEMBLY_RTOL * np.abs(expected_b).max()


def test_an_acceleration_without_its_reactions_is_the_solves_bit_for_bit():
    """``ClosedLoops.acceleration`` (the integrators' call) skips the loop forces, which only the read-back needs;
    its accelerations are ``_solve``'s (which forms them), to the last bit, off the manifolds too."""
    system = ClosedLoops(SCENES["bricard"]())
    rng = np.random.default_rng(2)
    for _ in range(3):
        q, v = system.q0 + 1e-6 * rng.normal(size=system.q0.shape), system.v0 + 1e-6 * rng.normal(size=system.nv)
        assert system.acceleration(0.0, q, v).tobytes() == system._solve(0.0, q, v)[0].tobytes()


def test_a_quaternion_blocks_rate_is_the_quaternion_derivative_bit_for_bit():
    """``configuration.qdot``'s quaternion block (``spatial.quat_derivative`` of one quaternion: in floats, once per
    block per right-hand side) is the stacked quaternion derivative's, ``1/2 q * (0, w)``, to the last bit, at
    magnitudes from 1e-8 to 1e8."""
    rng = np.random.default_rng(3)
    blocks = (Block("vector", slice(0, 3), slice(0, 3)), Block("quat", slice(3, 7), slice(3, 6)))
    for _ in range(2000):
        q, v = rng.normal(size=7) * 10.0 ** rng.integers(-8, 9), rng.normal(size=6) * 10.0 ** rng.integers(-8, 9)
        out = qdot(blocks, q, v)
        assert out[3:].tobytes() == spatial.quat_derivative(q[None, 3:], v[None, 3:])[0].tobytes()
        assert out[:3].tobytes() == v[:3].tobytes()


def test_the_projection_hands_the_solve_the_positions_of_the_configuration_it_returns():
    """``ClosedLoops._project`` returns the ``positions`` of its last Gauss-Newton pass for the solve to reuse: those
    of the configuration it returns, to the last bit, whether the projection moved it (off the manifold) or not
    (a configuration already projected)."""
    system = ClosedLoops(SCENES["andrews_squeezer"]())
    rng = np.random.default_rng(4)
    for scale in (1e-6, 1e-10, 0.0):
        q, v = system.q0 + scale * rng.normal(size=system.q0.shape), system.v0 + rng.normal(size=system.nv)
        if scale == 0.0:
            q = system.project(q, v)[0]
        q1, _, pos = system._project(q, v)
        assert (q1.tobytes() == q.tobytes()) == (scale == 0.0)
        fresh = system.positions(q1)
        for body in system._names:
            for key in ("R", "p", "Jv", "Jw"):
                assert pos[body][key].tobytes() == fresh[body][key].tobytes(), (scale, body, key)
