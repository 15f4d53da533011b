"""The ``dalembert`` command line.

Engines are imported lazily: listing and help work without any engine installed.
"""

from __future__ import annotations

import argparse
import os
import sys

EPILOG = """examples:
  dalembert cases --verbose
  dalembert truth free_top_intermediate --param t_final=5 --csv top.csv
  dalembert validate --out results
"""


def _parser():
    p = argparse.ArgumentParser(prog="dalembert", description="Validation harness for multibody physics engines.",
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)

    c = sub.add_parser("cases", help="list the registered cases",
                       epilog="example:\n  dalembert cases --verbose", formatter_class=argparse.RawDescriptionHelpFormatter)
    c.add_argument("--verbose", "-v", action="store_true", help="show parameters, defaults and units")

    t = sub.add_parser("truth", help="write a case's truth trajectory as CSV",
                       epilog="example:\n  dalembert truth particle_box --param omega0=0,1,1 --csv box.csv",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    t.add_argument("case")
    t.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="override a case parameter (vectors as comma-separated numbers); repeatable")
    t.add_argument("--csv", required=True, metavar="FILE", help="output file")

    v = sub.add_parser("validate", help="run every case with the reference solver against its closed form",
                       epilog="example:\n  dalembert validate --case pivoted_rod --out results",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    v.add_argument("--case", action="append", help="case name (repeatable; default: all)")
    v.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    v.add_argument("--out", default="results", metavar="DIR", help="where the report goes (default: results)")
    return p


def _fail(msg):
    print(f"dalembert: error: {msg}", file=sys.stderr)
    return 2


def cmd_cases(args):
    from dalembert.case import load_cases

    for name, factory in load_cases().items():
        print(f"{name:<24} [{', '.join(factory.tags)}]  {factory.summary}")
        if args.verbose:
            for key, default in factory.params.items():
                unit = factory.units.get(key, "")
                print(f"    {key:<18} = {default!r}" + (f"  ({unit})" if unit else ""))
    return 0


def cmd_truth(args):
    from dalembert.case import load_cases, parse_param
    from dalembert.registry import UnknownNameError
    from dalembert.scene import SceneError
    from dalembert.trajectory import write_csv

    try:
        factory = load_cases()[args.case]
        params = dict(parse_param(factory, p) for p in args.param)
        case = factory(**params)
    except (UnknownNameError, ValueError, SceneError) as e:
        return _fail(str(e))
    out_dir = os.path.dirname(os.path.abspath(args.csv))
    if not os.access(out_dir, os.W_OK):
        return _fail(f"--csv: cannot write to {out_dir!r}")
    from reference import truth

    write_csv(truth(case), args.csv)
    print(f"wrote {args.csv}: {case.name} (version {case.version}), {len(case.sample_times)} samples")
    return 0


def cmd_validate(args):
    from dalembert.case import load_cases
    from dalembert.registry import UnknownNameError
    from dalembert.validation import to_markdown, validate, write_csv

    try:
        for n in args.case or []:
            load_cases()[n]
        if args.jobs is not None and args.jobs < 1:
            raise ValueError(f"--jobs: must be at least 1, got {args.jobs}")
        os.makedirs(args.out, exist_ok=True)
        if not os.access(args.out, os.W_OK):
            raise ValueError(f"--out: cannot write to {args.out!r}")
    except (UnknownNameError, ValueError, OSError) as e:
        return _fail(str(e))
    rows = validate(args.case, args.jobs)
    md = to_markdown(rows)
    md_path, csv_path = os.path.join(args.out, "reference-validation.md"), os.path.join(args.out, "reference-validation.csv")
    with open(md_path, "w") as fh:
        fh.write(md)
    write_csv(rows, csv_path)
    print()
    print(md)
    print(f"wrote {md_path} and {csv_path}")
    bad = [r for r in rows if r["status"] not in ("ok", "unsupported")]
    return 1 if bad else 0


def main(argv=None):
    args = _parser().parse_args(argv)
    return {"cases": cmd_cases, "truth": cmd_truth, "validate": cmd_validate}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
