"""The ``dalembert`` command line.

Engines are imported lazily: listing and help work without any engine installed.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys

from dalembert.harness import session
from dalembert.record import BAD_STATUSES
from dalembert.registry import UnknownNameError
from dalembert.scene import SceneError
from dalembert.store import atomic_write
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
"""


def _floats(text):
    """Comma-separated numbers (repeatable flags are concatenated)."""
    try:
        return [float(x) for x in text.split(",") if x]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def _parser():
    p = argparse.ArgumentParser(prog="dalembert", description="Validation harness for multibody physics engines.",
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
    r.add_argument("--dt", action="append", type=_floats, help="step sizes in s, comma-separated (default 1e-2,1e-3)")
    r.add_argument("--rtol", action="append", type=_floats, help="tolerances for adaptive integrators (default 1e-6,1e-9)")
    r.add_argument("--param", action="append", default=[], metavar="KEY=VALUE", help="case parameter override")
    r.add_argument("--option", action="append", default=[], metavar="KEY=VALUE", help="engine option (every run)")
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
    r.add_argument("--no-maps", action="store_true",
                   help="leave out the default stability maps of the selected tags (e.g. --tag hard runs them)")
    r.add_argument("--force", action="store_true",
                   help=f"allow runs of more than 1e8 steps (refused by default: usually a typo in --dt)")
    r.add_argument("--strict", action="store_true",
                   help="exit 1 when any run failed, diverged or timed out (for CI; by default those are "
                        "findings in the report, and the exit is 0 once every run is stored)")

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
                               "  dalembert compare A B --only-changed --json changes.json",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    cp.add_argument("run_a")
    cp.add_argument("run_b")
    cp.add_argument("--threshold", type=float, default=2.0, help="error growth factor that is a regression (default 2)")
    cp.add_argument("--cost-threshold", type=float, default=None,
                    help="stepping-time growth factor that is a regression (default: costs are reported only)")
    cp.add_argument("--across-versions", action="store_true",
                    help="compare runs whose case version differs (e.g. after a change that only reworded a "
                         "case or re-hashed it); by default they are flagged, not compared")
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

    v = sub.add_parser("validate", help="run every case (not tagged hard) with the reference solver against its truth",
                       epilog="example:\n  dalembert validate --case pivoted_rod",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    v.add_argument("--case", action="append", help="case name (repeatable; default: every case not tagged hard)")
    v.add_argument("--jobs", type=int, default=None, help="worker processes (default: all cores)")
    v.add_argument("--out", metavar="DIR",
                   help="results directory for the validation runs and tables (default results/validation-<timestamp>)")
    return p


def _fail(msg):
    print(f"dalembert: error: {printable(msg)}", file=sys.stderr)
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
    import io

    from dalembert import output
    from dalembert.case import load_cases, parse_param
    from dalembert.trajectory import write_csv

    try:
        factory = load_cases()[args.case]
        params = dict(parse_param(factory, p) for p in args.param)
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


def cmd_validate(args):
    from dalembert.harness.validation import to_markdown, validate, validation_specs, write_csv

    if args.jobs is not None and args.jobs < 1:
        raise ValueError(f"--jobs: must be at least 1, got {args.jobs}")
    validation_specs(args.case)  # unknown names and bad settings fail here, before anything runs
    store, lock = session.start(args.out or session.default_out("validation"),
                                {"command": _command_line(), "specs": []})
    with lock:
        records = validate(store, args.case, args.jobs, _progress_printer())
        md = to_markdown(store)
        md_path = os.path.join(store.path, "reference-validation.md")
        csv_path = os.path.join(store.path, "reference-validation.csv")
        atomic_write(md_path, md)
        write_csv(store, csv_path)
    print()
    print(md)
    print(f"wrote {md_path} and {csv_path}")
    return 1 if any(r.status not in ("ok", "unsupported") for r in records) else 0


def cmd_engines(args):
    from dalembert.adapters import adapter_names, get_adapter

    for name in adapter_names():
        adapter = get_adapter(name)
        try:
            version = adapter.version()
        except ImportError as e:
            version = f"not installed ({e})"
        print(f"{name:<10} {version}")
        print(f"    effects: {', '.join(sorted(adapter.effects))}")
        for integ, spec in adapter.integrators.items():
            knobs = "dt" if spec.fixed_step else "rtol, atol"
            opts = f"; options: {', '.join(spec.options)}" if spec.options and args.verbose else ""
            print(f"    {integ:<20} {knobs}{opts}  {spec.description if args.verbose else ''}".rstrip())
        if args.verbose:  # each option's values, from the adapter's declaration (``Adapter.options``)
            for key, option in adapter.options.items():
                default = "" if option.default is None else f"; default {option.default}"
                only = f"; {', '.join(option.only)} only" if option.only else ""
                print(f"    option {key}: {option.allowed()}{default}{only}  {option.description}".rstrip())
    return 0


def _progress_printer(stream=None):
    import time

    stream = stream or sys.stderr
    start = time.monotonic()
    tty = stream.isatty()

    def show(done, total, bad, record):
        elapsed = time.monotonic() - start
        eta = elapsed / done * (total - done) if done else float("nan")
        status = f"[{done}/{total}] failures {bad}  elapsed {elapsed:.0f} s  eta {eta:.0f} s"
        run = printable(f"{record.case} {record.engine} {record.settings_label}", newlines=False)  # a store's names
        if tty:
            stream.write(f"\r{status}  {run} {record.status}\033[K")
            if done == total:
                stream.write("\n")
        else:
            stream.write(f"{status}  {run}: {record.status}"
                         f"{' — ' + printable(record.message) if record.message else ''}\n")
        stream.flush()

    return show


def _command_line():
    import shlex

    return shlex.join(["dalembert"] + sys.argv[1:])


def _resumable(path):
    """The store at ``path`` and its specs, if this dalembert may finish it: same schema, every
    stored run one of the manifest's, every engine registered here (its adapter is imported from
    the registry, never from a name the store holds), every case still at the version the matrix
    was made for. ValueError naming what does not belong together."""
    from dataclasses import replace

    from dalembert.adapters import adapter_names, adapter_path
    from dalembert.case import load_cases
    from dalembert.harness.matrix import RunSpec
    from dalembert.store import Store

    store = Store.open(path)
    try:
        specs = [RunSpec.from_json(d) for d in store.manifest()["specs"]]
    except (KeyError, TypeError) as e:
        raise ValueError(f"--resume {path}: manifest.json does not list the matrix's runs ({type(e).__name__}: {e}) "
                         "— it is not a manifest dalembert wrote; start a new matrix with --out") from None
    unknown = sorted({s.engine for s in specs} - set(adapter_names()))
    if unknown:
        raise ValueError(f"--resume {path}: engine(s) {unknown} are not registered here — install them, or start a "
                         "new matrix without them")
    specs = [replace(s, adapter=adapter_path(s.engine)) for s in specs]
    registry = load_cases()
    changed = []
    for name, params, version in sorted({(s.case, s.params, s.case_version) for s in specs}):
        if name not in registry:
            changed.append(f"case {name!r} is no longer registered")
            continue
        now = registry[name](**dict(params)).version
        if now != version:
            changed.append(f"case {name!r} is version {now} now, the store holds runs of version {version}")
    if changed:
        raise ValueError(f"--resume {path}: " + "; ".join(changed) + " — finishing it would mix two versions of a "
                         "case; start a new matrix with --out")
    strays = sorted(store.done_keys() - {s.key for s in specs})
    if strays:
        raise ValueError(f"--resume {path}: {len(strays)} stored run(s) are not in its manifest (e.g. rows/{strays[0]}"
                         ".json): the rows and the manifest come from different matrices — start a new matrix")
    return store, specs


def _connect(address, debug=False):
    """A Dask client on ``address``; ValueError naming ``--scheduler`` when it cannot be reached
    (before anything is written). Dask's own log is kept to its critical messages (a lost
    scheduler is reported once, as runs not run) unless ``debug``."""
    import logging

    try:
        from distributed import Client
    except ImportError as e:
        raise ImportError(f"--scheduler: Dask's distributed is not installed ({e}) — pip install distributed") from None
    if not debug:  # after the import: distributed configures its loggers' levels when imported
        for name in list(logging.root.manager.loggerDict):
            if name == "distributed" or name.startswith("distributed."):
                logging.getLogger(name).setLevel(logging.CRITICAL)
    try:
        return Client(address, timeout=SCHEDULER_CONNECT_S)
    except (OSError, TimeoutError, ValueError) as e:
        raise ValueError(f"--scheduler {address}: cannot connect ({type(e).__name__}: {e}) — start the scheduler or "
                         "check the address; nothing was written") from None


def _stop_on_sigterm():
    """SIGTERM ends a matrix as Ctrl-C does: every finished run stored, the workers gone."""
    import signal

    def stop(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)


def _search(store, plan, run):
    """Run the boundary search the manifest's ``plan`` describes; each round's probes join the
    manifest's specs before they run (so ``--resume`` knows them)."""
    from dalembert.harness.matrix import RunSpec
    from dalembert.harness.search import search

    def run_round(batch):
        manifest = store.manifest()
        known = {json.dumps(s, sort_keys=True) for s in manifest["specs"]}
        manifest["specs"] += [s.to_json() for s in batch if json.dumps(s.to_json(), sort_keys=True) not in known]
        store.write_manifest(manifest)
        return run(batch)

    def said(rnd, probes):
        print(f"dalembert: search round {rnd}: {len(probes)} probe(s)", file=sys.stderr)

    return search([RunSpec.from_json(s) for s in plan["first"]], store, run_round, plan["resolution"], said)


def cmd_run(args):
    from dalembert.harness.dask import run_matrix_dask
    from dalembert.harness.execute import QUICK, Timing
    from dalembert.harness.pool import DEFAULT_TIMEOUT_S, run_matrix
    from dalembert.harness.selection import select
    from dalembert.store import Store

    if args.resume:
        given = [flag for flag, value in (("--case", args.case), ("--tag", args.tag), ("--engine", args.engine),
                                          ("--integrator", args.integrator), ("--dt", args.dt), ("--rtol", args.rtol),
                                          ("--param", args.param), ("--option", args.option), ("--out", args.out),
                                          ("--timeout", args.timeout), ("--force", args.force),
                                          ("--search", args.search), ("--resolution", args.resolution),
                                          ("--no-maps", args.no_maps), ("--quick", args.quick)) if value]
        if given:
            return _fail(f"--resume {args.resume}: {', '.join(given)} cannot change a matrix already made (its "
                         "manifest fixes it) — drop them, or start a new matrix with --out")
        store = Store.open(args.resume)
        lock = store.writer(_command_line())
        try:
            store, specs = _resumable(args.resume)
        except BaseException:
            lock.release()
            raise
        timeout = store.manifest().get("timeout_s", DEFAULT_TIMEOUT_S)
        timing = Timing(**store.manifest().get("timing", {}))  # the rest of the matrix is timed as its start was
        jobs = min(args.jobs or os.cpu_count(), os.cpu_count())
        client = _connect(args.scheduler, args.debug) if args.scheduler else None
    else:
        timing = QUICK if args.quick else Timing()
        chosen = select(args, os.cpu_count() or 1)
        specs, timeout, jobs = chosen.specs, chosen.timeout, chosen.jobs
        for note in chosen.notes:
            print(f"dalembert: note: {note}", file=sys.stderr)
        for s in chosen.skipped:
            print(f"dalembert: skipping engine {s}", file=sys.stderr)
        client = _connect(args.scheduler, args.debug) if args.scheduler else None
        manifest = session.manifest(specs, _command_line(), timeout, timing, jobs, args.scheduler)
        if chosen.searches:
            manifest["searches"] = [{"parameter": "dt", "resolution": resolution, "first": [s.to_json() for s in first]}
                                    for first, resolution in chosen.searches]
        store, lock = session.start(args.out or session.default_out(), manifest)
    with lock:
        if lock.stale:
            print(f"dalembert: note: the last writer of {store.path} ended without releasing it "
                  f"({printable(lock.stale)}); "
                  "what it stored is kept", file=sys.stderr)
        print(f"dalembert: {len(specs)} runs, {len(specs) - len(store.done_keys())} to do -> {store.path}",
              file=sys.stderr)
        _stop_on_sigterm()
        progress = _progress_printer()

        def run(batch):
            if client is not None:
                return run_matrix_dask(batch, store, client, timeout, timing, progress)
            return run_matrix(batch, store, jobs, timeout, timing, progress)

        try:
            plans = store.manifest().get("searches", [])
            searched = {json.dumps(s, sort_keys=True) for plan in plans for s in plan["first"]}
            lost = run([s for s in specs if json.dumps(s.to_json(), sort_keys=True) not in searched])
            for plan in plans:
                lost += _search(store, plan, run)
        except KeyboardInterrupt:  # every finished run is stored; the workers are gone
            print(f"\ndalembert: interrupted; {len(store.done_keys())} of {len(specs)} runs stored in {store.path} — "
                  f"finish with: dalembert run --resume {store.path}", file=sys.stderr)
            return 130
        finally:
            if client is not None:
                client.close()
        session.end(store)
        records = store.records()
    by_status = {}
    for r in records:
        by_status[r.status] = by_status.get(r.status, 0) + 1
    print(f"dalembert: {len(records)} runs stored in {store.path}: "
          + ", ".join(f"{n} {s}" for s, n in sorted(by_status.items())), file=sys.stderr)
    if lost:  # the infrastructure's failure, not the runs': nothing stored, --resume runs them
        print(f"dalembert: {len(lost)} run(s) not run, lost to the infrastructure (first: {lost[0][1]}) — "
              f"finish with: dalembert run --resume {store.path}", file=sys.stderr)
        return 4
    return 1 if args.strict and any(r.status in BAD_STATUSES for r in records) else 0


def _open(path, schemas=None):
    from dalembert.record import SCHEMA_VERSION
    from dalembert.store import Store

    return Store.open(path, schemas or (SCHEMA_VERSION,))


def cmd_report(args):
    from dalembert.reports.render import build_report

    try:
        store = _open(args.run_dir)
    except ValueError as e:
        return _fail(str(e))
    for path in build_report(store):
        print(f"wrote {printable(path)}")
    return 0


def cmd_export(args):
    from dalembert import output
    from dalembert.reports.export import frame, select, write
    from dalembert.reports.findings import run_name

    fmt = "csv" if args.csv is not None else "parquet"
    path = args.csv if args.csv is not None else args.parquet
    try:
        store = _open(args.run_dir)
        options = dict(_key_value("--option", text) for text in args.option)
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
    if not args.all and not chosen[0].trajectory:
        return _fail(f"that run has no trajectory (status {chosen[0].status}: {chosen[0].message})")
    df = frame(store, chosen)
    write(df, path, fmt)
    with_traj = sum(1 for r in chosen if r.trajectory)
    print(f"wrote {printable(output.shown(path))}: {with_traj} run(s), {len(df)} rows"
          + (f" ({len(chosen) - with_traj} matching run(s) left no trajectory)" if with_traj < len(chosen) else ""),
          file=sys.stderr if path == output.STDOUT else sys.stdout)
    return 0


def _key_value(flag, text):
    """``KEY=VALUE`` as a pair; ValueError naming ``flag`` otherwise."""
    if "=" not in text:
        raise ValueError(f"{flag} {text!r}: write KEY=VALUE")
    key, value = text.split("=", 1)
    return key, value


def cmd_compare(args):
    import csv
    import io
    import json

    from dalembert import output
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


def cmd_show_model(args):
    from dalembert.adapters import get_adapter
    from dalembert.case import load_cases, parse_param
    from dalembert.settings import Settings

    try:
        factory = load_cases()[args.case]
        case = factory(**dict(parse_param(factory, p) for p in args.param))
        options = dict(_key_value("--option", text) for text in args.option)
        adapter = get_adapter(args.engine)

        def settings(integ, opts):
            spec = adapter.integrators.get(integ)
            if spec is None or spec.fixed_step:
                return Settings(integ, dt=args.dt, options=opts)
            return Settings(integ, rtol=1e-8, atol=1e-8, options=opts)

        def first_supported(opts):
            """(settings, None) for the first integrator that runs the case with ``opts``, else
            (the last settings tried, the reason)."""
            reason = None
            for integ in [args.integrator] if args.integrator else list(adapter.integrators):
                chosen = settings(integ, opts)
                adapter.check(case.scene, case.times, chosen)
                reason = adapter.unsupported(case.scene, chosen)
                if reason is None:
                    return chosen, None
            return chosen, reason

        chosen, reason = first_supported(options)
        if reason is not None:  # say so, and which of the engine's own variants would run it
            runs = [o for o in adapter.variants(case.scene) if o != options and first_supported(o)[1] is None]
            hint = ("; it runs with " + " or ".join(" ".join(f"--option {k}={v}" for k, v in sorted(o.items()))
                                                    or "its default options" for o in runs)) if runs else ""
            what = " ".join(f"{k}={v}" for k, v in sorted(options.items())) or "its default options"
            if args.integrator:  # the same options may run with another integrator
                others = [i for i in adapter.integrators if i != args.integrator
                          and adapter.unsupported(case.scene, settings(i, options)) is None]
                if others:
                    hint += f"; with {what} it runs {', '.join(others)}"
            print(f"dalembert: unsupported: {args.engine} does not run {args.case} "
                  f"({chosen.integrator if args.integrator else 'any integrator'}, {what}): {reason}{hint}",
                  file=sys.stderr)
            return 1
        text = adapter.describe(case.scene, chosen)
        if not text.strip():
            print(f"dalembert: {args.engine} describes no model for {args.case} with {chosen.integrator}",
                  file=sys.stderr)
            return 1
        print(text, end="" if text.endswith("\n") else "\n")
    except (UnknownNameError, ValueError, SceneError, ImportError) as e:
        return _fail(str(e))
    return 0


# How long ``--scheduler`` may take to answer before the run is refused (nothing written).
SCHEDULER_CONNECT_S = 10.0
# What a user can get wrong (a name, a value, a file): a message naming it, exit 2.
USER_ERRORS = (ValueError, KeyError, ImportError, OSError)


def main(argv=None):
    """Run one command; every error a user can cause is a one-line message (``--debug``: the
    traceback), an unexpected one says so and how to report it."""
    args = _parser().parse_args(argv)
    commands = {"cases": cmd_cases, "truth": cmd_truth, "validate": cmd_validate, "engines": cmd_engines,
                "run": cmd_run, "report": cmd_report, "export": cmd_export,
                "show-model": cmd_show_model, "compare": cmd_compare}
    try:
        return commands[args.command](args)
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
