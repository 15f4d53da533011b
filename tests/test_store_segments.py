"""The store's layout 2: rows appended to segments, read back exactly as written, as rows, records and a
table; a torn last line (a crash mid-write) is no run and ``--resume`` redoes it; damage is named by file
and line; a store of layout 1 (``rows/*.json``, or a manifest from before layouts) reads as before."""

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import fields, replace

import numpy as np
import pandas as pd
import pytest

import dalembert.store as store_module
from dalembert import runs_table
from dalembert.harness.cli import main
from dalembert.record import RunRecord
from dalembert.segments import segment_names
from dalembert.store import FILES_UP_TO, Store, StoreError
from stores import plain, segmented, small_store


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Real runs of two cases (their rows have different error and drift columns), in layout 1."""
    store = small_store(tmp_path_factory.mktemp("files") / "s", cases=("pivoted_rod", "free_top"),
                        integrators=("rk4",), dts=(1e-2, 5e-3))
    assert store.layout() == 1
    return store






def _same_records(got, want):
    assert [r.key for r in got] == [r.key for r in want]
    for a, b in zip(got, want):
        for f in fields(RunRecord):
            assert plain(getattr(a, f.name)) == plain(getattr(b, f.name)), (a.key, f.name)


def test_rows_read_back_field_by_field_as_written(files, tmp_path):
    seg = segmented(files, tmp_path / "seg")
    assert seg.layout() == 2 and not os.path.exists(seg.rows_dir) and len(segment_names(seg.segments_dir)) == 1
    assert len({frozenset(r) for r in files.rows()}) > 1  # rows of different columns: none may gain another's
    assert Store(seg.path).rows() == files.rows()
    _same_records(Store(seg.path).records(), files.records())
    assert Store(seg.path).done_keys() == files.done_keys()


def _same_table(got, want):
    assert set(got.columns) == set(want.columns)
    assert list(got["key"]) == list(want["key"])
    for col in want.columns:
        for a, b in zip(got[col], want[col]):
            assert (pd.isna(a) and pd.isna(b)) or a == b, (col, a, b)


def test_the_table_is_the_rows_as_columns_before_and_after_each_rebuild(files, tmp_path):
    records = files.records()
    seg = segmented(files, tmp_path / "seg", records[:3])
    want = pd.DataFrame(files.rows())
    _same_table(seg.table(), want.iloc[:3])  # from the segment alone
    _same_table(seg.write_table(), want.iloc[:3])
    assert os.path.exists(os.path.join(seg.path, "runs.parquet"))
    for r in records[3:]:  # rows appended after a rebuild: the table covers the first ones, the rest are read after
        seg.write_record(r)
    _same_table(Store(seg.path).table(), want)
    _same_table(seg.write_table(), want)
    _same_table(pd.read_parquet(os.path.join(seg.path, "runs.parquet")), want)


def test_the_table_is_sorted_by_key_whatever_order_the_rows_came_in(files, tmp_path):
    """Rows written in reverse key order (a matrix's workers finish in any order), read from the segment alone and
    then from a rebuilt table with the rest appended after it: the table is in key order either way; a run stored
    twice keeps both rows, in the order written (the sort is stable)."""
    import pyarrow as pa

    records = sorted(files.records(), key=lambda r: r.key, reverse=True)
    seg = segmented(files, tmp_path / "seg", records[:3])
    assert list(seg.table()["key"]) == sorted(r.key for r in records[:3])
    seg.write_table()
    for r in records[3:]:
        seg.write_record(r)
    assert list(Store(seg.path).table()["key"]) == sorted(r.key for r in records)
    twice = pa.table({"key": ["b", "a", "b", "c"], "n": [1, 2, 3, 4]})
    assert runs_table._by_key(twice).to_pydict() == {"key": ["a", "b", "b", "c"], "n": [2, 1, 3, 4]}


def test_rows_longer_than_the_json_readers_block_read_line_by_line_the_same(files, tmp_path, monkeypatch):
    monkeypatch.setattr(runs_table, "JSON_BLOCK_BYTES", 1000)  # every row of these runs is longer (2-3 kB)
    seg = segmented(files, tmp_path / "seg")
    _same_table(seg.write_table(), pd.DataFrame(files.rows()))


def _segment(store):
    (name,) = segment_names(store.segments_dir)
    return os.path.join(store.segments_dir, name)


def test_a_torn_last_line_is_no_run_and_is_redone(files, tmp_path):
    records = files.records()
    seg = segmented(files, tmp_path / "seg")
    path = _segment(seg)
    with open(path, "rb") as fh:
        lines = fh.read().splitlines(keepends=True)
    with open(path, "wb") as fh:  # the crash: the last row's write cut short halfway
        fh.write(b"".join(lines[:-1]) + lines[-1][:len(lines[-1]) // 2])
    torn = json.loads(lines[-1])["key"]
    again = Store(seg.path)
    assert again.done_keys() == files.done_keys() - {torn}
    assert [r["key"] for r in again.rows()] == sorted(files.done_keys() - {torn})
    assert torn not in set(again.table()["key"])
    (redo,) = [r for r in records if r.key == torn]
    again.write_record(redo)  # as --resume does: in a segment of its own, never after the torn line
    assert len(segment_names(seg.segments_dir)) == 2
    _same_records(Store(seg.path).records(), records)
    _same_table(Store(seg.path).write_table(), pd.DataFrame(files.rows()))


WRITER = """
import sys
import time
from dataclasses import replace
from dalembert.store import Store
source, out = Store(sys.argv[1]), Store(sys.argv[2])
records = source.records()
i = 0
while True:  # until killed
    r = records[i % len(records)]
    out.write_record(replace(r, key=f"{r.key}-{i:07d}"))
    i += 1
"""


def test_a_writer_killed_at_any_point_leaves_every_complete_row(files, tmp_path):
    seg = segmented(files, tmp_path / "seg", [])
    proc = subprocess.Popen([sys.executable, "-c", WRITER, files.path, seg.path])
    try:
        while proc.poll() is None and not (segment_names(seg.segments_dir)
                                           and os.path.getsize(_segment(seg)) > 200_000):
            time.sleep(0.01)
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    originals = {r.key: r for r in files.records()}
    got = Store(seg.path).records()
    assert len(got) > 10 and Store(seg.path).done_keys() == {r.key for r in got}
    _same_records(got, [replace(originals[r.key.rsplit("-", 1)[0]], key=r.key) for r in got])
    assert len(Store(seg.path).table()) == len(got)


def test_a_write_the_disk_cuts_short_leaves_a_torn_line_and_the_next_row_a_new_segment(files, tmp_path,
                                                                                      monkeypatch):
    records = files.records()
    seg = segmented(files, tmp_path / "seg", records[:2])
    write = os.write

    def full(fd, data):  # the disk fills halfway through the line
        monkeypatch.setattr(os, "write", write)
        write(fd, bytes(data[:len(data) // 2]))
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(os, "write", full)
    with pytest.raises(OSError, match="No space left"):
        seg.write_record(records[2])
    assert Store(seg.path).done_keys() == {r.key for r in records[:2]}
    for r in records[2:]:  # the disk freed: written after, in a segment of their own
        seg.write_record(r)
    assert len(segment_names(seg.segments_dir)) == 2
    _same_records(Store(seg.path).records(), records)


def test_a_damaged_line_is_named_with_its_file_and_line(files, tmp_path):
    seg = segmented(files, tmp_path / "seg")
    path = _segment(seg)
    with open(path, "rb") as fh:
        lines = fh.read().splitlines(keepends=True)
    for bad, phrase in ((b'{"key": "x", "status\n', "cannot be read as a stored run"),
                        (b'[1, 2]\n', "not a run dalembert wrote"),
                        (lines[0], "is stored twice")):
        with open(path, "wb") as fh:
            fh.write(b"".join([lines[0], bad, *lines[2:]]))
        for read in (Store(seg.path).rows, Store(seg.path).records, Store(seg.path).table_records):
            with pytest.raises(StoreError, match=rf"{path} line 2: .*{phrase}"):
                read()
    with open(path, "wb") as fh:
        fh.write(b"".join([lines[0], b'{"key": "x", "status\n', *lines[2:]]))
    with pytest.raises(StoreError, match=rf"{path} line 2: cannot be read as a stored run .* --resume"):
        Store(seg.path).table()


def test_a_table_that_covers_more_than_its_segments_is_refused(files, tmp_path):
    seg = segmented(files, tmp_path / "seg")
    seg.write_table()
    path = _segment(seg)
    with open(path, "rb") as fh:
        data = fh.read()
    with open(path, "wb") as fh:
        fh.write(data[:data.index(b"\n") + 1])
    with pytest.raises(StoreError, match="runs.parquet: covers .* bytes of segments/.*, which holds"):
        Store(seg.path).table()
    os.remove(path)
    with pytest.raises(StoreError, match="runs.parquet: covers segments/.*, which is missing"):
        Store(seg.path).table()


def test_the_layout_is_the_manifests_and_a_store_from_before_layouts_reads_as_files(files, tmp_path):
    assert Store(tmp_path / "a").create({"specs": [{}] * FILES_UP_TO}).layout() == 1
    assert Store(tmp_path / "b").create({"specs": [{}] * (FILES_UP_TO + 1)}).layout() == 2
    assert json.load(open(tmp_path / "b" / "manifest.json"))["store_layout"] == 2
    with pytest.raises(ValueError, match="layout: unknown store layout 3 — use one of"):
        Store(tmp_path / "c").create({"specs": []}, layout=3)
    old = tmp_path / "old"
    shutil.copytree(files.path, old)
    manifest = json.load(open(old / "manifest.json"))
    del manifest["store_layout"]
    json.dump(manifest, open(old / "manifest.json", "w"))
    assert Store(old).layout() == 1 and Store(old).rows() == files.rows()
    manifest["store_layout"] = 9
    json.dump(manifest, open(old / "manifest.json", "w"))
    with pytest.raises(StoreError, match="written in store layout 9, and this dalembert reads layouts 1 and 2"):
        Store(old).rows()


RUN = ["--case", "free_top", "--engine", "reference", "--integrator", "rk4", "--integrator", "euler", "--dt", "1e-2",
       "--param", "t_final=0.5", "--quick", "--jobs", "1"]


def test_a_matrix_in_segments_runs_reports_and_resumes_after_a_crash(tmp_path, monkeypatch):
    assert main(["run", *RUN, "--out", str(tmp_path / "files")]) == 0
    monkeypatch.setattr(store_module, "FILES_UP_TO", 0)  # a matrix "past" the limit: its store takes layout 2
    out = tmp_path / "seg"
    assert main(["run", *RUN, "--out", str(out)]) == 0
    store, files = Store(out), Store(tmp_path / "files")
    assert store.layout() == 2 and os.path.exists(out / "runs.parquet")
    numbers = ("key", "status", "errors", "drifts", "growths", "checks", "judgement")
    assert [[plain(getattr(r, n)) for n in numbers] for r in store.records()] == \
        [[plain(getattr(r, n)) for n in numbers] for r in files.records()]
    # the trajectories in a pack (its name in the row), read back as the files store's
    assert all(r.trajectory.startswith("trajectories/") and r.trajectory.endswith(".trajpack") for r in store.records())
    for key in files.done_keys():
        np.testing.assert_array_equal(store.trajectory(key).bodies["top"].quaternion,
                                      files.trajectory(key).bodies["top"].quaternion)
    assert main(["report", str(out)]) == 0
    path = _segment(store)
    with open(path, "rb") as fh:
        data = fh.read()
    os.remove(out / "runs.parquet")  # killed before the matrix's end: no table yet ...
    with open(path, "wb") as fh:  # ... while writing the second row
        fh.write(data[:data.index(b"\n") + 20])
    assert len(Store(out).done_keys()) == 1
    assert main(["run", "--resume", str(out)]) == 0
    assert len(segment_names(store.segments_dir)) == 2
    assert [[plain(getattr(r, n)) for n in numbers] for r in Store(out).records()] == \
        [[plain(getattr(r, n)) for n in numbers] for r in files.records()]
    assert list(Store(out).table()["key"]) == sorted(files.done_keys())
