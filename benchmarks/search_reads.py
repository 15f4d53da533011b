"""What a boundary search's round costs to read back, against the rows already stored.

    python -m benchmarks.search_reads --source STORE [--rows 10000,100000]

For each size and store layout (``dalembert.store.LAYOUTS``): a store of ``rows - 1000`` synthetic rows made from
``STORE``'s runs (``benchmarks.map._synthetic``), read by the search as its rounds ended; then a round of 1000
probes written, and read back two ways — as the search did before (every record, ``Store.records``, then the
round's) and as it does now (``dalembert.harness.search._StoredProbes``: only the round's rows). Prints the wall
and CPU time of each. Measured (2 shared cores, load ~5-7, the rows of a 205-probe MuJoCo map): with 1e4 rows
stored, 1.31 CPU s before against 0.087 now (layout 1; 1.34 against 0.085 in layout 2); with 1e5, 14.7 against
0.084 (layout 1; 14.2 against 0.166 in layout 2) — a round's read grew with the store, and now costs its probes.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from dataclasses import replace

ROUND = 1000  # probes in the round read back (a 1e4-probe map's rounds: benchmarks/map.py --probes 10000)


def round_read(source, path, rows, layout):
    """``(old wall s, old CPU s, new wall s, new CPU s)``: a round of ``ROUND`` probes read back from a store at
    ``path`` of ``rows`` rows in ``layout``, by the old search's read and by ``_StoredProbes``."""
    from benchmarks.map import _synthetic
    from dalembert.harness.search import _StoredProbes

    base = source.records()
    store, _ = _synthetic(source, path, rows - ROUND, layout)
    reader = _StoredProbes(store)
    reader.records(sorted(store.done_keys()))  # the earlier rounds, read as they ended
    last = [f"round{i:05d}" for i in range(ROUND)]
    for i, key in enumerate(last):
        store.write_record(replace(base[i % len(base)], key=key, trajectory=""))
    t0, c0 = time.perf_counter(), time.process_time()
    wanted = set(last)
    old = [r for r in store.records() if r.key in wanted]
    t1, c1 = time.perf_counter(), time.process_time()
    new = reader.records(last)
    t2, c2 = time.perf_counter(), time.process_time()
    if not sorted(r.key for r in old) == sorted(r.key for r in new) == last:
        raise SystemExit("the two reads found different rows")
    return t1 - t0, c1 - c0, t2 - t1, c2 - c1


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", required=True, metavar="STORE", help="take the rows' models from this store")
    p.add_argument("--rows", default="10000,100000", help="rows stored, comma-separated")
    args = p.parse_args(argv)
    from dalembert.store import LAYOUTS, Store

    source = Store.open(args.source)
    for rows in (int(x) for x in args.rows.split(",")):
        if rows <= ROUND:
            p.error(f"--rows: {rows} rows — give more than the round's {ROUND}")
        for layout in LAYOUTS:
            tmp = tempfile.mkdtemp()
            try:
                ow, oc, nw, nc = round_read(source, os.path.join(tmp, "store"), rows, layout)
            finally:
                shutil.rmtree(tmp, ignore_errors=True)
            print(f"layout {layout}, {rows} rows stored: a round of {ROUND} probes read back in {ow:.2f} s "
                  f"({oc:.2f} CPU s) before, {nw:.3f} s ({nc:.3f} CPU s) now", flush=True)


if __name__ == "__main__":
    main()
