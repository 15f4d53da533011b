"""How many threads a worker's native thread pools may start: its share of the cores.

A matrix runs in parallel over runs, one run per worker. numpy's and scipy's
OpenBLAS and the OpenMP runtimes the engines link each start as many threads as
the machine has cores, in every worker: with as many workers as cores that is
cores x cores threads competing for the cores (4 on 2 cores, 4096 on 64). Each
worker's pools are limited to ``cores // jobs`` threads (at least one), the rule
joblib's loky workers follow; ``--jobs 1`` leaves them at the cores.

On this project's 2-core machines the gain is within the run-to-run spread:
``python -m benchmarks.matrix``'s speed-up passes, the reference engine's 64 runs
at a 2-s horizon each timed once, took 78.6 s with 1 worker and 42.6 s with 2
(speed-up 1.85; 1.62 in another invocation) with the pools as wide as the
machine, and 77.1 s and 38.2 s (2.02) with them at one thread; two processes each
running a 7-s slice of the reference's contract showed no difference between
pools of 1 and 2 threads in three alternating tries.

XLA's own thread pool (MJX) is neither BLAS nor OpenMP and is left as the engine
configures it.
"""

from __future__ import annotations

import os

__all__ = ["per_worker", "limit"]


def per_worker(jobs, cores=None):
    """Threads each of ``jobs`` workers' native pools may use on ``cores`` (default: this machine's)."""
    return max(1, (cores or os.cpu_count() or 1) // max(1, jobs))


def limit(threads):
    """Limit this process's BLAS and OpenMP pools (those loaded now and their settings) to ``threads``."""
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=threads)
