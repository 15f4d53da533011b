"""``dalembert export``: stored trajectories (bodies, joints, reaction forces) as one long-format
CSV or Parquet table (``dalembert.reports.export``)."""

from __future__ import annotations

from dalembert.harness.commands.console import fail as _fail
from dalembert.harness.commands.stores import open_store as _open
from dalembert.harness.selection import pairs

__all__ = ["run", "main"]


def run(run_dir, csv=None, parquet=None, keys=(), case=None, engine=None, integrator=None, dt=None, rtol=None,
        options=(), all=False):
    """Write the matching runs of ``run_dir`` to ``csv`` or ``parquet`` (``options``: ``KEY=VALUE``
    texts); returns the exit status (2 with a message when not exactly one run matches and not
    ``all``)."""
    from types import SimpleNamespace

    return main(SimpleNamespace(run_dir=run_dir, csv=csv, parquet=parquet, key=list(keys), case=case, engine=engine,
                                integrator=integrator, dt=dt, rtol=rtol, option=list(options), all=all))


def main(args):
    """The command line's ``dalembert export`` (an argparse namespace in, the exit status out)."""
    import sys

    from dalembert import output
    from dalembert.reports.export import frame, select, write
    from dalembert.reports.findings import run_name
    from dalembert.terminal import printable

    fmt = "csv" if args.csv is not None else "parquet"
    path = args.csv if args.csv is not None else args.parquet
    try:
        store = _open(args.run_dir)
        options = pairs("--option", args.option)
        output.check(path, f"--{fmt}")
    except ValueError as e:
        return _fail(str(e))
    records = store.records()
    chosen = select(records, set(args.key), args.case, args.engine, args.integrator, args.dt, args.rtol, options)
    if not args.all and len(chosen) != 1:
        listed = chosen or records
        return _fail(f"{len(chosen)} stored runs match (need exactly one: add --dt, --rtol, --option or --key, or "
                     f"--all for every match). {'Matching' if chosen else 'Stored'}: "
                     + "; ".join(f"{r.key} ({r.case} {run_name(r)}, {r.status})" for r in listed[:40])
                     + (f"; and {len(listed) - 40} more" if len(listed) > 40 else ""))
    kept = [r for r in chosen if r.trajectory and store.has_trajectory(r.key)]
    not_kept = [r for r in chosen if r.status == "ok" and r not in kept and store.kept().keep != "all"]
    if not args.all and not_kept:
        return _fail(store.kept().not_kept(chosen[0].key))
    if not args.all and not chosen[0].trajectory:
        return _fail(f"that run has no trajectory (status {chosen[0].status}: {chosen[0].message})")
    df = frame(store, kept)
    write(df, path, fmt)
    with_traj = len(kept)
    print(f"wrote {printable(output.shown(path))}: {with_traj} run(s), {len(df)} rows"
          + (f" ({len(chosen) - with_traj - len(not_kept)} matching run(s) left no trajectory)"
             if with_traj + len(not_kept) < len(chosen) else "")
          + (f" ({len(not_kept)} matching run(s) whose trajectory the store did not keep: run.trajectories = "
             f"{store.kept().keep})" if not_kept else ""),
          file=sys.stderr if path == output.STDOUT else sys.stdout)
    return 0
