"""The contract every registered case meets — a new case gets these tests for free.

The checks themselves live in ``dalembert.testing`` (installed with the package), so a third
party's cases are held to the same contract (``check_case``); here each check is one test per
registered case. Hard cases run on a shortened horizon (``testing.HARD_HORIZON``, or their own where shorter).
"""

import pytest

from dalembert import testing
from dalembert.case import CASES, load_cases
from dalembert.reference import truth
from truths import contract_case, shared_reference, shared_truth

load_cases()
NAMES = list(CASES)


@pytest.fixture(scope="module", params=NAMES)
def case(request):
    """The case; a hard one shortened to ``HARD_HORIZON``, never lengthened (``truths.contract_case``): a hard case
    whose own horizon is shorter (``robot_free_fall``: 1 s) is checked over it, the truth ``test_hard_cases.py``
    needs too."""
    return contract_case(request.param)


@pytest.fixture
def case_truth(case, shared_dir):
    """The case's truth, computed once per case in the session (``truths.shared_truth``)."""
    return shared_truth(case, shared_dir)


def test_registry_is_not_empty():
    assert {"pivoted_rod", "free_top", "free_top_intermediate", "particle_box", "pendulum", "heavy_top", "chain",
            "kovalevskaya_top"} <= set(NAMES)


def test_a_hard_case_is_shortened_to_the_contract_horizon_never_lengthened():
    """``check_case`` (a third party's cases) and this module check a hard case over the same horizon: the
    shorter of ``HARD_HORIZON`` and its own."""
    cases = load_cases()
    assert cases["robot_free_fall"].params["t_final"] < testing.HARD_HORIZON  # (what makes it the case to ask)
    assert testing.contract_horizon(cases["robot_free_fall"]) is None
    assert testing.contract_horizon(cases["free_top_fast_spin"]) == testing.HARD_HORIZON
    assert testing.contract_horizon(cases["free_top"]) is None  # not hard: its own horizon
    assert contract_case("robot_free_fall").t_final == cases["robot_free_fall"].params["t_final"]


def test_builds_with_defaults_and_is_versioned(case):
    testing.check_builds(case.name, **case.params)
    for name, tol in case.tolerances.items():
        assert tol.reason.strip(), f"tolerance {name} needs a reason"


def test_truth_is_finite_and_starts_at_the_initial_state(case, case_truth):
    testing.check_truth_starts_at_initial_state(case, case_truth)


def test_truth_conserves_what_the_case_declares(case, case_truth):
    testing.check_truth_conserves(case, case_truth)


def test_an_independent_solution_agrees_with_the_truth(case, case_truth, shared_dir, monkeypatch):
    """The closed form against the reference; a truth from the reference against a second integrator
    (and formulation, where the truth's is not Kane's), never against itself. The reference against a closed
    form is computed once in the session (``truths.shared_reference``: test_reference_check.py judges it too)."""
    why = testing.reference_cannot_judge(case)
    if why:  # contact: tests/test_contact_cases.py checks each closed form against an event-driven integration
        pytest.skip(why)
    monkeypatch.setattr(testing, "_reference_through_singular_positions", lambda c: shared_reference(c, shared_dir))
    testing.check_reference_agrees(case, case_truth)


def test_second_solution_is_not_the_truth_itself():
    """The check above compares two different computations: for a case without a closed form the
    second solution differs from the truth (by roundoff and truncation, not by zero)."""
    chain = CASES["chain"](t_final=1.0)
    label, other = testing.second_solution(chain)
    assert "lsoda" in label and "kane" in label
    assert not (other.joints["link1"].q == truth(chain).joints["link1"].q).all()


def test_no_tolerance_below_the_floor(case):
    """A case may not ask for more accuracy than the physics allows."""
    testing.check_floor(case)


def test_truth_csv_round_trip_is_exact(case, case_truth, tmp_path):
    testing.check_csv_round_trip(case, case_truth, tmp_path)
