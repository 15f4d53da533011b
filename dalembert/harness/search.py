"""Boundary search: for each curve, the largest step that stays stable, and that stays finite.

Instead of a dense sweep, each curve (case variant, engine, integrator, options) is probed at
the ends of the bracket the ``--dt`` values give, then bisected on a log scale between its
largest passing and smallest failing step (``dalembert.boundary``) until they are within
``resolution`` of each other: first the stable boundary, then the finite one above it. Every
probe is an ordinary run, stored as usual; a probe's step is snapped to divide the case's
sample interval. Rounds run all curves' next probes at once (locally or on Dask), so a map
costs tens of runs per curve instead of hundreds. A stopped search resumes from what is
stored: the probes already run are not redone.

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

import math
from dataclasses import replace

from dalembert.boundary import boundaries, curve_of

__all__ = ["RESOLUTION", "search", "next_probes"]

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

    by_curve, intervals = {}, {}
    for s in specs:
        key = (s.case, s.case_version, s.engine, s.settings.integrator,
               " ".join(f"{k}={v}" for k, v in sorted(s.settings.options.items())))
        by_curve.setdefault(key, s)
        if key not in intervals:
            times = built_case(s.case, s.params)[0].times
            intervals[key] = float(times[1] - times[0])
    lost = list(run(specs))
    keys = {s.key for s in specs}
    rnd = 0
    while True:
        mine = [r for r in store.records() if r.key in keys]
        probes = next_probes(by_curve, mine, intervals, resolution)
        if not probes:
            return lost
        rnd += 1
        if progress:
            progress(rnd, probes)
        keys |= {p.key for p in probes}
        lost += run(probes)
