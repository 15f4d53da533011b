"""Running a matrix on this machine: a pool of long-lived worker processes.

Each worker is forked once, loads the matrix's engines (``Adapter.load``: their
imports, before any run, so that no run's time holds one), and runs one spec at a
time for as long as the matrix lasts. Every run keeps its own
timeout: a run that hangs past it, or a worker that dies, costs only that
worker, which is killed and replaced; the run is stored as ``timeout`` or
``failed`` (an engine that crashes its process is a finding) and the rest of
the matrix goes on. A worker stopped from outside, by SIGKILL (the system's
out-of-memory killer, an operator) or SIGTERM (an operator, a shutdown), ends its
run, which is not the run's failure: that run is not stored, the parent names it
among the runs lost to the infrastructure, and ``--resume`` runs it again. Every
finished run is written to the store at once; a store that cannot be written (its
disk full) ends the matrix with one error naming the store (``StoreWriteError``),
every run stored before it kept. Workers die with the process that started them
and end quietly on SIGTERM (``dalembert.harness.lifetime``), and each one's BLAS and
OpenMP thread pools are sized to its share of the cores (``dalembert.harness.threads``).

Affinity: a worker that becomes free takes, before anything else, a run of the same group as its last
(``affinity``: case, engine, integrator and options — the runs of a step or tolerance sweep), and
otherwise the first run of a group no other worker holds. An engine that compiles a program per model
and integrator (MJX: seconds per compilation, kept in the process) then compiles it once per worker
and group instead of once per run, where plain order would hand a sweep's runs to the workers in turn.
The matrix's runs and records are the same; only who runs which, and when, changes.

Batches (``run_matrix(batched=True)``, ``--batch``): the runs an engine steps as one batch of worlds
(``dalembert.harness.batches.groups``) go to one worker as one job, a ``Group``; its answer is a record
per world, its timeout, death or stop from outside every one of its runs'.

Engine environments: the runs of a versioned engine (``mujoco==3.6.0``, ``dalembert.environments``) go to
workers started from that environment's interpreter, a subprocess (``_Interpreter``: ``dalembert.harness.boot``,
on this process's dalembert code; the pipe's socket passed as a file descriptor) that serves the same protocol and sets up the same lifetime
(``die_with_parent``). A worker takes only runs of its interpreter; a free worker with none left in the
queue ends and a worker for the next run's interpreter starts in its place, so ``jobs`` workers run at
most. Timing, timeouts, deaths and stops from outside are told and stored as for any worker.
"""

from __future__ import annotations

import contextlib
import importlib
import json
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import threading
import time
from multiprocessing.connection import wait

from dalembert.harness import threads
from dalembert.harness.execute import Timing, execute, unfinished
from dalembert.harness.lifetime import die_with_parent, sigterm_held
from dalembert.harness.truths import prepare_cases
from dalembert.record import BAD_STATUSES

__all__ = ["run_matrix", "DEFAULT_TIMEOUT_S", "finish", "write_table", "affinity", "StoreWriteError",
           "STOPPED_FROM_OUTSIDE", "stopped_from_outside"]

DEFAULT_TIMEOUT_S = 600.0
# How long the parent waits for a worker's next message before checking the timeouts again.
POLL_S = 0.05
# How long a worker may take to leave when the matrix is done before it is killed.
SHUTDOWN_S = 5.0
# The signals that end a worker from outside (exit code -signal): the end of its run, not a failure of it.
STOPPED_FROM_OUTSIDE = {signal.SIGKILL: "(out of memory?)", signal.SIGTERM: "(an operator, a shutdown?)"}


class StoreWriteError(OSError):
    """The store could not be written (its disk full, read-only): the message names the store, the run and the fix;
    ``errno`` is the system's."""


def stopped_from_outside(spec, code):
    """Why ``spec``'s run was not run when its worker process ended with exit code ``code`` (``-signal``), if a
    signal in ``STOPPED_FROM_OUTSIDE`` ended it; else None (a crash: the run's failure)."""
    if code is None or -code not in STOPPED_FROM_OUTSIDE:
        return None
    sig = signal.Signals(-code)
    return (f"{spec.case} {spec.engine} {spec.settings.label()}: its worker was stopped by {sig.name} from outside "
            f"{STOPPED_FROM_OUTSIDE[sig]}")


def _jax_running():
    """Whether JAX's runtime is up in this process (its backends made: a computation ran, e.g. an MJX run in a
    notebook before ``api.run``): its threads are native, not counted by ``threading``, and JAX itself warns that
    a fork then "will likely lead to a deadlock". Its import alone starts none."""
    bridge = sys.modules.get("jax._src.xla_bridge")
    if bridge is None:
        return False
    initialized = getattr(bridge, "backends_are_initialized", None)
    return True if initialized is None else initialized()  # (a JAX without the question: assume it runs)


# What the workers use and get imported once, before they start (``_context``), not once each: the invariants'
# quadratures and the reference's adaptive integrators (``scipy.integrate``, with scipy's special, linalg and
# optimize: ~0.3 CPU-s), which dalembert imports where they are called so that a process starting no workers
# (``dalembert --help``, ``cases``, a report) does not pay them.
WORKER_IMPORTS = ("scipy.integrate",)


def _context():
    """``fork`` (fast: workers share the parent's imports, ``WORKER_IMPORTS`` imported here first) when this
    process has one thread; else a ``forkserver``, which preloads them: forking a process that has other
    threads (an in-process Dask client, a notebook's kernel threads, JAX's runtime) can copy a lock that
    another thread holds into the child (Python's documentation warns against it)."""
    if threading.active_count() == 1 and not _jax_running():
        for name in WORKER_IMPORTS:
            importlib.import_module(name)
        return mp.get_context("fork")
    ctx = mp.get_context("forkserver")
    # (the built-in cases too: every child's first run loads them, ~0.06 s of imports, nothing heavier than xml)
    ctx.set_forkserver_preload(["dalembert.harness.execute", "dalembert.adapters", "dalembert.cases", *WORKER_IMPORTS])
    return ctx


def _serve(conn, parent_pid, n_threads, engines):
    """A worker's life: run each ``(spec, timing, truth, concurrent, sent)`` it is sent, answer with
    ``(record, npz)``; a truth is sent once per case version (``None`` afterwards: kept here).
    ``n_threads``: what its native thread pools may use; ``engines``: ``(name, "module:Class")`` of the
    matrix's engines, loaded first (``Adapter.load``) so that the worker's first run holds no import."""
    from dalembert.adapters import get_adapter

    die_with_parent(parent_pid)
    threads.limit(n_threads)  # (before any engine starts its thread pools)
    for name, path in engines:
        try:
            get_adapter(name, path).load()
        except Exception:  # an engine that will not load fails each of its runs, with its message, in execute
            pass
    truths = {}
    while True:
        try:
            job = conn.recv()
        except EOFError:  # the parent closed the pipe: the matrix is over
            return
        if job is None:
            return
        spec, timing, truth, concurrent, sent = job
        if isinstance(spec, Group):  # several runs, one answer (``harness.batches``); truth: the new cases' truths
            from dalembert.harness.batches import execute_group

            truths.update(truth)
            conn.send(execute_group(spec.specs, timing, truths, concurrent, spec.batched, sent))
            continue
        key = (spec.case, spec.case_version)
        if truth is not None:
            truths[key] = truth
        conn.send(execute(spec, timing, truths[key], concurrent, sent))


class Group:
    """Runs a worker runs as one job (``run_matrix``'s ``groups``): ``specs`` (a tuple of RunSpec), as one batch of
    worlds when ``batched`` (``dalembert.harness.batches``). Its ``engine`` is its first run's, as its affinity."""

    def __init__(self, specs, batched=False):
        self.specs, self.batched = tuple(specs), batched
        self.engine = self.specs[0].engine


def _runs(job):
    """The runs of a job: a spec, or a ``Group``'s."""
    return job.specs if isinstance(job, Group) else (job,)


def affinity(spec):
    """The group of runs that share an engine's compiled program (module docstring); a ``Group``'s first run's."""
    spec = _runs(spec)[0]
    return (spec.case, spec.case_version, spec.engine, spec.settings.integrator, spec.settings.options)


def _take(queue, worker, held, pythons=None):
    """Pop from ``queue`` (``(group, spec)``, next run last) the run ``worker`` should do: one of its last
    run's group, else the first of a group not in ``held`` (the groups the busy workers are on), else the
    next; only runs of the worker's interpreter (``pythons``: engine -> interpreter, None for this one's),
    None when the queue holds none."""
    pythons = pythons or {}
    python = getattr(worker, "python", None)
    mine = [i for i in range(len(queue) - 1, -1, -1) if pythons.get(queue[i][0][2]) == python]
    for wanted in (lambda g: g == worker.group, lambda g: g not in held, lambda g: True):
        for i in mine:
            if wanted(queue[i][0]):
                return queue.pop(i)[1]
    return None


def _pythons(specs):
    """The interpreter of each engine of ``specs`` that runs in an engine environment (``mujoco==3.6.0``): its
    environment's; ValueError naming the command that makes a missing one (before any worker starts)."""
    from dalembert.adapters import get_adapter
    from dalembert.environments import is_versioned, require

    return {e: require(e, problem=get_adapter(e).version_problem).python for e in sorted({s.engine for s in specs})
            if is_versioned(e)}


class _Interpreter:
    """A worker process started from another interpreter (an engine environment's), with the interface of
    ``multiprocessing.Process`` the pool uses (``kill``, ``join``, ``is_alive``, ``exitcode``).

    ``fd``: the worker's end of the pipe (a socket), passed to it; the worker serves ``_serve``'s protocol on
    it (``dalembert.harness.worker.serve``), on this process's dalembert code (``dalembert.harness.boot``)."""

    def __init__(self, python, fd, parent, n_threads, engines):
        from dalembert.harness.boot import command

        args = json.dumps({"fd": fd, "parent": parent, "threads": n_threads, "engines": [list(e) for e in engines],
                           "environment": os.path.dirname(os.path.dirname(python))})  # (python: ENV/bin/python)
        self.popen = subprocess.Popen([*command(python, "serve"), args], pass_fds=(fd,), stdin=subprocess.DEVNULL)

    @property
    def exitcode(self):
        return self.popen.poll()  # -signal when a signal ended it, as multiprocessing's

    def is_alive(self):
        return self.popen.poll() is None

    def kill(self):
        with contextlib.suppress(ProcessLookupError):
            self.popen.kill()

    def join(self, timeout=None):
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.popen.wait(timeout)


class _Worker:
    """The parent's handle on one worker: its pipe, its process, the run it is doing."""

    def __init__(self, ctx, n_threads, engines, python=None):
        """``python``: the interpreter of an engine environment the worker runs in (None: this one's)."""
        self.conn, child = ctx.Pipe()
        self.python = python
        if python is not None:  # its parent is this process; SIGTERM held until it has its own, as a fork's
            with sigterm_held():
                self.proc = _Interpreter(python, child.fileno(), os.getpid(), n_threads, engines)
            child.close()
            self.spec, self.started, self.truths, self.group = None, 0.0, set(), None
            return
        # a forked worker's parent is this process; a forkserver's child's is the forkserver
        forked = ctx.get_start_method() == "fork"
        parent = os.getpid() if forked else None
        self.proc = ctx.Process(target=_serve, args=(child, parent, n_threads, engines), daemon=True)
        # a fork copies this process's SIGTERM handler (the command line's raises KeyboardInterrupt): held
        # until the worker has its own (``lifetime``); a forkserver's children start from its default
        with sigterm_held() if forked else contextlib.nullcontext():
            self.proc.start()
        child.close()
        self.spec, self.started, self.truths, self.group = None, 0.0, set(), None

    def submit(self, spec, timing, truth, concurrent, sent=None):
        """Send a run (``truth``: its case's) or a ``Group`` (``truth``: (case, version) -> truth of its runs)."""
        if isinstance(spec, Group):
            send = {k: t for k, t in truth.items() if k not in self.truths}
            keys = set(truth)
        else:
            key = (spec.case, spec.case_version)
            send, keys = None if key in self.truths else truth, {key}
        try:
            self.conn.send((spec, timing, send, concurrent, sent))
        except OSError:  # it died before it got the run (stopped, crashed): its end reaches ``wait`` as any death
            pass
        self.truths |= keys
        self.spec, self.started, self.group = spec, time.monotonic(), affinity(spec)

    def kill(self):
        self.proc.kill()
        self.proc.join()
        self.conn.close()

    def stop(self):
        try:
            self.conn.send(None)
        except OSError:
            pass
        self.proc.join(SHUTDOWN_S)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join()
        self.conn.close()


def finish(store, record, npz, progress, counts):
    """Store one finished run and report progress; ``StoreWriteError`` when the store cannot take it."""
    try:
        store.write_record(record, npz)
    except OSError as e:
        raise _unwritable(store, e, f"run {record.case} {record.engine} {record.settings_label}") from None
    counts["done"] += 1
    if record.status in BAD_STATUSES:
        counts["bad"] += 1
    if progress:
        progress(counts["done"], counts["total"], counts["bad"], record)


def write_table(store, failing=False):
    """Rebuild the store's table of runs at the end of a matrix. ``failing``: the matrix is ending on an
    error, which says more than a table that cannot be written (it is rebuilt from the rows by the next end)."""
    try:
        store.write_table()
    except OSError as e:
        if not failing:
            raise _unwritable(store, e, "its table of runs (runs.parquet)") from None


def _unwritable(store, e, what):
    """The ``StoreWriteError`` for ``e``, raised while writing ``what`` into ``store``."""
    err = StoreWriteError(f"{store.path}: cannot store {what} ({e.strerror or e}) — make room or fix the store's disk, "
                          f"then finish with: dalembert run --resume {store.path} (every run stored before is kept)")
    err.errno = e.errno
    return err


def run_matrix(specs, store, jobs=None, timeout=DEFAULT_TIMEOUT_S, timing=Timing(), progress=None, batched=False,
               sent=None):
    """Run ``specs`` not yet in ``store`` on ``jobs`` long-lived workers (default: the cores).

    ``batched``: the runs an engine can step as one batch of worlds (``dalembert.harness.batches``) go to a
    worker as one job, its timeout the batch's; the rest one by one. ``sent``: the trajectories the store keeps
    (``harness.sent.Sent``; None: all): a worker sends back no other.

    Returns the runs lost to the infrastructure, not stored: ``[(key, reason)]``.
    """
    from dalembert.harness.batches import groups

    pythons = _pythons(specs)  # (a missing environment refused before anything runs)
    truths = prepare_cases(specs, store)
    todo = [s for s in specs if s.key not in store.done_keys()]
    if batched:
        todo = [Group(g, True) if batch else g[0] for g, batch in groups(todo, True, chunk=1)]
    n_runs = sum(len(_runs(j)) for j in todo)
    n_threads = threads.per_worker(jobs or os.cpu_count())  # as asked (the manifest's), not as capped below
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(todo) or 1))
    ctx = _context()
    engines = tuple(sorted({(s.engine, s.adapter) for j in todo for s in _runs(j)}))

    def start(python):  # a worker for ``python``'s runs, loading only their engines
        return _Worker(ctx, n_threads, tuple(e for e in engines if pythons.get(e[0]) == python), python)

    counts = {"done": 0, "bad": 0, "total": n_runs}
    queue = [(affinity(s), s) for s in reversed(todo)]
    idle, busy, lost = [], {}, []  # busy: connection -> worker
    try:
        for i in range(jobs if todo else 0):  # one by one: a Ctrl-C meanwhile still finds the ones started
            idle.append(start(pythons.get(queue[-1 - i % len(queue)][1].engine)))
        while queue or busy:
            while queue and idle:
                worker = idle.pop()
                spec = _take(queue, worker, {w.group for w in busy.values()}, pythons)
                if spec is None:  # none of its interpreter's runs left: one for the next run's takes its place
                    worker.stop()
                    worker = start(pythons.get(queue[-1][1].engine))
                    spec = _take(queue, worker, {w.group for w in busy.values()}, pythons)
                truth = ({(s.case, s.case_version): truths[(s.case, s.case_version)] for s in _runs(spec)}
                         if isinstance(spec, Group) else truths[(spec.case, spec.case_version)])
                worker.submit(spec, timing, truth, len(busy) + 1, sent)
                busy[worker.conn] = worker
            # each worker stays in ``busy`` or ``idle`` until it is gone: a Ctrl-C at any point finds it
            for conn in wait(list(busy), timeout=POLL_S):
                worker = busy[conn]
                try:
                    answer = conn.recv()
                except EOFError:  # the worker died without an answer (crash, stopped): replace it
                    worker.kill()
                    del busy[conn]
                    code = worker.proc.exitcode
                    idle.append(start(worker.python))
                    for dead in _runs(worker.spec):
                        stopped = stopped_from_outside(dead, code)
                        if stopped:  # not the run's doing: not stored, --resume runs it
                            lost.append((dead.key, stopped))
                        else:
                            finish(store, unfinished(dead, "failed", f"worker process died (exit code {code})"), None,
                                   progress, counts)
                    continue
                idle.append(busy.pop(conn))  # (before a store that cannot take its run ends the matrix)
                for record, npz in (answer if isinstance(worker.spec, Group) else [answer]):
                    finish(store, record, npz, progress, counts)
            for conn, worker in list(busy.items()):
                if time.monotonic() - worker.started > timeout:
                    worker.kill()
                    del busy[conn]
                    for spec in _runs(worker.spec):
                        finish(store, unfinished(spec, "timeout", f"stopped after the per-run limit of {timeout:g} s"),
                               None, progress, counts)
                    idle.append(start(worker.python))
    except BaseException:  # an error or Ctrl-C: no worker is left behind, the error under way is the one told
        _close(idle, busy)
        write_table(store, failing=True)
        raise
    _close(idle, busy)
    write_table(store)
    return lost


def _close(idle, busy):
    """End every worker: the idle ones leave, the busy ones (their runs unfinished, not stored) are killed."""
    for worker in idle:
        worker.stop()
    for worker in busy.values():
        worker.kill()
