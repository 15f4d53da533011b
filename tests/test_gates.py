"""Gates an engine's CI can trust: a bound the run did not measure is "not measured", never within;
``run --strict=tolerance`` fails on runs beyond tolerance; ``compare`` exits non-zero when nothing pairs,
pairs two configurations of one engine (``--pair-options``), calls a quantity measured before and
missing after, and warns when the adapter's distribution changed; every run records that distribution."""

import csv
import json
import shutil
from dataclasses import replace
from importlib import metadata

import pytest

from dalembert.harness.cli import main
from dalembert.harness.commands.run import Outcome, strict_level
from dalembert.judge import judge
from dalembert.record import RunRecord
from dalembert.reports.compare import compare_stores, to_json
from dalembert.settings import Settings
from dalembert.store import Store
from dalembert.tolerance import Tolerance
from stores import small_store, tamper

TOLERANCES = {"orientation": Tolerance(1e-6, "test bound"), "reaction_force": Tolerance(1e-6, "test bound"),
              "energy": Tolerance(1e-9, "test bound")}


# ------------------------------------------------------------------------------------------ not measured
def test_a_bound_the_run_did_not_report_is_not_measured_never_within():
    unreported = judge("ok", "", {"orientation": 1e-8}, {"energy": 1e-12}, TOLERANCES)
    assert unreported.not_measured == ("reaction_force",) and unreported.within_tolerance is None
    assert unreported.beyond == () and unreported.verdict == "stable"
    beyond = judge("ok", "", {"orientation": 1e-3}, {"energy": 1e-12}, TOLERANCES)
    assert beyond.within_tolerance is False and beyond.beyond == ("orientation",)
    assert beyond.not_measured == ("reaction_force",)
    measured = judge("ok", "", {"orientation": 1e-8, "reaction_force": 1e-9}, {"energy": 1e-12}, TOLERANCES)
    assert measured.within_tolerance is True and measured.not_measured == ()
    # a non-finite value was reported: beyond, as before
    nan = judge("ok", "", {"orientation": float("nan"), "reaction_force": 1e-9}, {"energy": 1e-12}, TOLERANCES)
    assert nan.beyond == ("orientation",) and nan.within_tolerance is False


def test_not_measured_is_stored_and_older_rows_read_as_judged():
    record = RunRecord("k", "c", "v", "e", Settings("rk4", 1e-3), status="ok",
                       judgement=judge("ok", "", {"orientation": 1e-8}, {"energy": 0.0}, TOLERANCES),
                       adapter_distribution="dalembert-pybullet", adapter_version="0.2.0", integrator_order=4)
    row = json.loads(json.dumps(record.to_row()))
    assert row["not_measured"] == "reaction_force" and row["within_tolerance"] is None
    back = RunRecord.from_row(row)
    assert back.judgement == record.judgement and back.to_row() == row
    assert (back.adapter_distribution, back.adapter_version, back.integrator_order) == (
        "dalembert-pybullet", "0.2.0", 4)
    # a schema-3 row: no such columns; its stored within_tolerance as it was judged then
    old = {k: v for k, v in row.items()
           if k not in ("not_measured", "adapter_distribution", "adapter_version", "integrator_order")}
    old |= {"schema_version": 3, "within_tolerance": True}
    back = RunRecord.from_row(old)
    assert back.judgement.not_measured == () and back.judgement.within_tolerance is True
    assert (back.adapter_distribution, back.adapter_version, back.integrator_order, back.schema_version) == (
        "", "", None, 3)


def test_the_runs_table_and_the_validation_table_say_not_measured():
    from dalembert.harness.validation import _fmt
    from dalembert.reports.sections.runs import _beyond_text

    j = judge("ok", "", {"orientation": 1e-3}, {"energy": 0.0}, TOLERANCES)
    assert _beyond_text(j) == "orientation; not measured: reaction_force"
    assert _beyond_text(judge("ok", "", {"orientation": 1e-9}, {"energy": 0.0}, TOLERANCES)) == (
        "not measured: reaction_force")
    assert _fmt(True) == "yes"  # (the validation table shows "not measured: ..." for None, not this)


# ------------------------------------------------------------------------------------------ --strict
def _outcome(strict, *judgements):
    records = [RunRecord(f"k{i}", "c", "v", "e", Settings("rk4", 1e-3), status="ok", judgement=j)
               for i, j in enumerate(judgements)]
    return Outcome(store=None, records=records, lost=[], strict=strict_level(strict))


def test_strict_tolerance_fails_on_runs_beyond_and_plain_strict_does_not():
    beyond = judge("ok", "", {"orientation": 1e-3, "reaction_force": 0.0}, {"energy": 0.0}, TOLERANCES)
    unmeasured = judge("ok", "", {"orientation": 1e-9}, {"energy": 0.0}, TOLERANCES)
    assert _outcome(False, beyond).exit_status == 0
    assert _outcome(True, beyond).exit_status == 0  # --strict keeps its meaning: failed, diverged, timed out
    assert _outcome("tolerance", beyond).exit_status == 1
    assert _outcome("tolerance", unmeasured).exit_status == 0  # named, not failed: nothing measured is beyond
    assert _outcome("tolerance", unmeasured).not_measured
    with pytest.raises(ValueError, match="--strict: 'tol' is not a level"):
        strict_level("tol")


def test_run_strict_tolerance_exits_1_on_a_run_beyond_its_tolerance(tmp_path, capsys):
    # explicit Euler at 1e-2 s on the free top is beyond its orientation bound (and drifts in energy)
    args = ["run", "--case", "free_top", "--engine", "reference", "--integrator", "euler", "--dt", "1e-2",
            "--param", "t_final=0.5", "--quick", "--jobs", "1"]
    assert main([*args, "--out", str(tmp_path / "a"), "--strict"]) == 0
    assert "--strict=tolerance fails on them" in capsys.readouterr().err
    assert main([*args, "--out", str(tmp_path / "b"), "--strict=tolerance"]) == 1
    (record,) = Store(tmp_path / "b").records()
    assert record.judgement.within_tolerance is False and "orientation" in record.judgement.beyond
    # the run's record names the distribution that provides its adapter: dalembert's own for a built-in
    assert (record.adapter_distribution, record.adapter_version) == ("dalembert", metadata.version("dalembert"))


# ------------------------------------------------------------------------------------------ compare
@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return small_store(tmp_path_factory.mktemp("g"), cases=("free_top",), integrators=("rk4", "euler"))


def _copy(store, path, options=None):
    shutil.copytree(store.path, path)
    out = Store.open(path)
    if options is not None:
        for i in range(len(out.done_keys())):
            tamper(out, lambda r: replace(r, settings=replace(r.settings, options=options)), i)
    return out


def test_nothing_pairs_is_a_failure_that_says_why(store, tmp_path, capsys):
    pyramidal = _copy(store, tmp_path / "p", {"cone": "pyramidal"})
    elliptic = _copy(store, tmp_path / "e", {"cone": "elliptic"})
    cmp = compare_stores(pyramidal, elliptic)
    assert not cmp.changes and "engine options differ" in cmp.unpaired and "cone=elliptic" in cmp.unpaired
    assert main(["compare", pyramidal.path, elliptic.path]) == 2
    err = capsys.readouterr().err
    assert "no run pairs" in err and "--pair-options" in err and "nothing was compared" in err
    empty = Store(tmp_path / "empty").create({"specs": []})
    assert main(["compare", store.path, empty.path]) == 2
    assert "B holds no run" in capsys.readouterr().err
    assert main(["compare", store.path, store.path]) == 0  # what pairs still passes


def _engine(store, path, engine):
    out = _copy(store, path)
    for i in range(len(out.done_keys())):
        tamper(out, lambda r: replace(r, engine=engine), i)
    return out


def test_pair_engines_sets_two_versions_of_one_engine_against_each_other(store, tmp_path, capsys):
    """Runs of ``mujoco==3.6.0`` and of ``mujoco`` never pair by name; ``--pair-engines`` pairs them, all else
    equal, and a version whose error grew is a regression."""
    old, new = _engine(store, tmp_path / "old", "mujoco==3.6.0"), _engine(store, tmp_path / "new", "mujoco")
    assert main(["compare", old.path, new.path]) == 2
    assert "engines" in capsys.readouterr().err
    cmp = compare_stores(old, new, pair_engines=("mujoco==3.6.0", "mujoco"))
    assert len(cmp.changes) == 4 and not cmp.only_in_a and not cmp.only_in_b and not cmp.regressed
    assert {(c.a.engine, c.b.engine) for c in cmp.changes} == {("mujoco==3.6.0", "mujoco")}
    assert main(["compare", old.path, new.path, "--pair-engines", "mujoco==3.6.0", "mujoco"]) == 0
    assert "4 runs in both" in capsys.readouterr().out
    worse = _copy(new, tmp_path / "worse")
    tamper(worse, lambda r: replace(r, errors={q: (10 * e[0], 10 * e[1]) for q, e in r.errors.items()}))
    assert main(["compare", old.path, worse.path, "--pair-engines", "mujoco==3.6.0", "mujoco"]) == 1
    capsys.readouterr()
    assert main(["compare", old.path, new.path, "--pair-engines", "mujoco", "mujoco"]) == 2
    assert "both sides are" in capsys.readouterr().err


def test_pair_options_sets_two_configurations_of_one_engine_against_each_other(store, tmp_path, capsys):
    pyramidal = _copy(store, tmp_path / "p", {"cone": "pyramidal", "noslip": 10})
    elliptic = _copy(store, tmp_path / "e", {"cone": "elliptic", "noslip": 10})
    cmp = compare_stores(pyramidal, elliptic, pair_options=({"cone": "pyramidal"}, {"cone": "elliptic"}))
    assert len(cmp.changes) == 4 and not cmp.only_in_a and not cmp.only_in_b and not cmp.unpaired
    assert {c.a.settings.options["cone"] for c in cmp.changes} == {"pyramidal"}
    assert {c.b.settings.options["cone"] for c in cmp.changes} == {"elliptic"}
    assert main(["compare", pyramidal.path, elliptic.path, "--pair-options", "cone=pyramidal",
                 "cone=elliptic,noslip=10"]) == 0  # a numeric option given as text matches the stored 10
    assert "4 runs in both" in capsys.readouterr().out
    # within one store: both configurations beside each other
    both = _copy(pyramidal, tmp_path / "both")
    for r in elliptic.records():
        both.write_record(replace(r, key=r.key + "-elliptic"))
    assert main(["compare", both.path, both.path, "--pair-options", "cone=pyramidal", "cone=elliptic"]) == 0
    out = capsys.readouterr().out
    assert "4 runs in both" in out and "4 of A's 8 runs and 4 of B's 8" in out
    assert main(["compare", both.path, both.path, "--pair-options", "cone=pyramidal", "cone=pyramidal"]) == 2
    assert "both sides are" in capsys.readouterr().err
    # "default": the runs that leave the option to the engine (the store as run, without options)
    cmp = compare_stores(store, elliptic, pair_options=({"cone": "default"}, {"cone": "elliptic"}))
    assert not cmp.changes and "engine options differ" in cmp.unpaired  # B's runs also set noslip=10
    cmp = compare_stores(store, elliptic, pair_options=({"cone": "default", "noslip": "default"},
                                                        {"cone": "elliptic", "noslip": "10"}))
    assert len(cmp.changes) == 4 and not cmp.only_in_a


def test_a_quantity_missing_after_is_called_out_and_fails(store, tmp_path, capsys):
    after = _copy(store, tmp_path / "after")
    tamper(after, lambda r: replace(r, errors={q: v for q, v in r.errors.items() if q != "angular_velocity"},
                                    drifts={n: v for n, v in r.drifts.items() if n != "energy"}))
    cmp = compare_stores(store, after)
    (c,) = [c for c in cmp.changes if c.regression]
    assert c.missing == ("angular_velocity", "drift:energy") and c.change == "worse"
    assert main(["compare", store.path, after.path, "--csv", str(tmp_path / "c.csv"), "--only-changed"]) == 1
    out = capsys.readouterr().out
    assert "missing after" in out and "angular_velocity (rad/s)" in out and "REGRESSION" in out
    rows = [r for r in csv.DictReader(open(tmp_path / "c.csv")) if r["quantity"] == "angular_velocity"]
    assert "missing after" in {r["change"] for r in rows}
    assert to_json(cmp)["runs"][0]["missing_after"] == ["angular_velocity", "drift:energy"]


def test_a_changed_adapter_distribution_is_warned_about(store, tmp_path, capsys):
    after = _copy(store, tmp_path / "after")
    tamper(after, lambda r: replace(r, adapter_version="9.9"))
    version = metadata.version("dalembert")
    cmp = compare_stores(store, after)
    assert any(w.startswith("adapter versions differ") and f"dalembert {version} -> dalembert {version} and "
               "dalembert 9.9" in w for w in cmp.warnings), cmp.warnings
    assert not any("adapter versions" in w for w in compare_stores(store, store).warnings)
