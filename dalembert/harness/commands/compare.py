"""``dalembert compare``: two results directories run by run (``dalembert.reports.compare``); a
regression is exit 1, and a comparison in which nothing pairs is exit 2 with the reason (a gate that
compared nothing has checked nothing). ``--pair-options A_OPTIONS B_OPTIONS`` pairs two configurations of
one engine (``cone=pyramidal cone=elliptic``; A and B may be one store)."""

from __future__ import annotations

import math
import sys

from dalembert.harness.commands.console import fail as _fail
from dalembert.harness.commands.stores import open_store as _open
from dalembert import output
from dalembert.terminal import printable

__all__ = ["run", "main"]


def run(run_a, run_b, threshold=2.0, cost_threshold=None, across_versions=False, only_changed=False, json=None,
        csv=None, pair_options=None, pair_engines=None):
    """Compare the stores ``run_a`` and ``run_b`` and print (or write: ``json``, ``csv``, ``-`` for
    standard output) the comparison; returns the exit status (1 on a regression, 2 when nothing pairs).
    ``pair_options``: ``(A_OPTIONS, B_OPTIONS)``, each ``"key=value[,key=value]"``, as ``--pair-options``;
    ``pair_engines``: ``(A_ENGINE, B_ENGINE)``, as ``--pair-engines``."""
    from types import SimpleNamespace

    return main(SimpleNamespace(run_a=run_a, run_b=run_b, threshold=threshold, cost_threshold=cost_threshold,
                                across_versions=across_versions, only_changed=only_changed, json=json, csv=csv,
                                pair_options=pair_options, pair_engines=pair_engines))


def pair_options(texts):
    """``--pair-options``' two texts (``key=value[,key=value]``) as two dicts; ValueError naming the flag."""
    from dalembert.harness.selection import pairs

    if texts is None:
        return None
    out = tuple(pairs("--pair-options", [p for p in text.split(",") if p]) for text in texts)
    for side, options in zip("AB", out):
        if not options:
            raise ValueError(f"--pair-options: {side}'s options are empty — give KEY=VALUE[,KEY=VALUE] for each "
                             "side, e.g. --pair-options cone=pyramidal cone=elliptic")
    if out[0] == out[1]:
        raise ValueError(f"--pair-options: both sides are {texts[0]!r} — that pairs runs as they are; give the two "
                         "configurations to set against each other")
    return out


def pair_engines(names):
    """``--pair-engines``' two engine names (``mujoco==3.6.0 mujoco``), checked; ValueError naming the flag."""
    if names is None:
        return None
    if any(not n for n in names):
        raise ValueError("--pair-engines: an engine name is empty — give two, e.g. --pair-engines mujoco==3.6.0 mujoco")
    if names[0] == names[1]:
        raise ValueError(f"--pair-engines: both sides are {names[0]!r} — that pairs runs as they are; give the two "
                         "engines (or versions of one) to set against each other")
    return tuple(names)


def main(args):
    """The command line's ``dalembert compare`` (an argparse namespace in, the exit status out)."""
    import csv
    import io
    import json

    from dalembert.record import READABLE_SCHEMAS
    from dalembert.reports.compare import CSV_COLUMNS, compare_stores, csv_rows, to_json, to_text

    try:
        paired = pair_options(getattr(args, "pair_options", None))
        engines = pair_engines(getattr(args, "pair_engines", None))
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
                         across_versions=args.across_versions, pair_options=paired, pair_engines=engines)
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
    if cmp.unpaired:
        return _fail(f"{cmp.unpaired} — nothing was compared, so nothing is known about a regression")
    return 1 if cmp.regressed else 0
