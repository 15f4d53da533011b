"""Benchmark of the run matrix on every installed engine: harness overhead and parallel speed-up.

    python -m benchmarks.matrix [--t-final 4] [--engine mujoco ...]

Runs the default matrix's selection (every case not tagged ``hard``, every
installed engine, every integrator and option variant, dt 1e-2 and 1e-3, rtol
1e-6 and 1e-9) one engine at a time, each engine's runs three times in one
invocation — with the default timing policy on 1 worker, then timed once on 1 and
on 2 workers — and prints per engine:

* the share of each run's worker time spent outside building the model and
  stepping, for runs whose stepping takes more than 50 ms (median and worst) and
  over all its runs (worker seconds outside / worker seconds), from the first pass
  (the default policy, as a matrix runs it); and of it, the read-back (the
  adapter turning the engine's sampled states into body terms, once per run: where
  an engine gives reactions only from a dynamics evaluation, one per sample) and
  the rest (errors against the truth, invariants, the audit, serialization, timing
  bookkeeping, each repeat's time outside the engine's stepping); for the shorter
  runs, that time in ms (their fixed cost);
* the wall time of its runs with ``--jobs 1`` and ``--jobs 2``, the speed-up, and
  where it goes: the cores each pass kept busy (CPU seconds of the workers and of
  the parent, which writes the store, per wall second) and the CPU seconds the
  same runs took in each. Speed-up = (busy 2 / busy 1) / (CPU 2 / CPU 1): busy
  with 2 workers short of 2 is a core left idle (the harness's doing, or a tail of
  long runs); CPU seconds that grow with a second worker are contention, the
  machine's and the engine's (two vCPUs that share a physical core, a memory bus or
  a clock budget; an engine whose one worker already keeps more than one core busy
  with threads of its own). These two passes time each run once after its warm-up
  (``SPEEDUP_TIMING``), so both do the same work: the default policy repeats a run
  until a time budget is spent, so the work of two passes under different
  contention can differ. Each pass gets an empty JAX compilation cache of its
  own, so MJX compiles alike in all three.

The cases' records and truths are computed once, before any pass, and copied
into each pass's store: a matrix computes them once per case version, before its
runs (``dalembert.harness.truths``), so they are not the runs' wall time.

Goals: overhead <= 10% for runs over 50 ms, so that what a row records is the
engine's stepping, not the harness's; speed-up >= 1.7 on 2 cores (85% parallel
efficiency: the runs are independent, only starting workers and writing the store
are serial). Timings are taken on whatever else the machine is doing: the
figures are ratios within one invocation, and the load average is printed.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
import time

import numpy as np

from dalembert.harness.execute import QUICK, Timing
from dalembert.harness.matrix import expand, split
from dalembert.harness.pool import run_matrix
from dalembert.harness.truths import prepare_cases
from dalembert.store import Store

LONG_RUN_S = 0.05  # the overhead goal applies to runs whose stepping takes longer than this
OVERHEAD_GOAL = 0.10
SPEEDUP_GOAL = 1.7
JOBS = (1, 2)
# The speed-up passes' policy: one warm-up and one timed repeat, whatever the speed (module docstring).
SPEEDUP_TIMING = QUICK


def _outside(r):
    """Worker seconds of run ``r`` outside build and stepping."""
    return r.cost.worker_s - r.cost.build_s - r.cost.stepping_total_s


def _cpu_s():
    """CPU seconds (user + system) of this process and of its children that have ended (the workers)."""
    return sum(u.ru_utime + u.ru_stime for u in (resource.getrusage(resource.RUSAGE_SELF),
                                                 resource.getrusage(resource.RUSAGE_CHILDREN)))


def _pass(specs, cases, out, jobs, timing):
    """Run ``specs`` into a new store at ``out`` (holding ``cases``' records and truths) on ``jobs`` workers.

    Returns (records, wall s, busy cores: CPU s per wall s, 1-minute load average after).
    """
    shutil.copytree(cases, out)
    store = Store(out)
    if any(s.engine == "mjx" for s in specs):  # each pass compiles afresh: neither loads what another compiled
        import jax

        jax.config.update("jax_compilation_cache_dir", f"{out}-jax")
    cpu, t0 = _cpu_s(), time.perf_counter()
    run_matrix(specs, store, jobs=jobs, timing=timing)
    wall = time.perf_counter() - t0
    return store.records(), wall, (_cpu_s() - cpu) / wall, os.getloadavg()[0]


def _overhead_row(engine, records):
    ok = [r for r in records if r.ok]
    long = [r for r in ok if r.cost.wall_s_median > LONG_RUN_S]
    outside = np.array([_outside(r) / r.cost.worker_s for r in long])
    readback = np.array([r.cost.readback_s / r.cost.worker_s for r in long])
    overall = sum(_outside(r) for r in ok) / sum(r.cost.worker_s for r in ok) if ok else float("nan")
    worst = long[int(np.argmax(outside))] if long else None

    def spread(share):  # median and worst ("—": no run that long)
        if not len(share):
            return f"{'—':>8}{'—':>7}"
        return f"{np.median(share):>8.1%}{share.max():>7.1%}"

    return (f"{engine:<11}{len(long):>9}{spread(outside)}{spread(readback)}{spread(outside - readback)}"
            f"{overall:>9.1%}  "
            + (f"{worst.case} {worst.settings_label} ({_outside(worst):.3f} of {worst.cost.worker_s:.3f} s, read-back "
               f"{worst.cost.readback_s:.3f} s)" if worst else f"no run's stepping over {LONG_RUN_S * 1e3:.0f} ms"))


def _short_row(engine, records):
    short = [r for r in records if r.ok and r.cost.wall_s_median <= LONG_RUN_S]
    outside = np.array([_outside(r) for r in short]) * 1e3
    readback = np.array([r.cost.readback_s for r in short]) * 1e3
    if not short:
        return f"{engine:<11}{0:>6}"
    return (f"{engine:<11}{len(short):>6}{np.median(outside):>9.1f}{outside.max():>8.1f}{np.median(readback):>11.1f}"
            f"{np.median([r.cost.worker_s for r in short]) * 1e3:>9.1f}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--t-final", type=float, default=None, help="horizon of every case (s); default: each case's own")
    p.add_argument("--engine", action="append", help="engines (default: every installed one)")
    args = p.parse_args(argv)
    params = {"t_final": args.t_final} if args.t_final else {}
    specs, skipped = expand(engines=args.engine, dts=[1e-2, 1e-3], rtols=[1e-6, 1e-9], params=params)
    specs, refused = split(specs)  # as ``dalembert run``: a run an engine refuses is listed, not run
    engines = sorted({s.engine for s in specs})
    print(f"matrix: {len(specs)} runs ({len(refused)} refused, not run), engines {', '.join(engines)}, "
          f"{os.cpu_count()} cores"
          + (f" (not installed: {'; '.join(skipped)})" if skipped else ""))
    records, walls, busy = {}, {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        cases = f"{tmp}/cases"
        prepare_cases(specs, Store(cases).create({}))
        for engine in engines:
            mine = [s for s in specs if s.engine == engine]
            load = os.getloadavg()[0]
            records[engine], *_ = _pass(mine, cases, f"{tmp}/{engine}", 1, Timing())
            for jobs in JOBS:
                _, walls[engine, jobs], busy[engine, jobs], after = _pass(mine, cases, f"{tmp}/{engine}-{jobs}", jobs,
                                                                          SPEEDUP_TIMING)
            print(f"{engine}: {len(mine)} runs, timed once: --jobs 1 {walls[engine, 1]:.1f} s, --jobs 2 "
                  f"{walls[engine, 2]:.1f} s (load average {load:.2f} before, {after:.2f} after)", flush=True)
    print(f"\nshare of worker time outside build and stepping (default timing, --jobs 1; goal <= {OVERHEAD_GOAL:.0%} "
          f"for runs > {LONG_RUN_S * 1e3:.0f} ms)")
    print(f"{'':<20}{'outside':>15}{'read-back':>15}{'the rest':>15}")
    print(f"{'engine':<11}{'runs>50ms':>9}" + f"{'median':>8}{'worst':>7}" * 3 + f"{'all runs':>9}  worst run")
    for engine in engines:
        print(_overhead_row(engine, records[engine]))
    print(f"\nthe shorter runs (stepping <= {LONG_RUN_S * 1e3:.0f} ms): their fixed cost, ms of worker time outside "
          "build and stepping per run, and of it the read-back; and a run's whole worker time")
    print(f"{'engine':<11}{'runs':>6}{'median':>9}{'worst':>8}{'read-back':>11}{'worker':>9}")
    for engine in engines:
        print(_short_row(engine, records[engine]))
    print(f"\n--jobs 1 against --jobs 2, each run timed once (the same work): wall s, cores kept busy (CPU s per "
          f"wall s) and CPU s (goal: speed-up >= {SPEEDUP_GOAL})")
    print(f"{'engine':<11}{'runs':>6}{'wall 1':>8}{'busy':>6}{'CPU 1':>8}{'wall 2':>8}{'busy':>6}{'CPU 2':>8}"
          f"{'CPU +':>7}{'speed-up':>10}")
    for engine in engines + ["all"]:
        keys = engines if engine == "all" else [engine]
        w = {j: sum(walls[e, j] for e in keys) for j in JOBS}
        cpu = {j: sum(busy[e, j] * walls[e, j] for e in keys) for j in JOBS}
        n = sum(len(records[e]) for e in keys)
        print(f"{engine:<11}{n:>6}{w[1]:>8.1f}{cpu[1] / w[1]:>6.2f}{cpu[1]:>8.1f}{w[2]:>8.1f}{cpu[2] / w[2]:>6.2f}"
              f"{cpu[2]:>8.1f}{cpu[2] / cpu[1] - 1:>7.0%}{w[1] / w[2]:>10.2f}")
    print("speed-up = (busy 2 / busy 1) / (CPU 2 / CPU 1): busy 2 short of 2 is time a core sat idle (the harness's, "
          "or a tail of long runs); CPU + is what the same runs cost more when two share the machine (the machine's "
          "and the engine's)")


if __name__ == "__main__":
    main()
