"""Runs in groups: a batch of worlds in one engine call, or a chunk of runs in one worker.

``--batch`` (``dalembert run``) hands the runs that differ only in the case's parameters (a swept
parameter: ``--param spin=log:5,500,16``), on an engine that has batches
(``dalembert.adapters.batch``), to ONE engine call: ``execute_batch`` prepares the batch once, times
``run_batch`` as ``execute`` times ``run`` (one warm-up, then repeats by ``Timing``), and stores one
record per world, judged against its own case's truth as any run is. A batched record's cost says it is
a batch's (``dalembert.record.Cost``): ``batch_size``, the batch's wall time and throughput, the device;
its ``wall_s_*``, ``build_s``, ``overhead_s``, ``stepping_total_s`` and ``worker_s`` are the world's share
(the batch's over its size), never a single world's latency. The worlds may differ in model parameters where the engine
holds them per world (``adapters.batch``'s ``world_fields``: a swept mass or inertia on MuJoCo Warp). A
group an engine cannot batch (its models differ in structure or in a field it shares: ``batch_problem``)
runs world by world through ``execute``, its records those of ordinary runs but for the reason, in each
one's audit (``batch_refused``).

``groups`` makes the groups: batches where ``batched`` and the engine has batches, else chunks of at
most ``chunk`` runs of one case, engine, integrator and options (``chunk_key``: a search round's probes
across the swept parameter, or a sweep's steps), which a Dask task runs one after another in one process
(``execute_group``), so a cluster's task is a row or a chunk of probes, not one probe with a process of
its own.

Measured (2 shared cores, ``--quick``): the map ``dalembert run --case free_top_fast_spin --param
spin=log:5,500,16 --param t_final=1 --param sample_interval=0.1 --engine mujoco_warp --integrator rk4
--search dt --dt 1e-3,1e-1 --resolution 1.5`` takes 98 probes either way, the same keys, statuses,
errors and boundaries (MuJoCo Warp's worlds are its runs alone, bit for bit): 46 s with ``--batch``
(23 engine calls of 1 to 16 worlds) against 297 s probe by probe at a load of ~3, 739 s against 2139 s
at a load of ~15. MJX gains nothing there: one world's RK4 step costs ~0.03 ms, so the probes' cost is
building and reading back, not stepping (116 s batched with JAX's cache warm, 205 s cold, against
112 s probe by probe), and its vmapped worlds differ from the runs alone by float32 round-off, which
moved one verdict near its bound (spin 199 rad/s at dt 1e-3: angular-momentum drift 1.1e-3 against
5.0e-4 alone, bound 1e-3). The same map over a model parameter, six inertias of the top
(``benchmarks.batches --map``): 29 probes either way, the same boundaries, 154 s batched against 458 s
probe by probe at a load of ~17.

``python -m dalembert.harness.batches``: run one group read (pickled: specs, timing, truths by case,
parent pid, the engine environment, the trajectories the store keeps: ``harness.sent.Sent``) from stdin; write the pickled ``[(RunRecord, npz)]`` to stdout (a
Dask task's process, as ``dalembert.harness.worker`` is for one run).
"""

from __future__ import annotations

import pickle
import sys
from dataclasses import replace
import time
import traceback

import numpy as np

from dalembert.harness.execute import Timing, _load, _record, _truth, execute, sent_npz

__all__ = ["batch_key", "chunk_key", "groups", "execute_group", "execute_batch", "per_world", "DEFAULT_CHUNK"]

# Runs per Dask task where nothing is batched: enough that a task's process start and the engine's import and
# compilation (seconds: ~10 s to import dalembert and MuJoCo Warp on 2 loaded cores) are paid once per ~a map row
# rather than per probe, few enough that a cluster of tens of workers still has tasks for each.
DEFAULT_CHUNK = 16


def batch_key(spec):
    """What the runs of one batch share: everything but the case's parameters (and so its version)."""
    s = spec.settings
    return (spec.case, spec.engine, spec.adapter, s.integrator, s.dt, s.rtol, s.atol, tuple(sorted(s.options.items())))


def chunk_key(spec):
    """What the runs of one chunk share: the case (any parameters, any step), engine, integrator and options."""
    return (spec.case, spec.engine, spec.adapter, spec.settings.integrator, tuple(sorted(spec.settings.options.items())))


def groups(specs, batched=False, chunk=DEFAULT_CHUNK):
    """``specs`` as a list of tuples of specs, in the order first met: where ``batched`` and the engine has batches,
    one tuple per ``batch_key`` (at most ``adapters.batch.MAX_BATCH`` each), else chunks of at most ``chunk`` specs of
    one ``chunk_key`` (``chunk`` 1: every spec alone). Returns ``[(tuple of specs, batched)]``, ``batched`` True for a
    batch of more than one world."""
    from dalembert.adapters import get_adapter
    from dalembert.adapters.batch import MAX_BATCH, has_batches
    if chunk < 1:
        raise ValueError(f"chunk: {chunk} runs per task — give at least 1")
    batches = {}
    if batched:
        batches = {e: has_batches(get_adapter(e, a)) for e, a in {(s.engine, s.adapter) for s in specs}}
    out = {}
    for s in specs:
        if batches.get(s.engine):
            key, size = ("batch", batch_key(s)), MAX_BATCH
        else:
            key, size = ("chunk", chunk_key(s)), chunk
        parts = out.setdefault(key, [[]])
        if len(parts[-1]) == size:
            parts.append([])
        parts[-1].append(s)
    return [(tuple(g), kind == "batch" and len(g) > 1) for (kind, _), parts in out.items() for g in parts]


def execute_group(specs, timing=Timing(), truths=None, concurrent=1, batched=False, sent=None):
    """Run ``specs`` in this process: one batch when ``batched`` (``execute_batch``), else one after another
    (``execute``). ``truths``: (case, version) -> truth trajectory (computed where missing); ``sent``: which
    trajectories the store keeps (``harness.sent.Sent``; None: all). Returns ``[(RunRecord, npz or None)]`` in the
    order of ``specs``, npz None where ``sent`` does not want it; never raises."""
    truths = truths or {}
    if batched:
        return execute_batch(specs, timing, truths, concurrent, sent)
    return [execute(s, timing, truths.get((s.case, s.case_version)), concurrent, sent) for s in specs]


def execute_batch(specs, timing=Timing(), truths=None, concurrent=1, sent=None):
    """Run ``specs`` (one ``batch_key``) as the worlds of one engine call: ``[(RunRecord, npz or None)]`` in their
    order, npz None where ``sent`` does not want it (``execute_group``); never raises (a failure of the batch is
    every world's, with its traceback)."""
    from dalembert.adapters import get_adapter
    from dalembert.adapters.registry import adapter_distribution
    from dalembert.harness.truths import built_case
    from dalembert.identity import check_version

    started, load_start, truths = time.perf_counter(), _load(), truths or {}
    out, found = [None] * len(specs), {}
    try:
        adapter = get_adapter(specs[0].engine, specs[0].adapter)
        settings = specs[0].settings
        found["engine_version"] = adapter.version()
        found["adapter_distribution"], found["adapter_version"] = adapter_distribution(specs[0].engine)
        found["integrator_order"] = getattr(adapter.integrators.get(settings.integrator), "order", None)
        cases, worlds = {}, []
        for i, s in enumerate(specs):
            case, version = built_case(s.case, s.params)
            cases[i] = case
            changed = check_version(s.case, s.case_version, version, "the matrix was made for")
            reason = adapter.unsupported(case.scene, settings)
            if changed:
                out[i] = _record(s, "failed", f"{changed}: its code changed — start a new matrix", t_final=case.t_final,
                                 **found), None
            elif reason:
                out[i] = _record(s, "unsupported", reason, t_final=case.t_final, **found), None
            else:
                worlds.append(i)
        times = cases[worlds[0]].times if worlds else None
        problem = worlds and (adapter.batch_problem([cases[i].scene for i in worlds], times, settings)
                              or next((f"world {k}'s sample times differ from world 0's" for k, i in enumerate(worlds)
                                       if not np.array_equal(cases[i].times, times)), None))
        if problem:  # not one model: each world run alone, as ordinary runs, its audit saying why
            for i in worlds:
                record, npz = execute(specs[i], timing, truths.get((specs[i].case, specs[i].case_version)), concurrent,
                                      sent)
                out[i] = replace(record, audit={**record.audit, "batch_refused": problem}), npz
        elif worlds:
            _run_batch(adapter, [specs[i] for i in worlds], [cases[i] for i in worlds], timing, truths, concurrent,
                       found, started, load_start, out, worlds)
    except Exception as e:  # a failure is data: every world not yet recorded failed with it
        for i, s in enumerate(specs):
            if out[i] is None:
                out[i] = _record(s, "failed", f"{type(e).__name__}: {e}", traceback=traceback.format_exc(), **found), None
    for i, (record, traj) in enumerate(out):  # a world's Trajectory (``_run_batch``) to bytes where the store keeps it
        if traj is not None and not isinstance(traj, bytes):
            try:
                out[i] = record, sent_npz(record, traj, sent, specs[i].params)
            except Exception as e:  # noqa: BLE001 - a failure is data
                out[i] = _record(specs[i], "failed", f"{type(e).__name__}: {e}", traceback=traceback.format_exc(),
                                 **found), None
    return out


def _run_batch(adapter, specs, cases, timing, truths, concurrent, found, started, load_start, out, where):
    """Prepare, warm up, time and read back the batch of ``specs`` (every one runnable, one model), writing each
    world's ``(record, Trajectory or None)`` into ``out[where[k]]``."""
    from dalembert import invariants
    from dalembert.errors import trajectory_errors
    from dalembert.record import Cost

    n, settings = len(specs), specs[0].settings
    t0 = time.perf_counter()
    prepared = adapter.prepare_batch([c.scene for c in cases], cases[0].times, settings)
    build_s = time.perf_counter() - t0
    first = adapter.run_batch(prepared)  # warm-up, not timed
    walls, totals = [], []
    while ((len(walls) < timing.min_repeats or sum(walls) < timing.min_total_s) and len(walls) < timing.max_repeats
           and not (walls and first.wall_s + sum(walls) > timing.max_total_s)):
        t0 = time.perf_counter()
        walls.append(adapter.run_batch(prepared).wall_s)
        totals.append(time.perf_counter() - t0)
    walls = walls or [first.wall_s]
    batch_wall = float(np.median(walls))
    steps = sum(o.n_steps for o in first.worlds)
    batch = dict(batch_size=n, batch_wall_s=batch_wall, world_steps_per_s=steps / batch_wall if batch_wall > 0
                 else float("nan"), device=prepared.device, build_s=build_s / n, concurrent=concurrent,
                 load_start=load_start)
    share = [w / n for w in walls]
    for k, (s, case, world) in enumerate(zip(specs, cases, first.worlds)):
        t0 = time.perf_counter()
        traj = world.trajectory  # the read-back, once per world
        readback_s = time.perf_counter() - t0
        here = dict(found, t_final=case.t_final, audit=adapter.audit(prepared.worlds[k], world))
        model = adapter.describe(case.scene, settings)
        if model:
            here["model"] = model
        timed = dict(batch, n_steps=world.n_steps, n_rhs=world.n_rhs, readback_s=readback_s, load_end=_load())
        if not traj.is_finite():
            t_bad = traj.first_nonfinite_time()
            w = first.wall_s / n
            cost = Cost(wall_s_median=w, wall_s_min=w, wall_s_max=w, wall_s_repeats=(w,), repeats=1, **timed)
            why = world.info.get("message", "")
            out[where[k]] = _record(s, "diverged", f"non-finite state from t = {t_bad:.10g} s"
                                    + (f" ({why})" if why else ""), t_diverged=t_bad, cost=cost, **here), traj
            continue
        if world.n_steps == 0:
            out[where[k]] = _record(s, "failed", f"the engine took no step over the {case.t_final:g}-s horizon",
                                    **here), None
            continue
        truth = truths.get((s.case, s.case_version))
        truth = truth if truth is not None else _truth(case)
        if traj.is_still() and not truth.is_still():
            out[where[k]] = _record(s, "failed", f"the state never left its initial value over {case.t_final:g} s "
                                    "while the truth moves: the engine did not integrate it, or left out what drives "
                                    "it", **here), None
            continue
        errors = trajectory_errors(traj, truth)
        summary = invariants.summary(case.scene, traj, case.conserved, case.invariants, truth)
        cost = Cost(wall_s_median=float(np.median(share)), wall_s_min=float(np.min(share)),
                    wall_s_max=float(np.max(share)), wall_s_repeats=tuple(float(w) for w in share), repeats=len(walls),
                    overhead_s=float(np.median(np.array(totals) - np.array(walls))) / n if totals else float("nan"),
                    stepping_total_s=(first.wall_s + sum(walls)) / n, worker_s=(time.perf_counter() - started) / n,
                    **timed)
        out[where[k]] = _record(s, "ok", "", errors, summary.drifts, case.tolerances, drift_rates=summary.drift_rates,
                                growths=summary.growths, checks=summary.checks, cost=cost, **here), traj


def per_world(cost, info):
    """``cost`` (a ``Cost`` of one run, as ``execute`` times it) with what the run's ``Outcome.info`` says of its
    device (``device``) and of the worlds it stepped beside its own (``batch_size``: MuJoCo Warp's option ``worlds``,
    copies of the run whose wall time is the batch's): then its stepping times are per world, the batch's
    median, size and throughput beside them."""
    n, device = int(info.get("batch_size", 1)), str(info.get("device", cost.device))
    if n == 1:
        return replace(cost, device=device)
    batch = cost.wall_s_median
    return replace(cost, device=device, batch_size=n, batch_wall_s=batch,
                   world_steps_per_s=n * cost.n_steps / batch if batch > 0 else float("nan"),
                   wall_s_median=batch / n, wall_s_min=cost.wall_s_min / n, wall_s_max=cost.wall_s_max / n,
                   wall_s_repeats=tuple(w / n for w in cost.wall_s_repeats), overhead_s=cost.overhead_s / n,
                   stepping_total_s=cost.stepping_total_s / n)


def main():
    """One group from stdin, its results to stdout (module docstring)."""
    from dalembert.harness.lifetime import die_with_parent
    from dalembert.harness.matrix import RunSpec
    from dalembert.store import trajectory_from_npz

    request = pickle.loads(sys.stdin.buffer.read())
    die_with_parent(request["parent"])
    if request.get("environment"):  # started for an engine environment: its versioned engine runs here
        from dalembert.environments import serving

        serving(request["environment"])
    truths = {tuple(k): trajectory_from_npz(t) for k, t in request["truths"]}
    specs = [RunSpec.from_json(s) for s in request["specs"]]
    result = execute_group(specs, Timing(**request["timing"]), truths, batched=request["batched"],
                           sent=request.get("sent"))
    sys.stdout.buffer.write(pickle.dumps(result))


if __name__ == "__main__":
    main()
