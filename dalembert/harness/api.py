"""dalembert from Python: run a selection and get its records as a DataFrame, load a store, read
what it found, build its report, compare two stores, and take its trajectories as one table.

Everything the command line does, for a notebook or a script::

    from dalembert.harness import api

    runs = api.run(cases=["free_top"], engines=["reference", "mujoco"], integrators=["rk4"],
                   dts=[1e-2, 1e-3], params={"t_final": 2.0}, out="results/top")
    runs[["engine", "settings", "err_orientation_max", "wall_s_median", "verdict"]]
    store = api.load("results/top")            # a Store: records(), table(), case(), trajectory()
    api.findings(store)[0].sentences           # what the report says first, as data
    api.report(store)                          # report.html, report.md, summary.csv
    api.compare("results/before", "results/top").regressed
    api.trajectories(store, engine="mujoco")   # every sample of every run, long format
    api.repro(store, key)                      # one run as a standalone script (the engine, no dalembert)

It is the command line's code, not a copy: ``run`` and ``report`` are the ``run`` of
``dalembert.harness.commands.run`` and ``.report`` (a keyword for every flag, checked
the same way, refused before anything is written), the rest read stores.

A record's columns are ``dalembert.record.RunRecord``'s (``to_row``): one per
identity field, ``err_<quantity>_max``/``_final``, ``drift_<name>``, the cost,
the stored verdict. The trajectory table's are ``dalembert.reports.export``'s.

Why ``dalembert.harness.api`` and not ``dalembert.api``: running a selection
needs the cases, the engines' adapters and the worker pool, which sit above the
core; ``dalembert`` itself is the core, which imports none of them (the layers in
docs/DESIGN.md; ``tests/test_layers.py`` walks every import, function-level ones
included, so not even a lazy re-export from ``dalembert/__init__.py`` would
hold). The harness is the layer that joins them all, as the command line does,
so the API is one module of it: importing it costs what importing the command
line costs, and ``import dalembert`` stays as light as it is.
"""

from __future__ import annotations

from dalembert.harness.commands import run as run_command
from dalembert.harness.commands.report import run as _report
from dalembert.record import READABLE_SCHEMAS, SCHEMA_VERSION
from dalembert.store import Store

__all__ = ["run", "load", "table", "findings", "report", "compare", "trajectories", "repro", "MatrixError"]


class MatrixError(RuntimeError):
    """A matrix that ended without every run stored (lost to the infrastructure: ``resume`` finishes
    it) or, with ``strict``, with runs that failed, diverged or timed out; ``.outcome`` is
    ``dalembert.harness.commands.run.Outcome`` (its store and records)."""

    def __init__(self, message, outcome):
        super().__init__(message)
        self.outcome = outcome


def run(cases=None, tags=None, engines=None, integrators=None, dts=None, rtols=None, params=None, options=None,
        jobs=None, timeout=None, quick=False, scheduler=None, out=None, resume=None, search=None, resolution=None,
        no_maps=False, force=False, strict=False, timing=None, progress=None, debug=False, batch=False,
        trajectories=None):
    """Run a selection of the matrix into a new store (or finish one: ``resume``) and return its
    records as a DataFrame: ``dalembert run``, a keyword per flag (``dalembert.harness.commands.run.run``
    documents each; a repeatable flag's keyword is its plural, ``--no-maps`` is ``no_maps``).

    Parameters
    ----------
    cases, tags : list of str or None — case names, or tags selecting cases (default: every case
        not tagged ``hard``)
    engines, integrators : list of str or None — default: every installed engine, every integrator
    dts : list of float or None — fixed steps, s (default 1e-2, 5e-3, 2e-3, 1e-3)
    rtols : list of float or None — tolerances of adaptive integrators (default 1e-6, 1e-9)
    params : dict or None — case parameters, e.g. ``{"t_final": 2.0}``; a list sweeps
        (``{"spin": [5, 50]}``), a tuple is a vector, a str is the command line's text
    options : dict or None — engine options for every run (default: each engine's variants); a list of
        values, or the command line's ``"lin:a,b,n"`` / ``"log:a,b,n"``, sweeps one (each value its own run)
    jobs : int or None — worker processes (default and cap: every core)
    timeout : float or None — per-run limit, s (default 600)
    quick : bool — time each run once after its warm-up (``--quick``)
    scheduler : str or None — a Dask scheduler's address (``--scheduler``)
    out : str or None — the new store's directory (default ``results/<time>``); must not hold a run
    resume : str or None — finish this store instead (no flag that makes a matrix with it)
    search, resolution : "dt" and float or None — the stability-boundary search (``--search dt``)
    no_maps, force : bool — as ``--no-maps``, ``--force``
    strict : bool or str — as ``--strict`` (True) or ``--strict=tolerance`` ("tolerance")
    timing : dalembert.harness.execute.Timing or None — how each run is timed (not with ``quick``)
    progress : callable or None — ``progress(done, total, failures, record)`` after each run
    debug : bool — keep Dask's own log
    batch : bool — as ``--batch``: runs that differ only in the case's parameters stepped as one batch of worlds
    trajectories : "all", "drawn", "none" or None — as ``--trajectories``: which runs' trajectories the store keeps

    Returns
    -------
    pandas.DataFrame — one row per run (``Store.table``); ``.attrs["store"]`` is the store's path

    Raises ValueError (or KeyError with a "did you mean") on an unknown name, parameter or a bad
    setting, as the command line does and before anything is written; ``MatrixError`` when runs
    were lost, or with ``strict`` when a run failed; KeyboardInterrupt when interrupted (every
    finished run stored). A run that fails, diverges or times out is otherwise a row.
    """
    given = {k: v for k, v in dict(cases=cases, tags=tags, engines=engines, integrators=integrators, dts=dts,
                                   rtols=rtols, params=params, options=options, out=out, resume=resume,
                                   search=search).items() if v is not None}
    outcome = run_command.run(cases, tags, engines, integrators, dts, rtols, params, options, jobs, timeout, quick,
                              scheduler, out, resume, search, resolution, no_maps, force, strict, timing, progress,
                              debug, command="dalembert.harness.api.run("
                              + ", ".join(f"{k}={v!r}" for k, v in given.items()) + ")", batch=batch,
                              trajectories=trajectories)
    if outcome.interrupted:
        raise KeyboardInterrupt(f"interrupted; finish with api.run(resume={outcome.store.path!r})")
    if outcome.lost:
        raise MatrixError(f"{len(outcome.lost)} run(s) lost to the infrastructure (first: {outcome.lost[0][1]}) — "
                          f"finish with api.run(resume={outcome.store.path!r})", outcome)
    if outcome.exit_status:
        first = outcome.failing[0]
        why = first.status if not first.ok else "beyond " + " ".join(first.judgement.beyond)
        raise MatrixError(f"strict: {len(outcome.failing)} run(s) failed, diverged or timed out"
                          + (" or are beyond their case's tolerance" if outcome.strict == "tolerance" else "")
                          + f" (first: {first.key}: {why})", outcome)
    df = outcome.store.table()
    df.attrs["store"] = outcome.store.path
    return df


def load(path, any_schema=False):
    """The store at ``path`` (``dalembert.store.Store``); with ``any_schema``, one written by an older
    dalembert too (as ``compare`` reads them), else only this version's schema."""
    return Store.open(path, READABLE_SCHEMAS if any_schema else (SCHEMA_VERSION,))


def _store(store):
    return store if isinstance(store, Store) else load(store)


def table(store):
    """Every run of ``store`` (a Store or a path) as a DataFrame, one row per ``RunRecord``."""
    return _store(store).table()


def findings(store):
    """What the report opens with, as data: a ``dalembert.reports.findings.CaseFindings`` per case
    (cheapest run per target accuracy and engine, hazards naming their runs, the sentences)."""
    from dalembert.reports.findings import find

    return find(_store(store))


def report(store, out_dir=None):
    """Write the report of ``store`` (a Store or a path; into ``out_dir``, default the store);
    returns the paths of report.html, report.md and summary.csv (``dalembert report``)."""
    return _report(store, out_dir)


def compare(before, after, threshold=2.0, cost_threshold=None, across_versions=False, pair_options=None,
            pair_engines=None):
    """Compare two stores (Stores or paths) as ``dalembert compare`` does; a
    ``dalembert.reports.compare.Comparison`` (``.regressed``, ``.unpaired``: why nothing pairs, ``.changes``,
    ``.only_in_a``, ...; ``dalembert.reports.compare.to_json`` turns it into plain data). ``pair_options``:
    ``({"cone": "pyramidal"}, {"cone": "elliptic"})``, as ``--pair-options``; ``pair_engines``:
    ``("mujoco==3.6.0", "mujoco")``, as ``--pair-engines``."""
    from dalembert.reports.compare import compare_stores

    a, b = (s if isinstance(s, Store) else load(s, any_schema=True) for s in (before, after))
    return compare_stores(a, b, threshold, cost_threshold, across_versions, pair_options, pair_engines)


def trajectories(store, keys=(), case=None, engine=None, integrator=None, dt=None, rtol=None, options=None):
    """The stored trajectories of the runs that match (all by default) as one long-format DataFrame
    (``dalembert.reports.export``: a row per run, sample time and body, joint or reaction force); the runs whose
    trajectory the store did not keep (``--trajectories drawn`` or ``none``) are left out, and ``Store.trajectory``
    of one raises ``TrajectoryNotKept`` saying so."""
    from dalembert.reports.export import frame, select

    s = _store(store)
    return frame(s, select(s.records(), set(keys), case, engine, integrator, dt, rtol, options))


def repro(store, key):
    """The standalone reproduction of run ``key`` of ``store`` (a Store or a path) as the text of a Python script
    that needs the engine and numpy, never dalembert (``dalembert repro``; ``dalembert.harness.commands.repro``).
    ValueError naming the field for an unknown key, or a run the engine's repro does not cover."""
    from dalembert.harness.commands.repro import write

    return write(_store(store), key)
