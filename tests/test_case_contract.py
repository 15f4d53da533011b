"""The contract every registered case meets — a new case gets these tests for free."""

import numpy as np
import pytest

from dalembert import Settings, invariants, spatial
from dalembert.case import CASES, load_cases
from dalembert.errors import QUANTITIES, trajectory_errors
from dalembert.trajectory import read_csv, write_csv
from dalembert.reference import simulate, truth

load_cases()
NAMES = list(CASES)
INITIAL_STATE_TOL = 1e-14  # the truth at t = 0 is the scene's initial state, to roundoff


# Hard cases run the contract on a shortened horizon (their full horizons cost
# minutes in the pure-Python reference); every other case on its own.
HARD_CONTRACT_HORIZON = 2.0


@pytest.fixture(scope="module", params=NAMES)
def case(request):
    factory = CASES[request.param]
    if "hard" in factory.tags:
        return factory(t_final=HARD_CONTRACT_HORIZON)
    return factory()


def test_registry_is_not_empty():
    assert {"pivoted_rod", "free_top", "free_top_intermediate", "particle_box"} <= set(NAMES)


def test_builds_with_defaults_and_is_versioned(case):
    factory = CASES[case.name]
    assert case.version == factory(**case.params).version  # deterministic
    assert case.tags and set(factory.tags) <= set(case.tags)
    assert case.tolerances, "a case states its tolerances"
    for name, tol in case.tolerances.items():
        assert tol.reason, f"tolerance {name} needs a reason"
    changed = factory(**{**case.params, "t_final": 2 * case.t_final})
    assert changed.version != case.version


def test_truth_is_finite_and_starts_at_the_initial_state(case):
    tr = truth(case)
    assert tr.is_finite()
    assert np.array_equal(tr.t, case.times)
    for j in case.scene.joints:
        b = tr.bodies[j.child]
        if j.kind == "free":
            assert np.allclose(b.position[0], j.q0[:3], atol=INITIAL_STATE_TOL)
            assert spatial.rotation_angle(b.quaternion[0], j.q0[3:]) < INITIAL_STATE_TOL
            assert np.allclose(b.velocity[0], j.v0[:3], atol=INITIAL_STATE_TOL)
            assert np.allclose(b.angular_velocity_body[0], j.v0[3:], atol=INITIAL_STATE_TOL)
        if j.name in tr.joints:
            assert np.allclose(tr.joints[j.name].q[0], j.q0, atol=INITIAL_STATE_TOL)


def test_truth_conserves_what_the_case_declares(case):
    tr = truth(case)
    for name in case.conserved:
        tol = case.tolerances.get(name)
        assert tol is not None, f"conserved {name!r} needs a tolerance"
        assert invariants.drift(name, case.scene, tr) <= tol.value, name


def test_reference_agrees_with_truth_within_the_case_tolerances(case):
    traj = simulate(case.scene, case.times, Settings("dop853", rtol=1e-12, atol=1e-12))[0]
    errors = trajectory_errors(traj, truth(case))
    for quantity, tol in case.tolerances.items():
        if quantity in QUANTITIES and quantity in errors:
            assert errors[quantity][0] <= tol.value, (quantity, errors[quantity])
        elif quantity in invariants.CONSERVED:
            assert invariants.drift(quantity, case.scene, traj) <= tol.value, quantity


def test_no_tolerance_below_the_floor(case):
    """A case may not ask for more accuracy than the physics allows."""
    for quantity, floor in case.floor().items():
        assert floor > 0.0
        if quantity in case.tolerances:
            assert case.tolerances[quantity].value >= floor, (quantity, floor)


def test_truth_csv_round_trip_is_exact(case, tmp_path):
    tr = truth(case)
    write_csv(tr, tmp_path / "t.csv")
    back = read_csv(tmp_path / "t.csv")
    for name, b in tr.bodies.items():
        for field in ("position", "quaternion", "velocity", "angular_velocity"):
            assert np.array_equal(getattr(back.bodies[name], field), getattr(b, field))
