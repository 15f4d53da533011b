"""A hazard of many runs lists at most ``LISTED_RUNS`` of them and counts the rest: a map of a million probes
must not make a page of a million lines."""

from dalembert.reports.hazards import Hazard
from dalembert.reports.sections import hazards as section


def _hazard(n):
    return Hazard(kind="diverged", engine="e", runs=(), text="Diverged.", details=tuple(f"run {i}" for i in range(n)))


def test_a_hazard_of_more_runs_than_listed_names_the_first_and_counts_the_rest(monkeypatch):
    monkeypatch.setattr(section, "LISTED_RUNS", 4)
    html, md = section._block([("diverged", [_hazard(10)])])
    listed = [line for line in md if line.startswith("  - ")]
    assert listed[:4] == [f"  - run {i}" for i in range(4)] and len(listed) == 5
    assert "6 more runs" in listed[4] and "the 10 runs" in "".join(md)
    assert "run 3" in "".join(html) and "run 4" not in "".join(html) and "6 more runs" in "".join(html)


def test_a_hazard_of_as_many_runs_as_listed_names_every_one(monkeypatch):
    monkeypatch.setattr(section, "LISTED_RUNS", 10)
    _, md = section._block([("diverged", [_hazard(10)])])
    assert [line for line in md if line.startswith("  - ")] == [f"  - run {i}" for i in range(10)]
