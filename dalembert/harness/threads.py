"""How many threads a worker's native thread pools may start: its share of the cores.

A matrix runs in parallel over runs, one run per worker. numpy's and scipy's
OpenBLAS and the OpenMP runtimes the engines link each start as many threads as
the machine has cores, in every worker: with as many workers as cores that is
cores x cores threads competing for the cores (4 on 2 cores, 4096 on 64). Each
worker's pools are limited to ``cores // jobs`` threads (at least one), the rule
joblib's loky workers follow; ``--jobs 1`` leaves them at the cores. On a Dask
cluster each task's process gets its host's cores // the tasks that host's
workers run at once (``harness.dask``). Each run's provenance records the width.

Measured on this project's 2-core machine, whose run-to-run spread is some 15%
(``python -m benchmarks.matrix --t-final 2``, one invocation each, its speed-up
passes: every run timed once, with 1 and with 2 workers): every engine's runs
together went from a speed-up of 1.43 with the pools as wide as the machine to
1.73 with this limit, the reference engine's 64 runs from 1.62 to 2.07 (the same
runs in a separate pair of passes: 1.85 and 2.02). Two processes each running a
7-s slice of the reference's contract showed no difference between pools of 1
and 2 threads in three alternating tries: the gain is not in every workload.

XLA's own thread pool (MJX) is neither BLAS nor OpenMP and is left as the engine
configures it.
"""

from __future__ import annotations

import os

__all__ = ["per_worker", "limit", "VARIABLES"]

# What OpenBLAS and the OpenMP runtimes read for their pools' width when they load.
VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")


def per_worker(jobs, cores=None):
    """Threads each of ``jobs`` workers' native pools may use on ``cores`` (default: this machine's)."""
    return max(1, (cores or os.cpu_count() or 1) // max(1, jobs))


def limit(threads):
    """Limit this process's BLAS and OpenMP pools to ``threads``: those loaded now through their libraries'
    calls, those loaded later (an engine imported in a forkserver's worker) through the variables they read
    when they load."""
    from threadpoolctl import threadpool_limits

    for var in VARIABLES:
        os.environ[var] = str(threads)
    threadpool_limits(limits=threads)
