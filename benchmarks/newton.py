"""Newton on Warp's CPU backend: what the adapter's stepping costs against bare Newton, and each solver family's
accuracy against the truth beside the float32 floor.

    python -m benchmarks.newton                         # both parts, 0.2 s of each canonical case Newton runs
    python -m benchmarks.newton cost                    # part 1 only (also: accuracy)
    python -m benchmarks.newton --seconds 1             # the cases' first second
    python -m benchmarks.newton --family featherstone   # one family (repeatable; default all)
    python -m benchmarks.newton batch                   # part 3: throughput vs batch size (free_top, featherstone)
    python -m benchmarks.newton batch --worlds 1,8,64,256 --case free_top --family xpbd

1. Cost, per canonical case Newton supports and family at dt = 1e-3: the first step's kernel compilation or cache
   load (build), the adapter's stepping per simulated second (``Outcome.wall_s``: loads into ``body_f``,
   ``solver.step``, a host copy per sample) against a bare loop of ``solver.step`` over the same steps on the
   same model and solver (no loads, no sampling), each the median of 3 runs after a warm-up.
2. Accuracy, the same runs: the largest attitude error (rad) and position error (m) against the case's truth
   over the span, beside the float32 floor of the torque-free tops (RK4 in float32 against itself in double:
   ``mjx.parity.float32_floor``; NaN for the other cases), and whether the run diverged.
3. Batches (``batch``): N worlds of one case (``--case``, default ``free_top``), each its initial velocities scaled by
   ``1 + k PERTURBATION`` (world k), stepped in one Newton model (``prepare_batch``, ``run_batch``) for each N of
   ``--worlds`` (default 1, 8, 64, 256): the batch's stepping wall time per step, world-steps per second, and the
   single-world latency (``run`` of world 0 alone, per step) beside them; the largest difference between a batch's
   first and last worlds and their runs alone (0: bit for bit).
   Measured (``python -m benchmarks.newton batch --family featherstone --family xpbd``, 2 cores shared at a load of
   ~12): Featherstone 1.7, 1.8, 2.3 and 5.6 ms a step for 1, 8, 64 and 256 worlds (588 to 45,958 world-steps/s, 91
   times one world's 2.0 ms a step), XPBD 1.1, 0.59, 0.58 and 0.65 ms (904 to 397,157 world-steps/s, 437 times);
   parity 0 in every batch. Python's launch of each kernel, not the arithmetic, is a step's cost up to ~64 worlds.

Every step launches its kernels one by one from Python (no CUDA graphs on the CPU), so the cost is Python's
launch overhead more than arithmetic; the figures scale with how busy the machine is.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from dalembert import Settings, spatial
from dalembert.adapters import get_adapter
from dalembert.case import load_cases

REPEATS = 3
DT = 1e-3
SECONDS = 0.2  # model time per case (``--seconds``): VBD costs ~10-30 ms a step here
FAMILIES = ()  # (``--family``; empty: every family)
WORLDS = (1, 8, 64, 256)  # batch sizes (``--worlds``)
CASE = "free_top"  # the batch part's case (``--case``)
# world k's initial velocities are scaled by 1 + k * PERTURBATION: distinct worlds, none far from the case's
PERTURBATION = 1e-3


def cases():
    """The canonical cases Newton supports."""
    adapter = get_adapter("newton")
    out = []
    for _, f in load_cases().items():
        if "canonical" in f.tags:
            case = f()
            if adapter.unsupported(case.scene, Settings("featherstone", dt=DT)) is None:
                out.append(case)
    return out


def span(case):
    """The case's samples within its first ``SECONDS`` (s)."""
    t = np.asarray(case.times, dtype=float)
    return t[t <= t[0] + SECONDS + 1e-12]


def families():
    """``--family``'s, or every family that runs here (not Newton's MuJoCo solver's where its MuJoCo is not
    installed: ``mujoco_solver.problem``)."""
    from dalembert.adapters.newton import mujoco_solver

    here = mujoco_solver.problem() is None
    return FAMILIES or tuple(f for f in get_adapter("newton").integrators if here or f not in mujoco_solver.FAMILIES)


def bare_loop(prepared):
    """All the run's steps as ``solver.step`` calls between two states, no loads, no sampling (median, s)."""
    from dalembert.adapters.newton.engine import DEVICE, engine
    from dalembert.adapters.newton.stepping import fresh_states

    wp, _, _ = engine()
    p, n, walls = prepared, int(prepared.steps.sum()), []
    control = p.model.model.control()
    for _ in range(REPEATS):
        a, b = fresh_states(p.model)
        with wp.ScopedDevice(DEVICE):
            t0 = time.perf_counter()
            for _ in range(n):
                p.solver.step(a, b, control, None, DT)
                a, b = b, a
            wp.synchronize_device(DEVICE)
            walls.append(time.perf_counter() - t0)
    return float(np.median(walls))


def _errors(case, traj, times):
    truth = case.exact(times) if case.exact is not None else None
    if truth is None:
        return float("nan"), float("nan")
    att = max(float(np.nanmax(spatial.rotation_angle(traj.bodies[n].quaternion, truth.bodies[n].quaternion)))
              for n in truth.bodies)
    pos = max(float(np.nanmax(np.abs(traj.bodies[n].position - truth.bodies[n].position))) for n in truth.bodies)
    return att, pos


def cost(accuracy=False, timing=True):
    adapter = get_adapter("newton")
    print(f"Newton {adapter.version()} (float32, CPU), dt = {DT:g}, first {SECONDS:g} s; kernel compile or cache "
          "load (s), stepping per simulated second (s)")
    print(f"{'case':<24}{'family':<15}{'compile':>9}" + (f"{'adapter':>10}{'bare':>10}{'ratio':>7}" if timing else "")
          + (f"{'attitude':>10}{'position':>10}{'f32 floor':>10}  diverged" if accuracy else ""))
    for case in cases():
        times = span(case)
        per_s = 1.0 / (times[-1] - times[0])
        for family in families():
            p = adapter.prepare(case.scene, times, Settings(family, dt=DT))
            out = adapter.run(p)
            row = f"{case.name:<24}{family:<15}{p.compile_s:>9.2f}"
            if timing:
                ours = np.median([adapter.run(p).wall_s for _ in range(REPEATS)])
                theirs = bare_loop(p)
                row += f"{ours * per_s:>10.2f}{theirs * per_s:>10.2f}{ours / theirs:>7.2f}"
            if accuracy:
                att, pos = _errors(case, out.trajectory, times)
                floor = adapter.audit(p, out).get("float32_floor", float("nan"))
                row += f"{att:>10.1e}{pos:>10.1e}{floor:>10.1e}  {bool(out.info.get('message'))}"
            print(row, flush=True)


def _perturbed(scene, factor):
    """``scene`` with every joint's initial velocities scaled by ``factor``."""
    from dataclasses import replace

    return replace(scene, joints=tuple(replace(j, v0=tuple(float(v) * factor for v in j.v0)) for j in scene.joints))


def batches():
    """Part 3: throughput vs batch size, per family (default featherstone), on ``CASE``'s first ``SECONDS``."""
    from dalembert import make_case

    adapter = get_adapter("newton")
    case = make_case(CASE)
    times = span(case)
    print(f"Newton {adapter.version()} (float32, CPU), {CASE}, dt = {DT:g}, first {SECONDS:g} s; median of "
          f"{REPEATS}; worlds perturbed by {PERTURBATION:g} x k")
    print(f"{'family':<15}{'worlds':>7}{'batch ms/step':>15}{'world-steps/s':>15}{'single ms/step':>16}"
          f"{'speed-up':>10}{'parity':>10}")
    for family in FAMILIES or ("featherstone",):
        settings = Settings(family, dt=DT)
        alone = adapter.prepare(case.scene, times, settings)
        n = int(alone.steps.sum())
        single = float(np.median([adapter.run(alone).wall_s for _ in range(REPEATS + 1)][1:])) / n
        for worlds in WORLDS:
            scenes = [_perturbed(case.scene, 1.0 + k * PERTURBATION) for k in range(worlds)]
            batch = adapter.prepare_batch(scenes, times, settings)
            outs = [adapter.run_batch(batch) for _ in range(REPEATS + 1)]  # the first: a warm-up
            wall = float(np.median([o.wall_s for o in outs[1:]])) / n
            parity = 0.0
            for k in {0, worlds - 1}:
                ref = adapter.run(adapter.prepare(scenes[k], times, settings)).trajectory
                got = outs[-1].worlds[k].trajectory
                parity = max(parity, max(float(np.nanmax(np.abs(got.bodies[b].quaternion - ref.bodies[b].quaternion)))
                                         for b in ref.bodies))
            print(f"{family:<15}{worlds:>7}{wall * 1e3:>15.3f}{worlds / wall:>15.0f}{single * 1e3:>16.3f}"
                  f"{worlds * single / wall:>10.1f}{parity:>10.1e}", flush=True)


def main(argv):
    global SECONDS, FAMILIES, WORLDS, CASE
    while "--family" in argv:
        i = argv.index("--family")
        FAMILIES = (*FAMILIES, argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if "--seconds" in argv:
        i = argv.index("--seconds")
        SECONDS = float(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if "--worlds" in argv:
        i = argv.index("--worlds")
        WORLDS = tuple(int(w) for w in argv[i + 1].split(","))
        argv = argv[:i] + argv[i + 2:]
    if "--case" in argv:
        i = argv.index("--case")
        CASE = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    parts = argv or ["cost", "accuracy"]
    if "batch" in parts:
        batches()
    if "cost" in parts or "accuracy" in parts:
        cost(accuracy="accuracy" in parts, timing="cost" in parts)


if __name__ == "__main__":
    main(sys.argv[1:])
