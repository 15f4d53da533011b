"""Pinocchio refuses contact scenes: pin 4 solves contact problems but has no contact time-stepper; its reason
names the solvers it has (checked against the installed pin) and what a time-stepper would take."""

import pytest

pin = pytest.importorskip("pinocchio")

from dalembert.adapters import get_adapter  # noqa: E402
from dalembert.case import make_case  # noqa: E402
from dalembert.settings import Settings  # noqa: E402

ADAPTER = get_adapter("pinocchio")


def test_a_contact_scene_is_refused_with_the_missing_time_stepper():
    case = make_case("ball_slide_to_roll")
    reason = ADAPTER.unsupported(case.scene, Settings("rk4", dt=1e-3))
    assert reason.startswith("contact not yet mapped for pinocchio")
    assert "has no time-stepper" in reason and "Delassus operator" in reason and "one solve per step" in reason
    # the solvers the reason names are pin's own
    for name in ("ADMMConstraintSolver", "PGSConstraintSolver"):
        assert f"pin.{name}" in reason and hasattr(pin, name)
    assert hasattr(pin, "constraintDynamics") and hasattr(pin, "computeDelassusMatrix")


def test_a_contact_free_scene_is_not_refused_for_contact():
    assert ADAPTER.unsupported(make_case("pivoted_rod").scene, Settings("rk4", dt=1e-3)) is None
