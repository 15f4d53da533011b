"""Running a matrix on a Dask cluster: the same runs, records and store as the local pool.

Each run is a Dask task that runs it in a fresh Python process; that process stopped from
outside (SIGTERM, SIGKILL: ``pool.STOPPED_FROM_OUTSIDE``) ends the run without failing it, as a
local worker's: the task raises ``WorkerStopped``, the run is not stored, ``--resume`` runs it.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from dataclasses import asdict

from dalembert.environments import is_versioned, require
from dalembert.harness import boot, threads
from dalembert.harness.execute import Timing, unfinished
from dalembert.harness.matrix import RunSpec
from dalembert.harness.pool import DEFAULT_TIMEOUT_S, finish, stopped_from_outside, write_table
from dalembert.harness.truths import prepare_cases

__all__ = ["run_matrix_dask", "execute_isolated", "tasks_per_host", "WorkerStopped"]


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


def execute_isolated(spec_json, timing_json, truth_npz, timeout, hosts=None):
    """Run one spec in a fresh Python subprocess (the Dask task): ``(RunRecord, npz)``.

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
                            "environment": environment})
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


def run_matrix_dask(specs, store, scheduler, timeout=DEFAULT_TIMEOUT_S, timing=Timing(), progress=None):
    """Like ``dalembert.harness.pool.run_matrix`` on the Dask cluster at ``scheduler`` (address or Client).

    A run whose task the cluster lost (the scheduler gone, a worker lost) is the infrastructure's
    failure: it is not stored, and is returned in ``[(key, reason)]`` for ``--resume`` to run again.
    (A run's own failure never reaches here as an exception: ``execute_isolated`` returns it; a run whose process
    was stopped from outside, ``WorkerStopped``, is lost too, named by its message.)
    """
    from distributed import Client, as_completed

    from dalembert.store import trajectory_to_npz

    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    truths = {k: trajectory_to_npz(t) for k, t in prepare_cases(specs, store).items()}
    todo = [s for s in specs if s.key not in store.done_keys()]
    counts = {"done": 0, "bad": 0, "total": len(todo)}
    hosts = tasks_per_host(client)  # (workers that join later share by their own threads)
    futures = {client.submit(execute_isolated, s.to_json(), asdict(timing), truths[(s.case, s.case_version)],
                             timeout, hosts, pure=False): s for s in todo}
    lost = []
    try:
        for fut in as_completed(futures):
            spec = futures[fut]
            try:
                record, npz = fut.result()
            except WorkerStopped as e:
                lost.append((spec.key, str(e)))
                continue
            except Exception as e:  # noqa: BLE001 - whatever the cluster raises, the run was not run
                lost.append((spec.key, f"{spec.case} {spec.engine} {spec.settings.label()}: the cluster lost its task "
                                       f"({type(e).__name__}: {e})"))
                continue
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
