"""Benchmark of stability maps at scale: runs per second on a Dask cluster, and how the store and
the report grow with the number of rows.

    python -m benchmarks.map [--rows 10000,100000,1000000] [--json FILE] [--layout 2] [--source STORE]

1. A small map on a ``LocalCluster`` of 2 worker processes (1 thread each): the reference's RK4
   and RKMK4 on ``free_top_fast_spin`` swept over 4 spins from 5 to 500 rad/s, each curve
   searched for its stability boundary (``--search dt``, bracket 1e-3..1e-1 s, resolution 1.5,
   1-s horizon sampled every 0.1 s), through the command line as a user runs it. Prints the
   runs and the wall time: runs per second.
2. The store and the report fed synthetic rows (copies of that map's runs under new keys, each
   a new probe of its curve) in the store layout ``--layout`` (``dalembert.store.LAYOUTS``; 2, the
   segments a map past ``FILES_UP_TO`` runs takes, by default): for each size, the time to write
   the rows (``Store.write_record`` one by one, as the matrix's parent does), to rebuild
   ``runs.parquet`` (``write_table``, as at the end of a matrix), to read the rows back as a table
   (``Store.table``: what aggregates read), to read them back as ``RunRecord`` objects
   in bulk (``Store.table_records``, what the report reads) and to build the report (``build_report``) — each
   per 1000 rows, so that growth worse than linear shows. ``--json FILE`` writes the totals, s:
   ``{"rows": {"10000": {"write_s": .., "table_s": .., "read_s": .., "records_s": .., "report_s": ..}}}``,
   each step's CPU time beside (``write_cpu_s``, ...: on a loaded machine the wall time is mostly waiting)
   (``read_s`` was the records' read before layouts: compare it with ``records_s`` across versions).
   ``--report-up-to N`` leaves the records and the report out above N rows (null in the JSON): a
   million records need several GB of memory. ``--source STORE`` takes the rows' models from a store
   already written instead of running part 1.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import replace

SIZES = (10_000, 100_000, 1_000_000)


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


def _synthetic(source, path, n, layout):
    """A store at ``path`` of ``layout`` holding ``n`` rows made from ``source``'s runs and its case records."""
    import shutil

    from dalembert.store import Store

    records = source.records()
    store = Store(path).create(source.manifest(), layout=layout)
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


def _cpu():
    """This process's CPU time so far, s, every thread's (Arrow reads with threads): beside the wall time, it
    shows what a loaded machine took from a step."""
    import resource

    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def store_figures(source, path, size, layout, report=True):
    """The store's times, s, for ``size`` synthetic rows written at ``path``: ``{"write_s", "table_s", "read_s",
    "records_s", "report_s"}`` (the module docstring; the last two None without ``report``), each step's CPU
    time beside as ``<step>_cpu_s``, and the 1-minute load average at the end, ``load``."""
    from dalembert.reports.render import build_report

    steps = ("write_s", "table_s", "read_s", "records_s", "report_s")
    figures = {k: None for k in steps} | {k.replace("_s", "_cpu_s"): None for k in steps}
    c0 = _cpu()
    store, figures["write_s"] = _synthetic(source, path, size, layout)
    figures["write_cpu_s"] = _cpu() - c0
    for name, step in (("table_s", store.write_table), ("read_s", store.table),
                       *((("records_s", store.table_records), ("report_s", lambda: build_report(store))) if report else ())):
        t0, c0 = time.perf_counter(), _cpu()
        step()
        figures[name], figures[name.replace("_s", "_cpu_s")] = time.perf_counter() - t0, _cpu() - c0
    return {**figures, "load": os.getloadavg()[0]}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--rows", default=",".join(map(str, SIZES)), help="store sizes to feed, comma-separated")
    p.add_argument("--json", metavar="FILE", help="write the store's figures to FILE as JSON")
    p.add_argument("--layout", type=int, default=2, help="the store layout of the synthetic stores (1 or 2)")
    p.add_argument("--report-up-to", type=int, default=None, metavar="N",
                   help="read the records and build the report only for stores of up to N rows")
    p.add_argument("--source", metavar="STORE", help="take the rows' models from this store (no cluster map)")
    args = p.parse_args(argv)
    from dalembert.store import Store

    with tempfile.TemporaryDirectory() as tmp:
        if args.source:
            source = Store.open(args.source)
        else:
            out, wall = _cluster_map(tmp)
            source = Store(out)
            n = len(source.done_keys())
            print(f"map on a 2-worker LocalCluster: {n} runs in {wall:.1f} s = {n / wall:.2f} runs/s "
                  f"(4 spins x 2 integrators, boundary search; {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f})")
        print(f"\nstore layout {args.layout}; s per 1000 rows (totals in s after them)\n"
              f"{'rows':>8} {'write':>8} {'parquet':>8} {'table':>8} {'records':>8} {'report':>8}")
        results = {}
        for size in (int(x) for x in args.rows.split(",")):
            report = args.report_up_to is None or size <= args.report_up_to
            f = store_figures(source, os.path.join(tmp, f"rows{size}"), size, args.layout, report)
            results[str(size)] = f
            order = ("write_s", "table_s", "read_s", "records_s", "report_s")
            per = " ".join("       -" if f[k] is None else f"{f[k] / (size / 1000):>8.3f}" for k in order)
            total = " / ".join("-" if f[k] is None else f"{f[k]:.1f} ({f[k.replace('_s', '_cpu_s')]:.1f})" for k in order)
            print(f"{size:>8} {per}   (totals, s (CPU s): {total}; load {f['load']:.2f})", flush=True)
            shutil_rm(os.path.join(tmp, f"rows{size}"))
            if args.json:  # after each size: a long run stopped later keeps what it measured
                with open(args.json, "w") as fh:
                    json.dump({"rows": results, "layout": args.layout, "cores": os.cpu_count()}, fh, indent=1)


def shutil_rm(path):
    import shutil

    shutil.rmtree(path, ignore_errors=True)


if __name__ == "__main__":
    main()
