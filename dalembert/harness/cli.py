"""The ``dalembert`` command line: the parser and the dispatch to ``dalembert.harness.commands``.

Each command is a module there whose ``run`` the Python API (``dalembert.harness.api``) shares;
this module only builds the flags, refuses an empty value of any of them (empty never means
"not given"), and turns errors into one-line messages and exit statuses. Engines are imported
lazily: listing and help work without any engine installed.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from dalembert.harness.commands import (cases, check_engine, compare, engines, env, export, report, repro,
                                         show_model, truth, validate)
from dalembert.harness.commands import run as run_command
from dalembert.harness.commands.console import fail as _fail
from dalembert.terminal import printable

EPILOG = """examples:
  dalembert cases --verbose
  dalembert engines
  dalembert run --case free_top --engine reference --integrator rk4 --dt 1e-2,1e-3 --out results/top
  dalembert run --resume results/top
  dalembert report results/top
  dalembert export results/top --case free_top --engine reference --integrator rk4 --dt 1e-3 --csv top.csv
  dalembert truth free_top_intermediate --param t_final=5 --csv top.csv
  dalembert validate --case pivoted_rod
  dalembert check-engine mujoco --integrator rk4
  dalembert repro results/top --key free_top__mujoco__rk4__0123456789ab --out top_mujoco.py
  dalembert env create mujoco==3.6.0
  dalembert run --engine mujoco==3.6.0 --engine mujoco --case free_top_intermediate --integrator rk4 --dt 5e-3
"""


def _floats(text):
    """Comma-separated numbers (repeatable flags are concatenated)."""
    try:
        return [float(x) for x in text.split(",") if x]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


class _Once(argparse.Action):
    """A single-valued flag: stored, and refused when given twice (which one was meant is a guess;
    argparse would keep the last). Repeatable flags (``action="append"``) are not this."""

    def __call__(self, parser, namespace, values, option_string=None):
        before = getattr(namespace, self.dest, None)
        if before is not self.default:  # a value parsed from the command line is never the default object
            raise argparse.ArgumentError(self, f"given twice ({before!r} and {values!r}) — give it once")
        setattr(namespace, self.dest, values)


class _Parser(argparse.ArgumentParser):
    """The parser of ``dalembert`` and of each command (subparsers take their parent's class): a
    plain ``add_argument`` stores once (``_Once``)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.register("action", None, _Once)
        self.register("action", "store", _Once)


def _parser():
    p = _Parser(prog="dalembert", description="Validation harness for multibody physics engines.",
                                epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--debug", action="store_true", help="show the traceback of an error instead of its message")
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
    t.add_argument("--csv", required=True, metavar="FILE", help="output file (- for standard output)")

    e = sub.add_parser("engines", help="list engines, what they support and their integrators",
                       epilog="example:\n  dalembert engines", formatter_class=argparse.RawDescriptionHelpFormatter)
    e.add_argument("--verbose", "-v", action="store_true", help="show integrator options")

    r = sub.add_parser("run", help="run a matrix of cases x engines x integrators x dt/tolerances",
                       epilog="examples:\n  dalembert run\n  dalembert run --tag free --engine reference --dt 1e-3\n"
                              "  dalembert run --resume results/2026-11-22T10-00-00",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    r.add_argument("--case", action="append", help="case name (repeatable; default: all)")
    r.add_argument("--tag", action="append", help="select cases by tag (repeatable)")
    r.add_argument("--engine", action="append", help="engine name (repeatable; default: every installed one)")
    r.add_argument("--integrator", action="append", help="integrator name (repeatable; default: all)")
    r.add_argument("--dt", action="append", type=_floats,
                   help="step sizes in s, comma-separated (default 1e-2,5e-3,2e-3,1e-3)")
    r.add_argument("--rtol", action="append", type=_floats, help="tolerances for adaptive integrators (default 1e-6,1e-9)")
    r.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="case parameter override")
    r.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                   help="engine option (every run); KEY=V1,V2 or KEY=log:a,b,n / lin:a,b,n sweeps it, a run each")
    r.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    r.add_argument("--timeout", type=float, default=None, help="per-run limit in s (default 600)")
    r.add_argument("--quick", action="store_true",
                   help="time each run once after its warm-up (as validate does), not until its timing is steady: "
                        "for matrices whose accuracy, not cost, is the point (short runs take a fraction of the time)")
    r.add_argument("--scheduler", metavar="ADDRESS", help="run on a Dask cluster, e.g. tcp://host:8786")
    r.add_argument("--out", metavar="DIR", help="results directory (default results/<timestamp>)")
    r.add_argument("--resume", metavar="DIR", help="finish an interrupted run directory")
    r.add_argument("--search", choices=["dt"],
                   help="find each fixed-step integrator's stability boundary in the step by bisection within "
                        "the bracket the --dt values give (stored probes are reused)")
    r.add_argument("--resolution", type=float, default=None,
                   help="with --search: stop when the failing step is within this factor of the passing one "
                        "(default 1.2)")
    r.add_argument("--batch", action="store_true",
                   help="step the runs that differ only in the case's parameters (--param sweeps, a map's swept "
                        "parameter) as the worlds of one engine call, on engines that have batches (mujoco_warp, "
                        "mjx); their costs are then per world, the batch's beside them")
    r.add_argument("--trajectories", metavar="all|drawn|none", default=None,
                   help="which runs' trajectories the store keeps: all, drawn (only those the report draws; the "
                        "rest are dropped when the matrix ends) or none (default: all up to 2000 runs, else drawn); "
                        "--resume keeps the store's")
    r.add_argument("--no-maps", action="store_true",
                   help="leave out the default stability maps of the selected tags (e.g. --tag hard runs them)")
    r.add_argument("--force", action="store_true",
                   help="allow sizes refused by default (usually a typo): runs of more than 1e8 steps, matrices or "
                        "sweeps of more than 1e4 runs, models of more than 1000 parts")
    r.add_argument("--strict", nargs="?", const="status", default=False, choices=["status", "tolerance"],
                   help="exit 1 when any run failed, diverged or timed out (for CI; by default those are "
                        "findings in the report, and the exit is 0 once every run is stored); --strict=tolerance: "
                        "also when a finished run is beyond its case's tolerance")

    rp = sub.add_parser("report", help="write report.html, report.md and summary.csv for a results directory",
                        epilog="example:\n  dalembert report results/latest",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    rp.add_argument("run_dir")

    x = sub.add_parser("export", help="write stored trajectories (bodies, joints, reaction forces) as CSV or Parquet",
                       epilog="examples:\n  dalembert export results/latest --case free_top --engine reference "
                              "--integrator rk4 --dt 1e-3 --csv top.csv\n"
                              "  dalembert export results/latest --case free_top --engine exudyn --integrator "
                              "generalized-alpha --dt 1e-3 --option node=ep --csv ep.csv\n"
                              "  dalembert export results/latest --key free_top__mujoco__rk4__0123456789ab --csv run.csv\n"
                              "  dalembert export results/latest --all --parquet runs.parquet\n\n"
                              "One long-format table: a row per run, sample time and body, joint or reaction force "
                              "(columns kind, name); see dalembert.reports.export.",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    x.add_argument("run_dir")
    x.add_argument("--key", action="append", default=[], help="a run's key (repeatable; the report's run tables "
                                                              "and runs.parquet list them)")
    x.add_argument("--case")
    x.add_argument("--engine")
    x.add_argument("--integrator")
    x.add_argument("--dt", type=float)
    x.add_argument("--rtol", type=float)
    x.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                   help="engine option the run had (repeatable; KEY= for a run that did not set it)")
    x.add_argument("--all", action="store_true", help="every run that matches (all runs when nothing else is "
                                                      "given), into one file; without it exactly one must match")
    out = x.add_mutually_exclusive_group(required=True)
    out.add_argument("--csv", metavar="FILE", help="CSV, 17 significant digits (- for standard output)")
    out.add_argument("--parquet", metavar="FILE", help="Parquet (- for standard output)")

    cp = sub.add_parser("compare", help="compare two results directories; non-zero exit on a regression",
                        epilog="examples:\n  dalembert compare results/before results/after --threshold 2\n"
                               "  dalembert compare A B --only-changed --json changes.json\n"
                               "  dalembert compare S S --pair-options cone=pyramidal cone=elliptic",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    cp.add_argument("run_a")
    cp.add_argument("run_b")
    cp.add_argument("--threshold", type=float, default=2.0, help="error growth factor that is a regression (default 2)")
    cp.add_argument("--cost-threshold", type=float, default=None,
                    help="stepping-time growth factor that is a regression (default: costs are reported only)")
    cp.add_argument("--across-versions", action="store_true",
                    help="compare runs whose case version differs (e.g. after a change that only reworded a "
                         "case or re-hashed it); by default they are flagged, not compared")
    cp.add_argument("--pair-options", nargs=2, metavar=("A_OPTIONS", "B_OPTIONS"),
                    help="pair two configurations of one engine: A's runs with A_OPTIONS (KEY=VALUE[,KEY=VALUE]; "
                         "KEY=default: the option not given) against B's with B_OPTIONS, all else equal (A and B "
                         "may be one directory)")
    cp.add_argument("--pair-engines", nargs=2, metavar=("A_ENGINE", "B_ENGINE"),
                    help="pair A's runs of A_ENGINE against B's of B_ENGINE, all else equal: two versions of one "
                         "engine (--pair-engines mujoco==3.6.0 mujoco; A and B may be one directory)")
    cp.add_argument("--only-changed", action="store_true", help="print only the runs that changed")
    cp.add_argument("--json", metavar="FILE", help="also write the comparison as JSON (- for stdout, instead of the text)")
    cp.add_argument("--csv", metavar="FILE",
                    help="also write it as CSV, a row per run and quantity (- for stdout, instead of the text)")

    sm = sub.add_parser("show-model", help="print the model an engine builds for a case (e.g. MJCF)",
                        epilog="examples:\n  dalembert show-model pivoted_rod --engine mujoco\n"
                               "  dalembert show-model free_top --engine exudyn --option node=ep",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    sm.add_argument("case")
    sm.add_argument("--engine", required=True)
    sm.add_argument("--integrator", default=None, help="default: the engine's first that runs the case")
    sm.add_argument("--dt", type=float, default=1e-3)
    sm.add_argument("--param", action="append", default=[], metavar="KEY=VALUE")
    sm.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                    help="engine option (repeatable), e.g. joints=redundant for Exudyn")

    ce = sub.add_parser("check-engine", help="probe an engine's adapter with known answers; exit 1 on any problem",
                        epilog="examples:\n  dalembert check-engine mujoco\n  dalembert check-engine mjx --integrator "
                               "euler --option precision=float64\n\nThe probes and what each looks for: "
                               "docs/engines.md (check-engine).", formatter_class=argparse.RawDescriptionHelpFormatter)
    ce.add_argument("engine")
    ce.add_argument("--integrator", action="append", default=None,
                    help="integrator to probe (repeatable; default: the first for the motion probes, every fixed-step "
                         "one for the order probe)")
    ce.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                    help="engine option for every run whose integrator takes it (repeatable)")
    ce.add_argument("--verbose", "-v", action="store_true", help="also print the notes (figures measured, probes "
                                                                 "that did not apply)")
    rr = sub.add_parser("repro", help="write one stored run as a standalone script (the engine and numpy, no "
                                      "dalembert) that reproduces its headline error",
                        epilog="example:\n  dalembert repro results/latest --key pendulum__mujoco__rk4__0123456789ab "
                               "--out pendulum_mujoco.py\n\nThe script prints its error and the stored one and exits "
                               f"1 when they differ by more than {repro.REPRO_REL_TOL:g} relative; see "
                               "dalembert.harness.commands.repro.",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    rr.add_argument("run_dir")
    rr.add_argument("--key", required=True, help="the run's key (the report's run tables and runs.parquet list them)")
    rr.add_argument("--out", default="-", metavar="FILE", help="the script (default - : standard output)")

    en = sub.add_parser("env", help="engine environments: an engine at a version of its own (create, list, remove)",
                        epilog="examples:\n  dalembert env create mujoco==3.6.0\n  dalembert env list\n"
                               "  dalembert env remove mujoco==3.6.0\n\ncreate reaches the package index (uv if on "
                               "PATH, else venv and pip); run --engine mujoco==3.6.0 then runs its runs there.",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    en.add_argument("env_action", choices=("create", "list", "remove"), metavar="{create,list,remove}")
    en.add_argument("engine", nargs="?", default=None, help="ENGINE==VERSION (a PEP 440 requirement), e.g. "
                                                            "mujoco==3.6.0; none for list")
    en.add_argument("--verbose", "-v", action="store_true", help="print each install command, and each path")
    en.add_argument("--force", action="store_true", help="create: make an existing environment again (one that "
                                                          "env list says is stale), replacing it once made")

    v = sub.add_parser("validate", help="run every case (not tagged hard) with the reference solver against its truth",
                       epilog="example:\n  dalembert validate --case pivoted_rod",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    v.add_argument("--case", action="append", help="case name (repeatable; default: every case not tagged hard)")
    v.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    v.add_argument("--out", metavar="DIR",
                   help="results directory for the validation runs and tables (default results/validation-<timestamp>)")
    return p


# What a user can get wrong (a name, a value, a file): a message naming it, exit 2.
USER_ERRORS = (ValueError, KeyError, ImportError, OSError)
# Each command's module (its ``main(args)``).
COMMANDS = {"cases": cases.main, "engines": engines.main, "run": run_command.main, "report": report.main,
            "show-model": show_model.main, "validate": validate.main, "truth": truth.main, "export": export.main,
            "compare": compare.main, "check-engine": check_engine.main, "repro": repro.main, "env": env.main}


def _refuse_empty(parser, args):
    """ValueError naming the first flag (or argument) of ``args.command`` given an empty value:
    ``--resume ''`` or ``--scheduler ''`` is a slip, never "use the default"."""
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[args.command]
    for action in sub._actions:
        value = getattr(args, action.dest, None)
        texts = [value] if isinstance(value, str) else [v for v in value if isinstance(v, str)] \
            if isinstance(value, list) else []
        if any(not t.strip() for t in texts):
            flag = max(action.option_strings, key=len) if action.option_strings else action.dest.upper()
            raise ValueError(f"{flag}: empty — give a value, or leave {flag} out (an empty value is never the "
                             "default)")


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A plugin left out (``adapters.registry.PluginWarning``) as the command line's one-line warning; any other
    warning as Python shows it."""
    from dalembert.adapters.registry import PluginWarning

    if issubclass(category, PluginWarning):
        print(f"dalembert: warning: {printable(message)}", file=file or sys.stderr)
    else:
        print(warnings.formatwarning(message, category, filename, lineno, line), end="", file=file or sys.stderr)


def main(argv=None):
    """Run one command; every error a user can cause is a one-line message (``--debug``: the
    traceback), an unexpected one says so and how to report it."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        _refuse_empty(parser, args)
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            return COMMANDS[args.command](args)
    except BrokenPipeError:  # the reader left (e.g. `dalembert cases | head`): not an error
        try:  # Python's documented recipe: stdout to /dev/null, so the final flush cannot fail again
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (AttributeError, OSError, ValueError):
            pass
        return 0
    except KeyboardInterrupt:
        print("\ndalembert: interrupted", file=sys.stderr)
        return 130
    except USER_ERRORS as e:
        if args.debug:
            raise
        return _fail(str(e.args[0]) if type(e) is KeyError and e.args else str(e))
    except Exception as e:  # a bug of dalembert's, not the user's
        if args.debug:
            raise
        print(f"dalembert: internal error: {type(e).__name__}: {printable(e)} — rerun with --debug for the traceback "
              "and report it", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
