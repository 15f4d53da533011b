"""``dalembert validate``: the reference solver against every case's truth (not the hard cases),
tabulated per case as reference-validation.md and .csv in the results directory."""

from __future__ import annotations

import os

from dalembert.harness import session
from dalembert.harness.commands.console import command_line, note, progress_printer
from dalembert.harness.selection import given
from dalembert.store import atomic_write

__all__ = ["run", "main"]


def run(cases=None, jobs=None, out=None, progress=None, command=None):
    """Run the validation matrix of ``cases`` (default: every case not tagged hard) on ``jobs``
    workers into the new store ``out`` (default ``results/validation-<time>``) and write its tables.

    Returns ``(store, records, markdown)``. ValueError or KeyError (an unknown case, with a "did
    you mean") naming the flag, before anything is written: every case and its truth are built
    before the store is made.
    """
    from dalembert.harness.truths import build
    from dalembert.harness.validation import to_markdown, validate, validation_specs, write_csv

    if out is not None:
        given("--out", out)
    if jobs is not None and jobs < 1:
        raise ValueError(f"--jobs: must be at least 1, got {jobs}")
    notes = []
    specs = validation_specs(cases, notes)  # unknown names and bad settings fail here, before anything runs
    for text in notes:
        note(text)
    built = build(specs)
    store, lock = session.start(out or session.default_out("validation"),
                                {"command": command or command_line(), "specs": []}, built)
    with lock:
        records = validate(store, None, jobs, progress, specs)
        md = to_markdown(store)
        atomic_write(os.path.join(store.path, "reference-validation.md"), md)
        write_csv(store, os.path.join(store.path, "reference-validation.csv"))
    return store, records, md


def main(args):
    """The command line's: the table printed, the files named; exit 1 when a run is not ok."""
    store, records, md = run(args.case, args.jobs, args.out, progress_printer(), command_line())
    print()
    print(md)
    print(f"wrote {os.path.join(store.path, 'reference-validation.md')} and "
          f"{os.path.join(store.path, 'reference-validation.csv')}")
    return 1 if any(r.status not in ("ok", "unsupported") for r in records) else 0
