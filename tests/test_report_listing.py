"""A hazard of many runs lists at most ``LISTED_RUNS`` of them and counts the rest: a map of a million probes
must not make a page of a million lines, nor a line per run it does not list."""

from types import SimpleNamespace

from dalembert.reports import hazards as found
from dalembert.reports.hazards import Hazard
from dalembert.reports.sections import hazards as section


def _hazard(n, listed=None):
    """A hazard of ``n`` runs whose details name the first ``listed`` (all by default)."""
    return Hazard(kind="diverged", engine="e", runs=tuple(range(n)), text="Diverged.",
                  details=tuple(f"run {i}" for i in range(n if listed is None else listed)))


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


def test_the_runs_are_counted_from_the_hazard_s_runs_not_its_lines(monkeypatch):
    # a hazard names only its first LISTED_RUNS runs (``Hazard.details``): the count is of every run
    monkeypatch.setattr(section, "LISTED_RUNS", 4)
    _, md = section._block([("diverged", [_hazard(10, listed=4)])])
    assert "the 10 runs" in "".join(md) and "6 more runs" in "".join(md)
    assert [line for line in md if line.startswith("  - run")] == [f"  - run {i}" for i in range(4)]


def test_a_hazard_names_only_the_runs_it_lists(monkeypatch):
    monkeypatch.setattr(found, "LISTED_RUNS", 4)
    runs = [SimpleNamespace(i=i, settings=SimpleNamespace(integrator="rk4", dt=float(i), rtol=None, options={}),
                            sweep_label=f"dt={i}", options_text="")
            for i in range(10)]
    named = []

    def line(r):
        named.append(r.i)
        return f"run {r.i}"

    h = found._hazard("diverged", SimpleNamespace(engine="e"), runs, "10 runs diverged", line, worst=runs[9])
    assert h.runs == tuple(runs) and h.details == tuple(f"run {i}" for i in range(4))
    assert sorted(set(named)) == [0, 1, 2, 3, 9]  # the listed ones and the worst, for the sentence


def test_what_a_hazards_runs_share_is_read_in_words():
    """``_shared`` compares the runs' settings as they are, and their words where those differ: values that differ
    may read alike (a step past ``:g``'s 6 digits, an option past ``option_text``'s 4)."""
    from dalembert.settings import option_text

    def run(dt, k):
        s = SimpleNamespace(integrator="rk4", dt=dt, rtol=None, options={"k": k})
        return SimpleNamespace(settings=s, sweep_label=f"dt={dt:g}", options_text=f"k={option_text(k)}")

    runs = [run(0.1, 0.123451), run(0.1000000001, 0.123452), run(0.1, 0.123451)]
    assert found._shared(runs) == "all rk4 at dt=0.1 with k=0.1235"
    assert found._shared(runs + [run(0.2, 0.123451)]) == "all rk4 with k=0.1235"
    assert found._shared(runs + [run(0.1, 0.2)]) == "all rk4 at dt=0.1"
    assert found._shared(runs[:1]) == ""
