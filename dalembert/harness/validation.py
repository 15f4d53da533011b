"""The reference solver against the closed forms: every case, several integrators.

Until the run matrix exists this is the main job (``dalembert validate``): it
runs each case with the reference engine, compares with the case's truth and
its conserved quantities, and writes a table (Markdown and CSV). A run that
fails is a row with its status and message, never a crash of the suite.
"""

from __future__ import annotations

import csv
import os
import traceback
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from dalembert import invariants
from dalembert.errors import trajectory_errors
from dalembert.settings import Settings

__all__ = ["DEFAULT_SETTINGS", "validate_case", "validate", "to_markdown", "write_csv"]

# What the validation runs per case. dt = 1e-3 is the step the engine issues
# quote their accuracy at; the two extra formulations cross-check Newton-Euler.
DEFAULT_SETTINGS = (
    Settings("dop853", rtol=1e-12, atol=1e-12),
    Settings("rk4", dt=1e-3),
    Settings("rkmk4", dt=1e-3),
    Settings("euler", dt=1e-3),
    Settings("euler", dt=1e-4),
)
FREE_BODY_EXTRA = (
    Settings("rk4", dt=1e-3, options={"formulation": "newton-euler-matrix"}),
    Settings("rk4", dt=1e-3, options={"formulation": "kane"}),
)


def settings_for(case):
    """The settings the validation runs on ``case``."""
    free = all(j.kind == "free" for j in case.scene.joints)
    return DEFAULT_SETTINGS + (FREE_BODY_EXTRA if free else ())


def validate_case(name, params, settings):
    """One row: the reference on case ``name`` with ``settings``, against its truth."""
    from dalembert.case import make_case
    from dalembert.reference import simulate, truth

    case = make_case(name, **params)
    row = {"case": name, "version": case.version, "settings": settings.label(), "status": "ok", "message": ""}
    try:
        traj, stats, wall = simulate(case.scene, case.times, settings)
        row.update(wall_s=wall, n_steps=stats.n_steps, n_rhs=stats.n_rhs)
        if not traj.is_finite():
            row.update(status="diverged", message=f"non-finite state at t = {traj.first_nonfinite_time()} s")
            return row
        errors = trajectory_errors(traj, truth(case))
        for q, (mx, _final) in errors.items():
            row[f"err:{q}"] = mx
        summary = invariants.summary(case.scene, traj, case.conserved)
        row.update(summary)
        failures = case.beyond_tolerance({q: mx for q, (mx, _) in errors.items()},
                                         {k[len("drift:"):]: v for k, v in summary.items() if k.startswith("drift:")})
        row["within_tolerance"] = not failures
        row["beyond"] = " ".join(failures)
    except Exception as e:  # a failure is data
        row.update(status="failed", message=f"{type(e).__name__}: {e}", traceback=traceback.format_exc())
    return row


def validate(case_names=None, jobs=None, progress=print):
    """Rows for every (case, settings) pair, run in a process pool of ``jobs`` workers."""
    from dalembert.case import load_cases

    registry = load_cases()
    names = list(case_names or registry)
    for n in names:
        registry[n]  # unknown names fail here, before anything runs
    work = [(n, {}, s) for n in names for s in settings_for(registry[n]())]
    rows = []
    with ProcessPoolExecutor(max_workers=jobs or os.cpu_count() or 1) as pool:
        futures = [pool.submit(validate_case, *w) for w in work]
        for k, (f, (name, _params, settings)) in enumerate(zip(futures, work), 1):
            try:
                row = f.result()
            except Exception as e:  # a worker that died is a failed row, not a crashed suite
                row = {"case": name, "settings": settings.label(), "status": "failed",
                       "message": f"worker died: {type(e).__name__}: {e}"}
            rows.append(row)
            progress(f"[{k}/{len(work)}] {row['case']:<24} {row['settings']:<40} {row['status']}"
                     + (f"  {row.get('wall_s', float('nan')):.2f} s" if row["status"] == "ok" else
                        f"  {row['message']}"))
    return rows


def _fmt(x):
    if isinstance(x, (bool, np.bool_)):
        return "yes" if x else "**no**"
    if isinstance(x, float):
        return "—" if np.isnan(x) else f"{x:.2e}"
    return str(x)


def to_markdown(rows):
    """A Markdown report: one table per case, errors (max over time) and invariant drift."""
    from dalembert.case import make_case

    lines = ["# dalembert — reference solver against the closed forms", "",
             "Errors are the maximum over the horizon against the case's closed-form truth; "
             "drifts are the maximum change of each conserved quantity (see `dalembert.invariants`). "
             "`within tol` compares with the case's named tolerances.", ""]
    for name in dict.fromkeys(r["case"] for r in rows):
        case_rows = [r for r in rows if r["case"] == name]
        case = make_case(name)
        lines += [f"## {name} (version {case.version})", ""]
        lines += [f"- tolerance `{k}`: {t.value:g} — {t.reason}" for k, t in case.tolerances.items()]
        lines.append("")
        keys = sorted({k for r in case_rows for k in r if k.startswith(("err:", "drift:"))})
        keys += [k for k in ("orthonormality", "quaternion_norm", "joint_residual") if any(k in r for r in case_rows)]
        head = ["settings", "status", "wall s", "RHS evals"] + [k.replace("err:", "") for k in keys] + ["within tol"]
        lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for r in case_rows:
            cells = [r["settings"], r["status"] if r["status"] == "ok" else f"{r['status']}: {r['message']}",
                     _fmt(r.get("wall_s", float("nan"))), str(r.get("n_rhs", ""))]
            cells += [_fmt(r.get(k, float("nan"))) for k in keys] + [_fmt(r.get("within_tolerance", False))]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def write_csv(rows, path):
    keys = list(dict.fromkeys(k for r in rows for k in r if k != "traceback"))
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, keys, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items() if k != "traceback"})
