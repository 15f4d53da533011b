"""Benchmark of a large map's trajectories in a store: a file per run against a pack per writing process.

    python -m benchmarks.trajectories [--runs 10000,100000] [--ways files,packs] [--sample-interval 0.1] [--json FILE]

The trajectory is a real one: a probe of ``benchmarks/map.py``'s map (the reference's RK4 on
``free_top_fast_spin`` at spin 50 rad/s, dt = 1e-3 s, a 1-s horizon sampled every ``--sample-interval`` s),
run once through ``dalembert.harness.api.run``. Each size writes it under that many keys, as the matrix's
parent does (``dalembert.trajectory_store.Trajectories.write``), in two ways:

- ``files``: a ``.npz`` per run, written atomically (layout 1, and layout 2 before packs);
- ``packs``: appended to this process's pack (layout 2 now), synced (and its index written) once at the end, as
  at a batch's end.

For each: the files and bytes per run (apparent, and on the disk: a small file takes a whole block), the write
time per 1000 runs, the time to read 1000 runs' trajectories picked at random from a fresh reader (as a report
does: ``Store.trajectory``'s reading, the packs' index built on the first read included), and the time to keep
1 % of them (``keep_only``: what a ``--trajectories drawn`` matrix does when it ends). ``--json FILE`` writes
``{"runs": {"10000": {"files": {"files_per_run": .., "bytes_per_run": .., "disk_bytes_per_run": .., "write_s": ..,
"read_1000_s": .., "keep_s": ..}, "packs": {...}}}}`` (s: the write's total, the reads' per 1000), each with its
CPU time beside (``write_cpu_s``, ``read_1000_cpu_s``: on a loaded machine the wall time is mostly waiting).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import tempfile
import time

SIZES = (10_000, 100_000)
READS = 1000  # trajectories read per size: what a report of a large map draws is of this order or less
KEPT = 0.01  # the share a drawn store keeps, for the drop's time


def _source(tmp, sample_interval):
    """The ``.npz`` bytes of one real probe (the module docstring)."""
    from dalembert.harness import api

    out = os.path.join(tmp, "source")
    api.run(cases=["free_top_fast_spin"], engines=["reference"], integrators=["rk4"], dts=[1e-3],
            params={"spin": 50.0, "t_final": 1.0, "sample_interval": sample_interval}, quick=True, out=out, jobs=1)
    traj = os.path.join(out, "trajectories")
    [name] = os.listdir(traj)
    with open(os.path.join(traj, name), "rb") as fh:
        return fh.read()


def _usage(directory):
    """``(files, apparent bytes, bytes on the disk)`` under ``directory``."""
    files = size = disk = 0
    for entry in os.scandir(directory):
        st = entry.stat()
        files, size, disk = files + 1, size + st.st_size, disk + st.st_blocks * 512
    return files, size, disk


def figures(npz, directory, n, packed):
    """The figures of ``n`` copies of ``npz`` kept at ``directory`` as files or a pack (the module docstring)."""
    from dalembert.store import atomic_write
    from dalembert.trajectory_files import trajectory_from_npz
    from dalembert.trajectory_store import Trajectories

    os.makedirs(directory)
    keys = [f"probe{i:07d}" for i in range(n)]
    kept = Trajectories(directory, packed, "drawn")
    t0, c0 = time.perf_counter(), time.process_time()
    for key in keys:
        kept.write(key, npz, atomic_write)
    kept.sync(atomic_write)
    write_s, write_cpu_s = time.perf_counter() - t0, time.process_time() - c0
    files, size, disk = _usage(directory)
    picks = random.Random(0).sample(keys, min(READS, n))
    reader = Trajectories(directory, packed, "drawn")  # a fresh reader: a report's Store
    t0, c0 = time.perf_counter(), time.process_time()
    for key in picks:
        trajectory_from_npz(reader.source(key))
    read_s, read_cpu_s = time.perf_counter() - t0, time.process_time() - c0
    t0 = time.perf_counter()
    reader.keep_only(keys[::int(1 / KEPT)], atomic_write)
    keep_s = time.perf_counter() - t0
    return {"files_per_run": files / n, "bytes_per_run": size / n, "disk_bytes_per_run": disk / n,
            "write_s": write_s, "write_cpu_s": write_cpu_s, "read_1000_s": read_s * 1000 / len(picks),
            "read_1000_cpu_s": read_cpu_s * 1000 / len(picks), "keep_s": keep_s}


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--runs", default=",".join(map(str, SIZES)), help="numbers of runs, comma-separated")
    p.add_argument("--ways", default="files,packs", help="which of files and packs to measure, comma-separated")
    p.add_argument("--sample-interval", type=float, default=0.1, help="the probe's sample interval, s (1-s horizon)")
    p.add_argument("--json", metavar="FILE", help="write the figures to FILE as JSON")
    args = p.parse_args(argv)
    import shutil

    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        npz = _source(tmp, args.sample_interval)
        print(f"one probe's trajectory: {len(npz)} bytes (.npz); {os.cpu_count()} cores, "
              f"load {os.getloadavg()[0]:.2f}\n\n{'runs':>8} {'how':>6} {'files/run':>10} {'B/run':>8} "
              f"{'disk B/run':>10} {'write s/1000':>12} {'read s/1000':>11} {'keep 1% s':>9}  (CPU s: write/1000, "
              "read/1000)")
        for n in (int(x) for x in args.runs.split(",")):
            results[str(n)] = {}
            for how in args.ways.split(","):
                directory = os.path.join(tmp, f"{how}{n}")
                f = figures(npz, directory, n, how == "packs")
                shutil.rmtree(directory)
                results[str(n)][how] = f
                print(f"{n:>8} {how:>6} {f['files_per_run']:>10.4g} {f['bytes_per_run']:>8.0f} "
                      f"{f['disk_bytes_per_run']:>10.0f} {f['write_s'] / (n / 1000):>12.3f} {f['read_1000_s']:>11.3f} "
                      f"{f['keep_s']:>9.2f}  ({f['write_cpu_s'] / (n / 1000):.3f}, {f['read_1000_cpu_s']:.3f}; "
                      f"load {os.getloadavg()[0]:.2f})", flush=True)
                if args.json:  # after each: a long run stopped later keeps what it measured
                    with open(args.json, "w") as fh:
                        json.dump({"runs": results, "npz_bytes": len(npz), "cores": os.cpu_count()}, fh, indent=1)


if __name__ == "__main__":
    main()
