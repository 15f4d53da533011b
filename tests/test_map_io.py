"""What a map moves that it does not keep (``dalembert.harness.sent``): a worker told the store's choice builds,
pickles and sends no trajectory the store drops, and the store it leaves is the one the parent's own dropping
left; a search's rounds append their new probes to the manifest without serializing every known spec again."""

import io
import json
import os
from dataclasses import asdict, fields, replace

import numpy as np
import pytest

import dalembert.harness.pool as pool
import dalembert.harness.sent as sent_module
from dalembert.harness.cli import main
from dalembert.harness.dask import execute_group_isolated
from dalembert.harness.execute import QUICK, execute
from dalembert.harness.matrix import expand
from dalembert.harness.sent import Sent, told
from dalembert.record import Cost
from dalembert.reports.drawn import may_be_drawn
from dalembert.reports.drawn import DETAILED_VERSIONS
from dalembert.store import Store

BASE = ["--case", "pivoted_rod", "--engine", "reference", "--integrator", "rk4", "--param", "t_final=0.2", "--quick",
        "--jobs", "1"]
SWEEP = [*BASE, "--dt", "1e-2", "--param", "force=1,2,3,4,5"]  # 5 versions: past DETAILED_VERSIONS, never drawn
STEPS = [*BASE, "--integrator", "euler", "--dt", "1e-2,5e-3"]  # 1 version: drawn runs, and 2 dropped at the end
# The columns a run's timing or process sets (its cost, its pid): two runs of the same spec differ there
TIMED = {f.name for f in fields(Cost)} | {"provenance"}


def _run(out, args, monkeypatch, told_workers):
    """Run ``args`` into ``out``, the workers told the store's choice or (``told_workers`` False) not, as before
    ``harness.sent``: every trajectory sent, the parent dropping what the store does not keep. Returns the store
    and how many trajectories reached the parent."""
    sent = []

    def finish(store, record, npz, progress, counts):
        sent.append(npz is not None)
        return real_finish(store, record, npz, progress, counts)

    def untold(store, specs):
        told(store, specs)  # (the parent's own rule, as it was)
        return None

    real_finish = pool.finish
    with monkeypatch.context() as m:
        m.setattr(pool, "finish", finish)
        if not told_workers:
            m.setattr(sent_module, "told", untold)
        assert main(["run", *args, "--out", str(out)]) == 0
    return Store.open(out), sum(sent)


def _arrays(store, key):
    """Every array of run ``key``'s stored ``.npz`` (a pack's entry or its file)."""
    source = store.kept().source(key)
    with np.load(io.BytesIO(source) if isinstance(source, bytes) else source) as z:
        return {n: z[n] for n in z.files}


@pytest.mark.parametrize("keep, args, moved", [("none", SWEEP, 0), ("drawn", SWEEP, 0), ("drawn", STEPS, 4),
                                               ("all", SWEEP, 5)])
def test_a_store_keeps_the_same_rows_and_trajectories_whatever_the_workers_send(keep, args, moved, tmp_path,
                                                                               monkeypatch):
    """Each keep, the workers told it and not: the same rows column by column (but for timing and pid), the same
    trajectories kept (their arrays); told, a worker sends only what the store keeps (``moved``), untold every
    finished run's (the parent dropped the rest)."""
    args = [*args, "--trajectories", keep]
    before, sent_before = _run(tmp_path / "untold", args, monkeypatch, told_workers=False)
    after, sent_after = _run(tmp_path / "told", args, monkeypatch, told_workers=True)
    assert sent_before == len(before.done_keys()) and sent_after == moved
    rows_before, rows_after = before.rows(), after.rows()
    assert [r["key"] for r in rows_before] == [r["key"] for r in rows_after] and rows_after
    for a, b in zip(rows_before, rows_after):
        assert set(a) == set(b)
        for column in set(a) - TIMED:
            assert a[column] == b[column] or (a[column] != a[column] and b[column] != b[column]), (a["key"], column)
    assert sorted(os.listdir(before.traj_dir)) == sorted(os.listdir(after.traj_dir))
    kept = sorted(k for k in after.done_keys() if after.has_trajectory(k))
    assert kept == sorted(k for k in before.done_keys() if before.has_trajectory(k))
    for key in kept:
        x, y = _arrays(before, key), _arrays(after, key)
        assert x.keys() == y.keys() and all(np.array_equal(x[n], y[n], equal_nan=True) for n in x)
    assert len(kept) == {"none": 0, "all": 5}.get(keep, 0 if args[:len(SWEEP)] == SWEEP else 2)


def test_a_worker_that_sends_no_trajectory_builds_none_and_measures_the_same(monkeypatch):
    """``execute`` told ``none`` never builds the ``.npz`` (its builder fails the test if called) and its record's
    errors, drifts and checks are those computed when it is sent."""
    import dalembert.store

    (spec,), _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                        params={"t_final": 0.2})
    sent_record, npz = execute(spec, QUICK)
    assert npz is not None

    def never(traj):
        raise AssertionError("a trajectory the store drops was built")

    monkeypatch.setattr(dalembert.store, "trajectory_to_npz", never)
    record, none = execute(spec, QUICK, sent=Sent("none"))
    assert none is None and record.status == "ok"
    assert record.errors == sent_record.errors and record.drifts == sent_record.drifts
    assert record.checks == sent_record.checks and record.judgement == sent_record.judgement
    assert record.errors  # (measured: the trajectory was read in the worker)


def test_a_dask_task_sends_back_only_what_it_is_told():
    """A Dask task's process (``execute_group_isolated``, run here without a cluster) told ``none`` answers records
    with no trajectory, told nothing with every one."""
    specs, _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4"], dts=[1e-2, 5e-3],
                      params={"t_final": 0.2})
    told_none = execute_group_isolated([s.to_json() for s in specs], asdict(QUICK), [], 120.0, sent=Sent("none"))
    assert [r.status for r, _ in told_none] == ["ok", "ok"] and [n for _, n in told_none] == [None, None]
    untold = execute_group_isolated([s.to_json() for s in specs], asdict(QUICK), [], 120.0)
    assert all(isinstance(n, bytes) for _, n in untold)
    assert [r.errors for r, _ in told_none] == [r.errors for r, _ in untold]


def test_drawn_in_the_worker_is_the_parents_rule_on_a_few_versions_per_case():
    """``Sent.of`` keeps at most DETAILED_VERSIONS + 1 versions of a case (what ``may_be_drawn`` compares with) and
    answers as the parent's rule on the whole manifest: a case of 1 or DETAILED_VERSIONS versions is drawable, one
    of more is not (on an engine without a port)."""
    from dalembert.harness.truths import built_case

    many = [{"case": "pivoted_rod", "case_version": f"v{i}"} for i in range(1000)]
    few = [{"case": "free_top", "case_version": f"w{i}"} for i in range(DETAILED_VERSIONS)] * 3
    sent = Sent.of("drawn", many + few)
    assert len(sent.versions) == DETAILED_VERSIONS + 1 + DETAILED_VERSIONS
    (spec,), _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                        params={"t_final": 0.2})
    record, _ = execute(spec, QUICK)
    case_of = lambda name, version: built_case(name, dict(spec.params))[0]  # noqa: E731
    for specs in (many, few, [{"case": "pivoted_rod", "case_version": "v0"}]):
        for r in (record, replace(record, case="free_top")):
            assert Sent.of("drawn", specs).wants(r, case_of) == may_be_drawn(specs, case_of)(r)
    assert not Sent.of("drawn", many).wants(record, case_of)
    assert Sent.of("drawn", few).wants(replace(record, case="free_top"), case_of)
    assert Sent("all").wants(record, case_of) and not Sent("none").wants(record, case_of)
    with pytest.raises(ValueError, match=r"Sent.keep: 'some' is not a choice — use one of all, drawn, none"):
        Sent("some")


def test_a_search_round_appends_its_new_probes_serializing_only_them(tmp_path, monkeypatch):
    """``_search``'s rounds: each appends its probes not yet in the manifest (once, in order), the manifest on disk
    readable after each round; a spec is serialized once when first met, never again each round."""
    import dalembert.harness.commands.run as run_module
    import dalembert.harness.search as search_module

    specs, _ = expand(cases=["pivoted_rod"], engines=["reference"], integrators=["rk4", "euler"],
                      dts=[1e-2, 5e-3, 2.5e-3, 2e-3, 1e-3, 5e-4], params={"t_final": 0.2})
    first, rounds = specs[:3], [specs[:5], specs[3:8], specs[6:], specs[:12]]
    store = Store(tmp_path / "s").create({"specs": [s.to_json() for s in first], "searches": []})
    on_disk, dumped = [], []

    def search(initial, store_, run_round, resolution, said):
        for batch in rounds:
            run_round(batch)
            on_disk.append(Store.open(store_.path).manifest()["specs"])
        return []

    class Counting:
        @staticmethod
        def dumps(obj, **kwargs):
            dumped.append(obj)
            return json.dumps(obj, **kwargs)

    monkeypatch.setattr(search_module, "search", search)
    monkeypatch.setattr(run_module, "json", Counting)
    plan = {"first": [s.to_json() for s in first], "resolution": 1.5}
    assert run_module._search(store, store.manifest(), plan, lambda batch: []) == []
    expected = [s.to_json() for s in first]
    for batch, written in zip(rounds, on_disk):
        expected += [s.to_json() for s in batch if s.to_json() not in expected]
        assert written == expected
    assert len(dumped) == len(first) + sum(len(b) for b in rounds)  # the known ones once, each round's own
    assert Store.open(store.path).manifest()["specs"] == [s.to_json() for s in specs]
