"""Parameter sweeps and the boundary search in the step."""

import numpy as np
import pytest

from dalembert.boundary import Bracket, bracket
from dalembert.harness.cli import main
from dalembert.harness.matrix import RunSpec, expand
from dalembert.store import Store


def test_a_swept_parameter_makes_one_case_version_per_value():
    specs, _ = expand(cases=["free_top_fast_spin"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                      params={"spin": [5.0, 50.0], "offset": [1e-3, 2e-3], "t_final": 1.0})
    assert len(specs) == 4 and len({s.case_version for s in specs}) == 4  # the product of the two sweeps
    assert {dict(s.params)["spin"] for s in specs} == {5.0, 50.0}


@pytest.mark.parametrize("text,values", [("spin=5,50,500", [5.0, 50.0, 500.0]),
                                         ("spin=log:5,500,3", [5.0, 50.0, 500.0]),
                                         ("spin=lin:0,1,3", [0.0, 0.5, 1.0])])
def test_sweep_syntax(text, values):
    from dalembert.case import load_cases
    from dalembert.harness.selection import sweep

    key, value = text.split("=", 1)
    assert np.allclose(sweep(load_cases()["free_top_fast_spin"], key, value), values, rtol=1e-15, atol=0)


def test_a_vector_parameter_sweeps_by_semicolons(tmp_path):
    out = tmp_path / "r"
    assert main(["run", "--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2",
                 "--param", "omega0=0,1,5;0,2,5", "--param", "t_final=0.2", "--out", str(out)]) == 0
    table = Store(out).table()
    assert sorted(table["param_omega0"]) == ["[0.0, 1.0, 5.0]", "[0.0, 2.0, 5.0]"]  # swept values are columns


@pytest.mark.parametrize("probes,expected", [
    ([(1e-3, "stable"), (1e-2, "drifts"), (1e-1, "diverged")], Bracket(1e-3, 1e-2, True)),
    ([(1e-3, "stable"), (1e-1, "stable")], Bracket(1e-1, None, True)),
    ([(1e-3, "drifts"), (1e-1, "diverged")], Bracket(None, 1e-3, True)),
    ([(1e-3, "stable"), (1e-2, "drifts"), (5e-2, "stable")], Bracket(1e-3, 1e-2, False)),
])
def test_the_stable_bracket_of_probes(probes, expected):
    assert bracket(probes, lambda v: v == "stable") == expected


def test_the_search_bisects_to_the_resolution(tmp_path):
    """The reference's RK4 on a 500 rad/s spin, sampled every 0.1 s so that steps up to 0.1 s divide
    it: the search narrows both boundaries (near 1e-3 and 6e-3 s) to the resolution, each probe a stored run.
    The bracket's small end, 5e-4 s, is stable and over two decades below its large end: a 1e-4 s end bisected
    the same way, its one probe 5000 steps (a third of the test's time)."""
    from dalembert.boundary import boundaries

    out = tmp_path / "r"
    assert main(["run", "--case", "free_top_fast_spin", "--param", "spin=500", "--param", "t_final=0.5",
                 "--param", "sample_interval=0.1", "--engine", "reference", "--integrator", "rk4", "--search", "dt",
                 "--dt", "5e-4,1e-1", "--resolution", "1.5", "--quick", "--out", str(out)]) == 0
    (b,) = boundaries(Store(out).records())
    assert b.stable.ratio <= 1.5 and b.finite.ratio <= 1.5 and b.stable.monotone and b.finite.monotone
    assert b.stable.passed <= b.finite.passed and b.probes == len(Store(out).records())


def test_the_report_maps_the_stored_boundaries(tmp_path):
    """A sweep over spin with a step search: the report's stability map states, per curve, the
    largest stable and finite steps the store holds (read back from the records)."""
    from dalembert.boundary import boundaries

    out = tmp_path / "r"
    assert main(["run", "--case", "free_top_fast_spin", "--param", "spin=50,500", "--param", "t_final=0.5",
                 "--param", "sample_interval=0.1", "--engine", "reference", "--integrator", "rk4", "--search", "dt",
                 "--dt", "1e-3,1e-1", "--resolution", "2", "--quick", "--out", str(out)]) == 0
    assert main(["report", str(out)]) == 0
    md = (out / "report.md").read_text()
    assert "## Stability maps" in md and "against spin" in md
    assert "Each run was timed once after its warm-up (dalembert run --quick)" in md  # its costs are one sample
    found = boundaries(Store(out).records())
    scale = (lambda b: b.params["spin"]) if "spin x dt" in md else (lambda b: 1.0)
    stable = [b.stable.passed * scale(b) for b in found if b.stable.passed is not None]
    assert stable  # the resolution-2 search at these spins brackets both
    line = next(x for x in md.splitlines() if x.startswith("- reference rk4"))
    assert f"{min(stable):.3g}" in line and f"{max(stable):.3g}" in line


def test_the_hard_suite_carries_its_stability_maps():
    """--tag hard adds each map's first probes (every swept value at both ends of its bracket) as a
    search of its own; --no-maps leaves them out; the maps are declared beside their cases."""
    from dalembert.harness.cli import _parser
    from dalembert.harness.selection import select
    from dalembert.maps import MAPS

    def chosen(*flags):
        return select(_parser().parse_args(["run", "--tag", "hard", "--engine", "reference", "--integrator", "rk4",
                                            "--dt", "1e-2", *flags]), 2)

    with_maps, without = chosen(), chosen("--no-maps")
    assert without.searches == ()
    plans = [MAPS[name] for name in MAPS if "hard" in MAPS[name].tags]
    assert len(with_maps.searches) == len(plans) >= 2
    for (first, _), plan in zip(with_maps.searches, plans):
        assert {s.case for s in first} == {plan.case}
        assert {s.settings.dt for s in first} == set(plan.bracket)
        assert len({dict(s.params)[plan.parameter] for s in first}) == int(plan.values.rsplit(",", 1)[1])
    assert set(without.specs) < set(with_maps.specs)


# The map the search's tests replay: three spins of the fast-spinning free top, the reference's RK4 (both
# boundaries bracketed at 100 and 500 rad/s) and Euler (nothing to bisect), in the bracket 1e-3..1e-1 s.
REPLAYED_MAP = ["run", "--case", "free_top_fast_spin", "--param", "spin=log:20,500,3", "--param", "t_final=0.5",
                "--param", "sample_interval=0.1", "--engine", "reference", "--integrator", "rk4", "--integrator",
                "euler", "--search", "dt", "--dt", "1e-3,1e-1", "--resolution", "1.5", "--quick", "--jobs", "1"]
# What the search probed on REPLAYED_MAP, (spin, integrator, dt, verdict), written down from a run of the search
# that reread the whole store every round (commit ec194c5), before it read only each round's probes.
REPLAYED_PROBES = sorted([
    (20.0, "euler", 0.001, "stable"), (20.0, "euler", 0.1, "stable"), (20.0, "rk4", 0.001, "stable"),
    (20.0, "rk4", 0.1, "stable"), (100.0, "euler", 0.001, "drifts"), (100.0, "euler", 0.1, "drifts"),
    (100.0, "rk4", 0.001, "stable"), (100.0, "rk4", 0.003125, "stable"), (100.0, "rk4", 0.005555555555555556, "stable"),
    (100.0, "rk4", 0.007692307692307693, "drifts"), (100.0, "rk4", 0.01, "drifts"),
    (100.0, "rk4", 0.03333333333333333, "drifts"), (100.0, "rk4", 0.05, "diverged"), (100.0, "rk4", 0.1, "diverged"),
    (500.0, "euler", 0.001, "diverged"), (500.0, "euler", 0.1, "diverged"), (500.0, "rk4", 0.001, "drifts"),
    (500.0, "rk4", 0.003125, "drifts"), (500.0, "rk4", 0.004166666666666667, "drifts"),
    (500.0, "rk4", 0.005555555555555556, "diverged"), (500.0, "rk4", 0.01, "diverged"),
    (500.0, "rk4", 0.1, "diverged")])
# Its boundaries, (spin, integrator, stable passed, stable failed, finite passed, finite failed, probes), from that run.
REPLAYED_BOUNDARIES = sorted([
    (20.0, "euler", 0.1, None, 0.1, None, 2), (20.0, "rk4", 0.1, None, 0.1, None, 2),
    (500.0, "euler", None, 0.001, None, 0.001, 2), (500.0, "rk4", None, 0.001, 0.004166666666666667,
                                                     0.005555555555555556, 6),
    (100.0, "euler", None, 0.001, 0.1, None, 2),
    (100.0, "rk4", 0.005555555555555556, 0.007692307692307693, 0.03333333333333333, 0.05, 8)])


def _probes_and_boundaries(store):
    from dalembert.boundary import boundaries

    records = store.records()
    probes = sorted((r.params["spin"], r.settings.integrator, r.settings.dt, r.judgement.verdict) for r in records)
    found = sorted((b.params["spin"], b.integrator, b.stable.passed, b.stable.failed, b.finite.passed, b.finite.failed,
                    b.probes) for b in boundaries(records))
    return probes, found


@pytest.mark.parametrize("layout", [1, 2])
def test_the_search_reads_each_probe_once_and_finds_what_it_found(tmp_path, monkeypatch, layout):
    """In either store layout (2: the segments a map of more than FILES_UP_TO first probes takes) the search
    probes the same steps, with the same verdicts, and finds the same boundaries as the search that reread the
    whole store every round, while reading each probe's row once: a round costs its own probes. ``--resume`` of
    the finished map finds every probe stored on its first read (layout 2 keeps the later rounds' lines until
    their round asks for them) and runs none again."""
    import dalembert.harness.search as search_module
    import dalembert.store

    # 20 lies between the map's 12 first probes and the most it can store (``probes_at_most``: 60): the store is
    # sized by the whole search, not by its first round.
    monkeypatch.setattr(dalembert.store, "FILES_UP_TO", 2000 if layout == 1 else 20)
    parsed, from_row = [], search_module.RunRecord.from_row

    class Counted:
        @staticmethod
        def from_row(row):
            parsed.append(row["key"])
            return from_row(row)

    monkeypatch.setattr(search_module, "RunRecord", Counted)
    out = tmp_path / "r"
    assert main([*REPLAYED_MAP, "--out", str(out)]) == 0
    store = Store(out)
    assert store.layout() == layout
    assert _probes_and_boundaries(store) == (REPLAYED_PROBES, REPLAYED_BOUNDARIES)
    first = [RunSpec.from_json(s) for s in store.manifest()["searches"][0]["first"]]
    assert len(first) == 12 and len(REPLAYED_PROBES) <= search_module.probes_at_most(first, 1.5) == 60
    assert sorted(parsed) == sorted(store.done_keys())  # every probe read back once, none twice
    rows = sorted(p.name for p in (out / ("rows" if layout == 1 else "segments")).iterdir())
    parsed.clear()
    assert main(["run", "--resume", str(out)]) == 0
    assert sorted(p.name for p in (out / ("rows" if layout == 1 else "segments")).iterdir()) == rows  # none rerun
    assert sorted(parsed) == sorted(store.done_keys())
    assert _probes_and_boundaries(Store(out)) == (REPLAYED_PROBES, REPLAYED_BOUNDARIES)


def test_a_probe_the_infrastructure_lost_stops_its_curve(tmp_path, monkeypatch):
    """A probe lost to the infrastructure (not stored, returned as lost) stops its curve where it was: the search
    does not ask for it again round after round, and the other curves are bisected as before."""
    import dalembert.harness.pool as pool

    run_matrix, calls = pool.run_matrix, []

    def losing(runs, store, *args, **kwargs):  # loses the 100-rad/s RK4 curve's first bisection probe
        calls.append(len(runs))
        assert len(calls) < 30, "the search asks for a lost probe again and again"
        dropped = [s for s in runs if dict(s.params)["spin"] == 100.0 and s.settings.integrator == "rk4"
                   and s.settings.dt not in (1e-3, 1e-1)]
        kept = [s for s in runs if s not in dropped]
        return run_matrix(kept, store, *args, **kwargs) + [(s.key, "the cluster lost its task") for s in dropped]

    monkeypatch.setattr(pool, "run_matrix", losing)
    out = tmp_path / "r"
    assert main([*REPLAYED_MAP, "--out", str(out)]) == 4  # runs lost
    probes, _ = _probes_and_boundaries(Store(out))
    assert probes == [p for p in REPLAYED_PROBES if p[:2] != (100.0, "rk4") or p[2] in (1e-3, 1e-1)]
