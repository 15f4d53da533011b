"""What a command says on the terminal: an error, a note, progress, and the command line it was."""

from __future__ import annotations

import shlex
import sys
import time

from dalembert.terminal import printable

__all__ = ["fail", "note", "progress_printer", "command_line"]


def fail(msg):
    """Print ``msg`` as the command line's error and return its exit status, 2 (the user's error)."""
    print(f"dalembert: error: {printable(msg)}", file=sys.stderr)
    return 2


def note(msg):
    """Print ``msg`` as a note on standard error (what the user should know, not an error)."""
    print(f"dalembert: note: {msg}", file=sys.stderr)


def progress_printer(stream=None):
    """``show(done, total, failures, record)``: one status line per finished run (rewritten in place
    on a terminal), with elapsed time and an estimate of what is left."""
    stream = stream or sys.stderr
    start = time.monotonic()
    tty = stream.isatty()

    def show(done, total, bad, record):
        elapsed = time.monotonic() - start
        eta = elapsed / done * (total - done) if done else float("nan")
        status = f"[{done}/{total}] failures {bad}  elapsed {elapsed:.0f} s  eta {eta:.0f} s"
        run = printable(f"{record.case} {record.engine} {record.settings_label}", newlines=False)  # a store's names
        if tty:
            stream.write(f"\r{status}  {run} {record.status}\033[K")
            if done == total:
                stream.write("\n")
        else:
            stream.write(f"{status}  {run}: {record.status}"
                         f"{' — ' + printable(record.message) if record.message else ''}\n")
        stream.flush()

    return show


def command_line():
    """This process's command line as ``dalembert ...`` (shell-quoted), for a manifest."""
    return shlex.join(["dalembert"] + sys.argv[1:])
