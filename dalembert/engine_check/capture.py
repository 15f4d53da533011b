"""What an engine prints: captured at file descriptors 1 and 2 (engines print from C, past ``sys.stdout``), and
on import in a fresh interpreter (a module imports once per process)."""

from __future__ import annotations

import contextlib
import ctypes
import functools
import importlib.util
import io
import os
import subprocess
import sys
import tempfile

__all__ = ["output", "printed_problem", "import_output", "IMPORT_TIMEOUT_S", "SHOWN_CHARS"]

# A fresh interpreter that imports dalembert and the engine (Drake, JAX: several seconds on 2 busy cores) is
# given this long (s) before it counts as hung: a guard against a stuck import, not a measure of speed.
IMPORT_TIMEOUT_S = 600.0
# How much of what was printed a problem quotes (characters).
SHOWN_CHARS = 200

_LOOK_AT = ("contract item 9: an adapter prints nothing — remove the print, silence the engine's own output (its "
            "verbosity option, a log level) or send it to the Outcome's info")


class _Printed:
    text = ""


def _flush_c():
    """Flush C's stdio buffers (an engine's printf to a pipe or file is block-buffered)."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):  # no C library to flush (Windows: CDLL(None) is a TypeError)
        pass


@contextlib.contextmanager
def output():
    """Capture everything written to file descriptors 1 and 2 and to ``sys.stdout``/``sys.stderr`` (warnings
    included) in the block; yields an object whose ``text`` holds it once the block ends."""
    printed = _Printed()
    sys.stdout.flush()
    sys.stderr.flush()
    _flush_c()
    python_level = io.StringIO()
    with tempfile.TemporaryFile() as sink:
        saved = [os.dup(1), os.dup(2)]
        try:
            os.dup2(sink.fileno(), 1)
            os.dup2(sink.fileno(), 2)
            with contextlib.redirect_stdout(python_level), contextlib.redirect_stderr(python_level):
                yield printed
        finally:
            _flush_c()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            sink.seek(0)
            printed.text = (sink.read().decode(errors="replace") + python_level.getvalue()).strip()


def printed_problem(where, text):
    """The ``Problem`` of output ``text`` printed during ``where``."""
    from dalembert.engine_check import Problem

    shown = text if len(text) <= SHOWN_CHARS else text[:SHOWN_CHARS] + "..."
    return Problem("quiet", f"printed during {where}: {shown!r}", _LOOK_AT)


def import_output(path):
    """What importing the adapter ``path`` (``"module:Class"``), making one and calling its ``load()`` prints in a
    fresh interpreter that sees this one's ``sys.path``: ``(text, error)``, error a line or ``""``.

    Asked once per process for the same adapter, ``sys.path`` and module file (its path and modification time): a
    fresh interpreter's import is the same then, and costs a second or more (Drake, JAX: several).
    """
    module = path.partition(":")[0]
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError):  # (its parent package fails to import: the fresh interpreter says how)
        spec = None
    origin = spec.origin if spec is not None and spec.origin and os.path.exists(spec.origin) else None
    return _import_output(path, tuple(sys.path), origin, os.stat(origin).st_mtime_ns if origin else None)


@functools.lru_cache(maxsize=None)
def _import_output(path, sys_path, origin, mtime_ns):
    """``import_output`` of ``path`` with this ``sys.path`` (``origin`` and ``mtime_ns``: the cache's key only)."""
    code = ("import importlib, sys\n"
            "module, name = sys.argv[1].split(':')\n"
            "adapter = getattr(importlib.import_module(module), name)()\n"
            "try:\n    adapter.load()\nexcept ImportError:\n    pass\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys_path if p))
    with tempfile.TemporaryDirectory() as empty:  # run from an empty folder: nothing there shadows a module
        done = subprocess.run([sys.executable, "-c", code, path], capture_output=True, text=True, env=env, cwd=empty,
                              timeout=IMPORT_TIMEOUT_S)
    if done.returncode != 0:
        return "", (done.stderr.strip().splitlines() or ["(no message)"])[-1]
    return (done.stdout + done.stderr).strip(), ""
