"""Worker processes never outlive the process that started them, and end quietly on SIGTERM.

A worker calls ``die_with_parent`` first thing: on Linux the kernel sends it
SIGKILL the moment its parent dies (``prctl(PR_SET_PDEATHSIG)``), whatever
killed the parent (SIGKILL included, which no handler of the parent can see);
elsewhere a watchdog thread notices within ``WATCH_INTERVAL_S`` that the parent
is gone. Workers also ignore SIGINT: Ctrl-C reaches the whole process group,
and the parent alone ends the matrix (and its workers) cleanly.

SIGTERM ends a worker at once, quietly (the signal's default action, whatever handler
the parent had when it forked the worker: the command line's raises KeyboardInterrupt,
which would print a traceback in every worker of a group SIGTERM). A worker so stopped
dies of the signal, so its parent can tell the end of a run from outside (the run is
not stored, ``--resume`` runs it) from a run that crashed its process. The parent forks
inside ``sigterm_held`` so that a SIGTERM arriving before the worker has set this up
waits for it instead of reaching the parent's handler in the child.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
import time

__all__ = ["die_with_parent", "sigterm_held", "WATCH_INTERVAL_S"]

PR_SET_PDEATHSIG = 1  # <linux/prctl.h>
# How often the watchdog (platforms without PR_SET_PDEATHSIG) checks the parent.
WATCH_INTERVAL_S = 0.5


def die_with_parent(parent_pid=None):
    """End this process when its parent dies; ignore SIGINT, end at once on SIGTERM (module docstring).

    ``parent_pid``: the parent as the caller knows it (a forked worker's is the matrix
    process), so that a parent already dead before this call is noticed; None when the
    parent is an intermediary (a forkserver, which itself ends with the matrix process).
    """
    parent_pid = parent_pid or os.getppid()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if hasattr(signal, "pthread_sigmask"):  # a SIGTERM held since the fork (``sigterm_held``) ends it here
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
    armed = False
    if sys.platform.startswith("linux"):
        try:
            armed = ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
        except (OSError, AttributeError):
            armed = False
    if not armed:
        threading.Thread(target=_watch, args=(parent_pid,), daemon=True).start()
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os._exit(1)


@contextlib.contextmanager
def sigterm_held():
    """Hold SIGTERM in this thread while the block runs (a worker forked in it starts with SIGTERM held,
    until ``die_with_parent`` sets it to end the worker); a SIGTERM to this process that arrives meanwhile
    is delivered when the block ends. Does nothing where the platform cannot hold a signal."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def _watch(parent_pid):
    while os.getppid() == parent_pid:
        time.sleep(WATCH_INTERVAL_S)
    os._exit(1)
