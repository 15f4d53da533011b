"""Benchmark of stability maps at scale: runs per second on a Dask cluster, and how the store and
the report grow with the number of rows.

    python -m benchmarks.map [--rows 1000,10000,100000]

1. A small map on a ``LocalCluster`` of 2 worker processes (1 thread each): the reference's RK4
   and RKMK4 on ``free_top_fast_spin`` swept over 4 spins from 5 to 500 rad/s, each curve
   searched for its stability boundary (``--search dt``, bracket 1e-3..1e-1 s, resolution 1.5,
   1-s horizon sampled every 0.1 s), through the command line as a user runs it. Prints the
   runs and the wall time: runs per second.
2. The store and the report fed synthetic rows (copies of that map's runs under new keys, each
   a new probe of its curve): for each size, the time to write the rows (one atomic file each,
   as workers do), to read them back as records, to rebuild ``runs.parquet``, and to build the
   report — each per 1000 rows, so that growth worse than linear shows.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import replace

SIZES = (1_000, 10_000, 100_000)


def _cluster_map(tmp, engine="reference", integrators=("rk4", "rkmk4"), spins=4, batch=False):
    """The map of part 1 on a 2-worker ``LocalCluster``: ``(store path, wall s)``. Each Dask task runs a chunk of
    probes (a search round's probes of one curve family: ``dalembert.harness.batches``), or with ``batch`` on an
    engine that has batches (``mujoco_warp``, ``mjx``) the spins of one step as one batch of worlds."""
    from distributed import LocalCluster

    out = os.path.join(tmp, "map")
    args = [a for i in integrators for a in ("--integrator", i)] + (["--batch"] if batch else [])
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "dalembert.harness.cli", "run", "--case", "free_top_fast_spin",
                               "--param", f"spin=log:5,500,{spins}", "--param", "t_final=1", "--param",
                               "sample_interval=0.1", "--engine", engine, *args,
                               "--search", "dt", "--dt", "1e-3,1e-1", "--resolution", "1.5",
                               "--scheduler", cluster.scheduler_address, "--out", out], capture_output=True, text=True)
        wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(proc.stderr[-2000:])
    return out, wall


def _synthetic(source, path, n):
    """A store at ``path`` holding ``n`` rows made from ``source``'s runs and its case records."""
    import shutil

    from dalembert.store import Store

    records = source.records()
    store = Store(path).create(source.manifest())
    for d in ("cases", "truth"):
        shutil.copytree(os.path.join(source.path, d), os.path.join(path, d), dirs_exist_ok=True)
    t0 = time.perf_counter()
    for i in range(n):
        base = records[i % len(records)]
        k = 1 + i // len(records)  # each copy a finer probe of the same curve
        dt = base.settings.dt / k if base.settings.dt else None
        store.write_record(replace(base, key=f"synthetic{i:07d}", settings=replace(base.settings, dt=dt),
                                   trajectory=""))
    return store, time.perf_counter() - t0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--rows", default=",".join(map(str, SIZES)), help="store sizes to feed, comma-separated")
    args = p.parse_args(argv)
    from dalembert.reports.render import build_report
    from dalembert.store import Store

    with tempfile.TemporaryDirectory() as tmp:
        out, wall = _cluster_map(tmp)
        source = Store(out)
        n = len(source.done_keys())
        print(f"map on a 2-worker LocalCluster: {n} runs in {wall:.1f} s = {n / wall:.2f} runs/s "
              f"(4 spins x 2 integrators, boundary search; {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f})")
        print(f"\n{'rows':>8} {'write':>10} {'read':>10} {'parquet':>10} {'report':>10}   (s per 1000 rows)")
        for size in (int(x) for x in args.rows.split(",")):
            store, write = _synthetic(source, os.path.join(tmp, f"rows{size}"), size)
            t0 = time.perf_counter()
            store.records()
            read = time.perf_counter() - t0
            t0 = time.perf_counter()
            store.write_table()
            table = time.perf_counter() - t0
            t0 = time.perf_counter()
            build_report(store)
            report = time.perf_counter() - t0
            k = size / 1000
            print(f"{size:>8} {write / k:>10.3f} {read / k:>10.3f} {table / k:>10.3f} {report / k:>10.3f}"
                  f"   (totals {write:.1f} / {read:.1f} / {table:.1f} / {report:.1f} s)", flush=True)
            shutil_rm(store.path)


def shutil_rm(path):
    import shutil

    shutil.rmtree(path, ignore_errors=True)


if __name__ == "__main__":
    main()
