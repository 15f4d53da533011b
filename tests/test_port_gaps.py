"""A port's systematic gaps from its original (``reports.port_gaps``) on records made from one real run: the float32
floor where the float64 twin agrees, an order lost where the original keeps it, an integrator giving another's
numbers where the original's two differ; and the MJX section opening with them."""

import math
from types import SimpleNamespace

import pytest

from dalembert.reports.parity import Parity
from dalembert.reports.port_gaps import joint_kinds, number_floors, order_gaps, same_as
from stores import base, changed, seed_store


@pytest.fixture(scope="module")
def seed(tmp_path_factory):
    return seed_store(tmp_path_factory.mktemp("seed"))


def _run(first, key, engine, integrator, dt, error, **options):
    return changed(first, key=key, engine=engine, integrator=integrator, dt=dt, options=options, audit={},
                   errors={**first.errors, "orientation": (error, error)})


def _found(seed, runs):
    first = base(seed)
    return [SimpleNamespace(case=seed.case(first.case, first.case_version), runs=tuple(runs), quantity="orientation")]


def test_an_order_lost_where_the_original_keeps_it_is_a_gap(seed):
    first = base(seed)
    port = [_run(first, "p1", "mjx", "rk4", 1e-2, 1e-5, precision="float64"),
            _run(first, "p2", "mjx", "rk4", 1e-3, 1e-7, precision="float64")]  # order 2
    original = [_run(first, "o1", "mujoco", "rk4", 1e-2, 1e-7), _run(first, "o2", "mujoco", "rk4", 1e-3, 1e-11)]
    (gap,) = order_gaps(_found(seed, port + original))
    assert (gap.port, gap.original, gap.integrator, gap.options) == ("mjx", "mujoco", "rk4", "precision=float64")
    assert gap.port_order == pytest.approx(2.0) and gap.original_order == pytest.approx(4.0)
    assert gap.cases == ("free_top",) and gap.example == ("free_top", (1e-2, 1e-3), (1e-5, 1e-7), (1e-7, 1e-11))
    # the same order in both: no gap
    same = [_run(first, "o1", "mujoco", "rk4", 1e-2, 2e-5), _run(first, "o2", "mujoco", "rk4", 1e-3, 2e-7)]
    assert order_gaps(_found(seed, port + same)) == []
    # a port ahead of the original at the coarse step (the original's error is something else there): no gap
    ahead = [_run(first, "o1", "mujoco", "rk4", 1e-2, 1e-4), _run(first, "o2", "mujoco", "rk4", 1e-3, 1e-8)]
    assert order_gaps(_found(seed, port + ahead)) == []


def test_an_integrator_giving_another_s_numbers_is_a_gap_only_where_the_original_s_two_differ(seed):
    first = base(seed)
    port = [_run(first, "pe", "mjx", "euler", 1e-2, 0.3, precision="float64"),
            _run(first, "pi", "mjx", "implicitfast", 1e-2, 0.3, precision="float64")]
    original = [_run(first, "oe", "mujoco", "euler", 1e-2, 0.3),
                _run(first, "oi", "mujoco", "implicitfast", 1e-2, 0.012)]
    (gap,) = same_as(_found(seed, port + original))
    assert (gap.port, gap.integrator, gap.like, gap.cases) == ("mjx", "implicitfast", "euler", ("free_top",))
    assert gap.example == ("free_top", 1e-2, "orientation", 0.3, 0.012)
    alike = original[:1] + [_run(first, "oi", "mujoco", "implicitfast", 1e-2, 0.3)]
    assert same_as(_found(seed, port + alike)) == []  # the original's implicitfast is its euler here too
    both = [_run(first, "oe", "mujoco", "euler", 1e-2, 0.25), _run(first, "oi", "mujoco", "implicitfast", 1e-2, 0.25)]
    assert same_as(_found(seed, port + both)) == []  # the original's two alike (another computation than the port's)
    apart = [port[0], _run(first, "pi", "mjx", "implicitfast", 1e-2, 0.012, precision="float64")]
    assert same_as(_found(seed, apart + original)) == []  # the port's implicitfast is the original's


def _parity(key, number_type, orientation):
    return Parity("free_top", "v", "mjx", "mujoco", "euler dt=0.01", number_type, orientation, 0.0, math.nan,
                  math.nan, key, "o")


def test_the_float32_floor_is_taken_where_the_float64_twin_is_the_same_computation(seed):
    first = base(seed)
    records = {"s": _run(first, "s", "mjx", "euler", 1e-2, 1e-3),
               "d": _run(first, "d", "mjx", "euler", 1e-2, 1e-3, precision="float64")}
    (floor,) = number_floors([_parity("s", "float32", 3e-6), _parity("d", "float64", 1e-14)], records)
    assert (floor.port, floor.low, floor.high, floor.settings, floor.cases) == ("mjx", 3e-6, 3e-6, 1, ("free_top",))
    # a float64 twin already apart (a chaotic case): its float32 difference is no floor
    assert number_floors([_parity("s", "float32", 3.1), _parity("d", "float64", 2e-8)], records) == []
    # nor where the motion is far from the truth (3 rad: roundoff amplified at every step)
    far = {**records, "d": _run(first, "d", "mjx", "euler", 1e-2, 3.0, precision="float64")}
    assert number_floors([_parity("s", "float32", 0.2), _parity("d", "float64", 1e-14)], far) == []


def test_a_body_no_joint_holds_is_a_free_joint():
    bodies = (SimpleNamespace(name="a"), SimpleNamespace(name="b"))
    assert joint_kinds(SimpleNamespace(joints=(), bodies=bodies)) == ("free",)
    hinge = SimpleNamespace(kind="revolute", child="b")
    assert joint_kinds(SimpleNamespace(joints=(hinge,), bodies=bodies)) == ("free", "revolute")
    assert joint_kinds(SimpleNamespace(joints=(hinge, SimpleNamespace(kind="ball", child="a")), bodies=bodies)) == (
        "ball", "revolute")
