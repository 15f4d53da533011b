"""``dalembert compare``: two results directories run by run (``dalembert.reports.compare``); a
regression is exit 1."""

from __future__ import annotations

import math
import sys

from dalembert.harness.commands.console import fail as _fail
from dalembert.harness.commands.stores import open_store as _open
from dalembert import output
from dalembert.terminal import printable

__all__ = ["run", "main"]


def run(run_a, run_b, threshold=2.0, cost_threshold=None, across_versions=False, only_changed=False, json=None,
        csv=None):
    """Compare the stores ``run_a`` and ``run_b`` and print (or write: ``json``, ``csv``, ``-`` for
    standard output) the comparison; returns the exit status (1 on a regression)."""
    from types import SimpleNamespace

    return main(SimpleNamespace(run_a=run_a, run_b=run_b, threshold=threshold, cost_threshold=cost_threshold,
                                across_versions=across_versions, only_changed=only_changed, json=json, csv=csv))


def main(args):
    """The command line's ``dalembert compare`` (an argparse namespace in, the exit status out)."""
    import csv
    import io
    import json

    from dalembert.record import READABLE_SCHEMAS
    from dalembert.reports.compare import CSV_COLUMNS, compare_stores, csv_rows, to_json, to_text

    try:
        stores = [_open(d, READABLE_SCHEMAS) for d in (args.run_a, args.run_b)]
        for flag, path in (("--json", args.json), ("--csv", args.csv)):
            if path is not None:
                output.check(path, flag)
    except ValueError as e:
        return _fail(str(e))
    for flag, value in (("--threshold", args.threshold), ("--cost-threshold", args.cost_threshold)):
        if value is not None and not (math.isfinite(value) and value > 1.0):
            return _fail(f"{flag}: a growth factor, must be finite and greater than 1, got {value}")
    schemas = [s.schema_version() for s in stores]
    if schemas[0] != schemas[1]:
        print(f"dalembert: note: the stores have schemas {schemas[0]} and {schemas[1]}; runs are matched by case, "
              "engine and settings", file=sys.stderr)
    cmp = compare_stores(*stores, threshold=args.threshold, cost_threshold=args.cost_threshold,
                         across_versions=args.across_versions)
    outputs = []  # (flag, path, text)
    if args.json is not None:
        outputs.append(("--json", args.json, json.dumps(to_json(cmp), indent=1, allow_nan=False) + "\n"))
    if args.csv is not None:
        buf = io.StringIO()
        writer = csv.DictWriter(buf, CSV_COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows({k: (repr(v) if isinstance(v, float) else v) for k, v in row.items()} for row in csv_rows(cmp))
        outputs.append(("--csv", args.csv, buf.getvalue()))
    if all(path != output.STDOUT for _, path, _ in outputs):
        sys.stdout.write(to_text(cmp, args.only_changed))
    for flag, path, text in outputs:
        output.write(path, text, flag)
        if path != output.STDOUT:
            print(f"wrote {printable(path)}", file=sys.stderr)
    return 1 if cmp.regressed else 0
