"""Stability maps on Dask: how a round's probes are cut into tasks."""

import pytest

from dalembert.harness.batches import DEFAULT_CHUNK, groups
from dalembert.harness.matrix import expand


@pytest.mark.parametrize("runs,threads,chunk", [
    (10, 2, DEFAULT_CHUNK),  # a small round: chunks of DEFAULT_CHUNK, as before
    (1000, 2, 125),  # a map's round on a small cluster: TASKS_PER_THREAD (4) tasks per thread
    (1000, 100, DEFAULT_CHUNK),  # a large cluster: never fewer runs per task than DEFAULT_CHUNK
    (1000, 0, 250),  # a cluster that reports no thread yet counts as one
])
def test_a_task_takes_more_runs_where_a_round_has_many_per_thread(runs, threads, chunk):
    from dalembert.harness.dask import chunk_for

    assert chunk_for(runs, threads) == chunk


def test_a_large_round_on_two_workers_is_a_few_tasks_per_thread():
    """A round of 240 probes of one curve family (240 spins at one step) on 2 worker threads: 8 tasks of 30, not
    15 of DEFAULT_CHUNK; an explicit chunk is kept."""
    from dalembert.harness.dask import TASKS_PER_THREAD, chunk_for

    specs, _ = expand(cases=["free_top_fast_spin"], engines=["reference"], integrators=["rk4"], dts=[1e-2],
                      params={"spin": [5.0 + i for i in range(240)], "t_final": 0.5, "sample_interval": 0.1})
    tasks = groups(specs, chunk=chunk_for(len(specs), 2))
    assert len(tasks) == 2 * TASKS_PER_THREAD and {len(g) for g, _ in tasks} == {30}
    assert len(groups(specs, chunk=DEFAULT_CHUNK)) == 15
