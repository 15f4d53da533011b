"""One case against time: each engine's most accurate run per step size and tolerance (headline
error, drift of each conserved quantity, loop closure), and the runs that diverged."""

from __future__ import annotations

import numpy as np

from dalembert.reports import figures, time_series
from dalembert.reports.formatting import counted
from dalembert.reports.findings import settings_text
from dalembert.reports.loops import RESIDUALS
from dalembert.reports.page import Part
from dalembert.reports.sections.common import drift_unit
from dalembert.reports.work_precision import sweep_key

__all__ = ["against_time", "DECADES"]

DECADES = 100.0  # a time plot's values spanning more than this factor (two decades) get a log axis


def against_time(rep, f, name):
    """Case version ``f``'s time plots (a ``Part``; empty without a stored truth, a headline error
    or a run to draw); ``name`` prefixes its figures."""
    part = Part()
    truth = rep.store.truth(f.case.name, f.case.version)
    if truth is None or f.quantity is None:
        return part
    reps = time_series.representatives(f.runs, f.quantity)
    divs = time_series.diverged(f.runs)
    if not reps and not divs:
        keep = rep.store.kept().keep
        if keep != "all" and any(r.ok for r in f.runs):  # drawn keeps these runs' (``reports.drawn``): none, then
            part.heading("Against time", 3)
            part.para(f"No figure against time: the store kept no run's trajectory (run.trajectories = {keep}; "
                      "dalembert run --trajectories all keeps them).")
        return part
    part.heading("Against time", 3)
    if reps:
        _representatives(part, rep.store, f, name, truth, reps)
    if divs:
        _diverged(part, rep.store, f, name, truth, divs)
    return part


def _representatives(part, store, f, name, truth, reps):
    sweeps = list(dict.fromkeys(r.sweep_label for rs in reps.values() for r in sorted(rs, key=sweep_key)))
    sweeps.sort(key=lambda s: (s.startswith("tol"), -float(s.split("=")[1])))
    colours = {s: figures.SWEEP_COLOURS[i % len(figures.SWEEP_COLOURS)] for i, s in enumerate(sweeps)}
    rows = [dict(ylabel=f"{f.quantity} error ({f.unit})", log=True, series={}, bound=f.tolerance)]
    for e, rs in reps.items():
        for r in rs:
            s = time_series.headline_series(store, r, truth, f.quantity)
            if s:
                label = " ".join(x for x in (r.sweep_label, r.settings.integrator, r.options_text) if x)
                rows[0]["series"].setdefault(e, []).append((label, r.sweep_label, *s))
    for cname in f.case.conserved:
        tol = f.case.tolerances.get(cname)
        row = dict(ylabel=f"{cname} drift ({drift_unit(cname)})", log=True, series={},
                   bound=tol.value if tol else None)
        for e, rs in reps.items():
            for r in rs:
                if r.drifts.get(cname, 0.0) > 0.0:  # identically conserved: nothing to draw on a log axis
                    row["series"].setdefault(e, []).append((r.sweep_label, r.sweep_label,
                                                            *time_series.drift_series(store, r, f.case, cname)))
        if row["series"]:
            rows.append(row)
    for level, rname in (RESIDUALS.items() if f.case.scene.loops else ()):
        tol = f.case.tolerances.get(rname)
        row = dict(ylabel=f"loop closure, {level} ({'m' if level == 'position' else 'm/s'})", log=True,
                   series={}, bound=tol.value if tol else None)
        for e, rs in reps.items():
            for r in rs:
                if r.drifts.get(rname, 0.0) > 0.0:
                    row["series"].setdefault(e, []).append(
                        (r.sweep_label, r.sweep_label, *time_series.loop_residual_series(store, r, f.case, level)))
        if row["series"]:
            rows.append(row)
    for row in rows:  # a log axis where the values span decades, a linear one where they do not
        values = [v for runs in row["series"].values() for *_, y in runs for v in y[np.isfinite(y) & (y > 0)]]
        row["log"] = bool(values) and max(values) > DECADES * min(values)
    part.figure(figures.time_grid(rows, list(reps), colours),
                f"{name}: each engine's most accurate run at each step size and tolerance (colour), its "
                f"{f.quantity} error and the drift of each conserved quantity against time (log scales where "
                "they span decades); dashed: the case's tolerance on each.",
                f"{name}-time")


def _diverged(part, store, f, name, truth, divs):
    panels = {}
    for e, rs in divs.items():
        for r in rs:
            s = time_series.headline_series(store, r, truth, f.quantity)
            if s:
                panels.setdefault(e, []).append((settings_text(r), *s, r.t_diverged))
    if panels:
        n = sum(len(v) for v in panels.values())
        part.figure(figures.diverged_runs(panels, f"{f.quantity} error ({f.unit})"),
                    f"{name}: the {counted(n, 'run')} that diverged, their {f.quantity} error until it stopped being finite "
                    "(log scale over every run's whole range: none is cut off); x and dotted line: the time the run "
                    "diverged.", f"{name}-diverged")
