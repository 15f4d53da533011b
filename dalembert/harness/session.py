"""A matrix's store from start to end: what its manifest says, and the one writer that holds it.

``start`` makes the new store (taking its one-writer lock before checking that no run is
there yet) with the manifest of a matrix and the cases and truths built for it (by
``truths.build``, before: every refusal comes before the store exists); ``end`` records
when and under what load it ended. The command line and the Python API both go through them.
"""

from __future__ import annotations

import os
from datetime import datetime

from dalembert.harness import threads

__all__ = ["manifest", "start", "end", "load_average", "default_out"]


def load_average():
    """The machine's 1, 5 and 15-minute load averages (None where the OS has none)."""
    try:
        return list(os.getloadavg())
    except OSError:
        return None


def default_out(prefix=""):
    """``results/<prefix>-<local time>``: where a matrix goes when no directory is given."""
    return os.path.join("results", prefix + ("-" if prefix else "") + datetime.now().strftime("%Y-%m-%dT%H-%M-%S"))


def manifest(specs, command, timeout, timing, jobs, scheduler=None):
    """The manifest of a new matrix of ``specs``: harness, machine, engines, command, timing, load."""
    import dalembert
    from dalembert.adapters import get_adapter
    from dalembert.store import harness_commit, library_versions, machine_info, now

    return {
        "harness_version": dalembert.__version__, "harness_commit": harness_commit(), "machine": machine_info(),
        "engines": {e: get_adapter(e).version() for e in sorted({s.engine for s in specs})},
        "libraries": library_versions(),
        "command": command, "started": now(), "ended": None, "timeout_s": timeout, "timing": vars(timing),
        "jobs": jobs, "threads_per_worker": None if scheduler else threads.per_worker(jobs), "scheduler": scheduler,
        "load_average": {"start": load_average(), "end": None},
        "specs": [s.to_json() for s in specs],
    }


def start(out, manifest, cases=None, runs=None):
    """A new store at ``out`` (created) and its one-writer lock, taken before the check that no
    run is there yet (two runs into one directory cannot both pass it); ValueError naming
    ``--out`` when it cannot be. ``cases``: what ``truths.build`` made for the matrix, written
    into the new store; ``runs``: the most runs it will hold (None: its specs; ``Store.create``)."""
    from dalembert.harness.truths import store_cases
    from dalembert.store import Store

    try:
        os.makedirs(out, exist_ok=True)
    except OSError as err:
        raise ValueError(f"--out: cannot create {out!r}: {err.strerror}") from None
    if not os.access(out, os.W_OK):
        raise ValueError(f"--out: cannot write to {out!r}")
    store = Store(out)
    lock = store.writer(manifest.get("command", ""))
    if store.exists():
        lock.release()
        raise ValueError(f"--out: {out!r} already holds a run — use --resume {out} or another directory")
    try:
        store = store.create(manifest, runs=runs)
        store_cases(store, cases or {})
    except BaseException:
        lock.release()
        raise
    return store, lock


def end(store):
    """Record in the manifest when the matrix ended and the load then."""
    from dalembert.store import now

    manifest = store.manifest()
    manifest["ended"] = now()
    manifest.setdefault("load_average", {})["end"] = load_average()
    store.write_manifest(manifest)
