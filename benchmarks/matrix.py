"""Benchmark of the run matrix: parallel speed-up and harness overhead.

    python -m benchmarks.matrix [--t-final 4]

Runs the same matrix (every case, the reference engine, every integrator,
dt 1e-2 and 2e-3, rtol 1e-6 and 1e-9: 32 runs) with 1 and with 2 worker
processes in one invocation, and prints both wall times, the speed-up, and the
harness overhead per run: the time a worker spends outside the engine's
stepping (build, warm-up bookkeeping, errors against the truth, serialization)
as a fraction of its total. Goals: speed-up >= 1.7 on 2 cores (85% parallel
efficiency: the runs are independent, so only starting the workers and writing
the store may be serial); overhead <= 10% for runs longer than 50 ms, so that
the cost each row records is the engine's stepping, not the harness's.
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np

from dalembert.harness.matrix import expand
from dalembert.harness.pool import run_matrix
from dalembert.store import Store

LONG_RUN_S = 0.05  # the overhead goal applies to runs whose stepping takes longer than this


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--t-final", type=float, default=4.0, help="horizon of every case (s), default 4")
    args = p.parse_args(argv)
    specs, _ = expand(engines=["reference"], dts=[1e-2, 2e-3], rtols=[1e-6, 1e-9],
                      params={"t_final": args.t_final})
    print(f"matrix: {len(specs)} runs (every case, reference engine, t_final = {args.t_final:g} s)")
    walls = {}
    with tempfile.TemporaryDirectory() as tmp:
        for jobs in (1, 2):
            store = Store(f"{tmp}/jobs{jobs}").create({})
            t0 = time.perf_counter()
            run_matrix(specs, store, jobs=jobs)
            walls[jobs] = time.perf_counter() - t0
            records = store.records()
            print(f"--jobs {jobs}: {walls[jobs]:.1f} s wall, {sum(r.ok for r in records)} ok")
        long_runs = [r for r in records if r.ok and r.cost.wall_s_median > LONG_RUN_S]
        frac = np.array([1.0 - r.cost.stepping_total_s / r.cost.worker_s for r in long_runs])
    speedup = walls[1] / walls[2]
    print(f"speed-up with 2 jobs: {speedup:.2f} (goal >= 1.7)")
    print(f"harness overhead, runs > {LONG_RUN_S * 1e3:.0f} ms ({len(frac)} runs): median {np.median(frac):.1%}, "
          f"max {np.max(frac):.1%} of the worker's time (goal <= 10%)")


if __name__ == "__main__":
    main()
