"""The trajectories a store keeps (``dalembert.trajectory_store``): packs in layout 2, read back as written after a
crash at any point; ``--trajectories all|drawn|none``, kept by ``--resume``; ``drawn`` is exactly what the report
reads (``dalembert.reports.drawn``); every reader says when one was not kept."""

import os
import shutil
from dataclasses import replace

import numpy as np
import pytest

import dalembert.trajectory_store as trajectory_store
from dalembert.harness.cli import main
from dalembert.reports.drawn import drawn_keys, may_be_drawn
from dalembert.reports.render import build_report
from dalembert.store import Store, StoreError, TrajectoryNotKept
from dalembert.trajectory_store import MAGIC, PACK_SUFFIX, check_keep, default_keep, pack_entries
from stores import add_run, small_store

RUN = ["--case", "pivoted_rod", "--engine", "reference", "--integrator", "rk4", "--integrator", "euler",
       "--dt", "1e-2,5e-3", "--param", "t_final=0.5", "--quick", "--jobs", "1"]


@pytest.fixture(scope="module")
def source(tmp_path_factory):
    """A real run of each of two cases and two integrators at two steps (8 runs, a trajectory each)."""
    return small_store(tmp_path_factory.mktemp("source") / "s", t_final=0.5)


def _copy(source, path, layout, keep="all", n=None):
    """A new store of ``layout`` keeping ``keep``, holding ``source``'s runs (or ``n`` copies of its first) as the
    matrix's parent writes them: a trajectory then a row each. Returns it and ``{key: the .npz written}``."""
    store = Store(path).create({**source.manifest(), "trajectories": keep}, layout=layout)
    for d in ("cases", "truth"):
        shutil.copytree(os.path.join(source.path, d), os.path.join(store.path, d), dirs_exist_ok=True)
    records = source.records() if n is None else [replace(source.records()[0], key=f"run{i:04d}") for i in range(n)]
    written = {}
    for r in records:
        with open(os.path.join(source.path, (source.records()[0] if n is not None else r).trajectory), "rb") as fh:
            written[r.key] = fh.read()
        store.write_record(r, written[r.key])
    return store, written


def _pack(store):
    [name] = [n for n in os.listdir(store.traj_dir) if n.endswith(PACK_SUFFIX)]
    return os.path.join(store.traj_dir, name)


def test_layout_2_packs_every_trajectory_into_one_file_read_back_as_written(source, tmp_path):
    files, _ = _copy(source, tmp_path / "files", 1)
    packed, _ = _copy(source, tmp_path / "packed", 2)
    assert sorted(os.listdir(files.traj_dir)) == sorted(f"{k}.npz" for k in files.done_keys())
    assert len(os.listdir(packed.traj_dir)) == 1  # one pack for the writing process, not a file per run
    reopened = Store.open(packed.path)
    for r in reopened.records():
        assert r.trajectory == "trajectories/" + os.path.basename(_pack(packed))
        a, b = reopened.trajectory(r.key), files.trajectory(r.key)
        assert list(a.bodies) == list(b.bodies) and list(a.joints) == list(b.joints)
        for name in a.bodies:
            for f in ("position", "quaternion", "velocity", "angular_velocity"):
                np.testing.assert_array_equal(getattr(a.bodies[name], f), getattr(b.bodies[name], f))
        np.testing.assert_array_equal(a.t, b.t)


def test_a_torn_last_entry_is_ignored_and_its_run_redone_reads_as_the_last_written(source, tmp_path):
    store, written = _copy(source, tmp_path / "s", 2, n=3)
    path = _pack(store)
    entries = pack_entries(path)
    assert [k for k, _, _ in entries] == ["run0000", "run0001", "run0002"]
    with open(path, "rb") as fh:
        data = fh.read()
    for cut in (entries[2][1] - 5, entries[2][1] + 100, len(data) - 1):  # in the head, the key's end, the .npz
        with open(path, "wb") as fh:
            fh.write(data[:cut])
        fresh = Store.open(store.path)
        assert [k for k, _, _ in pack_entries(path)] == ["run0000", "run0001"]
        assert fresh.has_trajectory("run0001") and not fresh.has_trajectory("run0002")
        with pytest.raises(StoreError, match="run0002.npz: missing"):
            fresh.trajectory("run0002")
    # the run redone (by --resume: a new process, a new pack) is read from its new entry
    redo = Store.open(store.path)
    redo.kept()._writer._pid = None  # (as a new process would)
    redo.write_record(replace(source.records()[0], key="run0001"), written["run0001"])
    assert len(os.listdir(store.traj_dir)) == 2
    assert Store.open(store.path).kept().source("run0001") == written["run0001"]


def test_a_damaged_pack_is_named_with_its_offset(source, tmp_path):
    store, _ = _copy(source, tmp_path / "s", 2, n=2)
    path = _pack(store)
    with open(path, "r+b") as fh:
        start = pack_entries(path)[1][1] - len("run0001") - 16
        fh.seek(start)
        assert fh.read(4) == MAGIC
        fh.seek(start)
        fh.write(b"XXXX")
    with pytest.raises(StoreError, match=f"{path} offset {start}: not a trajectory entry dalembert wrote"):
        Store.open(store.path).trajectory("run0001")


@pytest.mark.parametrize("layout", [1, 2])
def test_keeping_some_drops_the_rest_and_says_so_where_one_is_read(source, tmp_path, layout):
    store, written = _copy(source, tmp_path / "s", layout, keep="drawn", n=4)
    assert store.keep_trajectories({"run0001", "run0003"}) == 2
    fresh = Store.open(store.path)
    assert [fresh.has_trajectory(f"run{i:04d}") for i in range(4)] == [False, True, False, True]
    assert fresh.kept().source("run0003") == written["run0003"] or layout == 1
    with pytest.raises(TrajectoryNotKept, match="run run0002: its trajectory was not kept \\(the store keeps only "
                                                "the trajectories its report draws: run.trajectories = drawn\\) — "
                                                "rerun it into a new store with `dalembert run --trajectories all`"):
        fresh.trajectory("run0002")
    assert len([n for n in os.listdir(store.traj_dir) if n.endswith((".npz", PACK_SUFFIX))]) == (2 if layout == 1 else 1)


def test_the_choice_is_checked_and_defaults_by_the_matrix_size():
    assert [check_keep(v) for v in ("all", "drawn", "none", None)] == ["all", "drawn", "none", None]
    with pytest.raises(ValueError, match="run.trajectories: 'foo' is not a choice — use all"):
        check_keep("foo")
    assert default_keep(2000, 2000) == "all" and default_keep(2001, 2000) == "drawn"


def test_a_bad_choice_is_refused_before_anything_runs(tmp_path, capsys):
    assert main(["run", *RUN, "--trajectories", "foo", "--out", str(tmp_path / "s")]) == 2
    assert "run.trajectories: 'foo' is not a choice — use all (every run's trajectory), drawn" in capsys.readouterr().err
    assert not os.path.exists(tmp_path / "s")


def test_none_keeps_none_and_every_reader_says_so(tmp_path, capsys):
    out = tmp_path / "s"
    assert main(["run", *RUN, "--trajectories", "none", "--out", str(out)]) == 0
    store = Store.open(out)
    assert store.manifest()["trajectories"] == "none" and os.listdir(store.traj_dir) == []
    assert all(r.ok and r.trajectory == "" for r in store.records())
    key = store.records()[0].key
    capsys.readouterr()
    assert main(["repro", str(out), "--key", key]) == 2
    assert f"--key: run {key}: its trajectory was not kept (the store keeps no trajectory" in capsys.readouterr().err
    assert main(["export", str(out), "--key", key, "--csv", str(tmp_path / "x.csv")]) == 2
    assert "its trajectory was not kept" in capsys.readouterr().err
    assert main(["report", str(out)]) == 0
    with open(out / "report_details.md") as fh:
        assert "No figure against time: the store kept no run's trajectory (run.trajectories = none" in fh.read()
    # --resume keeps the choice, and refuses another before anything runs
    assert main(["run", "--resume", str(out), "--trajectories", "none"]) == 0
    assert main(["run", "--resume", str(out), "--trajectories", "all"]) == 2
    assert ("run.trajectories: 'all', and the store " + str(out) + " keeps 'none' — drop --trajectories"
            in capsys.readouterr().err)


def _reads(store, tmp_path):
    """The keys of the trajectories ``build_report`` reads from ``store``."""
    read, real = set(), store.trajectory
    store.trajectory = lambda key: (read.add(key), real(key))[1]
    build_report(store, str(tmp_path))
    return read


def test_drawn_is_what_the_report_reads(source, tmp_path):
    store, _ = _copy(source, tmp_path / "s", 1)
    first = store.records()[0]
    add_run(store, "diverged", nan_from=0.2, verdict="diverged", verdict_reason="not finite")
    add_run(store, "drifts", verdict="drifts", drifts={**first.drifts, "energy": 1.0})
    add_run(store, "worse", errors={k: (v[0] * 10, v[1]) for k, v in first.errors.items()}, verdict="stable",
            drifts={k: 0.0 for k in first.drifts})  # beside the run it is made from, at its step: not the best
    add_run(store, "failed", status="failed", message="stopped")
    read = _reads(Store.open(store.path), tmp_path)
    drawn = drawn_keys(Store.open(store.path))
    assert read == drawn
    assert {"diverged", "drifts"} <= drawn and not {"worse", "failed"} & drawn
    assert len(drawn) < len(store.done_keys())


def test_a_matrix_that_keeps_drawn_drops_the_rest_when_it_ends_and_reports_the_same(tmp_path, capsys):
    everything, drawn = tmp_path / "all", tmp_path / "drawn"
    assert main(["run", *RUN, "--out", str(everything)]) == 0
    assert main(["run", *RUN, "--trajectories", "drawn", "--out", str(drawn)]) == 0
    assert "kept only the trajectories the report draws (--trajectories drawn): 2 dropped" in capsys.readouterr().err
    store = Store.open(drawn)
    kept = {k for k in store.done_keys() if store.has_trajectory(k)}
    assert kept == drawn_keys(store) and len(kept) == len(store.done_keys()) - 2
    assert sorted(os.listdir(store.traj_dir)) == sorted(f"{k}.npz" for k in kept)
    assert main(["report", str(drawn)]) == 0
    # the same runs with every trajectory and with the drawn ones only: the same report
    pruned = tmp_path / "pruned"
    shutil.copytree(everything, pruned)
    manifest = Store.open(pruned).manifest()
    Store(pruned).write_manifest({**manifest, "trajectories": "drawn"})
    assert Store.open(pruned).keep_trajectories(drawn_keys(Store.open(pruned))) == 2
    assert main(["report", str(pruned)]) == 0 and main(["report", str(everything)]) == 0
    for name in ("report.md", "report_details.md"):
        with open(pruned / name) as a, open(everything / name) as b:
            assert a.read().replace(str(pruned), str(everything)) == b.read()
    dropped = sorted(store.done_keys() - kept)[0]
    assert main(["export", str(drawn), "--key", dropped, "--csv", str(tmp_path / "x.csv")]) == 2
    assert f"run {dropped}: its trajectory was not kept" in capsys.readouterr().err


SWEEP = ["--case", "pivoted_rod", "--engine", "reference", "--integrator", "rk4", "--dt", "1e-2", "--param",
         "t_final=0.2", "--param", "force=1,2,3,4,5", "--quick", "--jobs", "1"]  # 5 versions: one note in the report


def test_a_sweep_past_the_detailed_versions_writes_none_of_its_trajectories(tmp_path, capsys):
    everything, drawn = tmp_path / "all", tmp_path / "drawn"
    assert main(["run", *SWEEP, "--out", str(everything)]) == 0
    assert main(["run", *SWEEP, "--trajectories", "drawn", "--out", str(drawn)]) == 0
    store = Store.open(drawn)
    assert len(store.done_keys()) == 5 and all(r.ok and r.trajectory == "" for r in store.records())
    assert os.listdir(store.traj_dir) == []
    assert "dropped" not in capsys.readouterr().err  # nothing written, nothing to drop
    # what the report of the same sweep reads, kept all, is nothing may_be_drawn refuses
    source = Store.open(everything)
    test = may_be_drawn(source.manifest()["specs"], source.case)
    assert not any(test(r) for r in source.records())
    assert _reads(source, tmp_path / "report") == set()


def test_export_all_leaves_out_the_runs_not_kept_and_counts_them(source, tmp_path, capsys):
    store, _ = _copy(source, tmp_path / "s", 2, keep="drawn")
    keep = sorted(store.done_keys())[:3]
    store.keep_trajectories(keep)
    assert main(["export", str(store.path), "--all", "--csv", str(tmp_path / "x.csv")]) == 0
    out = capsys.readouterr().out
    assert "wrote" in out and ": 3 run(s)" in out
    assert "(5 matching run(s) whose trajectory the store did not keep: run.trajectories = drawn)" in out
    with open(tmp_path / "x.csv") as fh:
        assert {line.split(",")[0] for line in fh.readlines()[1:]} == set(keep)


def test_a_reader_finds_entries_through_the_packs_index_and_scans_only_what_it_does_not_cover(source, tmp_path,
                                                                                              monkeypatch):
    store, written = _copy(source, tmp_path / "s", 2, n=3)
    store.write_table()  # the end of a batch: the pack synced, its index written
    index = _pack(store)[:-len(PACK_SUFFIX)] + ".trajidx"
    assert os.path.exists(index)
    first = store.records()[0]
    store.write_record(replace(first, key="later"), written["run0000"])  # after the index: found by a scan
    scanned = []
    real = trajectory_store.pack_entries
    monkeypatch.setattr(trajectory_store, "pack_entries", lambda path, start=0: scanned.append(start) or real(path, start))
    fresh = Store.open(store.path)
    assert [fresh.kept().source(k) for k in ("run0001", "later")] == [written["run0001"], written["run0000"]]
    assert scanned == [os.path.getsize(_pack(store)) - len(written["run0000"]) - len("later") - 16]
    with open(index, "wb") as fh:  # an index that does not read: the pack is scanned whole
        fh.write(b"not an index")
    scanned.clear()
    assert Store.open(store.path).kept().source("run0002") == written["run0002"] and scanned == [0]
