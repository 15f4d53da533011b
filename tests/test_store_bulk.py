"""A store read in bulk: records from its table (``Store.table_records``, what the report reads), the keys stored
from its table and the lines since (``Store.done_keys``), and a column whose type differs between rows kept in
``runs.parquet`` in its widest type (both layouts)."""

import json
import math
import os
import shutil
from dataclasses import fields, replace

import pyarrow.parquet as pq
import pytest

from dalembert import runs_table
from dalembert.record import RunRecord, SchemaError
from dalembert.segments import segment_names
from dalembert.store import Store, StoreError
from stores import plain, segmented, small_store


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Real runs of two cases (different error and drift columns), one of them made not finite (its metrics NaN,
    stored as null), in layout 1."""
    store = small_store(tmp_path_factory.mktemp("files") / "s", cases=("pivoted_rod", "free_top"),
                        integrators=("rk4",), dts=(1e-2, 5e-3))
    r = store.records()[0]
    nan = float("nan")
    store.write_record(replace(r, key=r.key + "-diverged", status="diverged", message="not finite at t = 0.5 s",
                               errors={q: (nan, nan) for q in r.errors}, drifts={n: nan for n in r.drifts},
                               t_diverged=0.5))
    return store






# The metric dicts, whose null entries a table reads as absent (``records_from_table``'s notes).
METRICS = ("errors", "drifts", "drift_rates", "growths", "checks")


def _measured(record):
    """``record`` as the table keeps it: each metric stored as null (NaN; an error's max NaN) left out."""
    def kept(value):
        v = value[0] if isinstance(value, tuple) else value
        return not (isinstance(v, float) and math.isnan(v))

    return replace(record, **{m: {k: v for k, v in getattr(record, m).items() if kept(v)} for m in METRICS})


def _same_records(got, want):
    assert [r.key for r in got] == [r.key for r in want]
    for a, b in zip(got, want):
        for f in fields(RunRecord):
            assert plain(getattr(a, f.name)) == plain(getattr(b, f.name)), (a.key, f.name)


def test_records_read_from_the_table_are_the_records_written(files, tmp_path):
    records = files.records()
    assert any(not r.errors or any(math.isnan(mx) for mx, _ in r.errors.values()) for r in records)
    want = [_measured(r) for r in records]
    assert any(len(w.errors) < len(r.errors) for w, r in zip(want, records))  # the rule is exercised
    seg = segmented(files, tmp_path / "seg", records[:3])
    _same_records(Store(seg.path).table_records(), want[:3])  # from the segment alone
    seg.write_table()
    for r in records[3:]:  # from runs.parquet and the lines appended since
        seg.write_record(r)
    _same_records(Store(seg.path).table_records(), want)
    seg.write_table()
    _same_records(Store(seg.path).table_records(), want)
    _same_records(files.table_records(), records)  # layout 1: the rows as written


def test_a_row_of_another_schema_is_refused_in_bulk(files, tmp_path):
    seg = segmented(files, tmp_path / "seg", files.records()[:2])
    seg.write_record(replace(files.records()[2], schema_version=99))
    with pytest.raises(SchemaError, match="schema 99"):
        Store(seg.path).table_records()


def test_a_name_outside_the_store_is_refused_in_bulk(files, tmp_path):
    seg = segmented(files, tmp_path / "seg", files.records()[:2])
    seg.write_record(replace(files.records()[2], case="../outside"))
    with pytest.raises(StoreError, match="case '../outside' is not a file name"):
        Store(seg.path).table_records()


# What a record derives from its fields (``record._cached``): a record read in bulk has them made already.
DERIVED = ("ok", "sweep_label", "options_label", "options_text", "cost_per_sim_s")


def test_records_read_in_bulk_derive_what_a_record_made_alone_derives(files, tmp_path):
    records = files.records()
    options = [replace(r, key=f"{r.key}-{i}", settings=replace(r.settings, options=o))
               for i, (r, o) in enumerate(zip(records, ({"solver": "newton", "tolerance": 1.23456789e-7}, {"b": 2})))]
    seg = segmented(files, tmp_path / "seg", records + options)
    got = Store(seg.path).table_records()
    assert {r.options_label for r in got} >= {"solver=newton tolerance=1.23456789e-07", "b=2"}
    assert {r.options_text for r in got} >= {"solver=newton tolerance=1.235e-07"} and not all(r.ok for r in got)
    for r in got:
        alone = replace(r)  # (made by its ``__init__``: its derived values made on reading them)
        assert [plain(getattr(r, d)) for d in DERIVED] == [plain(getattr(alone, d)) for d in DERIVED], r.key
        # at most one derived value kept in a record's own dict (``record.py``: so that records' dicts share keys)
        assert len(vars(r)) <= len(fields(RunRecord)) + 1 and len(vars(alone)) <= len(fields(RunRecord)) + 1


def test_a_row_of_an_unknown_status_is_refused_in_bulk(files, tmp_path):
    seg = segmented(files, tmp_path / "seg", files.records()[:2])
    bad = replace(files.records()[2])
    object.__setattr__(bad, "status", "lost")  # (a row no dalembert wrote)
    seg.write_record(bad)
    with pytest.raises(StoreError, match="status: unknown 'lost'"):
        Store(seg.path).table_records()


def _segment_keys_alone(store):
    """The keys as the segments alone give them (no table)."""
    from dalembert.segments import segment_keys

    return {k for name in segment_names(store.segments_dir)
            for k in segment_keys(os.path.join(store.segments_dir, name)) if k is not None}


def test_the_keys_stored_come_from_the_table_and_the_lines_since(files, tmp_path, monkeypatch):
    records = files.records()
    seg = segmented(files, tmp_path / "seg", records[:3])
    seg.write_table()
    for r in records[3:]:
        seg.write_record(r)
    with open(os.path.join(seg.segments_dir, seg._segment.name), "ab") as fh:
        fh.write(b'{"key": "torn')  # a torn last line: no run
    keys = {r.key for r in records}
    assert Store(seg.path).done_keys() == keys == _segment_keys_alone(seg)
    # the table's rows are not read again from their lines: only the ones after what it covers
    read = []
    monkeypatch.setattr(runs_table, "line_key", lambda line: read.append(line) or json.loads(line)["key"])
    assert Store(seg.path).done_keys() == keys and len(read) == len(records) - 3


def test_the_keys_stored_pass_over_a_damaged_table(files, tmp_path):
    seg = segmented(files, tmp_path / "seg", files.records())
    seg.write_table()
    with open(os.path.join(seg.path, "runs.parquet"), "wb") as fh:
        fh.write(b"not a table")
    assert Store(seg.path).done_keys() == {r.key for r in files.records()}


def _mixed(records):
    """``records`` whose first two give case parameter ``p`` as a number and as a vector (stored as JSON text)."""
    out = [replace(r, params={**r.params, "p": 2}) for r in records[:1]]
    out += [replace(r, params={**r.params, "p": (1.0, 2.0)}) for r in records[1:2]]
    return out + list(records[2:])


@pytest.mark.parametrize("split", [False, True])
def test_a_column_of_two_types_is_kept_in_its_widest_in_layout_2(files, tmp_path, split):
    records = _mixed(files.records())
    if split:  # the number in the table, the text in a line after it: two tables of two types concatenated
        seg = segmented(files, tmp_path / "seg", records[:1] + records[2:])
        seg.write_table()
        seg.write_record(records[1])
    else:  # both in one segment: Arrow's JSON reader refuses it, the lines are read one by one
        seg = segmented(files, tmp_path / "seg", records)
    table = Store(seg.path).write_table()
    by_key = dict(zip(table["key"], table["param_p"]))
    assert by_key[records[0].key] == "2" and by_key[records[1].key] == "[1.0, 2.0]"
    assert pq.read_table(os.path.join(seg.path, "runs.parquet")).column("param_p").type == "string"
    got = {r.key: r.params.get("p") for r in Store(seg.path).table_records()}
    assert got[records[0].key] == 2 and got[records[1].key] == (1.0, 2.0)  # the records read their params as given


def test_a_column_of_two_types_is_kept_in_its_widest_in_layout_1(files, tmp_path):
    path = tmp_path / "files"
    shutil.copytree(files.path, path)
    store = Store(str(path))
    for r in _mixed(store.records())[:2]:
        store.write_record(r)
    store.write_table()
    table = pq.read_table(os.path.join(store.path, "runs.parquet")).to_pydict()
    assert sorted(v for v in table["param_p"] if v is not None) == ["2", "[1.0, 2.0]"]


def test_widest_types():
    assert runs_table.widest([1, None, 2]) == [1, None, 2]
    assert runs_table.widest([1, None, 2.5]) == [1.0, None, 2.5]
    assert runs_table.widest([1, "[1, 2]", True, None]) == ["1", "[1, 2]", "true", None]


def test_a_matrix_outcome_reads_its_counts_and_failing_runs_from_the_table(files, tmp_path):
    from dalembert.harness.commands.run import Outcome
    from dalembert.judge import Judgement
    from dalembert.stored_runs import StoredRuns

    records = files.records()
    beyond = Judgement(beyond=("orientation",), verdict="stable", reason="", within_tolerance=False)
    unmeasured = Judgement(beyond=(), verdict="stable", reason="", within_tolerance=None,
                           not_measured=("reaction_force",))
    a, b, c = [r for r in records if r.ok][:3]
    changes = {a.key: dict(judgement=beyond), b.key: dict(judgement=unmeasured),
               c.key: dict(status="failed", message="an error")}
    records = [replace(r, **changes.get(r.key, {})) for r in records]
    seg = segmented(files, tmp_path / "seg", records)
    runs = StoredRuns(Store(seg.path))
    lazy, listed = (Outcome(seg, rs, [], strict="tolerance") for rs in (runs, Store(seg.path).table_records()))
    assert runs._records is None  # nothing read as records yet
    assert lazy.statuses == listed.statuses and (lazy.statuses["failed"], lazy.statuses["diverged"]) == (1, 1)
    for kind in ("bad", "beyond", "not_measured", "failing"):  # what `dalembert run` says: counts, the first one
        got, want = getattr(lazy, kind), getattr(listed, kind)
        assert len(got) == len(want) > 0 and got[0].key in {r.key for r in want}, kind
        assert got._records is None, kind  # its count and first run read no record of the others
        assert sorted(r.key for r in got) == sorted(r.key for r in want), kind
        assert got[0].key == next(iter(got)).key and got[-1].key == list(got)[-1].key
    assert runs._records is None and lazy.exit_status == listed.exit_status == 1
    assert len(runs) == len(records) and [r.key for r in runs] == sorted(r.key for r in records)


def test_records_read_in_bulk_share_the_values_their_rows_repeat(files):
    """A value most rows repeat (engine, model text, a step count, a timing copied) is one object the records share;
    a value of a row's own (the key, a message) its own; each the value written, a null number NaN."""
    from dalembert.bulk_records import records_from_table

    r = next(x for x in files.records() if x.ok)
    nan = float("nan")
    many = [replace(r, key=f"{r.key}-{i}") for i in range(8)] + [
        replace(r, key=f"{r.key}-own", status="diverged", message="not finite", t_diverged=0.5,
                cost=replace(r.cost, n_steps=123457, wall_s_median=nan))]
    got = records_from_table(runs_table.rows_table([x.to_row() for x in many]))
    _same_records(got, [_measured(x) for x in many])
    assert math.isnan(got[-1].cost.wall_s_median) and got[-1].cost.n_steps == 123457
    first, second = got[0], got[1]
    assert first.engine is second.engine and first.model is second.model and first.case_version is second.case_version
    assert first.cost.n_steps is second.cost.n_steps and first.cost.wall_s_median is second.cost.wall_s_median
    assert first.params is second.params and first.audit is second.audit and first.message is second.message
    assert len({id(x.key) for x in got}) == len(got)
