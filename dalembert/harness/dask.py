"""Running a matrix on a Dask cluster: the same runs, records and store as the local pool."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from dataclasses import asdict

from dalembert.harness import threads
from dalembert.harness.execute import Timing, unfinished
from dalembert.harness.matrix import RunSpec
from dalembert.harness.pool import DEFAULT_TIMEOUT_S, finish
from dalembert.harness.truths import prepare_cases

__all__ = ["run_matrix_dask", "execute_isolated", "tasks_per_host"]


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
    payload = pickle.dumps({"spec": spec_json, "timing": timing_json, "truth": truth_npz, "parent": os.getpid()})
    n = _threads(hosts or {})
    env = None if n is None else {**os.environ, **{var: str(n) for var in threads.VARIABLES}}
    try:
        proc = subprocess.run([sys.executable, "-m", "dalembert.harness.worker"], input=payload, capture_output=True,
                              timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return unfinished(spec, "timeout", f"stopped after the per-run limit of {timeout:g} s"), None
    if proc.returncode != 0:
        return unfinished(spec, "failed", f"worker exited with {proc.returncode}: {proc.stderr.decode()[-500:]}"), None
    return pickle.loads(proc.stdout)


def run_matrix_dask(specs, store, scheduler, timeout=DEFAULT_TIMEOUT_S, timing=Timing(), progress=None):
    """Like ``dalembert.harness.pool.run_matrix`` on the Dask cluster at ``scheduler`` (address or Client).

    A run whose task the cluster lost (the scheduler gone, a worker lost) is the infrastructure's
    failure: it is not stored, and is returned in ``[(key, reason)]`` for ``--resume`` to run again.
    (A run's own failure never reaches here as an exception: ``execute_isolated`` returns it.)
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
            try:
                record, npz = fut.result()
            except Exception as e:  # noqa: BLE001 - whatever the cluster raises, the run was not run
                spec = futures[fut]
                lost.append((spec.key, f"{spec.case} {spec.engine} {spec.settings.label()}: the cluster lost its task "
                                       f"({type(e).__name__}: {e})"))
                continue
            finish(store, record, npz, progress, counts)
    finally:
        store.write_table()
        if client is not scheduler:
            client.close()
    return lost
