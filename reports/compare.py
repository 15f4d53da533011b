"""Compare two results stores: what got better, worse, or stayed the same.

Runs are matched by case, engine, integrator, dt, tolerances and options.
A run whose case version differs between the stores is flagged, not compared
(unless asked: ``across_versions``, e.g. when only the way versions are computed
changed). An error counts as a regression when it grows by more than
``threshold`` times (errors at roundoff level, below ``ERROR_FLOOR``, are
compared as if they were ``ERROR_FLOOR``); a status that turns from ok into
failed/diverged/timeout is a regression too. Cost ratios are reported; they count
as regressions only with ``cost_threshold`` (timings on shared machines are noisy).
"""

from __future__ import annotations

import math

from dalembert.record import BAD_STATUSES

__all__ = ["ERROR_FLOOR", "compare_stores"]

# Errors below this are roundoff; a change among them is not a regression.
ERROR_FLOOR = 1e-13


def _match(r):
    """What identifies a run across stores, as a dict (also the comparison row's label)."""
    return {"case": r.case, "engine": r.engine, "integrator": r.integrator, "dt": r.dt, "rtol": r.rtol,
            "atol": r.atol, "options": r.options_label}


def compare_stores(store_a, store_b, threshold=2.0, cost_threshold=None, across_versions=False):
    """Rows of the comparison and whether any regression was found: ``(rows, regressed)``."""
    a = {tuple(_match(r).values()): r for r in store_a.records()}
    b = {tuple(_match(r).values()): r for r in store_b.records()}
    rows, regressed = [], False
    for key in sorted(set(a) | set(b), key=str):
        ra, rb = a.get(key), b.get(key)
        label = _match(ra or rb)
        if ra is None or rb is None:
            rows.append({**label, "change": "only in " + ("B" if ra is None else "A")})
            continue
        if ra.case_version != rb.case_version and not across_versions:
            rows.append({**label, "change": f"case version differs ({ra.case_version} vs {rb.case_version}): "
                                            "not compared"})
            continue
        if ra.status == "ok" and rb.status in BAD_STATUSES:
            rows.append({**label, "change": f"REGRESSION: status ok -> {rb.status} ({rb.message})"})
            regressed = True
            continue
        if not (ra.ok and rb.ok):
            rows.append({**label, "change": "same" if ra.status == rb.status else f"status {ra.status} -> {rb.status}"})
            continue
        worst, notes = 1.0, []
        for q in sorted(set(ra.errors) & set(rb.errors)):
            ea, eb = ra.max_error(q), rb.max_error(q)
            if math.isnan(ea) or math.isnan(eb):
                continue
            ratio = max(eb, ERROR_FLOOR) / max(ea, ERROR_FLOOR)
            if ratio > threshold or ratio < 1.0 / threshold:
                notes.append(f"{q} x{ratio:.3g}")
            worst = max(worst, ratio)
        wa, wb = ra.cost.wall_s_median, rb.cost.wall_s_median
        cost = wb / wa if wa and not math.isnan(wa) else float("nan")
        change = "same"
        if worst > threshold:
            change, regressed = "REGRESSION: " + ", ".join(notes), True
        elif notes:
            change = "better: " + ", ".join(notes)
        if cost_threshold is not None and cost == cost and cost > cost_threshold:
            change = ("REGRESSION: " if not change.startswith("REGRESSION") else change + "; ") + f"cost x{cost:.3g}"
            regressed = True
        rows.append({**label, "error_ratio": worst, "cost_ratio": cost, "change": change})
    return rows, regressed
