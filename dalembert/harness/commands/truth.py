"""``dalembert truth``: a case's truth trajectory as CSV, at full precision (one row per sample
time and body); a parameter given twice is refused."""

from __future__ import annotations

from dalembert.harness.commands.console import fail as _fail
from dalembert.harness.selection import pairs
from dalembert.registry import UnknownNameError
from dalembert.scene import SceneError

__all__ = ["run", "main"]


def run(case, params=(), csv=None):
    """Write the truth of ``case`` (``params``: ``KEY=VALUE`` texts) to the file ``csv``; returns the
    exit status (2 with a message on a bad input)."""
    from types import SimpleNamespace

    return main(SimpleNamespace(case=case, param=list(params), csv=csv))


def main(args):
    """The command line's ``dalembert truth`` (an argparse namespace in, the exit status out)."""
    import io
    import sys

    from dalembert import output
    from dalembert.case import load_cases, parse_param
    from dalembert.terminal import printable
    from dalembert.trajectory import write_csv

    try:
        factory = load_cases()[args.case]
        params = dict(parse_param(factory, f"{k}={v}") for k, v in pairs("--param", args.param).items())
        case = factory(**params)
    except (UnknownNameError, ValueError, SceneError) as e:
        return _fail(str(e))
    output.check(args.csv, "--csv")
    from dalembert.reference import truth

    text = io.StringIO()
    write_csv(truth(case), text)
    output.write(args.csv, text.getvalue(), "--csv")
    print(f"wrote {printable(output.shown(args.csv))}: {case.name} (version {case.version}), "
          f"{len(case.sample_times)} samples", file=sys.stderr if args.csv == output.STDOUT else sys.stdout)
    return 0
