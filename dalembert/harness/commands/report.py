"""``dalembert report``: report.html, report.md and summary.csv of a results directory."""

from __future__ import annotations

from dalembert.harness.commands.console import fail
from dalembert.terminal import printable

__all__ = ["run", "main"]


def run(run_dir, out_dir=None):
    """Write the report of ``run_dir`` (a store's path, or a ``dalembert.store.Store``) into
    ``out_dir`` (default: the store); returns the paths of report.html, report.md and summary.csv.
    ValueError when ``run_dir`` holds no store of this dalembert's schema."""
    from dalembert.harness.commands.stores import open_store
    from dalembert.reports.render import build_report
    from dalembert.store import Store

    store = run_dir if isinstance(run_dir, Store) else open_store(run_dir)
    return build_report(store, out_dir)


def main(args):
    try:
        paths = run(args.run_dir)
    except ValueError as e:
        return fail(str(e))
    for path in paths:
        print(f"wrote {printable(path)}")
    return 0
