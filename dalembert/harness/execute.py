"""One run, in this process: build, warm up, time, read back, measure, judge.

Timing (per run): the model is built once (not timed), run once to warm up
(not timed), then run until at least ``Timing.min_repeats`` runs and
``Timing.min_total_s`` seconds of stepping are reached (at most
``Timing.max_repeats``, and no more once warm-up plus repeats pass
``Timing.max_total_s``: a run of a second or more is timed once or twice); every
repeat's stepping wall time is stored, with their median, min and max.

The run is judged here, once (``dalembert.judge``), and its verdict is part of
its record.
"""

from __future__ import annotations

import os
import socket
import sys
import time
import traceback
from dataclasses import dataclass, replace

import numpy as np

from dalembert.harness.threads import VARIABLES
from dalembert.identity import check_version
from dalembert.judge import judge
from dalembert.record import Cost, RunRecord

__all__ = ["QUICK", "Timing", "execute", "sent_npz", "unfinished"]


@dataclass(frozen=True)
class Timing:
    """Repeat policy for timing one run (see the module docstring)."""

    min_repeats: int = 3  # the median of 3 is robust to one outlier
    min_total_s: float = 0.2  # short runs are repeated until timer noise is small against the total
    max_repeats: int = 30
    # ...but once the warm-up plus timed runs exceed this, stop: a run of a second or more has
    # negligible timer noise, and a third and fourth repeat of it were half the default matrix's
    # wall time (the reference's Python runs at dt = 1e-3, ~2.5 s each); its spread is stored.
    max_total_s: float = 3.0


# One timed run after the warm-up: for matrices whose accuracy, not cost, is the point (``dalembert
# validate``, ``dalembert run --quick``); a short run's timing is then one sample of its noise.
QUICK = Timing(min_repeats=1, min_total_s=0.0, max_repeats=1)


def _record(spec, status, message="", errors=None, drifts=None, tolerances=None, **fields):
    """The record of ``spec`` ending in ``status``, judged."""
    errors, drifts = errors or {}, drifts or {}
    verdict = judge(status, message, {q: mx for q, (mx, _) in errors.items()}, drifts, tolerances or {},
                    fields.get("growths"), fields.pop("beyond_scene", None))
    return RunRecord(key=spec.key, case=spec.case, case_version=spec.case_version, engine=spec.engine,
                     settings=spec.settings, params=dict(spec.params), status=status, message=message,
                     errors=errors, drifts=drifts, judgement=verdict,
                     provenance={"host": socket.gethostname(), "pid": os.getpid(), "threads": _pool_width()},
                     **fields)


def _libraries():
    """The version of every library loaded in this process (``{distribution: version}``): the engine's, what its
    adapter and the engine import, numpy's and scipy's — every public top-level module in ``sys.modules`` outside
    the standard library and dalembert (the record's ``adapter_version``), by the distribution that installs it.
    In a forked worker that includes what the parent had loaded; in an engine environment's worker, only what
    this worker imported."""
    from importlib import metadata

    from dalembert.distributions import installed

    global _LAST
    loaded = frozenset(sys.modules)  # the modules the last run saw: its answer (~0.15 s a run: most of a MuJoCo probe)
    if _LAST[0] == loaded:
        return dict(_LAST[1])
    # (every installed distribution's file list, read once per environment: ~0.2 s of a fresh worker's first run)
    installs = installed()
    distributions = installs.packages
    files_of = {}  # top-level name -> the files of its loaded modules (real paths taken only where needed: ~1e4 modules)
    for name, module in list(sys.modules.items()):
        files_of.setdefault(name.partition(".")[0], []).append(getattr(module, "__file__", None))
    # a private top-level name is an import hook or a compiled helper of a public one (``_distutils_hack``)
    tops = set(files_of) - set(sys.stdlib_module_names) - {"dalembert"} - {n for n in files_of if n.startswith("_")}
    out = {}
    for top in tops:
        dists = distributions.get(top)
        files = None
        if not dists or len(dists) > 1:
            files = {os.path.realpath(f) for f in files_of[top] if f}
        if not dists:
            dists = sorted({d for f in files for folder in _folders(f) for d in distributions.get(folder, ())})
        if len(dists) > 1:  # one folder, several distributions (mujoco's and mujoco-mjx's): those of a loaded file
            dists = [d for d in dists if files & installs.files(d)]
        for dist in dists:
            try:
                out[dist] = installs.version(dist)
            except metadata.PackageNotFoundError:  # (a name packages_distributions read but no metadata answers to)
                continue
    _LAST = (loaded, dict(sorted(out.items())))
    return dict(_LAST[1])


def _folders(path):
    """The top folder of file ``path`` under each ``sys.path`` entry that holds it: a package installed inside
    another folder (cmeel's ``cmeel.prefix/lib/.../site-packages/pinocchio``, Pinocchio's) is known to
    ``packages_distributions`` by that folder, not by its own name."""
    out = set()
    for entry in sys.path:
        entry = os.path.realpath(entry or ".")
        if path.startswith(entry + os.sep):
            out.add(os.path.relpath(path, entry).split(os.sep)[0])
    return out


# (the modules loaded, ``_libraries``' answer for them) at its last call: a worker's next run asks it again
_LAST = (None, None)


def _pool_width():
    """The width this process's BLAS and OpenMP pools were given (``harness.threads``), or None."""
    width = os.environ.get(VARIABLES[0])
    return int(width) if width and width.isdigit() else None


def unfinished(spec, status, message):
    """The record of a run that ended outside its worker's control (timeout, a dead worker)."""
    return _record(spec, status, message)


def _load():
    """The machine's 1-minute load average (NaN where the OS has none)."""
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


def _execute(spec, timing, truth, concurrent):
    """``execute``'s run, without its libraries: ``(RunRecord, its Trajectory or None)``."""
    from dalembert import invariants
    from dalembert.adapters import get_adapter
    from dalembert.adapters.registry import adapter_distribution
    from dalembert.errors import trajectory_errors
    from dalembert.harness.batches import per_world
    from dalembert.harness.truths import built_case

    started, load_start = time.perf_counter(), _load()
    found = {}  # what is known so far, for the record of a run that fails part-way
    try:
        adapter = get_adapter(spec.engine, spec.adapter)
        found["engine_version"] = adapter.version()
        found["adapter_distribution"], found["adapter_version"] = adapter_distribution(spec.engine)
        # the order it declares (``IntegratorSpec.order``, where the contract has it): the report sets the
        # observed order beside it from the store alone
        found["integrator_order"] = getattr(adapter.integrators.get(spec.settings.integrator), "order", None)
        case, version = built_case(spec.case, spec.params)  # built once per worker, not once per run
        found["t_final"] = case.t_final
        changed = check_version(spec.case, spec.case_version, version, "the matrix was made for")
        if changed:
            return _record(spec, "failed", f"{changed}: its code changed — start a new matrix", **found), None
        settings = spec.settings
        reason = adapter.unsupported(case.scene, settings)
        if reason:
            return _record(spec, "unsupported", reason, **found), None
        found["beyond_scene"] = adapter.beyond_scene(case.scene, settings)
        t0 = time.perf_counter()
        prepared = adapter.prepare(case.scene, case.times, settings)
        build_s = time.perf_counter() - t0
        first = adapter.run(prepared)  # warm-up, not timed
        t0 = time.perf_counter()
        traj = first.trajectory  # the read-back, once
        readback_s = time.perf_counter() - t0
        found["audit"] = adapter.audit(prepared, first)
        model = adapter.describe(case.scene, settings)
        if model:  # (an engine that describes none stores none)
            found["model"] = model
        if not traj.is_finite():
            t_bad = traj.first_nonfinite_time()
            cost = Cost(build_s=build_s, wall_s_median=first.wall_s, wall_s_min=first.wall_s,
                        wall_s_max=first.wall_s, wall_s_repeats=(first.wall_s,), repeats=1, n_steps=first.n_steps, n_rhs=first.n_rhs,
                        readback_s=readback_s, concurrent=concurrent, load_start=load_start, load_end=_load(),
                        device=str(first.info.get("device", "")))  # where it diverged (no batch share: no timing)
            why = first.info.get("message", "")  # the engine's own account, where it gives one
            return _record(spec, "diverged", f"non-finite state from t = {t_bad:.10g} s" + (f" ({why})" if why else ""),
                           t_diverged=t_bad, cost=cost,
                           **found), traj
        truth = truth if truth is not None else _truth(case)
        if first.n_steps == 0:  # e.g. a step too small to count: never a result that looks right
            return _record(spec, "failed", f"the engine took no step over the {case.t_final:g}-s horizon",
                           **found), None
        if traj.is_still() and not truth.is_still():
            return _record(spec, "failed", f"the state never left its initial value over {case.t_final:g} s while "
                                           "the truth moves: the engine did not integrate it, or left out what "
                                           "drives it", **found), None
        walls, totals = [], []
        while ((len(walls) < timing.min_repeats or sum(walls) < timing.min_total_s) and len(walls) < timing.max_repeats
               and not (walls and first.wall_s + sum(walls) > timing.max_total_s)):
            t0 = time.perf_counter()
            out = adapter.run(prepared)
            totals.append(time.perf_counter() - t0)
            walls.append(out.wall_s)
        errors = trajectory_errors(traj, truth)
        summary = invariants.summary(case.scene, traj, case.conserved, case.invariants, truth)
        cost = Cost(build_s=build_s, wall_s_median=float(np.median(walls)), wall_s_min=float(np.min(walls)),
                    wall_s_max=float(np.max(walls)), wall_s_repeats=tuple(float(w) for w in walls), repeats=len(walls), n_steps=first.n_steps, n_rhs=first.n_rhs,
                    overhead_s=float(np.median(np.array(totals) - np.array(walls))), readback_s=readback_s,
                    stepping_total_s=float(first.wall_s + sum(walls)), worker_s=time.perf_counter() - started,
                    concurrent=concurrent, load_start=load_start, load_end=_load())
        cost = per_world(cost, first.info)  # its device; a batch the adapter stepped beside it: cost per world
        return _record(spec, "ok", "", errors, summary.drifts, case.tolerances, drift_rates=summary.drift_rates,
                       growths=summary.growths,
                       checks=summary.checks, cost=cost, **found), traj
    except Exception as e:  # a failure is data
        return _record(spec, "failed", f"{type(e).__name__}: {e}", traceback=traceback.format_exc(), **found), None


def execute(spec, timing=Timing(), truth=None, concurrent=1, sent=None):
    """Run ``spec`` in this process: ``(RunRecord, trajectory npz or None)``. Never raises.

    ``truth``: the case's truth trajectory at its sample times (computed here when None);
    ``concurrent``: runs in flight when this one started, itself included (stored with its cost); ``sent``:
    which trajectories the store keeps (``harness.sent.Sent``; None: every one), the npz None for one it does
    not (never built). The record's ``provenance`` names the versions of the libraries loaded where it ran
    (``libraries``: ``_libraries``).
    """
    record, traj = _execute(spec, timing, truth, concurrent)
    try:
        libraries = _libraries()
    except Exception as e:  # noqa: BLE001 - a broken distribution's metadata must not lose the run
        libraries = {"(unread)": f"{type(e).__name__}: {e}"}
    record = replace(record, provenance={**record.provenance, "libraries": libraries})
    try:
        return record, sent_npz(record, traj, sent, spec.params)
    except Exception as e:  # a failure is data (as one inside the run)
        failed = _record(spec, "failed", f"{type(e).__name__}: {e}", traceback=traceback.format_exc())
        return replace(failed, provenance=record.provenance), None


def sent_npz(record, traj, sent, params):
    """The ``.npz`` bytes of ``traj`` (the trajectory of ``record``'s run, or None) where ``sent`` (a
    ``harness.sent.Sent``, None: all) wants them, else None; ``params``: its spec's, to build its case."""
    from dalembert.store import trajectory_to_npz

    if traj is None:
        return None
    if sent is not None and not sent.wants(record, lambda name, version: _built(name, params)):
        return None
    return trajectory_to_npz(traj)


def _built(name, params):
    from dalembert.harness.truths import built_case

    return built_case(name, params)[0]


def _truth(case):
    from dalembert.reference import truth

    return truth(case)
