"""A curve's bracket (``dalembert.boundary.bracket``): the largest passing step below the smallest failing one, the
smallest failing one, and whether every passing step lies below it — on probes whose answer is known."""

from dalembert.boundary import FINITE, Bracket, bracket


def _stable(v):
    return v == "stable"


def test_a_monotone_curve_brackets_between_its_last_pass_and_first_fail():
    probes = [(1e-2, "diverged"), (1e-3, "stable"), (5e-3, "drifts"), (2e-3, "stable")]
    assert bracket(probes, _stable) == Bracket(2e-3, 5e-3, True)
    assert bracket(probes, lambda v: v in FINITE) == Bracket(5e-3, 1e-2, True)


def test_a_pass_above_the_first_fail_is_not_monotone_and_not_the_bracket():
    probes = [(4e-3, "stable"), (2e-3, "diverged"), (1e-3, "stable"), (8e-3, "diverged")]
    assert bracket(probes, _stable) == Bracket(1e-3, 2e-3, False)


def test_a_curve_that_never_fails_or_never_passes_has_one_side():
    assert bracket([(1e-3, "stable"), (2e-3, "stable")], _stable) == Bracket(2e-3, None, True)
    assert bracket([(1e-3, "diverged"), (2e-3, "failed")], _stable) == Bracket(None, 1e-3, True)


def test_each_verdict_is_asked_once():
    asked = []

    def passes(v):
        asked.append(v)
        return v == "stable"

    bracket([(1e-3, "stable"), (2e-3, "stable"), (4e-3, "diverged"), (8e-3, "diverged")], passes)
    assert sorted(asked) == ["diverged", "stable"]
