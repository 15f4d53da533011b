"""A store's table read as ``RunRecord`` objects in bulk: what ``RunRecord.from_row`` does one row at a time,
done column by column, so that a report of a million runs reads them in seconds (``Store.table_records``).
"""

from __future__ import annotations

import json
from dataclasses import fields

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
    ``audit`` and ``provenance`` dicts (read-only, like the frozen record; ``params`` is each record's own).

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

    def objects(name, default=None):
        """Column ``name`` as Python values (None for null), or ``default`` in every row when absent."""
        return table.column(name).to_pylist() if name in names else [default] * n

    def floats(name):
        """Column ``name`` as Python floats, null (and absent) as NaN."""
        if name not in names:
            return [_NAN] * n
        col = table.column(name)
        if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type) or pa.types.is_null(col.type)):
            return [_num(v) for v in col.to_pylist()]  # (a text column: float() names the bad value)
        return col.cast(pa.float64()).to_numpy(zero_copy_only=False).astype(float, copy=False).tolist()

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
        memo = {}
        out = []
        for text in objects(name):
            if not isinstance(text, str):
                out.append(empty)
                continue
            value = memo.get(text)
            if value is None:
                value = memo[text] = convert(json.loads(text))
            out.append(value)
        return out

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
    for q, _ in metric["err"]:  # (max, final) pairs: the final NaN where null
        finals = floats(f"err_{q}_final")
        for i, row in enumerate(errors):
            if q in row:
                row[q] = (row[q], finals[i])
    drifts, rates, growths = (dicts(metric[kind]) for kind in ("drift", "drift_rate", "growth"))
    checks = dicts([(c, c) for c in CHECKS if c in names])

    settings_memo, judgement_memo = {}, {}
    integrators, options = objects("integrator"), objects("options")
    dts, rtols, atols = ([_opt(v) for v in floats(name)] for name in ("dt", "rtol", "atol"))
    beyond, verdicts, reasons = objects("beyond_tolerance"), objects("verdict"), objects("verdict_reason")
    withins, not_measured = objects("within_tolerance"), objects("not_measured")
    params = parsed("params", {}, lambda p: {k: tuple(v) if isinstance(v, list) else v for k, v in p.items()})
    audits, provenances = parsed("audit", {}), parsed("provenance", {})
    repeats = parsed("wall_s_repeats", (), lambda ws: tuple(_num(w) for w in ws))
    cost_cols = []
    for f in fields(Cost):
        if f.name not in names:
            continue
        if f.name == "wall_s_repeats":
            cost_cols.append((f.name, repeats))
        elif f.name in _TEXTS:
            cost_cols.append((f.name, [_text(v) for v in objects(f.name)]))
        elif f.name in _COUNTS:
            cost_cols.append((f.name, [_cost_field(f.name, v) for v in objects(f.name)]))
        else:
            cost_cols.append((f.name, floats(f.name)))
    orders = [None if v != v else int(v) for v in floats("integrator_order")]
    keys, cases, versions, engines = objects("key"), objects("case"), objects("case_version"), objects("engine")
    statuses, messages, engine_versions = objects("status"), objects("message"), objects("engine_version")
    dists, adapters = objects("adapter_distribution"), objects("adapter_version")
    t_finals, t_divs = floats("t_final"), floats("t_diverged")
    models, trajectories, tracebacks = objects("model"), objects("trajectory"), objects("traceback")

    out = []
    for i in range(n):
        s_key = (integrators[i], dts[i], rtols[i], atols[i], options[i])
        settings = settings_memo.get(s_key)
        if settings is None:
            settings = settings_memo[s_key] = Settings(
                integrators[i], dts[i], rtols[i], atols[i], json.loads(options[i] or "{}"))
        within = withins[i]
        j_key = (beyond[i], verdicts[i], reasons[i], within, not_measured[i])
        judgement = judgement_memo.get(j_key)
        if judgement is None:
            judgement = judgement_memo[j_key] = Judgement(
                beyond=tuple((beyond[i] or "").split()), verdict=verdicts[i] or "", reason=reasons[i] or "",
                within_tolerance=None if within is None or within != within else bool(within),
                not_measured=tuple(_text(not_measured[i]).split()))
        out.append(RunRecord(
            key=keys[i], case=cases[i], case_version=versions[i], engine=engines[i], settings=settings,
            params=dict(params[i]), status=statuses[i], message=messages[i] or "",
            engine_version=engine_versions[i] or "", adapter_distribution=_text(dists[i]),
            adapter_version=_text(adapters[i]), integrator_order=orders[i], t_final=t_finals[i],
            t_diverged=_opt(t_divs[i]), cost=Cost(**{name: col[i] for name, col in cost_cols}),
            errors=errors[i], drifts=drifts[i], drift_rates=rates[i], growths=growths[i], checks=checks[i],
            judgement=judgement,
            audit=audits[i], model=_text(models[i]), provenance=provenances[i],
            trajectory=_text(trajectories[i]), traceback=_text(tracebacks[i]),
            schema_version=1 if schemas[i] is None else schemas[i]))
    return out
