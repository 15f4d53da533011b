"""Files the user names (``--csv``, ``--json``, ``--parquet``): opened and written where they are.

A path the user names is the user's. It may be a regular file, a symlink (its
target is written, the link stays a link), a FIFO another program reads or a
device; so it is opened and written as ``open(path, "w")`` does, and never
replaced by renaming a temporary file over it: renaming is for the files a store
owns (``dalembert.store.atomic_write``), which no one else holds open. ``-`` is
standard output.

The content is made before the file is opened, so a command that fails while
computing leaves the user's file as it was. A failure to open or to write (a
full disk, ENOSPC from ``/dev/full``, a directory, no permission) is an
``OutputError`` naming the flag, the path and the fix; the command line turns it
into a message and a non-zero exit, never a "wrote".
"""

from __future__ import annotations

import os
import sys

__all__ = ["STDOUT", "OutputError", "check", "write", "shown"]

STDOUT = "-"  # the name of standard output, as most command-line tools take it


class OutputError(OSError):
    """A file the user named that cannot be written; the message names the flag, the path and the fix."""


def shown(path):
    """How ``path`` is named in messages: ``standard output`` for ``-``."""
    return "standard output" if path == STDOUT else str(path)


def check(path, flag):
    """Refuse, before anything runs, an output ``path`` that cannot be written.

    Parameters
    ----------
    path : str or os.PathLike
        The file the user named for ``flag``; ``-`` is standard output (always accepted).
    flag : str
        The option that named it (``--csv``), for the message.

    Raises
    ------
    OutputError
        When ``path`` is empty, a directory, an existing file this process may not write, or
        a new file in a directory that does not exist or may not be written.
    """
    path = os.fspath(path)
    if path == STDOUT:
        return
    if not path:
        raise OutputError(f"{flag}: empty — name a file, or - for standard output")
    if os.path.isdir(path):
        raise OutputError(f"{flag} {path}: cannot write it (a directory) — name a file")
    if os.path.exists(path):  # through a symlink: its target is what is written
        if not os.access(path, os.W_OK):
            raise OutputError(f"{flag} {path}: cannot write it (not writable by this user) — change its "
                              "permissions, or name another file")
        return
    parent = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(parent):
        raise OutputError(f"{flag} {path}: cannot write it (no directory {parent}) — make the directory, or "
                          "name a file in one that exists")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{flag} {path}: cannot write it ({parent} is not writable by this user) — name a "
                          "file in a directory you may write")


def write(path, data, flag):
    """Write ``data`` to the file the user named, in place (see the module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The file the user named; ``-`` is standard output. A regular file is truncated and
        written; a symlink's target is written; a FIFO or a device is opened and written as it is.
    data : str or bytes
        The whole content, made before this is called (bytes for binary formats such as Parquet).
    flag : str
        The option that named ``path`` (``--csv``), for the message.

    Raises
    ------
    OutputError
        When ``path`` cannot be opened or written, or a write or the final flush fails (ENOSPC).
        A regular file this call created is removed again: no half file is left behind as a result.
    """
    path = os.fspath(path)
    if path == STDOUT:
        try:
            if isinstance(data, bytes):
                sys.stdout.flush()  # what was printed before goes first
                sys.stdout.buffer.write(data)
                sys.stdout.buffer.flush()
            else:
                sys.stdout.write(data)
                sys.stdout.flush()
        except BrokenPipeError:
            raise  # the reader left: not this output's fault (the command line treats it as an end)
        except OSError as e:
            raise OutputError(f"{flag} -: cannot write to standard output ({e.strerror or e}) — free space "
                              "where it goes, or name a file") from None
        return
    created = not os.path.lexists(path)
    try:
        # newline="": the text is written as it was made (a CSV's \r\n stays \r\n on every OS)
        with open(path, "wb") if isinstance(data, bytes) else open(path, "w", newline="") as fh:
            fh.write(data)
    except OSError as e:
        if created and os.path.isfile(path) and not os.path.islink(path):
            try:
                os.unlink(path)
            except OSError:
                pass
        left = "" if created or not os.path.isfile(path) else "; what it holds now is incomplete"
        raise OutputError(f"{flag} {path}: cannot write it ({e.strerror or e}{left}) — free space there, fix "
                          "its permissions, or name another file") from None
