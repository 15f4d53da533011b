"""Benchmark of the run matrix on every installed engine: harness overhead and parallel speed-up.

    python -m benchmarks.matrix [--t-final 4] [--engine mujoco ...]

Runs the default matrix's selection (every case not tagged ``hard``, every
installed engine, every integrator and option variant, dt 1e-2 and 1e-3, rtol
1e-6 and 1e-9) twice in one invocation, with 1 and with 2 worker processes, and
prints per engine:

* the share of each run's worker time spent outside building the model and
  stepping (read-back, errors against the truth, invariants, serialization,
  timing bookkeeping), for runs whose stepping takes more than 50 ms (median
  and worst) and over all its runs (worker seconds outside / worker seconds);
* the wall time of the matrix with ``--jobs 1`` and ``--jobs 2`` and the speed-up (each pass
  with an empty JAX compilation cache of its own, so MJX compiles alike in both).

Goals: overhead <= 10% for runs over 50 ms, so that what a row records is the
engine's stepping, not the harness's; speed-up >= 1.7 on 2 cores (85% parallel
efficiency: the runs are independent, only starting workers and writing the store
are serial). Timings are taken on whatever else the machine is doing: the
figures are ratios within one invocation, and the load average is printed.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time

import numpy as np

from dalembert.harness.execute import Timing
from dalembert.harness.matrix import expand
from dalembert.harness.pool import run_matrix
from dalembert.store import Store

LONG_RUN_S = 0.05  # the overhead goal applies to runs whose stepping takes longer than this
OVERHEAD_GOAL = 0.10
SPEEDUP_GOAL = 1.7


def _outside(r):
    """Worker seconds of run ``r`` outside build and stepping."""
    return r.cost.worker_s - r.cost.build_s - r.cost.stepping_total_s


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--t-final", type=float, default=None, help="horizon of every case (s); default: each case's own")
    p.add_argument("--engine", action="append", help="engines (default: every installed one)")
    args = p.parse_args(argv)
    params = {"t_final": args.t_final} if args.t_final else {}
    specs, skipped = expand(engines=args.engine, dts=[1e-2, 1e-3], rtols=[1e-6, 1e-9], params=params)
    engines = sorted({s.engine for s in specs})
    print(f"matrix: {len(specs)} runs, engines {', '.join(engines)}"
          + (f" (not installed: {'; '.join(skipped)})" if skipped else ""))
    walls, records = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for jobs in (1, 2):
            store = Store(f"{tmp}/jobs{jobs}").create({})
            if "mjx" in engines:  # each pass compiles afresh: neither loads what the other compiled
                import jax

                jax.config.update("jax_compilation_cache_dir", f"{tmp}/jax{jobs}")
            load = os.getloadavg()[0]
            t0 = time.perf_counter()
            run_matrix(specs, store, jobs=jobs, timing=Timing())
            walls[jobs] = time.perf_counter() - t0
            records[jobs] = store.records()
            print(f"--jobs {jobs}: {walls[jobs]:.1f} s wall, {sum(r.ok for r in records[jobs])} ok "
                  f"(load average {load:.2f} before, {os.getloadavg()[0]:.2f} after, {os.cpu_count()} cores)")
    print(f"\nshare of worker time outside build and stepping (--jobs 1 runs; goal <= {OVERHEAD_GOAL:.0%} "
          f"for runs > {LONG_RUN_S * 1e3:.0f} ms)")
    print(f"{'engine':<11}{'runs>50ms':>10}{'median':>9}{'worst':>9}   {'all runs':>9}  worst run")
    for engine in engines:
        ok = [r for r in records[1] if r.engine == engine and r.ok]
        long = [r for r in ok if r.cost.wall_s_median > LONG_RUN_S]
        share = np.array([_outside(r) / r.cost.worker_s for r in long])
        overall = sum(_outside(r) for r in ok) / sum(r.cost.worker_s for r in ok) if ok else float("nan")
        worst = max(long, key=lambda r: _outside(r) / r.cost.worker_s) if long else None
        print(f"{engine:<11}{len(long):>10}{np.median(share) if len(share) else float('nan'):>9.1%}"
              f"{share.max() if len(share) else float('nan'):>9.1%}   {overall:>9.1%}  "
              + (f"{worst.case} {worst.settings_label} ({_outside(worst):.3f} of {worst.cost.worker_s:.3f} s)"
                 if worst else ""))
    print(f"\nspeed-up with 2 jobs: {walls[1] / walls[2]:.2f} (goal >= {SPEEDUP_GOAL})")


if __name__ == "__main__":
    main()
