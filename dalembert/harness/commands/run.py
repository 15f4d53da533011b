"""``dalembert run``: a matrix of cases x engines x integrators x steps or tolerances, into a store.

The one place a matrix is run: the command line (``main``) and the Python API
(``dalembert.harness.api.run``) both call ``run``, with keywords named after the flags. Every
input is checked (``dalembert.harness.selection``) and every case and its truth built
(``dalembert.harness.truths.build``) before the store is made, so a refusal leaves nothing behind
and the same command, corrected, can use the same ``--out``. The runs an engine refuses by its
declarations are no runs: the manifest lists them once each (``"refused"``, ``dalembert.refusal``).
"""

from __future__ import annotations

import json
import numbers
import os
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from types import SimpleNamespace

from dalembert.harness import session
from dalembert.harness.commands.console import command_line, note, progress_printer
from dalembert.harness.selection import given
from dalembert.record import BAD_STATUSES
from dalembert.stored_runs import StoredRuns
from dalembert.terminal import printable

__all__ = ["run", "main", "Outcome", "KEYWORDS", "SCHEDULER_CONNECT_S"]

# How long ``--scheduler`` may take to answer before the run is refused (nothing written).
SCHEDULER_CONNECT_S = 10.0
# A flag's keyword where the two differ: a repeatable flag's is its plural (``--case a --case b``
# is ``cases=["a", "b"]``); every other flag's is its own name (``--no-maps``: ``no_maps``).
KEYWORDS = {"case": "cases", "tag": "tags", "engine": "engines", "integrator": "integrators", "dt": "dts",
            "rtol": "rtols", "param": "params", "option": "options"}
# The flags that make a matrix, which --resume cannot change (its manifest fixes them).
_MATRIX_FLAGS = ("cases", "tags", "engines", "integrators", "dts", "rtols", "params", "options", "out", "timeout",
                 "force", "search", "resolution", "no_maps", "quick", "timing", "batch")
_FLAG = {v: k for k, v in KEYWORDS.items()}


def _flag(keyword):
    return "--" + _FLAG.get(keyword, keyword).replace("_", "-")


@dataclass(frozen=True)
class Outcome:
    """What a matrix left: its store, every stored record, and how it ended."""

    store: object  # dalembert.store.Store
    records: Sequence  # RunRecord per stored run: a list, or ``StoredRuns`` (read from the table when asked)
    lost: list  # [(key, reason)]: runs lost to the infrastructure, not stored (--resume runs them)
    interrupted: bool = False  # Ctrl-C or SIGTERM: every finished run stored, the rest not run
    strict: bool | str = False  # ``STRICT``: False, True (= "status") or "tolerance"

    @property
    def statuses(self):
        """``Counter`` of the stored runs' statuses."""
        if isinstance(self.records, StoredRuns):
            return self.records.statuses()
        return Counter(r.status for r in self.records)

    @property
    def bad(self):
        """The records that failed, diverged or timed out."""
        if isinstance(self.records, StoredRuns):
            return self.records.where(bad=True)
        return [r for r in self.records if r.status in BAD_STATUSES]

    @property
    def beyond(self):
        """The finished records beyond one of their case's tolerances (``Judgement.within_tolerance`` False)."""
        if isinstance(self.records, StoredRuns):
            return self.records.where(beyond=True)
        return [r for r in self.records if r.ok and r.judgement.within_tolerance is False]

    @property
    def not_measured(self):
        """The finished records with a bounded quantity they did not report, none beyond (within not established)."""
        if isinstance(self.records, StoredRuns):
            return self.records.where(not_measured=True)
        return [r for r in self.records if r.ok and r.judgement.within_tolerance is None and r.judgement.not_measured]

    @property
    def failing(self):
        """What fails the matrix under ``strict``: the bad records, and with ``"tolerance"`` those beyond too."""
        if not self.strict:
            return []
        if isinstance(self.records, StoredRuns):  # (in key order)
            return self.records.where(bad=True, beyond=self.strict == "tolerance")
        return self.bad + (self.beyond if self.strict == "tolerance" else [])

    @property
    def exit_status(self):
        """The command line's: 130 interrupted, 4 runs lost, 1 a failing run under ``strict``, else 0."""
        if self.interrupted:
            return 130
        if self.lost:
            return 4
        return 1 if self.failing else 0


# ``--strict``'s levels: "status" fails a matrix with a run that failed, diverged or timed out; "tolerance" also
# with a finished run beyond its case's tolerance (a bound the run did not measure fails neither: it is named).
STRICT = ("status", "tolerance")


def strict_level(value):
    """``strict`` as ``Outcome`` takes it: False, or one of ``STRICT`` (True is "status"); ValueError naming
    ``--strict`` otherwise."""
    if value is False or value is None:
        return False
    if value is True:
        return "status"
    if value in STRICT:
        return value
    raise ValueError(f"--strict: {value!r} is not a level — use --strict (failed, diverged or timed-out runs) or "
                     "--strict=tolerance (those and runs beyond their case's tolerance)")


def _groups(values):
    """Numbers of a repeatable comma-separated flag as one list per use: the command line's
    ``[[1e-2, 1e-3], [1e-4]]`` as it is, the API's ``[1e-2, 1e-3]`` (or one number) as one use."""
    if values is None:
        return None
    if isinstance(values, (int, float)):
        return [[values]]
    values = list(values)
    if values and all(isinstance(v, (list, tuple)) for v in values):
        return [list(v) for v in values]
    return [values]


def _number(x):
    """A number as text that reads back to the same value (``repr`` of a float round-trips)."""
    return str(int(x)) if isinstance(x, numbers.Integral) else repr(float(x))


def _param_text(key, value):
    """A Python parameter value as the command line writes it (``--param KEY=TEXT``), so that the
    API's values are checked and typed by the same code: a list sweeps, a tuple is a vector, a str
    is taken as written (``"log:5,500,7"``)."""
    def one(v):
        if isinstance(v, str):
            return v
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (tuple, list)):
            return ",".join(_number(x) for x in v)
        return _number(v)

    if isinstance(value, list):
        if not value:
            raise ValueError(f"--param {key}: an empty list — give one value, or several to sweep")
        return f"{key}=" + (";" if isinstance(value[0], (tuple, list)) else ",").join(one(v) for v in value)
    return f"{key}={one(value)}"


def _texts(flag, values, to_text):
    """``KEY=VALUE`` texts of a flag: the command line's list as it is, the API's dict written out."""
    if values is None:
        return []
    if isinstance(values, dict):
        return [to_text(k, v) for k, v in values.items()]
    if isinstance(values, str):
        raise ValueError(f"{flag}: expected KEY=VALUE texts or a dict, got the string {values!r}")
    return list(values)


def _option_text(key, value):
    """A Python option value as the command line writes it (``--option KEY=TEXT``): a list sweeps
    (``[0.01, 0.02]`` is ``0.01,0.02``), anything else is its ``str`` (the text a run's settings hold)."""
    if isinstance(value, (list, tuple)):
        return f"{key}={','.join(str(v) for v in value)}"
    return f"{key}={value}"


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


def _resumable(path):
    """The store at ``path`` and its specs, if this dalembert may finish it: same schema, every
    stored run one of the manifest's, every engine registered here (its adapter is imported from
    the registry, never from a name the store holds), every case still at the version the matrix
    was made for. ValueError naming what does not belong together."""
    from dataclasses import replace

    from dalembert.adapters import adapter_names, adapter_path
    from dalembert.case import load_cases
    from dalembert.harness.matrix import RunSpec
    from dalembert.harness.truths import built_case
    from dalembert.identity import check_version
    from dalembert.store import Store

    store = Store.open(path)
    try:
        specs = [RunSpec.from_json(d) for d in store.manifest()["specs"]]
    except (KeyError, TypeError) as e:
        raise ValueError(f"--resume {path}: manifest.json does not list the matrix's runs ({type(e).__name__}: {e}) "
                         "— it is not a manifest dalembert wrote; start a new matrix with --out") from None
    from dalembert.environments import engine_of

    registered = set(adapter_names())
    unknown = sorted({s.engine for s in specs if engine_of(s.engine) not in registered})
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
        differs = check_version(name, version, built_case(name, params)[1], "the store holds runs of")
        if differs:
            changed.append(differs)
    if changed:
        raise ValueError(f"--resume {path}: " + "; ".join(changed) + " — finishing it would mix two versions of a "
                         "case; start a new matrix with --out")
    strays = sorted(store.done_keys() - {s.key for s in specs})
    if strays:
        raise ValueError(f"--resume {path}: {len(strays)} stored run(s) are not in its manifest (e.g. the run "
                         f"{strays[0]}): the rows and the manifest come from different matrices — start a new matrix")
    return store, specs


def _stop_on_sigterm():
    """SIGTERM ends a matrix as Ctrl-C does: every finished run stored, the workers gone (the
    command line's: a Python caller's process keeps its own handlers)."""
    import signal

    def stop(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)


def _search(store, manifest, plan, run_batch):
    """Run the boundary search ``plan`` of ``manifest`` (the store's, as read) describes; each round's new probes
    join the manifest's specs (in ``manifest`` too) before they run (so ``--resume`` knows them)."""
    from dalembert.harness.matrix import RunSpec
    from dalembert.harness.search import search

    known = {json.dumps(s, sort_keys=True) for s in manifest["specs"]}  # once, not every spec every round

    def run_round(batch):
        new = {t: d for t, d in ((json.dumps(d, sort_keys=True), d) for d in map(RunSpec.to_json, batch)) if t not in known}
        if new:  # the whole manifest written atomically, as ever: a crash leaves the old one or the new one
            manifest["specs"] += list(new.values())
            store.write_manifest(manifest)
            known.update(new)
        return run_batch(batch)

    def said(rnd, probes):
        print(f"dalembert: search round {rnd}: {len(probes)} probe(s)", file=sys.stderr)

    return search([RunSpec.from_json(s) for s in plan["first"]], store, run_round, plan["resolution"], said)


def _keep_drawn(store, lost):
    """A store that keeps ``drawn``, its matrix complete: drop every trajectory its report does not draw
    (``dalembert.reports.drawn``). Not before: a run still to come may change which are drawn."""
    from dalembert.harness.matrix import RunSpec
    from dalembert.reports.drawn import drawn_keys
    from dalembert.trajectory_store import DRAWN

    if (store.kept().keep != DRAWN or lost
            or {RunSpec.from_json(s).key for s in store.manifest()["specs"]} - store.done_keys()):
        return
    dropped = store.keep_trajectories(drawn_keys(store))
    if dropped:
        note(f"kept only the trajectories the report draws (--trajectories drawn): {dropped} dropped")


def _resume(path, given_flags, jobs, scheduler, debug):
    """The store of ``--resume path`` with its writer's lock, specs, timeout, timing and client."""
    from dalembert.harness.execute import Timing
    from dalembert.harness.pool import DEFAULT_TIMEOUT_S
    from dalembert.store import Store

    if given_flags:
        raise ValueError(f"--resume {path}: {', '.join(given_flags)} cannot change a matrix already made (its "
                         "manifest fixes it) — drop them, or start a new matrix with --out")
    if jobs is not None and jobs < 1:
        raise ValueError(f"--jobs: must be at least 1, got {jobs}")
    store = Store.open(path)
    lock = store.writer(command_line())
    try:
        store, specs = _resumable(path)
        client = _connect(scheduler, debug) if scheduler else None
    except BaseException:
        lock.release()
        raise
    manifest = store.manifest()
    timing = Timing(**manifest.get("timing", {}))  # the rest of the matrix is timed as its start was
    jobs = min(jobs or os.cpu_count(), os.cpu_count())
    return store, lock, specs, manifest.get("timeout_s", DEFAULT_TIMEOUT_S), timing, jobs, client


def run(cases=None, tags=None, engines=None, integrators=None, dts=None, rtols=None, params=None, options=None,
        jobs=None, timeout=None, quick=False, scheduler=None, out=None, resume=None, search=None, resolution=None,
        no_maps=False, force=False, strict=False, timing=None, progress=None, debug=False, command=None, batch=False,
        trajectories=None):
    """Run a matrix into a new store (or finish one, ``resume``); every input checked first.

    Each keyword is a flag of ``dalembert run`` (``KEYWORDS`` names those that differ; see
    ``dalembert run --help``), but for ``timing``, ``progress`` and ``command``.

    Parameters
    ----------
    cases, tags, engines, integrators : list of str or None — names (``--case``, ``--tag``, ...;
        default: every case not tagged ``hard``, every installed engine, every integrator); a name
        given twice counts once
    dts, rtols : list of float or None — steps, s, and tolerances (default 1e-2, 5e-3, 2e-3,
        1e-3 and 1e-6, 1e-9); the command line's one list per use is accepted too
    params : dict or list of str or None — case parameters, ``{"t_final": 2.0}`` (a list of values
        sweeps: ``{"spin": [5, 50]}``; a tuple is a vector; a str is the command line's text,
        ``"log:5,500,7"``) or the command line's ``["t_final=2"]``
    options : dict or list of str or None — engine options for every run that takes them (a list of
        values sweeps: ``{"contact_timeconst": [0.01, 0.02]}``, each its own run; a str is the command
        line's text, ``"log:0.002,0.05,5"``) or the command line's ``["cone=elliptic"]``
    jobs : int or None — worker processes (default and cap: the cores)
    timeout : float or None — per-run limit, s (default 600)
    quick : bool — time each run once after its warm-up, not until its timing is steady
    scheduler : str or None — a Dask scheduler's address (default: local workers)
    out : str or None — the new store's directory (default ``results/<time>``); must hold no run
    resume : str or None — a store to finish instead (then no flag that makes a matrix is allowed)
    search : "dt" or None — bisect each fixed-step integrator's stability boundary in ``dts``
    resolution : float or None — with ``search``: the factor the search stops at (default 1.2)
    no_maps : bool — leave out the stability maps the selected tags carry
    force : bool — allow sizes refused by default (``selection.MAX_RUNS``, ``MAX_MODEL_PARTS``,
        ``matrix.MAX_STEPS_PER_RUN``)
    strict : bool or str — make a failed, diverged or timed-out run the outcome's failure (exit 1): True or
        "status"; "tolerance" also a finished run beyond its case's tolerance (``STRICT``)
    timing : dalembert.harness.execute.Timing or None — how each run is timed (not with ``quick``)
    progress : callable or None — ``progress(done, total, failures, record)`` after each run
    debug : bool — keep Dask's own log
    command : str or None — the command line to record in the manifest
    batch : bool — step the runs that differ only in the case's parameters as one batch of worlds, where the
        engine has batches (``dalembert.harness.batches``; kept in the manifest for ``--resume``)
    trajectories : "all", "drawn", "none" or None — which runs' trajectories the store keeps
        (``dalembert.trajectory_store``; None: all up to ``store.FILES_UP_TO`` runs, else drawn; kept in the
        manifest: ``--resume`` keeps it, and refuses another)

    Returns
    -------
    Outcome — the store, its records and how the matrix ended (``exit_status``)

    Raises ValueError, KeyError (an unknown name, with a "did you mean") or ImportError (a named
    engine not installed), naming the flag, before anything is written.
    """
    from dalembert.harness.dask import run_matrix_dask
    from dalembert.harness.execute import QUICK, Timing
    from dalembert.harness.pool import run_matrix
    from dalembert.harness.selection import select
    from dalembert.harness.sent import told
    from dalembert.harness.truths import build
    from dalembert.trajectory_store import check_keep

    strict = strict_level(strict)
    check_keep(trajectories)
    for keyword, value in (("out", out), ("resume", resume), ("scheduler", scheduler), ("search", search)):
        if value is not None:
            given(_flag(keyword), value)
    if search is not None and search != "dt":
        raise ValueError(f"--search: {search!r} is not a parameter that can be searched — use --search dt")
    if quick and timing is not None:
        raise ValueError("quick: and timing both given — quick is Timing's QUICK; give one")
    keywords = dict(cases=cases, tags=tags, engines=engines, integrators=integrators, dts=dts, rtols=rtols,
                    params=params, options=options, out=out, timeout=timeout, force=force, search=search,
                    resolution=resolution, no_maps=no_maps, quick=quick, timing=timing, batch=batch)
    command = command or command_line()
    if resume is not None:
        given_flags = [_flag(k) for k in _MATRIX_FLAGS
                       if keywords[k] is not None and keywords[k] is not False and keywords[k] != []]
        store, lock, specs, timeout, timing, jobs, client = _resume(resume, given_flags, jobs, scheduler, debug)
        batch = bool(store.manifest().get("batch", False))
        kept = store.kept().keep
        if trajectories is not None and trajectories != kept:
            lock.release()
            if client is not None:
                client.close()
            raise ValueError(f"run.trajectories: {trajectories!r}, and the store {resume} keeps {kept!r} — drop "
                             "--trajectories (--resume keeps the store's choice), or start a new matrix with --out")
    else:
        args = SimpleNamespace(case=cases, tag=tags, engine=engines, integrator=integrators, dt=_groups(dts),
                               rtol=_groups(rtols), param=_texts("--param", params, _param_text),
                               option=_texts("--option", options, _option_text), jobs=jobs,
                               timeout=timeout, out=out, search=search, resolution=resolution, no_maps=no_maps,
                               force=force)
        chosen = select(args, os.cpu_count() or 1)
        specs, timeout, jobs = chosen.specs, chosen.timeout, chosen.jobs
        timing = QUICK if quick else (timing or Timing())
        for text in chosen.notes:
            note(text)
        for s in chosen.skipped:
            print(f"dalembert: skipping engine {s}", file=sys.stderr)
        built = build(specs)  # a case or truth that cannot be computed refuses here, before the store
        client = _connect(scheduler, debug) if scheduler else None
        manifest = session.manifest(specs, command, timeout, timing, jobs, scheduler)
        manifest["refused"] = [r.to_json() for r in chosen.refused]  # once each, not runs: a report reads them here
        manifest["batch"] = bool(batch)
        manifest["trajectories"] = trajectories  # None: by the matrix's size (``Store.create``)
        if chosen.searches:
            manifest["searches"] = [{"parameter": "dt", "resolution": res, "first": [s.to_json() for s in first]}
                                    for first, res in chosen.searches]
        try:
            store, lock = session.start(out or session.default_out(), manifest, built, runs=_runs_at_most(specs, chosen))
        except BaseException:
            if client is not None:
                client.close()
            raise
    with lock:
        if lock.stale:
            note(f"the last writer of {store.path} ended without releasing it ({printable(lock.stale)}); what it stored is kept")
        print(f"dalembert: {len(specs)} runs, {len(specs) - len(store.done_keys())} to do -> {store.path}",
              file=sys.stderr)

        made = store.manifest()  # (read once: a map's manifest holds every probe's spec)
        sent = told(store, made["specs"])  # a run never drawn (a map's probe) is not built, sent nor written

        def run_batch(runs):
            if client is not None:
                return run_matrix_dask(runs, store, client, timeout, timing, progress, batched=batch, sent=sent)
            return run_matrix(runs, store, jobs, timeout, timing, progress, batched=batch, sent=sent)

        try:
            plans = made.get("searches", [])
            searched = {json.dumps(s, sort_keys=True) for plan in plans for s in plan["first"]}
            lost = run_batch([s for s in specs if json.dumps(s.to_json(), sort_keys=True) not in searched])
            for plan in plans:
                lost += _search(store, made, plan, run_batch)
        except KeyboardInterrupt:  # every finished run is stored; the workers are gone
            print(f"\ndalembert: interrupted; {len(store.done_keys())} of {len(specs)} runs stored in {store.path} — "
                  f"finish with: dalembert run --resume {store.path}", file=sys.stderr)
            return Outcome(store, _stored(store), [], interrupted=True, strict=strict)
        finally:
            if client is not None:
                client.close()
        session.end(store)
        _keep_drawn(store, lost)
        return Outcome(store, _stored(store), lost, strict=strict)


def _runs_at_most(specs, chosen):
    """The most runs the matrix stores: its specs, and each search's probes beyond its first (``probes_at_most``)."""
    from dalembert.harness.search import probes_at_most

    return len(specs) + sum(probes_at_most(first, res) - len(first) for first, res in chosen.searches)


def _stored(store):
    """The store's records for ``Outcome``: as written (layout 1, a few thousand at most), or ``StoredRuns``."""
    return store.records() if store.layout() == 1 else StoredRuns(store)


def main(args):
    """``dalembert run`` on the command line: ``run`` with the flags of ``args``, a summary on
    standard error, the exit status (0, 1 with ``--strict`` and a failing run, 4 runs lost, 130
    interrupted)."""
    flags = {KEYWORDS.get(k, k): v for k, v in vars(args).items() if k not in ("command",)}
    _stop_on_sigterm()
    outcome = run(**flags, progress=progress_printer(), command=command_line())
    if outcome.interrupted:
        return outcome.exit_status
    by_status = outcome.statuses
    print(f"dalembert: {len(outcome.records)} runs stored in {outcome.store.path}: "
          + ", ".join(f"{n} {s}" for s, n in sorted(by_status.items())), file=sys.stderr)
    if outcome.beyond:
        print(f"dalembert: {len(outcome.beyond)} finished run(s) beyond their case's tolerance (first: "
              f"{outcome.beyond[0].key}: {', '.join(outcome.beyond[0].judgement.beyond)})"
              + ("" if outcome.strict == "tolerance" else "; --strict=tolerance fails on them"), file=sys.stderr)
    if outcome.not_measured:
        names = sorted({n for r in outcome.not_measured for n in r.judgement.not_measured})
        print(f"dalembert: {len(outcome.not_measured)} finished run(s) with bounded quantities they do not report "
              f"({', '.join(names)}): not measured, so not within tolerance either", file=sys.stderr)
    if outcome.lost:  # the infrastructure's failure, not the runs': nothing stored, --resume runs them
        print(f"dalembert: {len(outcome.lost)} run(s) not run, lost to the infrastructure (first: "
              f"{outcome.lost[0][1]}) — finish with: dalembert run --resume {outcome.store.path}", file=sys.stderr)
    return outcome.exit_status
