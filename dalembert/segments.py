"""Row segments: the append-only files a store of layout 2 keeps its runs in.

A segment (``segments/<name>.jsonl``) holds one finished run per line: its row
(``RunRecord.to_row()``) as strict JSON, ``key`` first and the other columns sorted,
ended by a newline. Each writing process appends to a segment of its own, named when
it writes its first row (``new_name``: the UTC time, the process, a random tag), so no
two processes ever write one file and a resumed matrix never appends after a line a
crash cut short.

A row is committed when its whole line, newline included, is in the file: each line is
given to the kernel in one ``os.write`` on a file opened ``O_APPEND`` (the rest of a
partial write follows at once), so a process killed at any point leaves complete lines
and at most one torn last line. Readers ignore a torn last line (the text after the
last newline): its run is not stored, and ``--resume`` runs it again. Any other line
that is not a row is damage, reported with the file and the line number. Like
``dalembert.store.atomic_write`` the lines are not synced one by one (a sync per run
would cost a disk flush per row); ``SegmentWriter.sync`` flushes the file to the disk
at the end of each batch, so a power cut loses at most the batch under way, which
``--resume`` redoes.

Rows are never rewritten: a segment only grows, and only while its process writes it.
"""

from __future__ import annotations

import json
import os
import secrets
import time

__all__ = ["SEGMENT_SUFFIX", "SegmentWriter", "close_synced", "complete_length", "complete_lines", "line_key", "new_name",
           "parse_lines", "row_line", "segment_keys", "segment_names", "segment_rows"]

SEGMENT_SUFFIX = ".jsonl"


def new_name():
    """A segment name no other process takes: UTC time (so names sort as written), PID, 8 random hex digits."""
    return f"{time.strftime('%Y%m%dT%H%M%S', time.gmtime())}-{os.getpid()}-{secrets.token_hex(4)}{SEGMENT_SUFFIX}"


def row_line(row):
    """The bytes of ``row`` (a dict with a ``key``) as one segment line: ``{"key": ..., <sorted columns>}\\n``.

    The key comes first so that ``line_key`` reads it without parsing the rest of the line.
    """
    ordered = {"key": row["key"], **{k: row[k] for k in sorted(row) if k != "key"}}
    return (json.dumps(ordered, allow_nan=False) + "\n").encode()


_KEY_PREFIX = b'{"key": '
_DECODER = json.JSONDecoder()


def line_key(line):
    """The run key of a segment line (bytes, newline excluded), read from its start only; None when the
    line does not start as ``row_line`` writes one (the full parse, ``segment_rows``, says why)."""
    if not line.startswith(_KEY_PREFIX):
        return None
    try:
        key, _ = _DECODER.raw_decode(line[:4096].decode("utf-8", "replace"), len(_KEY_PREFIX))
    except ValueError:
        return None
    return key if isinstance(key, str) else None


def complete_length(data):
    """The length of ``data``'s complete lines (up to and including its last newline): what follows is a
    torn last line, a row whose write a crash cut short."""
    return data.rfind(b"\n") + 1


def segment_names(directory):
    """The segments in ``directory``, sorted (as written); none when it does not exist. Other files are not
    segments (a temporary file, a note), as in ``rows/``."""
    try:
        names = os.listdir(directory)
    except FileNotFoundError:
        return []
    return sorted(n for n in names if n.endswith(SEGMENT_SUFFIX) and not n.startswith("."))


def parse_lines(lines, where, fix, first=1):
    """The rows of complete segment lines (bytes, newline ended or not): ``[(line number, row dict)]``.

    Parameters
    ----------
    lines : iterable of bytes
        Complete lines, in order (a torn last line already left out: ``complete_length``).
    where : str
        The segment's path, for messages.
    fix : callable(str) -> str
        The fix for a damaged line, given the line's key (or "?" when unreadable).
    first : int
        The number of the first line (1-based), for messages.

    Raises
    ------
    ValueError
        A line that is not a JSON object with a string ``key``: ``<where> line <n>: ... — <fix>``.
    """
    out = []
    for n, line in enumerate(lines, start=first):
        try:
            row = json.loads(line)
        except ValueError as e:
            raise ValueError(f"{where} line {n}: cannot be read as a stored run ({type(e).__name__}: {e}) — "
                             f"{fix(line_key(line) or '?')}") from None
        if not isinstance(row, dict) or not isinstance(row.get("key"), str):
            raise ValueError(f"{where} line {n}: not a run dalembert wrote (no key) — {fix('?')}")
        out.append((n, row))
    return out


def complete_lines(path):
    """The complete lines of the segment at ``path`` (bytes, newline included), read one by one: a torn last
    line is left out."""
    with open(path, "rb") as fh:
        for line in fh:
            if line.endswith(b"\n"):
                yield line


def segment_rows(path, fix):
    """Every row of the segment at ``path``, in order: ``[(line number, row dict)]`` (``parse_lines``)."""
    return parse_lines(complete_lines(path), path, fix)


def segment_keys(path):
    """The key of every complete line of the segment at ``path`` (None for a line ``line_key`` cannot read)."""
    return [line_key(line) for line in complete_lines(path)]


class SegmentWriter:
    """One process's segment, opened on its first row (``append``) and only ever appended to.

    Parameters
    ----------
    directory : str
        The store's ``segments/`` directory (made when missing).
    """

    def __init__(self, directory):
        self.directory = directory
        self.name = None  # the segment's file name, once its first row is written
        self._fd = None
        self._pid = None

    def append(self, row):
        """Append ``row`` as one line (``row_line``); returns when the kernel holds all of it."""
        if self._fd is None or self._pid != os.getpid():  # a forked child never writes its parent's segment
            os.makedirs(self.directory, exist_ok=True)
            self.name = new_name()
            self._fd = os.open(os.path.join(self.directory, self.name),
                               os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND | os.O_CLOEXEC, 0o666)
            self._pid = os.getpid()
        view = memoryview(row_line(row))
        try:
            while view:  # a write the kernel cut short (a signal, a disk filling up): the rest at once
                view = view[os.write(self._fd, view):]
        except OSError:  # (a full disk): the line may be torn, so no row may follow it in this segment
            fd, self._fd = self._fd, None
            os.close(fd)
            raise

    def sync(self):
        """Flush the segment to the disk (the end of a batch); nothing when no row was written."""
        if self._fd is not None and self._pid == os.getpid():
            os.fsync(self._fd)

    def close(self):
        """Sync and close; the next ``append`` starts a new segment."""
        if self._fd is not None:
            fd, self._fd = self._fd, None
            close_synced(fd, self._pid)


def close_synced(fd, pid):
    """Close an appending writer's file ``fd``, flushed to the disk first when this process (``pid``) opened it
    (a forked child's copy is closed unsynced: the parent owns the file)."""
    try:
        if pid == os.getpid():
            os.fsync(fd)
    finally:
        os.close(fd)
