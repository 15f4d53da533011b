"""Running a matrix on a Dask cluster: the same runs, records and store as the local pool.

Each task runs a group of runs in a fresh Python process (``harness.batches.groups``): with
``batched``, the runs an engine steps as one batch of worlds (a map's row: the swept parameter at one
step); otherwise a chunk of at most ``chunk`` runs of one engine, integrator and options, one after
another, so a task's process start, the engine's import and its compilation are paid once per chunk,
not per probe (``chunk=1``: a task per run). By default a chunk grows past ``DEFAULT_CHUNK`` runs where a
batch of runs would otherwise make more than ``TASKS_PER_THREAD`` tasks per worker thread (``chunk_for``):
a map's round of 1000 probes on 2 workers is ~8 tasks, not ~63. Progress and an estimate of the time left are
told per run as each task's runs are stored (``progress``). A task's process stopped from outside (SIGTERM,
SIGKILL: ``pool.STOPPED_FROM_OUTSIDE``) ends its runs without failing them, as a local worker's: the
task raises ``WorkerStopped``, its runs are not stored, ``--resume`` runs them.
"""

from __future__ import annotations

import math
import os
import pickle
import subprocess
import sys
from dataclasses import asdict

from dalembert.environments import is_versioned, require
from dalembert.harness import boot, threads
from dalembert.harness.batches import DEFAULT_CHUNK, groups
from dalembert.harness.execute import Timing, unfinished
from dalembert.harness.matrix import RunSpec
from dalembert.harness.pool import DEFAULT_TIMEOUT_S, finish, stopped_from_outside, write_table
from dalembert.harness.truths import prepare_cases

__all__ = ["run_matrix_dask", "execute_isolated", "execute_group_isolated", "tasks_per_host", "chunk_for",
           "TASKS_PER_THREAD", "WorkerStopped"]

# Tasks per worker thread a batch of runs is cut into, at the least: enough that a slow task (a loaded host, a
# long probe) leaves the other threads little to wait for at the end of a round, few enough that a task's process
# start (~1 CPU s: importing dalembert and the engine, against ~0.014 CPU s a MuJoCo probe of benchmarks/map.py
# --probes) is paid over many runs.
TASKS_PER_THREAD = 4


def chunk_for(runs, threads, chunk=DEFAULT_CHUNK):
    """Runs per task for a batch of ``runs`` runs on a cluster of ``threads`` worker threads: ``chunk``, or more
    where ``runs`` would make more than ``TASKS_PER_THREAD`` tasks per thread."""
    return max(chunk, math.ceil(runs / (TASKS_PER_THREAD * max(1, threads))))


class WorkerStopped(RuntimeError):
    """A run's process was stopped from outside: the run was not run (not its failure); the message names it."""


def tasks_per_host(client):
    """Tasks each host of the cluster at ``client`` runs at once: its workers' threads, summed (host -> int)."""
    from distributed.comm import get_address_host

    out = {}
    for address, n in client.nthreads().items():  # every worker (scheduler_info's list depends on the client)
        host = get_address_host(address)
        out[host] = out.get(host, 0) + n
    return out


def _threads(hosts):
    """This task's share of its host's cores (``harness.threads``): the host's cores over the tasks its workers
    run at once (``hosts``, from ``tasks_per_host``; this worker's own threads for a host not in it). None
    outside a Dask worker."""
    from distributed import get_worker
    from distributed.comm import get_address_host

    try:
        worker = get_worker()
    except ValueError:
        return None
    return threads.per_worker(hosts.get(get_address_host(worker.address), worker.state.nthreads))


def execute_isolated(spec_json, timing_json, truth_npz, timeout, hosts=None, sent=None):
    """Run one spec in a fresh Python subprocess (the Dask task): ``(RunRecord, npz)``, npz None where ``sent`` (a
    ``harness.sent.Sent``: the store's choice) does not want it.

    A subprocess, not a fork: Dask workers are daemonic and cannot have
    multiprocessing children; the subprocess also gives a hard timeout. Its BLAS and
    OpenMP pools get its share of the host's cores (``_threads``; ``hosts`` from
    ``tasks_per_host``), as a local pool's workers do.
    """
    spec = RunSpec.from_json(spec_json)
    command, environment = [sys.executable, "-m", "dalembert.harness.worker"], None
    if is_versioned(spec.engine):  # its environment's interpreter, on this worker's host (ValueError: none there)
        made = require(spec.engine)
        command, environment = boot.command(made.python, "run"), made.path
    payload = pickle.dumps({"spec": spec_json, "timing": timing_json, "truth": truth_npz, "parent": os.getpid(),
                            "environment": environment, "sent": sent})
    n = _threads(hosts or {})
    env = None if n is None else {**os.environ, **{var: str(n) for var in threads.VARIABLES}}
    try:
        proc = subprocess.run(command, input=payload, capture_output=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return unfinished(spec, "timeout", f"stopped after the per-run limit of {timeout:g} s"), None
    stopped = stopped_from_outside(spec, proc.returncode)
    if stopped:
        raise WorkerStopped(stopped)
    if proc.returncode != 0:
        return unfinished(spec, "failed", f"worker exited with {proc.returncode}: {proc.stderr.decode()[-500:]}"), None
    return pickle.loads(proc.stdout)


def execute_group_isolated(specs_json, timing_json, truths_npz, timeout, hosts=None, batched=False, sent=None):
    """Run a group of specs (``harness.batches.groups``) in one fresh Python subprocess (a Dask task):
    ``[(RunRecord, npz)]`` in their order. ``truths_npz``: ``[((case, version), npz)]`` of their cases; ``timeout``:
    the per-run limit, the group's being that times its runs; ``sent``: the trajectories wanted back. As
    ``execute_isolated`` otherwise."""
    specs = [RunSpec.from_json(s) for s in specs_json]
    command, environment = [sys.executable, "-m", "dalembert.harness.batches"], None
    if is_versioned(specs[0].engine):  # (a group is one engine's) its environment's interpreter, on this code
        made = require(specs[0].engine)
        command, environment = boot.command(made.python, "batches"), made.path
    payload = pickle.dumps({"specs": specs_json, "timing": timing_json, "truths": truths_npz, "parent": os.getpid(),
                            "environment": environment, "batched": batched, "sent": sent})
    n = _threads(hosts or {})
    env = None if n is None else {**os.environ, **{var: str(n) for var in threads.VARIABLES}}
    limit = timeout * len(specs)
    try:
        proc = subprocess.run(command, input=payload, capture_output=True, timeout=limit, env=env)
    except subprocess.TimeoutExpired:
        return [(unfinished(s, "timeout", f"stopped after its task's limit of {limit:g} s ({len(specs)} runs of "
                                          f"{timeout:g} s)"), None) for s in specs]
    stopped = stopped_from_outside(specs[0], proc.returncode)
    if stopped:
        raise WorkerStopped(stopped)
    if proc.returncode != 0:
        why = f"worker exited with {proc.returncode}: {proc.stderr.decode()[-500:]}"
        return [(unfinished(s, "failed", why), None) for s in specs]
    return pickle.loads(proc.stdout)


def run_matrix_dask(specs, store, scheduler, timeout=DEFAULT_TIMEOUT_S, timing=Timing(), progress=None,
                    batched=False, chunk=None, sent=None):
    """Like ``dalembert.harness.pool.run_matrix`` on the Dask cluster at ``scheduler`` (address or Client).

    ``sent``: the trajectories the store keeps (``harness.sent.Sent``; None: all): a task sends back no other.

    ``batched``: a task per batch of worlds where the engine has batches; the other runs in tasks of at most
    ``chunk`` runs (None: ``chunk_for`` the runs to do and the cluster's threads; module docstring).

    A run whose task the cluster lost (the scheduler gone, a worker lost) is the infrastructure's
    failure: it is not stored, and is returned in ``[(key, reason)]`` for ``--resume`` to run again.
    (A run's own failure never reaches here as an exception: the task returns it; the runs of a task whose
    process was stopped from outside, ``WorkerStopped``, are lost too, named by its message.)
    """
    from distributed import Client, as_completed

    from dalembert.store import trajectory_to_npz

    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    truths = {k: trajectory_to_npz(t) for k, t in prepare_cases(specs, store).items()}
    todo = [s for s in specs if s.key not in store.done_keys()]
    counts = {"done": 0, "bad": 0, "total": len(todo)}
    hosts = tasks_per_host(client)  # (workers that join later share by their own threads)
    chunk = chunk or chunk_for(len(todo), sum(hosts.values()))
    futures = {}
    for group, batch in groups(todo, batched, chunk):
        cases = sorted({(s.case, s.case_version) for s in group})
        futures[client.submit(execute_group_isolated, [s.to_json() for s in group], asdict(timing),
                              [(k, truths[k]) for k in cases], timeout, hosts, batch, sent, pure=False)] = group
    lost = []
    try:
        for fut in as_completed(futures):
            group = futures[fut]
            try:
                results = fut.result()
            except WorkerStopped as e:
                lost += [(s.key, str(e)) for s in group]
                continue
            except Exception as e:  # noqa: BLE001 - whatever the cluster raises, the runs were not run
                lost += [(s.key, f"{s.case} {s.engine} {s.settings.label()}: the cluster lost its task "
                                 f"({type(e).__name__}: {e})") for s in group]
                continue
            for record, npz in results:
                finish(store, record, npz, progress, counts)
    except BaseException:  # the error under way is the one told (``pool.write_table``)
        write_table(store, failing=True)
        raise
    else:
        write_table(store)
    finally:
        if client is not scheduler:
            client.close()
    return lost
