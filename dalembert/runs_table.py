"""The table of a store's runs (layout 2): every row of its segments as one columnar table.

``runs.parquet`` holds the rows of the segments it covers, sorted by key; its schema's
metadata (``COVERS``) names each segment it read and how many bytes of it, so that a
reader adds only what was appended since (``read``) and a rebuild at the end of a batch
parses only the new lines (``consolidate``): the JSON parsed grows with the rows added, and
the rows already in the table are never parsed again (the table itself is read and rewritten
whole, as columns). The segments stay the store's record
of its rows (``dalembert.segments``); the table is made from them, and a table that
covers more than its segments hold is refused as damage.

New lines are parsed by Arrow's JSON reader (columns in C++, no Python object per
value); where a segment's columns do not parse as one type, its rows are read line by
line as ``Store.rows`` reads them.

A column is one type in the table. Where its values differ in type between rows (a case
parameter a number in one row and a vector, stored as JSON text, in another; a column a
later version made text), the column takes the widest (``widest``): integers and floats
read as floats, and any other mix as text — a text value as it is, any other as its JSON
text (``5``, ``true``, ``[1, 2]``); null stays null. Both layouts' ``runs.parquet`` follow it.
"""

from __future__ import annotations

import io
import json
import os

from dalembert.segments import line_key, parse_lines, segment_names, segment_rows

__all__ = ["COVERS", "TABLE_FILE", "complete_size", "consolidate", "frame_parquet", "keys", "read", "rows_table", "widest"]

TABLE_FILE = "runs.parquet"
COVERS = b"dalembert.covers"  # the schema metadata: {"segments": {name: bytes read}}
# Arrow's JSON reader parses blocks of this many bytes, and a row must fit in one: 16 MiB is ~6000 times a row
# of benchmarks/map.py's map (2.7 kB); a longer row (a huge traceback) fails the reader and its segment is read
# line by line instead (``_parse``), slower but the same rows.
JSON_BLOCK_BYTES = 16 << 20
_TAIL_CHUNK = 1 << 16


def widest(values):
    """``values`` (one column's, Python, None for null) in the column's widest type (the module docstring): as
    they are when of one type, integers with floats as floats, any other mix as text."""
    kinds = {type(v) for v in values if v is not None}
    if len(kinds) <= 1 or kinds <= {int, float}:
        return values if kinds != {int, float} else [None if v is None else float(v) for v in values]
    return [v if v is None or isinstance(v, str) else json.dumps(v) for v in values]


def rows_table(rows):
    """``rows`` (dicts of columns, as written) as one Arrow table: a column per name any row has (null where a row
    has none), each in its ``widest`` type."""
    import pyarrow as pa

    columns = {}
    for row in rows:
        for name in row:
            columns.setdefault(name, None)
    return pa.table({name: widest([row.get(name) for row in rows]) for name in columns})


def frame_parquet(frame, rows):
    """The Parquet bytes of ``frame`` (a layout-1 store's rows as pandas reads them); where a column's values differ
    in type (pandas cannot write it), of ``rows()``'s table, each column in its ``widest`` type."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    buf = io.BytesIO()
    try:
        frame.to_parquet(buf, index=False)
    except (pa.ArrowInvalid, pa.ArrowTypeError):
        buf = io.BytesIO()
        pq.write_table(rows_table(rows()), buf)
    return buf.getvalue()


def _unify(tables):
    """``tables`` (Arrow) with each column that differs in type between them made ``widest``: numbers as float64,
    any other mix as text, so that they concatenate."""
    import pyarrow as pa

    types = {}
    for t in tables:
        for field in t.schema:
            if not pa.types.is_null(field.type):
                types.setdefault(field.name, set()).add(field.type)
    mixed = {name for name, kinds in types.items() if len(kinds) > 1}
    if not mixed:
        return tables
    numeric = {name for name in mixed if all(pa.types.is_integer(k) or pa.types.is_floating(k) for k in types[name])}
    out = []
    for t in tables:
        for name in mixed & set(t.column_names):
            i = t.column_names.index(name)
            if name in numeric:
                col = t.column(name).cast(pa.float64())
            else:
                col = pa.array([v if v is None or isinstance(v, str) else json.dumps(v)
                                for v in t.column(name).to_pylist()], pa.string())
            t = t.set_column(i, name, col)
        out.append(t)
    return out


def complete_size(path):
    """The size of ``path``'s complete lines: its size less a torn last line (text after the last newline)."""
    with open(path, "rb") as fh:
        pos = fh.seek(0, os.SEEK_END)
        while pos > 0:
            start = max(0, pos - _TAIL_CHUNK)
            fh.seek(start)
            chunk = fh.read(pos - start)
            i = chunk.rfind(b"\n")
            if i >= 0:
                return start + i + 1
            pos = start
        return 0


def _covers(path):
    """``{segment name: bytes}`` that ``runs.parquet`` at ``path`` covers, and the file's Arrow schema."""
    import pyarrow.parquet as pq

    schema = pq.read_schema(path)
    meta = (schema.metadata or {}).get(COVERS)
    covers = json.loads(meta)["segments"] if meta else {}
    return covers, schema


def _parse(path, start, end, fix):
    """The rows of ``path``'s bytes ``start:end`` (complete lines) as an Arrow table."""
    import pyarrow as pa
    import pyarrow.json as pj

    with pa.memory_map(path) as mm:
        data = mm.read_buffer()[start:end]
        try:
            return pj.read_json(pa.BufferReader(data), read_options=pj.ReadOptions(block_size=JSON_BLOCK_BYTES))
        except pa.ArrowInvalid:  # a column of two types, or a damaged line (``segment_rows`` names it)
            try:
                rows = [row for _, row in parse_lines(data.to_pybytes().splitlines(), path, fix)]
            except ValueError:  # a damaged line: named with its number in the whole segment
                segment_rows(path, fix)
                raise
    return rows_table(rows)


def read(store_dir, segments_dir, fix, with_covers=False):
    """Every row of the segments in ``segments_dir`` as one Arrow table sorted by ``key`` (None: no row).

    Parameters
    ----------
    store_dir : str
        The store (its ``runs.parquet``, when there is one, gives the rows it covers).
    segments_dir : str
        Its ``segments/``.
    fix : callable(str) -> str
        The fix for a damaged row of that key (``Store._redo``).
    with_covers : bool
        Also return ``{segment name: bytes read}``, what the table covers.

    Raises
    ------
    ValueError
        A damaged segment line (its file and line named), or a ``runs.parquet`` that covers a segment missing or
        shorter than it read.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    table_path = os.path.join(store_dir, TABLE_FILE)
    tables, covers = [], {}
    if os.path.exists(table_path):
        try:
            covers, _ = _covers(table_path)
            old = pq.read_table(table_path)
        except (OSError, ValueError, KeyError, TypeError, pa.ArrowException) as e:
            raise ValueError(f"{table_path}: cannot be read as the table of runs ({type(e).__name__}: {e}) — delete "
                             "it: it is rebuilt from segments/ by the next `dalembert run --resume`, and read from them "
                             "until then") from None
        tables.append(old)
    covers = dict(covers)
    names = segment_names(segments_dir)
    for name in sorted(set(covers) - set(names)):
        raise ValueError(f"{table_path}: covers segments/{name}, which is missing — the store was edited or damaged; "
                         "restore the segment, or delete runs.parquet (its runs are then redone by --resume)")
    for name in names:
        path = os.path.join(segments_dir, name)
        start, end = covers.get(name, 0), complete_size(path)
        if end < start:
            raise ValueError(f"{table_path}: covers {start} bytes of segments/{name}, which holds {end} — the store "
                             "was edited or damaged; delete runs.parquet (it is rebuilt from the segments)")
        if end > start:
            tables.append(_parse(path, start, end, fix))
        covers[name] = end
    tables = _unify([t.replace_schema_metadata(None) for t in tables if t.num_rows])
    table = _by_key(pa.concat_tables(tables, promote_options="permissive")) if tables else None
    return (table, covers) if with_covers else table


def _by_key(table):
    """``table`` sorted by ``key`` (stably): as it is when it already is (``runs.parquet`` is written sorted, and a
    store read after its matrix ended has no rows beside it; the check is one pass, the sort and its ``take`` of every
    column half of reading a million rows)."""
    import pyarrow.compute as pc

    keys = table.column("key")
    if len(keys) < 2 or pc.all(pc.less_equal(keys.slice(0, len(keys) - 1), keys.slice(1)), skip_nulls=False).as_py():
        return table
    return table.sort_by("key")


def keys(store_dir, segments_dir):
    """The run keys of the segments in ``segments_dir`` (a set; a complete line whose key does not read is left
    out, as ``segments.segment_keys`` reads it): the table's ``key`` column, and the lines appended since read from
    their start only (``segments.line_key``). A table that cannot be read, or covers more than the segments hold,
    is passed over: the keys are then read from the segments alone (``read`` names the damage)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    names = segment_names(segments_dir)
    table_path = os.path.join(store_dir, TABLE_FILE)
    covers, found = {}, set()
    if os.path.exists(table_path):
        try:
            covers, _ = _covers(table_path)
            found = set(pq.ParquetFile(table_path).read(columns=["key"]).column("key").to_pylist())
        except (OSError, ValueError, KeyError, TypeError, pa.ArrowException):
            covers, found = {}, set()
    if set(covers) - set(names) or any(complete_size(os.path.join(segments_dir, name)) < size
                                       for name, size in covers.items()):
        covers, found = {}, set()
    for name in names:
        with open(os.path.join(segments_dir, name), "rb") as fh:
            fh.seek(covers.get(name, 0))
            found.update(line_key(line) for line in fh if line.endswith(b"\n"))
    found.discard(None)
    return found


def consolidate(store_dir, segments_dir, fix, write):
    """Rebuild ``runs.parquet`` from the table it holds and the segment lines since; returns the table (Arrow,
    None when no row). ``write(path, bytes)`` writes a file atomically (``dalembert.store.atomic_write``)."""
    import pyarrow.parquet as pq

    table, covers = read(store_dir, segments_dir, fix, with_covers=True)
    if table is None:
        return None
    meta = {COVERS: json.dumps({"segments": covers}, sort_keys=True).encode()}
    buf = io.BytesIO()
    pq.write_table(table.replace_schema_metadata(meta), buf)
    write(os.path.join(store_dir, TABLE_FILE), buf.getvalue())
    return table
