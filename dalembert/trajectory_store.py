"""The trajectories a store keeps: which (``KEEPS``), and how (a file per run, or packs).

Which: the manifest's ``trajectories`` (``dalembert run --trajectories``; ``"all"`` when absent, as every
store written before the choice kept all): ``all`` keeps every run's trajectory; ``drawn`` keeps those the
report draws (``dalembert.reports.drawn``: a run that can never be drawn, ``Trajectories.drawable``, is not
written; the others are, and those not drawn are dropped when the matrix ends complete,
``Trajectories.keep_only``); ``none`` keeps none, and the rows say so (an
empty ``trajectory``). A matrix of up to ``dalembert.store.FILES_UP_TO`` runs keeps ``all`` unless told,
a larger one ``drawn`` (``default_keep``). The matrix's workers are told the same choice
(``dalembert.harness.sent``): they never build or send a trajectory ``write`` would drop, which it still drops
from a caller that does not tell its workers.

How: a store of layout 1 keeps a file per run, ``trajectories/<key>.npz``
(``dalembert.trajectory_files``). A store of layout 2 appends them to a pack per writing process,
``trajectories/<name>.trajpack`` (named as ``dalembert.segments`` names a segment): one entry per
run, ``MAGIC``, the key's and the ``.npz``'s lengths (``_HEAD``, little-endian), the key (UTF-8),
the ``.npz`` bytes, handed to the kernel in one ``O_APPEND`` write. An entry is committed when all of
it is in the file; a crash at any point leaves whole entries and at most one torn last entry, which
readers ignore (the run's row, written after it, is not stored either, and ``--resume`` redoes the
run in a new pack). A run stored twice (redone after a crash between its entry and its row) reads as
the last written: packs sort as written. Entries are never rewritten; ``keep_only`` writes a pack's
kept entries to a new pack (atomically) before it deletes the old one, so a crash meanwhile leaves both
(the same entries twice), never neither. A store of layout 2 written before packs keeps its
``.npz`` files, and reads them still.

A reader finds a run's entry through an index of each pack (``<name>.trajidx``: the keys, offsets and lengths
of its entries up to the bytes it covers), written atomically beside the pack when its writer syncs it (the
end of each batch) and when a drop rewrites it; the entries after what the index covers (or of a pack without
one, or whose index does not read) are found by scanning their heads. The index is a cache: the pack is the
record, and a pack of a million entries is not read through to find one.
"""

from __future__ import annotations

import io
import os
import struct
from array import array

import numpy as np

from dalembert.segments import close_synced, new_name

__all__ = ["KEEPS", "ALL", "DRAWN", "NONE", "PACK_SUFFIX", "INDEX_SUFFIX", "MAGIC", "TrajectoryNotKept", "Trajectories",
           "check_keep", "default_keep", "pack_entries", "read_index", "write_index"]

ALL, DRAWN, NONE = "all", "drawn", "none"
KEEPS = (ALL, DRAWN, NONE)
PACK_SUFFIX = ".trajpack"
INDEX_SUFFIX = ".trajidx"
MAGIC = b"DTJ1"  # each entry starts so: a pack read from the wrong offset, or damaged, is caught at once
_HEAD = struct.Struct("<4sIQ")  # magic, key length, .npz length (bytes)


class TrajectoryNotKept(LookupError, ValueError):
    """A run's trajectory the store did not keep (its ``trajectories`` choice); the message says which and the fix."""


def check_keep(value, where="run.trajectories"):
    """``value`` when it is one of ``KEEPS`` (or None: by the matrix's size), else ValueError naming ``where``."""
    if value is None or value in KEEPS:
        return value
    raise ValueError(f"{where}: {value!r} is not a choice — use all (every run's trajectory), drawn (only those "
                     "the report draws) or none")


def default_keep(n_runs, files_up_to):
    """``all`` for a matrix of up to ``files_up_to`` runs (every store before the choice kept all), else
    ``drawn``: a map's trajectories (1e5 probes of 4 kB to 100 kB each: 0.4 to 10 GB) are what the report never
    draws."""
    return ALL if n_runs <= files_up_to else DRAWN


def _pack_names(directory):
    try:
        names = os.listdir(directory)
    except FileNotFoundError:
        return []
    return sorted(n for n in names if n.endswith(PACK_SUFFIX) and not n.startswith("."))


def pack_entries(path, start=0):
    """``[(key, offset of its .npz, length)]`` of the whole entries of the pack at ``path`` from byte ``start`` (an
    entry's start), in order; a torn last entry is left out. ValueError ``<path> offset <n>: ...`` where an entry
    does not start with ``MAGIC``."""
    out = []
    with open(path, "rb") as fh:
        size = fh.seek(0, os.SEEK_END)
        pos = start
        while pos + _HEAD.size <= size:
            fh.seek(pos)
            magic, n_key, n_data = _HEAD.unpack(fh.read(_HEAD.size))
            if magic != MAGIC:
                raise ValueError(f"{path} offset {pos}: not a trajectory entry dalembert wrote")
            end = pos + _HEAD.size + n_key + n_data
            if end > size:
                break  # a torn last entry: its run was not stored
            key = fh.read(n_key).decode("utf-8", "replace")
            out.append((key, pos + _HEAD.size + n_key, n_data))
            pos = end
    return out


def _index_path(pack):
    return pack[:-len(PACK_SUFFIX)] + INDEX_SUFFIX


def write_index(pack, keys, offsets, lengths, covers, atomic_write):
    """Write the index of the pack at ``pack``: its entries' ``keys``, ``offsets`` and ``lengths`` (sequences), which
    end at byte ``covers``."""
    buf = io.BytesIO()
    np.savez(buf, keys=np.array(list(keys), dtype=str), offsets=np.asarray(offsets, np.int64),
             lengths=np.asarray(lengths, np.int64), covers=np.int64(covers))
    atomic_write(_index_path(pack), buf.getvalue())


def read_index(pack, size):
    """``(entries, covers)``: the entries the index of the pack at ``pack`` (of ``size`` bytes) lists and the bytes it
    covers; ``([], 0)`` when it has none, or one that does not read or covers more than the pack holds (damage:
    the pack is scanned instead)."""
    try:
        with np.load(_index_path(pack)) as z:
            keys, offsets, lengths, covers = z["keys"], z["offsets"], z["lengths"], int(z["covers"])
    except (OSError, ValueError, KeyError, TypeError):
        return [], 0
    if covers > size or not len(keys) == len(offsets) == len(lengths):
        return [], 0
    return list(zip(keys.tolist(), offsets.tolist(), lengths.tolist())), covers


def _entry(key, npz):
    k = key.encode()
    return _HEAD.pack(MAGIC, len(k), len(npz)) + k + npz


class _PackWriter:
    """This process's pack, opened on its first entry and only appended to (as ``segments.SegmentWriter``)."""

    def __init__(self, directory):
        self.directory, self.name, self._fd, self._pid = directory, None, None, None
        self._keys, self._offsets, self._lengths, self._size = [], array("q"), array("q"), 0  # (its index)

    def append(self, key, npz):
        if self._fd is None or self._pid != os.getpid():  # a forked child never writes its parent's pack
            os.makedirs(self.directory, exist_ok=True)
            self.name = new_name().rsplit(".", 1)[0] + PACK_SUFFIX
            self._fd = os.open(os.path.join(self.directory, self.name),
                               os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND | os.O_CLOEXEC, 0o666)
            self._pid = os.getpid()
            self._keys, self._offsets, self._lengths, self._size = [], array("q"), array("q"), 0
        entry = _entry(key, npz)
        view = memoryview(entry)
        try:
            while view:
                view = view[os.write(self._fd, view):]
        except OSError:  # the entry may be torn: nothing may follow it in this pack
            fd, self._fd = self._fd, None
            os.close(fd)
            raise
        self._keys.append(key)
        self._offsets.append(self._size + len(entry) - len(npz))
        self._lengths.append(len(npz))
        self._size += len(entry)
        return self.name

    def sync(self, atomic_write):
        """Flush the pack to the disk, then write its index."""
        if self._fd is not None and self._pid == os.getpid():
            os.fsync(self._fd)
            write_index(os.path.join(self.directory, self.name), self._keys, self._offsets, self._lengths, self._size,
                        atomic_write)

    def close(self):
        """Sync and close; the next ``append`` starts a new pack."""
        if self._fd is not None:
            fd, self._fd = self._fd, None
            close_synced(fd, self._pid)


class Trajectories:
    """A store's ``trajectories/`` directory, as its choice (``keep``) and layout (``packed``) keep it.

    Parameters
    ----------
    directory : str
        The store's ``trajectories/``.
    packed : bool
        True for a store of layout 2: new trajectories go to this process's pack.
    keep : str
        One of ``KEEPS``.
    """

    def __init__(self, directory, packed, keep):
        self.directory, self.packed, self.keep = directory, packed, keep
        self._writer = _PackWriter(directory)
        # ``drawable(record) -> bool``: False for a run whose trajectory is never drawn (``reports.drawn.may_be_drawn``,
        # set by the matrix of a ``drawn`` store): not written at all
        self.drawable = None
        self._index = {}  # key -> (pack path, offset, length): every pack entry read so far
        self._scanned = {}  # pack name -> bytes indexed

    def write(self, key, npz, atomic_write, record=None):
        """Keep run ``key``'s trajectory (``.npz`` bytes; ``record``: its ``RunRecord``, for ``drawable``); returns
        the path to put in its row (relative to the store), "" when the store does not keep it."""
        if self.keep == NONE or (self.keep == DRAWN and self.drawable is not None and record is not None
                                 and not self.drawable(record)):
            return ""
        if self.packed:
            name = self._writer.append(key, npz)
            self._index.pop(key, None)
            return f"trajectories/{name}"
        atomic_write(os.path.join(self.directory, f"{key}.npz"), npz)
        return f"trajectories/{key}.npz"

    def sync(self, atomic_write):
        """Flush this process's pack to the disk and write its index (the end of a batch)."""
        self._writer.sync(atomic_write)

    def _rescan(self):
        """Index the entries appended since the last scan (every pack, in the order written): from its index file
        the first time a pack is seen, then by scanning the heads after what is known."""
        for name in _pack_names(self.directory):
            path = os.path.join(self.directory, name)
            size = os.path.getsize(path)
            known = self._scanned.get(name)
            if known is None:
                entries, known = read_index(path, size)
                for key, offset, length in entries:
                    self._index[key] = (path, offset, length)
            if known < size:
                for key, offset, length in pack_entries(path, known):
                    self._index[key] = (path, offset, length)
                    known = offset + length
            self._scanned[name] = known

    def source(self, key):
        """Run ``key``'s ``.npz``: bytes (from a pack) or a path (its file). ``FileNotFoundError`` when the
        store has none (``TrajectoryNotKept`` when its choice left it out); ValueError for a damaged pack."""
        path = os.path.join(self.directory, f"{key}.npz")
        if key not in self._index and os.path.exists(path):  # a file per run (a store of layout 1, or 2 before packs)
            return path
        if key not in self._index and self.packed:
            self._rescan()  # (only packs' heads: a store of layout 1 never lists its files)
        if key in self._index:
            path, offset, length = self._index[key]
            with open(path, "rb") as fh:
                fh.seek(offset)
                data = fh.read(length)
            if len(data) != length:
                raise ValueError(f"{path}: shorter than its index says (offset {offset}, {length} bytes)")
            return data
        if self.keep == ALL:
            return path  # (missing: the reader says so)
        raise TrajectoryNotKept(self.not_kept(key))

    def has(self, key):
        """Whether run ``key``'s trajectory is kept (without reading it)."""
        if os.path.exists(os.path.join(self.directory, f"{key}.npz")):
            return True
        if key not in self._index and self.packed:
            self._rescan()
        return key in self._index

    def not_kept(self, key):
        """The message for run ``key``'s trajectory, not kept by the store's choice."""
        why = ("the store keeps no trajectory" if self.keep == NONE else
               "the store keeps only the trajectories its report draws")
        return (f"run {key}: its trajectory was not kept ({why}: run.trajectories = {self.keep}) — rerun it into a "
                "new store with `dalembert run --trajectories all` (its key's case, engine and settings)")

    def keep_only(self, keys, atomic_write):
        """Drop every kept trajectory whose run is not in ``keys`` (the matrix ended with ``drawn``): a file per
        run is deleted; a pack is rewritten with its kept entries (a new pack, then the old one deleted).
        Returns how many were dropped."""
        self._writer.close()  # (its pack may be rewritten: a later entry goes to a new one)
        keys, dropped = set(keys), 0
        names = sorted(os.listdir(self.directory)) if os.path.isdir(self.directory) else []
        for name in names:
            if name.endswith(".npz") and not name.startswith(".") and name[:-4] not in keys:
                os.unlink(os.path.join(self.directory, name))
                dropped += 1
        packs = [os.path.join(self.directory, n) for n in _pack_names(self.directory)]
        entries = {path: pack_entries(path) for path in packs}
        last = {key: (path, offset) for path in packs for key, offset, _ in entries[path]}  # a key's last written
        for path in packs:
            kept = [(k, o, n) for k, o, n in entries[path] if k in keys and last[k] == (path, o)]
            dropped += len(entries[path]) - len(kept)
            if len(kept) == len(entries[path]):
                continue
            if kept:
                buf, offsets = io.BytesIO(), []
                with open(path, "rb") as fh:
                    for key, offset, length in kept:
                        fh.seek(offset)
                        npz = fh.read(length)
                        buf.write(_entry(key, npz))
                        offsets.append(buf.tell() - length)
                new = os.path.join(self.directory, new_name().rsplit(".", 1)[0] + PACK_SUFFIX)
                atomic_write(new, buf.getvalue())
                write_index(new, [k for k, _, _ in kept], offsets, [n for _, _, n in kept], buf.tell(), atomic_write)
            os.unlink(path)
            if os.path.exists(_index_path(path)):
                os.unlink(_index_path(path))
        self._index.clear()
        self._scanned.clear()
        return dropped
