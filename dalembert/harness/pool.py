"""Running a matrix on this machine: each run in its own worker process, with a timeout.

Every finished run is written to the store at once; a failure, a divergence or
a timeout is a stored result, and the rest of the matrix goes on.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import threading
import time
from multiprocessing.connection import wait

from dalembert.harness.execute import Timing, execute, unfinished
from dalembert.harness.truths import prepare_cases
from dalembert.record import BAD_STATUSES

__all__ = ["run_matrix", "DEFAULT_TIMEOUT_S", "finish"]

DEFAULT_TIMEOUT_S = 600.0


def _context():
    """``fork`` (fast: workers share the parent's imports) when this process has one
    Python thread; else a ``forkserver``: forking a process that has other threads
    (an in-process Dask client, a notebook's kernel threads) can copy a lock that
    another thread holds into the child (Python's documentation warns against it)."""
    if threading.active_count() == 1:
        return mp.get_context("fork")
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["dalembert.harness.execute", "dalembert.adapters"])
    return ctx


def _child(conn, spec, timing, truth, concurrent):
    try:
        conn.send(execute(spec, timing, truth, concurrent))
    finally:
        conn.close()


def finish(store, record, npz, progress, counts):
    """Store one finished run and report progress."""
    store.write_record(record, npz)
    counts["done"] += 1
    if record.status in BAD_STATUSES:
        counts["bad"] += 1
    if progress:
        progress(counts["done"], counts["total"], counts["bad"], record)


def run_matrix(specs, store, jobs=None, timeout=DEFAULT_TIMEOUT_S, timing=Timing(), progress=None):
    """Run ``specs`` not yet in ``store``, ``jobs`` at a time, each in a forked worker.

    Returns the list of keys run now.
    """
    truths = prepare_cases(specs, store)
    todo = [s for s in specs if s.key not in store.done_keys()]
    jobs = max(1, jobs or os.cpu_count() or 1)
    ctx = _context()
    counts = {"done": 0, "bad": 0, "total": len(todo)}
    running = {}  # connection -> (process, spec, start)
    queue = list(reversed(todo))
    while queue or running:
        while queue and len(running) < jobs:
            spec = queue.pop()
            parent, child = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_child, daemon=True,
                               args=(child, spec, timing, truths[(spec.case, spec.case_version)], len(running) + 1))
            proc.start()
            child.close()
            running[parent] = (proc, spec, time.monotonic())
        ready = wait(list(running), timeout=0.05)
        for conn in ready:
            proc, spec, _ = running.pop(conn)
            try:
                record, npz = conn.recv()
            except EOFError:  # the worker died without an answer (crash, killed)
                proc.join()
                record, npz = unfinished(spec, "failed", f"worker process died (exit code {proc.exitcode})"), None
            proc.join()
            conn.close()
            finish(store, record, npz, progress, counts)
        for conn, (proc, spec, start) in list(running.items()):
            if time.monotonic() - start > timeout:
                proc.kill()
                proc.join()
                conn.close()
                running.pop(conn)
                finish(store, unfinished(spec, "timeout", f"stopped after the per-run limit of {timeout:g} s"), None,
                       progress, counts)
    store.write_table()
    return [s.key for s in todo]
