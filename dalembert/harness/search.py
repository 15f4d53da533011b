"""Boundary search: for each curve, the largest step that stays stable, and that stays finite.

Instead of a dense sweep, each curve (case variant, engine, integrator, options) is probed at
the ends of the bracket the ``--dt`` values give, then bisected on a log scale between its
largest passing and smallest failing step (``dalembert.boundary``) until they are within
``resolution`` of each other: first the stable boundary, then the finite one above it. Every
probe is an ordinary run, stored as usual; a probe's step is snapped to divide the case's
sample interval. Rounds run all curves' next probes at once (locally or on Dask), so a map
costs tens of runs per curve instead of hundreds. A stopped search resumes from what is
stored: the probes already run are not redone.

A round reads back only the rows of the probes it ran (``_StoredProbes``): their row files (store
layout 1), or the segment lines written since the last round (layout 2), never the whole store, so
a map's rounds cost what their probes cost, not the store's size: a round of 1000 probes reads back
in 0.08 to 0.17 CPU s with 1e4 or 1e5 rows stored, where rereading the store took 1.3 and 14-15
(``benchmarks/search_reads.py``).

Batches (``--batch``, ``dalembert.harness.batches``): a round's probes that share everything but the
case's parameters (the same engine, integrator, options and step, at different values of the swept
parameter) run as the worlds of one engine call, where the engine has batches. They batch across the
swept parameter, never across steps: every world of a batch takes the same number of steps per sample
interval (MuJoCo Warp's and MJX's batches step in lock-step, one ``dt`` for all), so probes of two
steps are two calls. The probes are the search's own either way (batching picks none), so a batched
map probes the same steps as one run probe by probe, and on an engine whose worlds are bit for bit
the runs alone (MuJoCo Warp) finds the same boundaries.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import replace

from dalembert.boundary import boundaries, curve_of
from dalembert.record import RunRecord, SchemaError
from dalembert.segments import complete_length, line_key, parse_lines, segment_names
from dalembert.store import SEGMENTS, StoreError

__all__ = ["RESOLUTION", "search", "next_probes", "probes_at_most"]

# The boundary is known when the failing step is within this factor of the passing one: finer
# than the spread of the verdict itself near a boundary (a drift bound crossed by a factor
# 1.2 in step is crossed by ~2x in a 4th-order drift).
RESOLUTION = 1.2


def _snap(dt, interval):
    """The step nearest ``dt`` that divides ``interval`` (``interval / n``, n a positive integer)."""
    return interval / max(1, round(interval / dt))


def next_probes(specs_by_curve, records, intervals, resolution):
    """The next probe of every curve whose stable or finite boundary is not yet known to
    ``resolution``: the geometric mean of its bracket, snapped. ``specs_by_curve``: curve ->
    a spec of it (any step); ``intervals``: curve -> the sample interval (s)."""
    probes = []
    done = {curve_of(r): set() for r in records}
    for r in records:
        done[curve_of(r)].add(r.settings.dt)
    for b in boundaries(records):
        key = (b.case, b.case_version, b.engine, b.integrator, b.options)
        if key not in specs_by_curve:
            continue
        for side in (b.stable, b.finite):
            if side.passed is None or side.failed is None or side.ratio <= resolution:
                continue
            dt = _snap(math.sqrt(side.passed * side.failed), intervals[key])
            if dt not in done[key] and side.passed < dt < side.failed:
                probes.append(replace(specs_by_curve[key], settings=replace(specs_by_curve[key].settings, dt=dt)))
                break  # one probe per curve per round: the stable side first
    return probes


def probes_at_most(first, resolution=RESOLUTION):
    """How many runs a search from ``first`` (its curves' probes at the bracket's ends) stores at most:
    each curve's first probes, then one bisection in log step per round for each of its two boundaries
    (stable, finite) until the bracket is within ``resolution`` — what sizes the store before it exists
    (``Store.create``: a map of 1000 curves starts with 2000 probes but stores ~10,000)."""
    curves = {}
    for s in first:
        curves.setdefault((s.case, s.case_version, s.engine, s.settings.integrator,
                           tuple(sorted(s.settings.options.items()))), []).append(s.settings.dt)
    total = 0
    for dts in curves.values():
        lo, hi = min(dts), max(dts)
        ratio = math.log(hi / lo) / math.log(resolution) if lo > 0 and hi > lo else 1.0
        total += len(dts) + 2 * max(0, math.ceil(math.log2(ratio)))
    return total


class _StoredProbes:
    """The stored records of the runs a search asks for, each row read once.

    Layout 1: a wanted run's row file. Layout 2: each segment read on from where the last call stopped (its
    complete lines only: a torn last line is a run not stored); a line whose run is not wanted yet (a stopped
    search's later probes, found by the first read of a resumed one; another plan's runs) is kept unparsed
    until it is. A damaged row is a ``StoreError`` naming its file or line, as ``Store.records`` says it.
    """

    def __init__(self, store):
        self.store = store
        self._read = {}  # segment name -> (bytes read: its complete lines, lines read)
        self._where = {}  # key -> "<segment> line <n>" of every segment line read (a run stored twice is damage)
        self._lines = {}  # key -> (segment path, line number, line bytes) of the lines not yet wanted

    def records(self, keys):
        """The ``RunRecord`` of each of ``keys`` that is stored (a run lost or not yet run has none)."""
        out = []
        if self.store.layout() == SEGMENTS:
            self._read_segments()
            for key in keys:
                if key in self._lines:
                    path, n, line = self._lines.pop(key)
                    ((_, row),) = parse_lines([line], path, self._fix, n)
                    out.append(self._record(f"{path} line {n}", row))
            return out
        for key in keys:
            path = os.path.join(self.store.rows_dir, f"{key}.json")
            try:
                with open(path) as fh:
                    row = json.load(fh)
            except FileNotFoundError:
                continue
            except (OSError, ValueError) as e:
                raise StoreError(f"{path}: cannot be read as a stored run ({type(e).__name__}: {e}) — "
                                 f"{self._fix(key)}") from None
            out.append(self._record(path, row))
        return out

    def _fix(self, key):
        """The fix for a damaged row of run ``key`` (``Store.records``'s): redo the run."""
        return f"delete it and run `dalembert run --resume {self.store.path}` to redo that run"

    def _read_segments(self):
        """Index the complete lines added to every segment since the last call by their run's key."""
        directory = self.store.segments_dir
        for name in segment_names(directory):
            start, n = self._read.get(name, (0, 0))
            path = os.path.join(directory, name)
            with open(path, "rb") as fh:
                fh.seek(start)
                data = fh.read()
            data = data[:complete_length(data)]
            for line in data.splitlines():
                n += 1
                key = line_key(line)
                if key is None:  # not a row: the full parse says why
                    parse_lines([line], path, self._fix, n)
                if key in self._where:
                    raise StoreError(f"{path} line {n}: run {key!r} is stored twice (first at {self._where[key]}) — "
                                     "the store was edited or damaged; delete one of the lines")
                self._where[key] = f"{path} line {n}"
                self._lines[key] = (path, n, line)
            self._read[name] = (start + len(data), n)

    def _record(self, where, row):
        """``row`` as a ``RunRecord``; a row that is not one is a ``StoreError`` naming ``where``."""
        try:
            return RunRecord.from_row(row)
        except SchemaError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError) as e:
            key = row.get("key", "?") if isinstance(row, dict) else "?"
            raise StoreError(f"{where}: not a run dalembert wrote ({type(e).__name__}: {e}) — "
                             f"{self._fix(key)}") from None


def search(specs, store, run, resolution=RESOLUTION, progress=None):
    """Bisect every curve of ``specs`` (fixed-step specs at the bracket's ends) to ``resolution``.

    Parameters
    ----------
    specs : list of RunSpec — the first probes (every curve at the smallest and largest step)
    store : Store — where every probe is stored (and what was stored before is reused)
    run : callable(list of RunSpec) -> list of (key, reason) lost — runs probes into ``store``
    progress : callable(round, probes) or None

    Returns the runs lost to the infrastructure (their curves stop where they were).
    """
    from dalembert.harness.truths import built_case

    def curve(s):
        return (s.case, s.case_version, s.engine, s.settings.integrator,
                " ".join(f"{k}={v}" for k, v in sorted(s.settings.options.items())))

    by_curve, intervals = {}, {}
    for s in specs:
        key = curve(s)
        by_curve.setdefault(key, s)
        if key not in intervals:
            times = built_case(s.case, s.params)[0].times
            intervals[key] = float(times[1] - times[0])
    stored = _StoredProbes(store)
    lost, probes, rnd, mine = [], specs, 0, []
    while True:
        lost_now = list(run(probes))
        lost += lost_now
        by_key = {p.key: curve(p) for p in probes}
        for key, _ in lost_now:  # a probe the infrastructure lost stops its curve (asked again, it could loop)
            by_curve.pop(by_key.get(key), None)
        mine += stored.records(list(by_key))  # this round's probes only: the earlier rounds' are in ``mine``
        probes = next_probes(by_curve, mine, intervals, resolution)
        if not probes:
            return lost
        rnd += 1
        if progress:
            progress(rnd, probes)
