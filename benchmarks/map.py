"""Benchmark of stability maps at scale: runs per second on a Dask cluster, and how the store and
the report grow with the number of rows.

    python -m benchmarks.map [--rows 10000,100000,1000000] [--json FILE] [--layout 2] [--source STORE]
    python -m benchmarks.map --probes 10000 [--jobs 2] [--trajectories all|drawn|none] [--json FILE] [--log FILE]

1. A small map on a ``LocalCluster`` of 2 worker processes (1 thread each): the reference's RK4
   and RKMK4 on ``free_top_fast_spin`` swept over 4 spins from 5 to 500 rad/s, each curve
   searched for its stability boundary (``--search dt``, bracket 1e-3..1e-1 s, resolution 1.5,
   1-s horizon sampled every 0.1 s), through the command line as a user runs it. Prints the
   runs and the wall time: runs per second. ``--probes N`` runs instead a map sized to ~N probes
   (``probe_map``: MuJoCo's RK4 on ``free_top_fast_spin`` over N / ``PROBES_PER_CURVE`` spins, each
   curve bisected to a resolution of 1.05), on the cluster or, with ``--jobs J``, on J local worker
   processes without Dask (the same map, for the ratio), and prints the probes, the wall time, probes
   per second, the search's rounds, the Dask tasks, the load average and the store's size on disk; the
   store's figures follow only with ``--rows``. ``--trajectories`` is ``dalembert run``'s (which trajectories
   the store keeps: every probe's, only those the report draws, or none; ``dalembert run``'s default
   without it), to see what keeping them costs in time and disk. ``--json FILE`` writes the map as
   ``{"cluster": {"probes", "wall_s", "probes_per_s", "workers", "tasks", "rounds", "load_start", "load_end",
   "trajectories", "store_mb"}}`` (``"local"`` with ``--jobs``).
   Measured on 2 idle cores (load 0.7 to 1.8) at 60b62a6: ``--probes 10000``, 10433 probes in 117 s on the
   cluster (88.9 probes/s; 102 Dask tasks, 12 rounds).
   Measured on 2 cores shared with other work: ``--probes 10000``, 10433 probes in 852 s (14.2 min, 12.2
   probes/s, load average 10.6 to 11.8; 102 Dask tasks; the 2000 first probes, then 12 rounds of 1000 to 86)
   and in 192 s with ``--jobs 2`` (54.4 probes/s, load 7.8 to 4.8); 377 CPU s against 179 for the whole
   command. ``--probes 1000``: 1042 probes in 605 s on the cluster (67 tasks, load 14 to 16), 199 s with
   ``--jobs 2`` (load 13 to 16). A Dask task is a fresh process (~1.2 CPU s to start then: dalembert, MuJoCo, the
   installed distributions' metadata, since read once per environment, ``dalembert.distributions``: a task's
   process of one MuJoCo run 0.99 -> 0.77 CPU s) and the cluster's own processes take their share, so on one small host
   the local pool is the faster; the cluster pays where it has more hosts than one.
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

from dalembert.trajectory_store import KEEPS

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


# The --probes map (``probe_map``). MuJoCo (C): a probe's stepping is microseconds, so the map measures what the
# harness and the cluster cost per probe (building the model, judging, storing), not an integrator; its RK4 on the
# free top has both boundaries inside the bracket from 30 to 500 rad/s (below ~30 rad/s the largest step stays
# stable: two probes and no bisection). A 0.5-s horizon sampled every 0.1 s keeps a probe at <= 500 steps.
PROBE_MAP = ["--case", "free_top_fast_spin", "--param", "t_final=0.5", "--param", "sample_interval=0.1",
             "--engine", "mujoco", "--integrator", "rk4", "--search", "dt", "--dt", "1e-3,1e-1", "--resolution", "1.05",
             "--quick"]
PROBE_SPINS = (30.0, 500.0)  # rad/s: the swept range, log-spaced
# Probes a curve of PROBE_MAP takes: 2 at the bracket's ends, then bisections on both sides to the resolution
# (log2(ln(100) / ln(1.05)) = 6.6 per side at most; fewer where a snapped step repeats one already probed).
# Measured (--probes 1000 and 10000): 100 spins from 30 to 500 rad/s took 1042 probes, 1000 spins 10433.
PROBES_PER_CURVE = 10


def probe_map(tmp, probes, jobs=None, log=None, trajectories=None):
    """The ``--probes`` map of ~``probes`` probes on a 2-worker ``LocalCluster`` (or on ``jobs`` local workers, no
    Dask): ``{"probes", "wall_s", "probes_per_s", "workers", "tasks", "rounds", "load_start", "load_end"}`` (tasks
    None without Dask), ``"trajectories"`` (what the store keeps: ``trajectories``, ``dalembert run``'s
    ``--trajectories``, or its default where None) and ``"store_mb"`` (the store's size on disk, MB); its store at
    ``tmp/probes``; ``log``: a file for what ``dalembert run`` told (its rounds and each probe's progress)."""
    from distributed import LocalCluster
    from distributed.diagnostics.plugin import SchedulerPlugin

    class Tasks(SchedulerPlugin):  # the tasks the cluster ran (each a chunk of probes, ``dalembert.harness.dask``)
        ran = 0

        def transition(self, key, start, finish, *args, **kwargs):
            self.ran += start == "processing" and finish in ("memory", "erred")

    spins = max(1, round(probes / PROBES_PER_CURVE))
    out = os.path.join(tmp, "probes")
    command = [sys.executable, "-m", "dalembert.harness.cli", "run", *PROBE_MAP, "--param",
               f"spin=log:{PROBE_SPINS[0]:g},{PROBE_SPINS[1]:g},{spins}", "--out", out,
               *(["--trajectories", trajectories] if trajectories else [])]
    load = os.getloadavg()[0]
    if jobs:
        t0 = time.perf_counter()
        proc = subprocess.run([*command, "--jobs", str(jobs)], capture_output=True, text=True)
        wall, tasks, workers = time.perf_counter() - t0, None, jobs
    else:
        workers, plugin = 2, Tasks()
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=None) as cluster:
            cluster.scheduler.add_plugin(plugin)
            t0 = time.perf_counter()
            proc = subprocess.run([*command, "--scheduler", cluster.scheduler_address], capture_output=True,
                                  text=True)
            wall, tasks = time.perf_counter() - t0, plugin.ran
    if log:
        with open(log, "w") as fh:
            fh.write(proc.stderr)
    if proc.returncode != 0:
        raise SystemExit(proc.stderr[-2000:])
    from dalembert.store import Store

    store = Store(out)
    n = len(store.done_keys())
    rounds = sum(line.startswith("dalembert: search round") for line in proc.stderr.splitlines())
    return {"probes": n, "wall_s": wall, "probes_per_s": n / wall, "workers": workers, "tasks": tasks,
            "rounds": rounds, "spins": spins, "load_start": load, "load_end": os.getloadavg()[0],
            "trajectories": store.kept().keep, "store_mb": _disk_bytes(out) / 1e6}


def _disk_bytes(path):
    """The bytes of every file under ``path``."""
    return sum(os.path.getsize(os.path.join(d, f)) for d, _, names in os.walk(path) for f in names)


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
    p.add_argument("--rows", default=None, help="store sizes to feed, comma-separated (default: "
                   f"{','.join(map(str, SIZES))}; none with --probes)")
    p.add_argument("--json", metavar="FILE", help="write the store's figures to FILE as JSON")
    p.add_argument("--layout", type=int, default=2, help="the store layout of the synthetic stores (1 or 2)")
    p.add_argument("--report-up-to", type=int, default=None, metavar="N",
                   help="read the records and build the report only for stores of up to N rows")
    p.add_argument("--source", metavar="STORE", help="take the rows' models from this store (no cluster map)")
    p.add_argument("--probes", type=int, default=None, metavar="N", help="run a map of ~N probes (probe_map)")
    p.add_argument("--jobs", type=int, default=None, metavar="J",
                   help="with --probes: run the map on J local worker processes, without Dask")
    p.add_argument("--log", metavar="FILE", help="with --probes: write what the map's `dalembert run` told to FILE")
    p.add_argument("--trajectories", default=None, metavar="KEEP",
                   help=f"with --probes: which trajectories the map's store keeps ({', '.join(KEEPS)}; "
                   "default: dalembert run's)")
    args = p.parse_args(argv)
    if args.probes is not None and args.probes < 1:
        p.error(f"--probes: {args.probes} probes — give at least 1")
    if args.jobs is not None and (args.probes is None or args.jobs < 1):
        p.error("--jobs: runs the --probes map locally — give --probes N and at least 1 job")
    if args.trajectories is not None and args.trajectories not in KEEPS:
        p.error(f"--trajectories: {args.trajectories!r} is not a choice — use one of {', '.join(KEEPS)}")
    if args.trajectories is not None and args.probes is None:
        p.error("--trajectories: says what the --probes map's store keeps — give --probes N")
    if args.probes is not None and args.source:
        p.error("--probes and --source: --source skips the cluster map — give one")
    rows = args.rows if args.rows is not None else ("" if args.probes else ",".join(map(str, SIZES)))
    from dalembert.store import Store

    head = {}  # what the JSON holds beside the store's figures: the map
    with tempfile.TemporaryDirectory() as tmp:
        if args.probes:
            where = "local" if args.jobs else "cluster"
            head[where] = m = probe_map(tmp, args.probes, args.jobs, args.log, args.trajectories)
            on = (f"{args.jobs} local workers (no Dask)" if args.jobs
                  else f"a 2-worker LocalCluster ({m['tasks']} Dask tasks)")
            print(f"map of {m['spins']} spins on {on}: {m['probes']} probes in {m['wall_s']:.1f} s = "
                  f"{m['probes_per_s']:.2f} probes/s, {m['rounds']} search rounds ({os.cpu_count()} cores, load "
                  f"{m['load_start']:.2f} at the start, {m['load_end']:.2f} at the end); store {m['store_mb']:.1f} MB "
                  f"on disk, trajectories kept: {m['trajectories']}", flush=True)
            if args.json:
                with open(args.json, "w") as fh:
                    json.dump({**head, "cores": os.cpu_count()}, fh, indent=1)
            if not rows:
                return
            source = Store(os.path.join(tmp, "probes"))
        elif args.source:
            source = Store.open(args.source)
        else:
            out, wall = _cluster_map(tmp)
            source = Store(out)
            n = len(source.done_keys())
            print(f"map on a 2-worker LocalCluster: {n} runs in {wall:.1f} s = {n / wall:.2f} runs/s "
                  f"(4 spins x 2 integrators, boundary search; {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f})")
            head["cluster"] = {"probes": n, "wall_s": wall, "probes_per_s": n / wall, "workers": 2}
        print(f"\nstore layout {args.layout}; s per 1000 rows (totals in s after them)\n"
              f"{'rows':>8} {'write':>8} {'parquet':>8} {'table':>8} {'records':>8} {'report':>8}")
        results = {}
        for size in (int(x) for x in rows.split(",")):
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
                    json.dump({**head, "rows": results, "layout": args.layout, "cores": os.cpu_count()}, fh, indent=1)


def shutil_rm(path):
    import shutil

    shutil.rmtree(path, ignore_errors=True)


if __name__ == "__main__":
    main()
