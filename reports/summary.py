"""Summary report of a results store: Markdown and CSV, read from the store only.

One table per case: every engine and setting with its status, stepping cost,
errors against the truth (max over time), invariant drift, and whether it is
within the case's tolerances. (The reports issue adds plots, HTML, work-precision
and stability pages on top of this.)
"""

from __future__ import annotations

import math
import os

__all__ = ["write_summary"]

ERROR_COLUMNS = ["err_position_max", "err_orientation_max", "err_velocity_max", "err_angular_velocity_max",
                 "err_joint_max", "err_reaction_force_max"]


def _fmt(x):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "—"
    if isinstance(x, bool):
        return "yes" if x else "**no**"
    if isinstance(x, float):
        return f"{x:.2e}"
    return str(x)


def write_summary(store, out_dir=None):
    """Write ``report.md`` and ``summary.csv`` into ``out_dir`` (default: the store). Returns the paths."""
    df = store.table()
    manifest = store.manifest()
    out_dir = out_dir or store.path
    lines = ["# dalembert report", "",
             f"- harness {manifest.get('harness_version')} at commit `{manifest.get('harness_commit')}`",
             f"- machine: {manifest.get('machine', {}).get('cpu')} ({manifest.get('machine', {}).get('cores')} cores), "
             f"{manifest.get('machine', {}).get('os')}, Python {manifest.get('machine', {}).get('python')}",
             f"- engines: " + ", ".join(f"{k} {v}" for k, v in sorted(manifest.get("engines", {}).items())),
             f"- command: `{manifest.get('command')}`; started {manifest.get('started')}, ended {manifest.get('ended')}",
             "", "Errors are maxima over the horizon against the case's truth (closed form); wall time is the "
             "median stepping time of the repeats; `ok?` says whether every error and drift is within the case's "
             "tolerances.", ""]
    if df.empty:
        lines.append("No runs stored.")
    for case in sorted(df["case"].unique()) if not df.empty else []:
        sub = df[df["case"] == case].sort_values(["engine", "integrator", "dt", "rtol"], na_position="last")
        errs = [c for c in ERROR_COLUMNS if c in sub and sub[c].notna().any()]
        drifts = sorted(c for c in sub.columns if c.startswith("drift_") and sub[c].notna().any())
        head = ["engine", "settings", "status", "wall s", "steps"] + [c[4:-4] for c in errs] + \
               [c[6:] + " drift" for c in drifts] + ["ok?"]
        lines += [f"## {case}", "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        for _, r in sub.iterrows():
            status = r["status"] if r["status"] == "ok" else f"{r['status']}: {r['message']}"
            ok = r.get("within_tolerance")
            beyond = r.get("beyond_tolerance") or ""
            cells = [r["engine"], r["settings"], status, _fmt(r.get("wall_s_median")), _fmt(r.get("n_steps"))]
            cells += [_fmt(r.get(c)) for c in errs + drifts]
            if r["status"] != "ok" or ok is None or (isinstance(ok, float) and math.isnan(ok)):
                cells.append("—")
            else:
                cells.append("yes" if ok else f"**no**: {beyond}")
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    md_path, csv_path = os.path.join(out_dir, "report.md"), os.path.join(out_dir, "summary.csv")
    from dalembert.store import atomic_write

    atomic_write(md_path, "\n".join(lines) + "\n")
    cols = [c for c in ["case", "engine", "settings", "status", "message", "wall_s_median", "n_steps", "n_rhs",
                        *ERROR_COLUMNS, "within_tolerance"] if c in df]
    atomic_write(csv_path, df[cols].to_csv(index=False, float_format="%.17g") if not df.empty else "")
    return md_path, csv_path
