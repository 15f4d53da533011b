"""Compare two results stores: what got better, worse, or stayed the same.

Runs are matched by case, engine, integrator, dt, tolerances and options.
A run whose case version differs between the stores is flagged, not compared.
An error counts as a regression when it grows by more than ``threshold`` times
(errors at roundoff level, below ``ERROR_FLOOR``, are compared as if they were
``ERROR_FLOOR``); a status that turns from ok into failed/diverged/timeout is a
regression too. Cost ratios are reported; they count as regressions only with
``cost_threshold`` (timings on shared machines are noisy).
"""

from __future__ import annotations

import math

__all__ = ["ERROR_FLOOR", "compare_stores"]

# Errors below this are roundoff; a change among them is not a regression.
ERROR_FLOOR = 1e-13
KEY = ("case", "engine", "integrator", "dt", "rtol", "atol", "options")
BAD = ("failed", "diverged", "timeout")


def _key(r):
    return tuple(None if (isinstance(r.get(k), float) and math.isnan(r[k])) else r.get(k) for k in KEY)


def compare_stores(store_a, store_b, threshold=2.0, cost_threshold=None):
    """Rows of the comparison and whether any regression was found: ``(rows, regressed)``."""
    a = {_key(r): r for r in store_a.rows()}
    b = {_key(r): r for r in store_b.rows()}
    rows, regressed = [], False
    for key in sorted(set(a) | set(b), key=str):
        ra, rb = a.get(key), b.get(key)
        label = dict(zip(KEY, key))
        if ra is None or rb is None:
            rows.append({**label, "change": "only in " + ("B" if ra is None else "A")})
            continue
        if ra["case_version"] != rb["case_version"]:
            rows.append({**label, "change": f"case version differs ({ra['case_version']} vs {rb['case_version']}): "
                                            "not compared"})
            continue
        if ra["status"] == "ok" and rb["status"] in BAD:
            rows.append({**label, "change": f"REGRESSION: status ok -> {rb['status']} ({rb.get('message', '')})"})
            regressed = True
            continue
        if ra["status"] != "ok" or rb["status"] != "ok":
            rows.append({**label, "change": f"status {ra['status']} -> {rb['status']}"})
            continue
        worst, notes = 1.0, []
        for col in sorted(c for c in ra if c.startswith("err_") and c.endswith("_max")):
            ea, eb = ra.get(col), rb.get(col)
            if ea is None or eb is None or any(isinstance(x, float) and math.isnan(x) for x in (ea, eb)):
                continue
            ratio = max(eb, ERROR_FLOOR) / max(ea, ERROR_FLOOR)
            if ratio > threshold or ratio < 1.0 / threshold:
                notes.append(f"{col[4:-4]} x{ratio:.3g}")
            worst = max(worst, ratio)
        cost = rb["wall_s_median"] / ra["wall_s_median"] if ra.get("wall_s_median") else float("nan")
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
