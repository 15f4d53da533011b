"""A store's records as a sequence read only when asked: what a matrix of a million runs hands back.

``dalembert run`` ends with the store's records (``dalembert.harness.commands.run.Outcome``), of which its summary
needs only the counts by status and the few runs that fail the matrix. ``StoredRuns`` takes those from the
table's ``status``, ``within_tolerance`` and ``not_measured`` columns (``Store.arrow_table``) and makes records
of the rows they name only; a caller that indexes or iterates it reads every record, once.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

from dalembert.record import BAD_STATUSES

__all__ = ["StoredRuns"]


class StoredRuns(Sequence):
    """A store's records as a sequence read only when asked (a matrix of a million runs ends without reading
    them): the counts and the runs that fail a matrix come from its table's status and verdict columns, and only
    the runs they name are made records (``Store.records_of``); indexing or iterating reads them all, once.

    Parameters
    ----------
    store : dalembert.store.Store
    """

    def __init__(self, store, table=None):
        self.store = store
        self._table = store.arrow_table() if table is None else table
        self._records = None

    def __len__(self):
        return 0 if self._table is None else self._table.num_rows

    def __getitem__(self, i):
        if self._records is None and isinstance(i, int):  # one run (the first of the failing ones): its row only
            i = range(len(self))[i]
            return self.store.records_of(self._table.slice(i, 1))[0]
        return self._all()[i]

    def __iter__(self):
        return iter(self._all())

    def _all(self):
        if self._records is None:
            self._records = self.store.records_of(self._table)
        return self._records

    def statuses(self):
        """``Counter`` of the runs' statuses."""
        return Counter() if self._table is None else Counter(self._table.column("status").to_pylist())

    def where(self, bad=False, beyond=False, not_measured=False):
        """The runs, as a ``StoredRuns`` of the rows that are (in key order), that failed, diverged or timed out
        (``bad``), or finished beyond a tolerance (``beyond``: ``within_tolerance`` false), or finished with a bound
        they did not measure, none beyond (``not_measured``): any of those asked."""
        import pyarrow as pa
        import pyarrow.compute as pc

        t = self._table
        if t is None:
            return []
        n, status = t.num_rows, t.column("status")
        within = t.column("within_tolerance") if "within_tolerance" in t.column_names else pa.nulls(n, pa.bool_())
        names = t.column("not_measured") if "not_measured" in t.column_names else pa.nulls(n, pa.string())
        ok = pc.equal(status, "ok")
        masks = [pc.is_in(status, pa.array(BAD_STATUSES))] if bad else []
        masks += [pc.and_(ok, pc.equal(within, False))] if beyond else []
        masks += [pc.and_(pc.and_(ok, pc.is_null(within)), pc.greater(pc.utf8_length(names), 0))] if not_measured else []
        mask = pa.array([False] * n)
        for m in masks:
            mask = pc.or_(mask, pc.fill_null(m, False))
        return StoredRuns(self.store, t.filter(mask))
