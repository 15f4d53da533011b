"""A store's table read as ``RunRecord`` objects in bulk: what ``RunRecord.from_row`` does one row at a time,
done column by column, so that a report of a million runs reads them in seconds (``Store.table_records``).
"""

from __future__ import annotations

import json
from dataclasses import fields
from functools import partial

from dalembert.judge import Judgement
from dalembert.record import (_COUNTS, _NAN, _TEXTS, CHECKS, READABLE_SCHEMAS, Cost, RunRecord, SchemaError,
                              _cost_field, _num, _opt, _text)
from dalembert.settings import Settings

__all__ = ["records_from_table"]


def records_from_table(table):
    """Every row of a store's table as a ``RunRecord``, in the table's order, read column by column.

    What ``from_row`` does one row at a time, done per column: numbers converted as whole columns, and each
    distinct JSON text (``params``, ``options``, ``audit``, ``provenance``, ``wall_s_repeats``) and each distinct
    settings and judgement parsed or made once — a map's rows repeat them. Records read together share their
    ``params``, ``audit`` and ``provenance`` dicts (read-only, like the frozen record): a reader may make what it
    derives from one once per distinct dict (``reports.order.step_pairs``).

    Parameters
    ----------
    table : pyarrow.Table
        One row per run, the columns of ``RunRecord.to_row`` (``dalembert.runs_table``).

    Returns
    -------
    list of RunRecord

    Notes
    -----
    A table holds every column in every row, so a metric a row does not have (``err_*``, ``drift_*``,
    ``drift_rate_*``, ``growth_*``, a check) and one stored as null (a run not finite) read alike: absent from the
    record's dicts, as ``from_row`` reads a null check. ``max_error`` and ``drifts.get`` read both as NaN.

    Raises
    ------
    SchemaError
        A row of a schema not in ``READABLE_SCHEMAS`` (the first one named).
    """
    import pyarrow as pa

    n = table.num_rows
    names = set(table.column_names)

    def objects(name, default=None, rows=table, convert=None):
        """Column ``name`` (of the table, or of ``rows``: some of its rows) as Python values (None for null), or
        ``default`` in every row when absent; ``convert(value)`` of each where given (``_values``)."""
        if name not in names:
            return [default if convert is None else convert(default)] * rows.num_rows
        return _values(rows.column(name), convert)

    def floats(name, rows=table, convert=None):
        """Column ``name`` (of the table, or of ``rows``) as Python floats, null (and absent) as NaN;
        ``convert(value)`` of each where given."""
        if name not in names:
            return [_NAN if convert is None else convert(_NAN)] * rows.num_rows
        col = rows.column(name)
        if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type) or pa.types.is_null(col.type)):
            return [_num(v) if convert is None else convert(_num(v))  # (a text column: float() names the bad value)
                    for v in col.to_pylist()]
        return _values(col.cast(pa.float64()).fill_null(_NAN), convert)

    def dicts(columns):
        """Per row, ``{name: value}`` of ``columns`` (``[(name, column name)]``) where the row's value is not null;
        the values as ``floats``, made column by column over the non-null cells only."""
        out = [{} for _ in range(n)]
        for name, col in columns:
            values = floats(col)
            for i in table.column(col).is_valid().to_numpy(zero_copy_only=False).nonzero()[0].tolist():
                out[i][name] = values[i]
        return out

    def parsed(name, empty, convert=lambda v: v):
        """Column ``name``'s JSON texts parsed, each distinct text once (``empty`` for null or absent)."""
        if name not in names:
            return [empty] * n
        return _values(table.column(name), lambda text: convert(json.loads(text)) if isinstance(text, str) else empty,
                       few=1)

    schemas = objects("schema_version", 1)
    bad = next((i for i, s in enumerate(schemas) if (1 if s is None else s) not in READABLE_SCHEMAS), None)
    if bad is not None:
        raise SchemaError(f"row {objects('key')[bad]!r}: schema {schemas[bad]!r}, this dalembert reads "
                          f"{list(READABLE_SCHEMAS)} — read it with the dalembert version that wrote it")

    metric = {"err": [], "drift": [], "drift_rate": [], "growth": []}
    for col in sorted(names):
        if col.startswith("err_") and col.endswith("_max"):
            metric["err"].append((col[len("err_"):-len("_max")], col))
        elif col.startswith("growth_"):
            metric["growth"].append((col[len("growth_"):], col))
        elif col.startswith("drift_rate_"):
            metric["drift_rate"].append((col[len("drift_rate_"):], col))
        elif col.startswith("drift_"):
            metric["drift"].append((col[len("drift_"):], col))
    errors = dicts(metric["err"])
    for q, col in metric["err"]:  # (max, final) pairs: the final NaN where null
        finals = floats(f"err_{q}_final")
        for i in table.column(col).is_valid().to_numpy(zero_copy_only=False).nonzero()[0].tolist():
            errors[i][q] = (errors[i][q], finals[i])
    drifts, rates, growths = (dicts(metric[kind]) for kind in ("drift", "drift_rate", "growth"))
    checks = dicts([(c, c) for c in CHECKS if c in names])

    def settings_of(integrator, dt, rtol, atol, options):
        return Settings(integrator, _opt(dt), _opt(rtol), _opt(atol), json.loads(options or "{}"))

    def judgement_of(beyond, verdict, reason, within, not_measured):
        return Judgement(beyond=tuple((beyond or "").split()), verdict=verdict or "", reason=reason or "",
                         within_tolerance=None if within is None or within != within else bool(within),
                         not_measured=tuple(_text(not_measured).split()))

    defaults = {f.name: f.default for f in fields(Cost)}
    cost = {"wall_s_repeats": parsed("wall_s_repeats", (), lambda ws: tuple(_num(w) for w in ws))}
    for name in defaults:
        if name == "wall_s_repeats":
            continue
        if name not in names:
            cost[name] = [defaults[name]] * n
        elif name in _TEXTS:
            cost[name] = objects(name, convert=_text)
        elif name in _COUNTS:
            cost[name] = objects(name, convert=partial(_cost_field, name))
        else:
            cost[name] = floats(name)
    column = {
        "key": objects("key"), "case": objects("case"), "case_version": objects("case_version"),
        "engine": objects("engine"),
        "settings": made(table, settings_of, (("integrator", objects), ("dt", floats), ("rtol", floats),
                                              ("atol", floats), ("options", objects))),
        "params": parsed("params", {}, lambda p: {k: tuple(v) if isinstance(v, list) else v for k, v in p.items()}),
        "status": objects("status"), "message": objects("message", convert=_or_empty),
        "engine_version": objects("engine_version", convert=_or_empty),
        "adapter_distribution": objects("adapter_distribution", convert=_text),
        "adapter_version": objects("adapter_version", convert=_text),
        "integrator_order": floats("integrator_order", convert=_order),
        "t_final": floats("t_final"), "t_diverged": floats("t_diverged", convert=_opt),
        "cost": made_each(Cost, defaults, (cost[name] for name in defaults)),
        "errors": errors, "drifts": drifts, "drift_rates": rates, "growths": growths, "checks": checks,
        "judgement": made(table, judgement_of, tuple((name, objects) for name in (
            "beyond_tolerance", "verdict", "verdict_reason", "within_tolerance", "not_measured"))),
        "audit": parsed("audit", {}), "model": objects("model", convert=_text),
        "provenance": parsed("provenance", {}), "trajectory": objects("trajectory", convert=_text),
        "traceback": objects("traceback", convert=_text),
        "schema_version": [1 if v is None else v for v in schemas]}
    for status in set(column["status"]):  # (``RunRecord.__post_init__``'s check, once per distinct status)
        RunRecord(key="", case="", case_version="", engine="", settings=column["settings"][0], status=status)
    names = [f.name for f in fields(RunRecord)]
    return made_each(RunRecord, names, (column[name] for name in names))


def _or_empty(v):
    return v or ""


def _order(v):
    return None if v != v else int(v)


def _values(column, convert=None, few=None):
    """``column`` (an Arrow array) as Python values, None for null, each ``convert(value)`` where given; where few of
    its values are distinct (a map's engine, case, model text, load, step count repeat row after row; one row in
    ``few`` at most, ``_FEW`` if None), each distinct value one object, converted once, that every row holding it
    shares: a million rows' columns of strings and numbers are not a million objects each, to make, keep and free
    (1e5 runs: records read 0.80 -> 0.70 s, 0.60 s with each distinct value converted once; freed 0.29 -> 0.09 s,
    measured)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    column = column.combine_chunks() if isinstance(column, pa.ChunkedArray) else column
    if pa.types.is_dictionary(column.type):
        column = column.dictionary_decode()
    encoded = pc.dictionary_encode(column, null_encoding="encode")  # (a null one entry: the indices have none)
    if len(encoded.dictionary) * (few or _FEW) > len(column):
        values = column.to_pylist()
        return values if convert is None else list(map(convert, values))
    values = encoded.dictionary.to_pylist()
    return list(map((values if convert is None else list(map(convert, values))).__getitem__,
                    encoded.indices.to_numpy(zero_copy_only=False).tolist()))


# A column's values are shared where at most one row in ``_FEW`` holds a value of its own (else each row's is made:
# sharing them costs more than it saves).
_FEW = 4


def made_each(cls, names, columns):
    """An instance of frozen dataclass ``cls`` per row of ``columns`` (an iterable of lists of one length, one per
    name in ``names``: its fields, in their order, so that its dict shares its keys as ``__init__``'s does), its
    ``__dict__`` filled from the row's values: what ``cls(*values)`` makes, less the per-field
    ``object.__setattr__`` of a frozen ``__init__`` (0.53 s of making 1e5 records and their costs that way, 0.28 s
    this way, measured). The caller checks the values as ``__post_init__`` would."""
    new = object.__new__

    def one(*values):
        obj = new(cls)
        obj.__dict__.update(zip(names, values))
        return obj

    return list(map(one, *columns))


def made(table, factory, columns):
    """``factory(*values)`` per row of ``table``, its values those of ``columns`` (``[(name, read)]``: ``read(name,
    rows)`` gives the Python values of column ``name`` in the table ``rows``), made once per distinct row of values:
    the objects are frozen, so rows alike share one.

    The distinct rows are found on the table's columns (each dictionary-encoded: a row's code combines its columns'
    indices), and only one row of each is read as Python values: a map's settings differ run by run in one column
    (each probe its own step), its judgements hardly at all: every row's values are not read to look them up one row
    at a time (1e5 runs, settings and judgements: 0.155 -> 0.123 s, measured)."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.compute as pc

    n = table.num_rows
    if n == 0:
        return []
    code = np.zeros(n, dtype=np.int64)
    distinct = 1
    for name, _ in columns:
        if name not in table.column_names:
            continue  # (the same in every row)
        col = table.column(name).combine_chunks()
        encoded = col if pa.types.is_dictionary(col.type) else pc.dictionary_encode(col, null_encoding="encode")
        size = len(encoded.dictionary) + 1  # (+1: a null, where the encoding leaves one)
        index = encoded.indices.fill_null(size - 1).to_numpy(zero_copy_only=False).astype(np.int64)
        if distinct * size >= 2 ** 62:  # (the combined code would overflow: renumber the distinct rows so far)
            distinct, code = _renumbered(code)
        code = code * size + index
        distinct *= size
    _, first, inverse = np.unique(code, return_index=True, return_inverse=True)
    rows = table.take(pa.array(first))
    objects = list(map(factory, *(read(name, rows=rows) for name, read in columns)))
    return list(map(objects.__getitem__, inverse.tolist()))


def _renumbered(code):
    """``code`` renumbered 0.. by distinct value, and how many there are."""
    import numpy as np

    values, inverse = np.unique(code, return_inverse=True)
    return len(values), inverse.astype(np.int64)
