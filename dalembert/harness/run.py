"""The run matrix: cases x engines x integrators x step sizes (or tolerances).

``expand(...)`` turns a selection into ``RunSpec``s (checking every name and
setting before anything runs); ``run_matrix(...)`` executes them, each in its
own worker process with a timeout, and writes every finished run to the store
at once. A failure, a divergence or a timeout is a stored result; the rest of
the matrix goes on. ``run_matrix_dask(...)`` does the same on a Dask cluster.

Timing (per run): the model is built once (not timed), run once to warm up
(not timed), then run until at least ``Timing.min_repeats`` runs and
``Timing.min_total_s`` seconds of stepping are reached (at most
``Timing.max_repeats``, and no more once warm-up plus repeats pass
``Timing.max_total_s``: long runs are timed once or twice); the median, min and
max stepping wall time are stored.
"""

from __future__ import annotations

import hashlib
import json
import multiprocessing as mp
import os
import pickle
import subprocess
import sys
import threading
import time
import traceback
from dataclasses import asdict, dataclass, field
from multiprocessing.connection import wait

import numpy as np

from dalembert.settings import Settings

__all__ = ["RunSpec", "Timing", "expand", "execute", "run_matrix", "run_matrix_dask", "DEFAULT_DTS",
           "DEFAULT_RTOLS"]

# Default sweeps: two decades of step size and of tolerance, enough for a
# work-precision slope, affordable for the pure-Python reference on 2 cores.
DEFAULT_DTS = (1e-2, 1e-3)
DEFAULT_RTOLS = (1e-6, 1e-9)
# atol = rtol * ATOL_PER_RTOL: the states are O(1) in SI units for the cases here.
ATOL_PER_RTOL = 1.0
DEFAULT_TIMEOUT_S = 600.0


@dataclass(frozen=True)
class Timing:
    """Repeat policy for timing one run (see the module docstring)."""

    min_repeats: int = 3  # the median of 3 is robust to one outlier
    min_total_s: float = 0.2  # short runs are repeated until timer noise is small against the total
    max_repeats: int = 30
    # ...but once the warm-up plus timed runs exceed this, stop: a run of many
    # seconds has negligible timer noise, and repeating it only costs time.
    max_total_s: float = 10.0


@dataclass(frozen=True)
class RunSpec:
    """One (case, engine, settings) run. ``params``: sorted (key, value) pairs."""

    case: str
    engine: str
    integrator: str
    dt: float | None = None
    rtol: float | None = None
    atol: float | None = None
    options: tuple = ()
    params: tuple = ()
    case_version: str = ""
    adapter: str = ""  # "module:Class" of the engine's adapter, for workers that must import it

    @property
    def settings(self):
        return Settings(self.integrator, self.dt, self.rtol, self.atol, dict(self.options))

    @property
    def key(self):
        """Deterministic, readable file key: case, engine, integrator and a content hash."""
        payload = json.dumps([self.case, self.case_version, self.engine, self.integrator, self.dt, self.rtol,
                              self.atol, list(self.options)], default=repr)
        digest = hashlib.sha256(payload.encode()).hexdigest()[:12]
        return f"{self.case}__{self.engine}__{self.integrator}__{digest}"

    def to_json(self):
        d = asdict(self)
        d["options"] = [list(x) for x in self.options]
        d["params"] = [[k, list(v) if isinstance(v, tuple) else v] for k, v in self.params]
        return d

    @classmethod
    def from_json(cls, d):
        d = dict(d)
        d["options"] = tuple(tuple(x) for x in d["options"])
        d["params"] = tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in d["params"])
        return cls(**d)


def expand(cases=None, tags=None, engines=None, integrators=None, dts=None, rtols=None, params=None,
           options=None):
    """Turn a selection into run specs. Raises ValueError/KeyError before anything runs.

    Parameters
    ----------
    cases, tags : names / tags of cases (default: every case)
    engines : engine names (default: every registered engine whose engine imports)
    integrators : integrator names (default: every integrator of each engine)
    dts, rtols : step sizes (s) for fixed-step and tolerances for adaptive integrators
    params : dict of case parameter overrides (applied to every selected case that has them)
    options : dict of engine options (applied to every run; default: each
        engine's ``variants`` for each case)

    Returns
    -------
    specs : list of RunSpec
    skipped : list of str — engines not installed (only when ``engines`` was not given)
    """
    from dalembert.adapters import adapter_names, adapter_path, get_adapter
    from dalembert.case import load_cases

    registry = load_cases()
    names = list(cases or [])
    for n in names:
        registry[n]  # "did you mean" for unknown names
    if tags:
        known_tags = {t for _, f in registry.items() for t in f.tags}
        for t in tags:
            if t not in known_tags:
                from dalembert.registry import suggest

                raise ValueError(f"--tag: unknown tag {t!r}{suggest(t, known_tags)}")
        names += [n for n, f in registry.items() if set(tags) & set(f.tags) and n not in names]
    if not names:  # the default matrix: every case except the hard ones (select those with --tag hard)
        names = [n for n, f in registry.items() if "hard" not in f.tags]
    skipped = []
    if engines:
        adapters = {e: get_adapter(e) for e in engines}
        for e, a in adapters.items():
            a.version()  # ImportError: the engine is not installed
    else:
        adapters = {}
        for e in adapter_names():
            a = get_adapter(e)
            try:
                a.version()
                adapters[e] = a
            except ImportError as err:
                skipped.append(f"{e} ({err})")
    for i in integrators or []:
        if not any(i in a.integrators for a in adapters.values()):
            from dalembert.registry import suggest

            offered = {n for a in adapters.values() for n in a.integrators}
            raise ValueError(f"--integrator: no selected engine offers {i!r}{suggest(i, offered)}")
    dts = tuple(dts or DEFAULT_DTS)
    rtols = tuple(rtols or DEFAULT_RTOLS)
    params = dict(params or {})
    user_options = tuple(sorted((options or {}).items()))
    specs = []
    for name in names:
        factory = registry[name]
        case_params = {k: v for k, v in params.items() if k in factory.params}
        case = factory(**case_params)
        frozen_params = tuple(sorted(case_params.items()))
        for e, adapter in adapters.items():
            for integ, ispec in adapter.integrators.items():
                if integrators and integ not in integrators:
                    continue
                if ispec.fixed_step:
                    variants = [dict(dt=dt) for dt in dts]
                else:
                    variants = [dict(rtol=r, atol=r * ATOL_PER_RTOL) for r in rtols]
                # given options apply to every run; else each engine's own variants for this scene
                option_sets = [user_options] if options else [tuple(sorted(o.items()))
                                                              for o in adapter.variants(case.scene)]
                for opts in option_sets:
                    for v in variants:
                        spec = RunSpec(name, e, integ, options=opts, params=frozen_params,
                                       case_version=case.version, adapter=adapter_path(e), **v)
                        adapter.check(case.scene, case.times, spec.settings)
                        specs.append(spec)
    return specs, skipped


# ---------------------------------------------------------------- one run
def _base_row(spec):
    return {"key": spec.key, "case": spec.case, "case_version": spec.case_version,
            "params": json.dumps(dict(spec.params), default=list), "engine": spec.engine,
            "integrator": spec.integrator, "dt": spec.dt, "rtol": spec.rtol, "atol": spec.atol,
            "options": json.dumps(dict(spec.options)), "settings": spec.settings.label(),
            "engine_version": "", "status": "failed", "message": "", "wall_s_median": float("nan"),
            "wall_s_min": float("nan"), "wall_s_max": float("nan"), "repeats": 0, "n_steps": 0, "n_rhs": 0,
            "overhead_s": float("nan"), "build_s": float("nan"), "stepping_total_s": float("nan"),
            "worker_s": float("nan")}


def execute(spec, timing=Timing()):
    """Run one spec in this process: ``(row, trajectory_npz or None)``. Never raises."""
    from dalembert.adapters import get_adapter
    from dalembert import invariants
    from dalembert.case import make_case
    from dalembert.errors import trajectory_errors
    from dalembert.store import trajectory_to_npz
    from dalembert.reference import truth

    row = _base_row(spec)
    started = time.perf_counter()
    try:
        adapter = get_adapter(spec.engine, spec.adapter)
        row["engine_version"] = adapter.version()
        case = make_case(spec.case, **dict(spec.params))
        row["t_final"] = case.t_final
        settings = spec.settings
        reason = adapter.unsupported(case.scene, settings)
        if reason:
            row.update(status="unsupported", message=reason)
            return row, None
        t0 = time.perf_counter()
        prepared = adapter.prepare(case.scene, case.times, settings)
        row["build_s"] = time.perf_counter() - t0
        first = adapter.run(prepared)  # warm-up, not timed
        traj = first.trajectory
        row.update(n_steps=first.n_steps, n_rhs=first.n_rhs, audit=json.dumps(adapter.audit(prepared, first),
                                                                              default=str))
        if hasattr(adapter, "describe"):
            row["model"] = adapter.describe(case.scene, settings)
        if not traj.is_finite():
            row.update(status="diverged", message=f"non-finite state from t = {traj.first_nonfinite_time()} s",
                       t_diverged=traj.first_nonfinite_time(), wall_s_median=first.wall_s,
                       wall_s_min=first.wall_s, wall_s_max=first.wall_s, repeats=1)
            return row, trajectory_to_npz(traj)
        walls, totals = [], []
        while ((len(walls) < timing.min_repeats or sum(walls) < timing.min_total_s) and len(walls) < timing.max_repeats
               and not (walls and first.wall_s + sum(walls) > timing.max_total_s)):
            t0 = time.perf_counter()
            out = adapter.run(prepared)
            totals.append(time.perf_counter() - t0)
            walls.append(out.wall_s)
        row.update(wall_s_median=float(np.median(walls)), wall_s_min=float(np.min(walls)),
                   wall_s_max=float(np.max(walls)), repeats=len(walls),
                   overhead_s=float(np.median(np.array(totals) - np.array(walls))),
                   stepping_total_s=float(first.wall_s + sum(walls)))
        errors = trajectory_errors(traj, truth(case))
        for q, (mx, final) in errors.items():
            row[f"err_{q}_max"], row[f"err_{q}_final"] = mx, final
        summary = invariants.summary(case.scene, traj, case.conserved)
        for k, v in summary.items():
            row[k.replace("drift_rate:", "drift_rate_").replace("drift:", "drift_")] = v
        beyond = case.beyond_tolerance({q: mx for q, (mx, _) in errors.items()},
                                       {k[len("drift:"):]: v for k, v in summary.items() if k.startswith("drift:")})
        row.update(status="ok", within_tolerance=not beyond, beyond_tolerance=" ".join(beyond))
        npz = trajectory_to_npz(traj)
        row["worker_s"] = time.perf_counter() - started
        return row, npz
    except Exception as e:  # a failure is data
        row.update(status="failed", message=f"{type(e).__name__}: {e}", traceback=traceback.format_exc())
        return row, None


# ---------------------------------------------------------------- local pool
def _context():
    """``fork`` (fast: workers share the parent's imports) when this process has one
    Python thread; else a ``forkserver``: forking a process that has other threads
    (an in-process Dask client, a notebook's kernel threads) can copy a lock that
    another thread holds into the child (Python's documentation warns against it)."""
    if threading.active_count() == 1:
        return mp.get_context("fork")
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["dalembert.harness.run", "dalembert.adapters"])
    return ctx


def _child(conn, spec, timing):
    try:
        conn.send(execute(spec, timing))
    finally:
        conn.close()


def _finish(store, row, npz, progress, counts):
    store.write_result(row, npz)
    counts["done"] += 1
    if row["status"] in ("failed", "diverged", "timeout"):
        counts["bad"] += 1
    if progress:
        progress(counts["done"], counts["total"], counts["bad"], row)


def write_truths(specs, store):
    """Store each selected case's truth once (closed form, else the reference), for the reports."""
    from dalembert.case import make_case
    from dalembert.reference import truth

    for name, params, version in sorted({(s.case, s.params, s.case_version) for s in specs}):
        if store.truth(name, version) is None:
            store.write_truth(name, version, truth(make_case(name, **dict(params))))


def run_matrix(specs, store, jobs=None, timeout=DEFAULT_TIMEOUT_S, timing=Timing(), progress=None):
    """Run ``specs`` not yet in ``store``, ``jobs`` at a time, each in a forked worker.

    Returns the list of keys run now.
    """
    write_truths(specs, store)
    todo = [s for s in specs if s.key not in store.done_keys()]
    jobs = max(1, jobs or os.cpu_count() or 1)
    ctx = _context()
    counts = {"done": 0, "bad": 0, "total": len(todo)}
    running = {}  # connection -> (process, spec, start)
    queue = list(reversed(todo))
    while queue or running:
        while queue and len(running) < jobs:
            spec = queue.pop()
            parent, child = ctx.Pipe(duplex=False)
            proc = ctx.Process(target=_child, args=(child, spec, timing), daemon=True)
            proc.start()
            child.close()
            running[parent] = (proc, spec, time.monotonic())
        ready = wait(list(running), timeout=0.05)
        for conn in ready:
            proc, spec, _ = running.pop(conn)
            try:
                row, npz = conn.recv()
            except EOFError:  # the worker died without an answer (crash, killed)
                proc.join()
                row, npz = _base_row(spec), None
                row["message"] = f"worker process died (exit code {proc.exitcode})"
            proc.join()
            conn.close()
            _finish(store, row, npz, progress, counts)
        for conn, (proc, spec, start) in list(running.items()):
            if time.monotonic() - start > timeout:
                proc.kill()
                proc.join()
                conn.close()
                running.pop(conn)
                row = _base_row(spec)
                row.update(status="timeout", message=f"stopped after the per-run limit of {timeout:g} s")
                _finish(store, row, None, progress, counts)
    store.write_table()
    return [s.key for s in todo]


# ---------------------------------------------------------------- Dask
def execute_isolated(spec_json, timing_json, timeout):
    """Run one spec in a fresh Python subprocess (the Dask task): ``(row, npz)``.

    A subprocess, not a fork: Dask workers are daemonic and cannot have
    multiprocessing children; the subprocess also gives a hard timeout.
    """
    spec = RunSpec.from_json(spec_json)
    payload = json.dumps({"spec": spec_json, "timing": timing_json}).encode()
    try:
        proc = subprocess.run([sys.executable, "-m", "dalembert.harness.worker"], input=payload, capture_output=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired:
        row = _base_row(spec)
        row.update(status="timeout", message=f"stopped after the per-run limit of {timeout:g} s")
        return row, None
    if proc.returncode != 0:
        row = _base_row(spec)
        row["message"] = f"worker exited with {proc.returncode}: {proc.stderr.decode()[-500:]}"
        return row, None
    return pickle.loads(proc.stdout)


def run_matrix_dask(specs, store, scheduler, timeout=DEFAULT_TIMEOUT_S, timing=Timing(), progress=None):
    """Like ``run_matrix`` on the Dask cluster at ``scheduler`` (address or Client)."""
    from distributed import Client, as_completed

    client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
    write_truths(specs, store)
    todo = [s for s in specs if s.key not in store.done_keys()]
    counts = {"done": 0, "bad": 0, "total": len(todo)}
    futures = {client.submit(execute_isolated, s.to_json(), asdict(timing), timeout, pure=False): s for s in todo}
    for fut in as_completed(futures):
        try:
            row, npz = fut.result()
        except Exception as e:
            row, npz = _base_row(futures[fut]), None
            row["message"] = f"dask task failed: {type(e).__name__}: {e}"
        _finish(store, row, npz, progress, counts)
    store.write_table()
    if client is not scheduler:
        client.close()
    return [s.key for s in todo]
