"""``compare`` as ``asv compare``: before, after and ratio per run for each error and the cost; runs in
one store only apart; costs judged against both runs' spreads; warnings when the machines or the
engine versions differ; the exit status is the CI gate."""

import csv
import json
import math
import shutil
from dataclasses import replace

import pytest

from dalembert.harness.cli import main
from dalembert.record import SCHEMA_VERSION
from dalembert.reports.compare import compare_stores, to_json
from dalembert.store import Store
from stores import small_store, tamper


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    return small_store(tmp_path_factory.mktemp("a"), cases=("free_top",), integrators=("rk4", "euler"))


def _copy(store, path):
    shutil.copytree(store.path, path)
    return Store.open(path)


def test_a_store_against_itself_is_unchanged(store, capsys):
    cmp = compare_stores(store, store)
    assert not cmp.regressed and {c.change for c in cmp.changes} == {"same"}
    assert not cmp.only_in_a and not cmp.only_in_b and not cmp.warnings
    assert main(["compare", store.path, store.path, "--only-changed"]) == 0
    out = capsys.readouterr().out
    assert "4 runs in both: 0 worse, 0 better, 0 changed status, 4 unchanged" in out
    assert "cost (s)" not in out  # --only-changed: no line for an unchanged run


def test_a_tenfold_error_is_a_regression_with_before_after_and_ratio(store, tmp_path, capsys):
    worse = _copy(store, tmp_path / "worse")
    tamper(worse, lambda r: replace(r, errors={q: (mx * 10.0 if mx > 1e-10 else mx, final)
                                               for q, (mx, final) in r.errors.items()}))
    cmp = compare_stores(store, worse)
    (bad,) = [c for c in cmp.changes if c.regression]
    before, after, ratio = bad.errors["orientation"]
    assert after == 10 * before and ratio == pytest.approx(10.0)
    assert main(["compare", store.path, worse.path, "--json", str(tmp_path / "c.json"), "--csv",
                 str(tmp_path / "c.csv")]) == 1
    out = capsys.readouterr().out
    line = next(x for x in out.splitlines() if x.startswith("+") and "orientation" in x)
    assert f"{before:.3e}" in line and f"{after:.3e}" in line and bad.label in line
    data = json.load(open(tmp_path / "c.json"))
    run = next(r for r in data["runs"] if r["regression"])
    assert run["errors"]["orientation"] == {"unit": "rad", "before": before, "after": after, "ratio": ratio}
    assert set(run["cost"]) == {"unit", "before", "after", "ratio", "change"}
    assert set(run["cost"]["before"]) == {"median", "min", "max", "repeats"}
    rows = list(csv.DictReader(open(tmp_path / "c.csv")))
    row = next(r for r in rows if r["label"] == bad.label and r["quantity"] == "orientation")
    assert float(row["before"]) == before and float(row["after"]) == after  # full precision


def test_options_are_in_the_labels_and_runs_in_one_store_are_apart(store, tmp_path, capsys):
    other = _copy(store, tmp_path / "other")
    # now a run A does not have, and B lacks one
    tamper(other, lambda r: replace(r, settings=replace(r.settings, options={"node": "ep"})))
    cmp = compare_stores(store, other)
    assert len(cmp.only_in_a) == 1 and len(cmp.only_in_b) == 1 and len(cmp.changes) == 3
    assert "node=ep" in to_json(cmp)["only_in_b"][0]["label"]
    assert main(["compare", store.path, other.path]) == 0  # nothing got worse
    out = capsys.readouterr().out
    assert "only in A (before): 1" in out and "only in B (after): 1" in out and "node=ep" in out
    assert "1 only in A, 1 only in B" in out
    assert main(["compare", store.path, other.path, "--only-changed"]) == 0
    out = capsys.readouterr().out  # only changes: the runs in one store are counted, not listed
    assert "only in A (before)" not in out and "only in B (after)" not in out and "node=ep" not in out
    assert "1 only in A, 1 only in B" in out


def test_cost_is_judged_against_both_spreads(store, tmp_path):
    """Twice the median is slower only when the spreads do not overlap; a regression only when asked."""
    def scaled(factor, spread):
        def change(r):
            m = r.cost.wall_s_median * factor
            return replace(r, cost=replace(r.cost, wall_s_median=m, wall_s_min=m / spread, wall_s_max=m * spread))
        return change

    base = _copy(store, tmp_path / "base")
    tamper(base, scaled(1.0, 1.1))
    noisy, slow = _copy(base, tmp_path / "noisy"), _copy(base, tmp_path / "slow")
    tamper(noisy, scaled(2.0, 3.0))  # the medians double, but the repeats scattered over x9
    tamper(slow, scaled(2.0, 1.1))
    (c,) = [c for c in compare_stores(base, noisy).changes if c.a.key == sorted(base.done_keys())[0]]
    assert c.cost_ratio == pytest.approx(2.0) and c.cost_change == "same" and not c.regression
    cmp = compare_stores(base, slow)
    (c,) = [c for c in cmp.changes if c.cost_change != "same"]
    assert c.cost_change == "slower" and c.change == "worse" and not cmp.regressed  # reported, not gating
    assert compare_stores(base, slow, cost_threshold=1.5).regressed
    assert not compare_stores(base, slow, cost_threshold=3.0).regressed


def test_different_machines_and_engine_versions_are_warned_about(store, tmp_path, capsys):
    other = _copy(store, tmp_path / "other")
    manifest = other.manifest()
    manifest["machine"] = {**manifest["machine"], "cpu": "Other CPU", "cores": 64}
    manifest["engines"] = {"reference": "9.9"}
    other.write_manifest(manifest)
    cmp = compare_stores(store, other)
    assert any("machines differ" in w and "cpu 'test' vs 'Other CPU'" in w and "cores 2 vs 64" in w
               for w in cmp.warnings)
    assert any(w == "engine versions differ: reference test -> 9.9" for w in cmp.warnings)
    main(["compare", store.path, other.path])
    assert "warning: engine versions differ: reference test -> 9.9" in capsys.readouterr().out


def test_a_changed_case_is_not_compared_unless_asked(store, tmp_path):
    other = _copy(store, tmp_path / "other")
    tamper(other, lambda r: replace(r, case_version="different", errors={q: (1.0, 1.0) for q in r.errors}))
    cmp = compare_stores(store, other)
    assert not cmp.regressed and len(cmp.not_compared) == 1 and "case version differs" in cmp.not_compared[0][2]
    assert compare_stores(store, other, across_versions=True).regressed


def test_a_run_that_now_diverges_is_a_regression(store, tmp_path):
    other = _copy(store, tmp_path / "other")
    tamper(other, lambda r: replace(r, status="diverged", judgement=replace(r.judgement, verdict="diverged"),
                                    message="non-finite state",
                                    errors={q: (math.nan, math.nan) for q in r.errors}))
    cmp = compare_stores(store, other)
    assert cmp.regressed and any("status ok -> diverged" in n for c in cmp.changes for n in c.notes)


def test_a_schema_1_store_compares_with_a_current_one(store, tmp_path, capsys):
    """Stores written before the schema was versioned (no verdicts) still compare, run by run."""
    import json
    import os

    old = _copy(store, tmp_path / "old")
    manifest = old.manifest()
    del manifest["schema_version"]
    old.write_manifest(manifest)
    for key in old.done_keys():
        path = os.path.join(old.rows_dir, f"{key}.json")
        row = json.load(open(path))
        for col in ("schema_version", "verdict", "verdict_reason", "provenance", "wall_s_repeats"):
            row.pop(col)
        json.dump(row, open(path, "w"))
    assert main(["compare", old.path, store.path]) == 0
    captured = capsys.readouterr()
    assert f"schemas 1 and {SCHEMA_VERSION}" in captured.err and "4 runs in both: 0 worse" in captured.out


def test_quick_stores_costs_are_single_samples_shown_not_judged(store, tmp_path, capsys):
    """Two stores timed once per run (``run --quick``: the manifest's timing): a cost that doubled is
    one sample against one, no spread to judge it by, so it is shown with a warning and never called
    slower, nor a regression even when a cost threshold is given."""
    from dalembert.harness.execute import QUICK

    def quick(s):
        manifest = s.manifest()
        manifest["timing"] = vars(QUICK)
        s.write_manifest(manifest)
        return s

    def once(factor):
        def change(r):
            m = r.cost.wall_s_median * factor
            return replace(r, cost=replace(r.cost, wall_s_median=m, wall_s_min=m, wall_s_max=m, repeats=1))
        return change

    before, after = quick(_copy(store, tmp_path / "before")), quick(_copy(store, tmp_path / "after"))
    tamper(before, once(1.0))
    tamper(after, once(2.0))
    cmp = compare_stores(before, after, cost_threshold=1.5)
    (c,) = [c for c in cmp.changes if c.a.key == sorted(before.done_keys())[0]]
    assert c.cost_ratio == pytest.approx(2.0) and c.cost_change == "unjudged" and c.change == "same"
    assert not cmp.regressed and cmp.stats["worse"] == 0 and cmp.stats["better"] == 0
    assert any("A (before) and B (after) were timed once per run" in w for w in cmp.warnings)
    assert main(["compare", before.path, after.path, "--cost-threshold", "1.5"]) == 0
    out = capsys.readouterr().out
    assert "warning: A (before) and B (after) were timed once per run (dalembert run --quick)" in out
    assert "one sample each: not judged" in out and "0 worse, 0 better" in out
    plain = _copy(store, tmp_path / "plain")  # the same samples in a store timed as by default: judged
    tamper(plain, once(1.0))
    slower = _copy(plain, tmp_path / "slower")
    tamper(slower, once(2.0))
    assert compare_stores(plain, slower, cost_threshold=1.5).regressed
