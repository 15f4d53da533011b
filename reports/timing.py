"""Were a store's timings taken on a quiet machine? A warning from what the store recorded.

The manifest holds the machine's cores, the pool size (``jobs``) and the
1-minute load average at the matrix's start and end; each run's ``Cost`` the
load average when it started and ended. A load above the core count by more than
the matrix's own footprint (``OWN_LOAD``) means the stepping shared the cores
with other work: its wall times are upper bounds, and costs compare only beyond
the min–max spread of their repeats.
"""

from __future__ import annotations

import math

from dalembert.reports.findings import run_name

__all__ = ["loaded_runs", "once_note", "timing_note", "OWN_LOAD"]

# What a matrix adds to the load beyond its busy workers (the parent writing the store, the engines' helper
# threads, the OS): measured on a quiet 2-core machine, seven default matrices with 2 workers (make run from fresh
# clones, 1040 runs each, run-start and run-end readings): 1-minute load medians 2.24-2.62, peaks 2.43-2.97. Judged
# at cores + OWN_LOAD, none of them is flagged, and one other busy process (+1 on a quiet median: 3.35) is.
OWN_LOAD = 1.0


def _loads(r):
    return [x for x in (r.cost.load_start, r.cost.load_end) if math.isfinite(x)]


def _shared(load, cores):
    """Whether a 1-minute load average says other work shared the ``cores`` (above them by more than ``OWN_LOAD``)."""
    return load > cores + OWN_LOAD


def loaded_runs(records, cores):
    """The runs that started or ended with the 1-minute load average above ``cores + OWN_LOAD``."""
    limit = cores + OWN_LOAD  # (``_shared`` of a finite reading, spelt out: it is asked of every run)
    return [r for r in records if limit < r.cost.load_start < math.inf or limit < r.cost.load_end < math.inf]


def timing_note(manifest, records):
    """A sentence warning that the machine was loaded while the runs were timed, or None."""
    cores = (manifest.get("machine") or {}).get("cores")
    if not cores:
        return None
    marks = [v[0] for v in ((manifest.get("load_average") or {}).get(k) for k in ("start", "end")) if v]
    loaded = loaded_runs(records, cores)
    readings = [_loads(r) for r in records]
    peak = max(marks + [x for loads in readings for x in loads], default=0.0)
    jobs = manifest.get("jobs") or 0
    parts = []
    if _shared(peak, cores):
        parts.append(f"the 1-minute load average reached {peak:.3g} on {cores} cores")
        if loaded:
            timed = sum(1 for loads in readings if loads)
            names = ", ".join(f"{r.case} {run_name(r)}" for r in loaded[:3])
            parts.append(f"{len(loaded)} of {timed} timed runs started or ended with the load above the cores "
                         f"by more than the matrix's own load of {OWN_LOAD:g} (e.g. {names})")
    if jobs > cores:
        parts.append(f"the matrix ran {jobs} runs at once on {cores} cores")
    if not parts:
        return None
    return ("Timings shared the machine: " + "; ".join(parts) + ". Their costs are upper bounds: compare costs "
            "only where the min–max spreads in the tables do not overlap.")


def once_note(manifest):
    """A sentence saying that each run was timed once (``dalembert run --quick``), or None."""
    if (manifest.get("timing") or {}).get("max_repeats") != 1:
        return None
    # the ~10 %: the stores' min-max spreads of one run's repeats on one machine (``compare.COST_NOTICE``)
    return ("Each run was timed once after its warm-up (dalembert run --quick): a cost is one sample, with no "
            "spread, and repeats of one run scatter by ~10 % on one machine: compare costs only where they "
            "differ by more.")
