"""Running a matrix on a Dask cluster: the same runs, records and store as the local pool."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
from dataclasses import asdict

from dalembert.harness.execute import Timing, unfinished
from dalembert.harness.matrix import RunSpec
from dalembert.harness.pool import DEFAULT_TIMEOUT_S, finish
from dalembert.harness.truths import prepare_cases

__all__ = ["run_matrix_dask", "execute_isolated"]


def execute_isolated(spec_json, timing_json, truth_npz, timeout):
    """Run one spec in a fresh Python subprocess (the Dask task): ``(RunRecord, npz)``.

    A subprocess, not a fork: Dask workers are daemonic and cannot have
    multiprocessing children; the subprocess also gives a hard timeout.
    """
    spec = RunSpec.from_json(spec_json)
    payload = pickle.dumps({"spec": spec_json, "timing": timing_json, "truth": truth_npz, "parent": os.getpid()})
    try:
        proc = subprocess.run([sys.executable, "-m", "dalembert.harness.worker"], input=payload, capture_output=True,
                              timeout=timeout)
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
    futures = {client.submit(execute_isolated, s.to_json(), asdict(timing), truths[(s.case, s.case_version)],
                             timeout, pure=False): s for s in todo}
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
