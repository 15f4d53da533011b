"""Results store: one directory per matrix run, immutable files, atomic writes.

Layout of a run directory::

    manifest.json          schema version, store layout, harness version/commit, machine, OS, Python,
                           engine versions, command line, start/end time, and the full list of run specs
    rows/<key>.json        layout 1: one finished run, ``RunRecord.to_row()`` (written atomically when it ends)
    segments/<name>.jsonl  layout 2: finished runs, one row per line, appended by each writing process to a
                           segment of its own (``dalembert.segments``)
    runs.parquet           all rows as a table (rebuilt after every batch; in layout 2 from the lines
                           added since, ``dalembert.runs_table``)
    trajectories/<key>.npz layout 1: one trajectory per run that produced one (``dalembert.trajectory_files``)
    trajectories/<name>.trajpack  layout 2: the trajectories, appended by each writing process to a pack of its
                           own; which runs' are kept is the manifest's ``trajectories`` (``dalembert.trajectory_store``)
    cases/<case>__<version>.json  each case as it was run (``CaseRecord``: scene, parameters,
                           tolerances with reasons, conserved quantities, floor)
    truth/<case>__<version>.npz   each case's truth at its sample times

A report or a comparison needs nothing but these files: no case is rebuilt from
code and no integrator runs to read a store.

The store layout (``LAYOUTS``, the manifest's ``store_layout``; 1 when absent: every store
written before layouts) is how the rows are kept, apart from the rows' schema. Layout 1, a
file per run, is what a user opens, diffs or deletes by hand, and reads linearly up to a few
thousand runs; past ``FILES_UP_TO`` runs a new store takes layout 2, whose rows append to
segments (a crash leaves at most a torn last line, ignored: its run is redone by
``--resume``) and whose table reads as columns (``Store.table``), linearly to a million runs.
Both layouts read and write through the same methods.

Every other write goes to a temporary file in the same directory, then ``os.replace``:
a reader or an interrupted run never sees half a file. (Files the user names
outside a store are written in place: ``dalembert.output``.) ``resume`` runs only
the specs without a row. The schema version (``dalembert.record.SCHEMA_VERSION``)
is in the manifest and in every row; a store of another schema is refused with
a message that says so.

Names the store holds become path components: a run's key (``rows/``,
``trajectories/``), a case's name and version (``cases/``, ``truth/``, the
report's figures). ``file_name`` checks each where it is read (the manifest's
specs, every row, every case record) and where a path is made of it, so a store
whose files were edited to name a path outside it (``x/../../outside``) is
refused, naming the file the name came from, before anything is read or written
outside it.
"""

from __future__ import annotations

import fcntl
import json
import os
import socket

from dalembert import runs_table
from dalembert.atomic import atomic_write
from dalembert.case import CaseRecord
from dalembert.provenance import harness_commit, library_versions, machine_info, now
from dalembert.bulk_records import records_from_table
from dalembert.record import SCHEMA_VERSION, RunRecord, SchemaError
from dalembert.segments import SegmentWriter, segment_names, segment_rows
from dalembert.trajectory_files import read_only, trajectory_from_npz, trajectory_to_npz
from dalembert.trajectory_store import ALL, Trajectories, TrajectoryNotKept, check_keep, default_keep

__all__ = ["Store", "StoreError", "StoreLock", "atomic_write", "file_name", "trajectory_to_npz", "trajectory_from_npz",
           "machine_info", "library_versions", "harness_commit", "now", "LAYOUTS", "FILES_UP_TO",
           "TrajectoryNotKept"]

# Store layouts: 1, a JSON file per run under rows/; 2, rows appended to segments/ (the module docstring).
FILES, SEGMENTS = 1, 2
LAYOUTS = (FILES, SEGMENTS)
# A new store of more runs than this takes layout 2: a file per run reads at ~0.1 ms per run while the
# directory is small (0.11 s per 1000 rows at 1e4, benchmarks/map.py) and 5-14x worse per row at 1e5, while
# 2000 files still read in well under a second; below it, rows stay files a user can edit by hand.
FILES_UP_TO = 2000


# The names a store holds that become path components: of a run spec in the manifest, of a row.
SPEC_NAMES = ("case", "engine", "integrator", "case_version")
ROW_NAMES = ("key", "case", "case_version", "engine", "integrator")


def _is_file_name(name):
    return (isinstance(name, str) and name not in ("", ".", "..") and "/" not in name and "\\" not in name
            and "\0" not in name)


def file_name(name, what, where, fix="the store was edited or damaged; rerun the matrix in a new directory"):
    """``name`` when it can be one component of a path inside a store, else ``StoreError``.

    Parameters
    ----------
    name : str
        A name the store holds that becomes (part of) a file name: a run key, a case name or version.
    what : str
        What the name is (``key``, ``specs[3].integrator``), for the message.
    where : str
        The file the name came from (or the directory it would go to), for the message.
    fix : str
        What the user can do, after "—" in the message.

    Returns
    -------
    str
        ``name``, unchanged: a non-empty string with no path separator (``/``; ``\\`` too, Windows'
        separator: a store may be copied there, and no name dalembert makes has one), no NUL, and
        neither ``.`` nor ``..``.
    """
    if _is_file_name(name):
        return name
    raise StoreError(f"{where}: {what} {name!r} is not a file name — {fix}")


class StoreLock:
    """A held one-writer lock on a store (``Store.writer``); ``release()`` or leave its ``with``."""

    def __init__(self, fh, stale):
        self._fh, self.stale = fh, stale

    def release(self):
        if not self._fh.closed:
            self._fh.truncate(0)  # an empty lock file: its last holder released it
            fcntl.flock(self._fh, fcntl.LOCK_UN)
            self._fh.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()


class StoreError(ValueError):
    """A results directory that cannot be read as asked; the message names the file and the fix."""


# Trajectories a ``Store`` keeps once read: every run a report section draws or a finding measures is read
# again by another (the headline error, the drifts, the loop residuals, the contact figures); 64 runs of the
# largest default case (27 bodies, 1001 samples: ~3 MB each) stay under 200 MB.
TRAJECTORY_CACHE = 64


class Store:
    """A results directory (see the module docstring)."""

    def __init__(self, path):
        self.path = os.path.abspath(path)
        self.rows_dir = os.path.join(self.path, "rows")
        self.traj_dir = os.path.join(self.path, "trajectories")
        self.cases_dir = os.path.join(self.path, "cases")
        self.truth_dir = os.path.join(self.path, "truth")
        self.segments_dir = os.path.join(self.path, "segments")
        self._layout = None  # the manifest's store layout, read once (``layout``): it is fixed when made
        self._segment = SegmentWriter(self.segments_dir)  # this process's segment (layout 2), opened on its first row
        self._cases = {}  # (name, version) -> CaseRecord, read once (``case``)
        self._trajectories = {}  # key -> Trajectory, the TRAJECTORY_CACHE last read (``trajectory``)
        self._kept = None  # the trajectories/ directory as the manifest keeps it (``kept``), made on first use

    # -------------------------------------------------------------- create, open
    def create(self, manifest, layout=None, runs=None):
        """Make the directories and write ``manifest`` (with the schema version and the store layout).

        ``layout``: one of ``LAYOUTS``; None: 1 for a matrix of up to ``FILES_UP_TO`` runs (``runs``, the most it
        will store; None: the manifest's ``specs``), else 2. The manifest's ``trajectories``
        (``dalembert.trajectory_store.KEEPS``) likewise: when absent or None, ``all`` up to ``FILES_UP_TO`` runs,
        else ``drawn``.
        """
        n_runs = runs if runs is not None else len(manifest["specs"]) if isinstance(manifest.get("specs"), list) else 0
        if layout is None:
            layout = SEGMENTS if n_runs > FILES_UP_TO else FILES
        keep = check_keep(manifest.get("trajectories")) or default_keep(n_runs, FILES_UP_TO)
        if layout not in LAYOUTS:
            raise ValueError(f"layout: unknown store layout {layout!r} — use one of {LAYOUTS} (or None: by the runs)")
        for d in (self.rows_dir if layout == FILES else self.segments_dir, self.traj_dir, self.cases_dir,
                  self.truth_dir):
            os.makedirs(d, exist_ok=True)
        self.write_manifest({**manifest, "schema_version": SCHEMA_VERSION, "store_layout": layout, "trajectories": keep})
        self._layout, self._kept = layout, None
        return self

    @classmethod
    def open(cls, path, schemas=(SCHEMA_VERSION,)):
        """An existing store whose schema is one of ``schemas``; ``StoreError`` naming the
        directory otherwise (not a store, or written by another schema)."""
        store = cls(path)
        if not store.exists():
            raise StoreError(f"{path!r} is not a results directory (no manifest.json) — give the directory "
                             "`dalembert run --out` wrote")
        schema = store.schema_version()
        if schema not in schemas:
            raise SchemaError(f"{path!r}: written with store schema {schema}, and this needs schema "
                              f"{' or '.join(map(str, schemas))} — rerun the matrix with this dalembert, or read "
                              "the store with the version that wrote it")
        return store

    def write_manifest(self, manifest):
        atomic_write(os.path.join(self.path, "manifest.json"), json.dumps(manifest, indent=2, sort_keys=True))

    def manifest(self):
        """The manifest, its specs' names checked (``file_name``): they become the runs' file names."""
        path = os.path.join(self.path, "manifest.json")
        manifest = self._json(path, "its manifest", "it is damaged: a store cannot be resumed or reported without it")
        if isinstance(manifest, dict):
            specs = manifest.get("specs")
            lists = [("specs", specs if isinstance(specs, list) else [])]
            searches = manifest.get("searches")
            for i, plan in enumerate(searches if isinstance(searches, list) else []):
                first = plan.get("first") if isinstance(plan, dict) else None
                lists.append((f"searches[{i}].first", first if isinstance(first, list) else []))
            for field, listed in lists:
                for k, spec in enumerate(listed):
                    for name in SPEC_NAMES if isinstance(spec, dict) else ():
                        if name in spec and not _is_file_name(spec[name]):  # (the message made only then)
                            file_name(spec[name], f"{field}[{k}].{name}", path)
        return manifest

    def _json(self, path, what, fix):
        """The JSON in ``path``; ``StoreError`` naming the file, ``what`` it is and the ``fix``."""
        try:
            with open(path) as fh:
                return json.load(fh)
        except FileNotFoundError:
            raise StoreError(f"{path}: missing ({what}) — {fix}") from None
        except (OSError, ValueError) as e:
            raise StoreError(f"{path}: cannot be read as {what} ({type(e).__name__}: {e}) — {fix}") from None

    def schema_version(self):
        """The store's schema (1 for stores written before the schema was recorded)."""
        return self.manifest().get("schema_version", 1)

    def layout(self):
        """The store layout (``LAYOUTS``; 1 for stores written before layouts); ``StoreError`` for another."""
        if self._layout is None:
            layout = self.manifest().get("store_layout", FILES) if self.exists() else FILES
            if layout not in LAYOUTS:
                raise StoreError(f"{self.path}: written in store layout {layout!r}, and this dalembert reads layouts "
                                 f"{' and '.join(map(str, LAYOUTS))} — read it with the version that wrote it")
            self._layout = layout
        return self._layout

    def exists(self):
        return os.path.exists(os.path.join(self.path, "manifest.json"))

    # -------------------------------------------------------------- one writer
    def writer(self, command=""):
        """Take the store's one-writer lock (``run`` and ``--resume`` hold it while they write).

        Returns a ``StoreLock`` (a context manager; the kernel also releases the lock when its
        process ends, however it ends). ``StoreError`` naming the holder (PID, host, since when,
        its command) when another process holds it. ``StoreLock.stale`` names a previous holder
        that ended without releasing it (killed), which is only worth a note.
        """
        os.makedirs(self.path, exist_ok=True)
        path = os.path.join(self.path, ".lock")
        fh = open(path, "a+")
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            fh.seek(0)
            owner = fh.read().strip() or "an unknown process"
            fh.close()
            raise StoreError(f"{self.path}: already being written by {owner} — wait for it to end, or stop it; "
                             "one store takes one writer") from None
        fh.seek(0)
        stale = fh.read().strip()
        fh.seek(0)
        fh.truncate()
        fh.write(f"PID {os.getpid()} on {socket.gethostname()} since {now()} ({command or 'dalembert'})")
        fh.flush()
        return StoreLock(fh, stale)

    # -------------------------------------------------------------- runs
    def write_record(self, record, trajectory_npz=None):
        """Store one finished run: its trajectory (if any), then its row (the commit point: its file in
        layout 1, its whole line in this process's segment in layout 2)."""
        file_name(record.key, "run key", self.rows_dir, "a run spec named outside the store; nothing was written")
        if trajectory_npz is not None:
            self._trajectories.pop(record.key, None)
            record = record.with_trajectory(self.kept().write(record.key, trajectory_npz, atomic_write, record))
        if self.layout() == SEGMENTS:
            self._segment.append(record.to_row())
        else:
            atomic_write(os.path.join(self.rows_dir, f"{record.key}.json"),
                         json.dumps(record.to_row(), sort_keys=True, allow_nan=False))

    def done_keys(self):
        """The keys of the runs stored (a row file, or a complete segment line whose key reads)."""
        if self.layout() == SEGMENTS:  # the table's keys and the lines added since (``runs_table.keys``)
            return runs_table.keys(self.path, self.segments_dir)
        if not os.path.isdir(self.rows_dir):
            return set()
        return {f[:-5] for f in os.listdir(self.rows_dir) if f.endswith(".json") and not f.startswith(".tmp-")}

    def rows(self):
        """Every stored row as written (a dict of columns), sorted by key. Only ``rows/*.json`` (layout 1) or the
        complete lines of ``segments/*.jsonl`` (layout 2) are rows (other files there are ignored); a damaged
        one is a ``StoreError`` naming it (and its line)."""
        return [row for _, row in self._stored()]

    def _stored(self):
        """``[(where, row)]`` sorted by key: the row's file, or its segment and line; the names in each row
        that become paths checked (``file_name``)."""
        out = self._found()
        for where, row in out:
            for name in ROW_NAMES:  # what becomes a path (a trajectory, a case record, a report's figure)
                if isinstance(row, dict) and isinstance(row.get(name), str):  # not a str: records() refuses it
                    file_name(row[name], name, where, "the store was edited or damaged; " + self._redo(row.get("key", "?")))
        return out

    def _found(self):
        """``[(where, row)]`` as read, sorted by key."""
        if self.layout() == FILES:
            out = []
            for key in sorted(self.done_keys()):
                path = os.path.join(self.rows_dir, f"{key}.json")
                out.append((path, self._json(path, "a stored run", self._redo(key))))
            return out
        found = {}
        for name in segment_names(self.segments_dir):
            path = os.path.join(self.segments_dir, name)
            try:
                rows = segment_rows(path, self._redo)
            except ValueError as e:
                raise StoreError(str(e)) from None
            for n, row in rows:
                where = f"{path} line {n}"
                if row["key"] in found:
                    raise StoreError(f"{where}: run {row['key']!r} is stored twice (first at {found[row['key']][0]}) — "
                                     f"the store was edited or damaged; delete one of the lines")
                found[row["key"]] = (where, row)
        return [found[k] for k in sorted(found)]

    def _redo(self, key, delete="it"):
        """The fix for a damaged file (or segment line) of run ``key``: redo the run."""
        return f"delete {delete} and run `dalembert run --resume {self.path}` to redo that run"

    def _row_name(self, key):  # where run ``key``'s row is, for a message
        return f"rows/{key}.json" if self.layout() == FILES else "its line in segments/"

    def records(self):
        """Every stored run as a ``RunRecord``, sorted by key."""
        out = []
        for where, row in self._stored():
            try:
                out.append(RunRecord.from_row(row))
            except SchemaError:
                raise
            except (KeyError, TypeError, ValueError) as e:
                key = row.get("key", "?") if isinstance(row, dict) else "?"
                raise StoreError(f"{where}: not a run dalembert wrote ({type(e).__name__}: {e}) — "
                                 f"{self._redo(key)}") from None
        return out

    def table_records(self):
        """Every stored run as a ``RunRecord``, sorted by key, read in bulk (``records_of``; layout 1: ``records``)."""
        if self.layout() == FILES:
            return self.records()
        table = self.arrow_table()
        if table is not None and len(table.column("key").unique()) < table.num_rows:
            self._found()  # a run stored twice: named there, with both lines
        return self.records_of(table)

    def arrow_table(self):
        """All rows as an Arrow table sorted by key (None: no row; layout 2: ``runs_table.read``)."""
        if self.layout() == FILES:
            return runs_table.rows_table(self.rows()) if self.done_keys() else None
        return self._read_table(runs_table.read)

    def records_of(self, table):
        """The ``RunRecord`` of each row of ``table`` (``arrow_table`` or rows of it; None: none), column by column
        (``bulk_records.records_from_table``: how a null metric reads); the names that become paths checked."""
        fix = f"the store was edited or damaged; delete its row and run `dalembert run --resume {self.path}`"
        for name in ROW_NAMES if table is not None else ():  # each distinct value once
            for value in table.column(name).unique().to_pylist() if name in table.column_names else ():
                file_name(value, name, self.path, fix)
        try:
            return [] if table is None else records_from_table(table)
        except SchemaError:
            raise
        except (KeyError, TypeError, ValueError) as e:
            raise StoreError(f"{self.path}: a row is not a run dalembert wrote ({type(e).__name__}: {e}) — {fix} "
                             "(`Store.records()` names its file and line)") from None

    def table(self):
        """All rows as a pandas DataFrame sorted by key, a column per row field (layout 2: ``arrow_table``)."""
        import pandas as pd

        if self.layout() == FILES:
            return pd.DataFrame(self.rows())
        table = self.arrow_table()
        return pd.DataFrame() if table is None else table.to_pandas()

    def _read_table(self, read, *args):
        try:
            return read(self.path, self.segments_dir, self._redo, *args)
        except ValueError as e:
            raise StoreError(str(e)) from None

    def write_table(self):
        """Rebuild ``runs.parquet`` atomically from the row files (layout 1), or its table and the lines since
        (layout 2: this process's segment synced first); a column of two types in its widest (``runs_table``)."""
        import pandas as pd

        self.kept().sync(atomic_write)
        if self.layout() == FILES:
            df = self.table()
            atomic_write(os.path.join(self.path, runs_table.TABLE_FILE), runs_table.frame_parquet(df, self.rows))
            return df
        self._segment.sync()
        table = self._read_table(runs_table.consolidate, atomic_write)
        return pd.DataFrame() if table is None else table.to_pandas()

    def trajectory(self, key):
        """The stored trajectory of run ``key``, read-only; ``StoreError`` naming the file when it is missing or
        damaged. The last ``TRAJECTORY_CACHE`` read are kept, so the report's sections and findings read
        each run's file once."""
        if key in self._trajectories:
            self._trajectories[key] = traj = self._trajectories.pop(key)  # (now the most recent)
            return traj
        traj = self._read_trajectory(key)
        self._trajectories[key] = traj
        while len(self._trajectories) > TRAJECTORY_CACHE:
            del self._trajectories[next(iter(self._trajectories))]  # the least recently read
        return traj

    def kept(self):
        """``trajectory_store.Trajectories``: the manifest's ``trajectories`` (all when absent), packed in layout 2."""
        if self._kept is None:
            keep = self.manifest().get("trajectories", ALL) if self.exists() else ALL
            self._kept = Trajectories(self.traj_dir, self.layout() == SEGMENTS, keep)
        return self._kept

    def has_trajectory(self, key):
        """Whether run ``key``'s trajectory is kept (``trajectory`` reads it), without reading it."""
        return key in self._trajectories or self.kept().has(file_name(key, "run key", self.traj_dir))

    def keep_trajectories(self, keys):
        """Drop every stored trajectory but those of ``keys`` (the end of a ``drawn`` matrix); returns how many."""
        self._trajectories.clear()
        return self.kept().keep_only(keys, atomic_write)

    def _read_trajectory(self, key):
        path = os.path.join(self.traj_dir, f"{file_name(key, 'run key', self.traj_dir)}.npz")
        try:
            return read_only(trajectory_from_npz(self.kept().source(key)))
        except TrajectoryNotKept:
            raise
        except FileNotFoundError:
            raise StoreError(f"{path}: missing — {self._redo(key, self._row_name(key))}") from None
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise StoreError(f"{path}: cannot be read as a trajectory ({type(e).__name__}: {e}) — "
                             f"{self._redo(key, 'it and ' + self._row_name(key))}") from None

    # -------------------------------------------------------------- cases and truths
    def _case_file(self, directory, name, version, ext):
        return os.path.join(directory, f"{file_name(name, 'case', directory)}__"
                                       f"{file_name(version, 'case version', directory)}.{ext}")

    def write_case(self, record, truth):
        """Store a case as run (``CaseRecord``) and its truth at its sample times, once per version."""
        os.makedirs(self.cases_dir, exist_ok=True)
        os.makedirs(self.truth_dir, exist_ok=True)
        self._cases.pop((record.name, record.version), None)
        atomic_write(self._case_file(self.truth_dir, record.name, record.version, "npz"), trajectory_to_npz(truth))
        atomic_write(self._case_file(self.cases_dir, record.name, record.version, "json"),
                     json.dumps(record.to_json(), indent=1, sort_keys=True, allow_nan=False))

    def has_case(self, name, version):
        return os.path.exists(self._case_file(self.cases_dir, name, version, "json"))

    def case(self, name, version):
        """The ``CaseRecord`` of case ``name`` at ``version``, read once per ``Store`` (a case version is
        written once, and a record is frozen); ``StoreError`` when the store has none."""
        if (name, version) not in self._cases:
            self._cases[name, version] = self._read_case(name, version)
        return self._cases[name, version]

    def _read_case(self, name, version):
        path = self._case_file(self.cases_dir, name, version, "json")
        if not os.path.exists(path):
            raise StoreError(f"{self.path}: no record of case {name!r} version {version} (cases/) — "
                             "the store is incomplete; rerun the matrix")
        data = self._json(path, "a case record", "the store is damaged; rerun the matrix")
        try:
            record = CaseRecord.from_json(data)
        except (KeyError, TypeError, ValueError) as e:
            raise StoreError(f"{path}: not a case record dalembert wrote ({type(e).__name__}: {e}) — the store is "
                             "damaged; rerun the matrix") from None
        file_name(record.name, "name", path)  # the report names its figures by it
        file_name(record.version, "version", path)
        return record

    def truth(self, name, version):
        """The case's stored truth trajectory, or None."""
        path = self._case_file(self.truth_dir, name, version, "npz")
        return trajectory_from_npz(path) if os.path.exists(path) else None
