"""Atomic file writes: a reader or an interrupted run never sees half a file.

Every file a store holds, and every file the report writes into it, goes to a temporary file in
the same directory first, then ``os.replace`` (atomic on POSIX within one file system).
"""

from __future__ import annotations

import os
import tempfile

__all__ = ["atomic_write"]


def _umask():
    """The process umask, read without changing it where the OS tells it (Linux's
    /proc/self/status): setting and restoring it would race with other threads' files."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write(path, data):
    """Write ``data`` (bytes or str) to ``path`` atomically, with the mode ``open()`` would give it
    (0o666 less the umask: ``mkstemp`` makes 0600 files, which a report served or shared cannot be)."""
    mode = "wb" if isinstance(data, bytes) else "w"
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=".tmp-", suffix=os.path.basename(path))
    try:
        os.fchmod(fd, 0o666 & ~_umask())
        with os.fdopen(fd, mode) as fh:
            fh.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
