"""MuJoCo Warp against MuJoCo C: parity at the same settings, what the adapter's stepping costs, and the
throughput of a batch of worlds, on Warp's CPU backend.

    python -m benchmarks.mujoco_warp                 # all three parts, 1 s of each case
    python -m benchmarks.mujoco_warp parity          # part 1 only (also: cost, worlds, batch)
    python -m benchmarks.mujoco_warp --seconds 20    # the cases' first 20 s (their whole horizon, or less)
    python -m benchmarks.mujoco_warp --all           # every integrator, not only RK4

1. Parity (``dalembert.adapters.mujoco_warp.parity``), per canonical case and integrator at dt = 1e-3: one
   step's largest ``qpos``/``qvel`` difference from MuJoCo C, the largest attitude (rad) and position (m)
   differences over the first ``--seconds`` of the case, the float32 floor of the torque-free tops (RK4 in
   float32 against itself in double) over the same span.
2. Cost, per canonical case at dt = 1e-3: the first step's kernel compilation or cache load (build), and the
   adapter's stepping per simulated second (``Outcome.wall_s``: ``mjw.step`` per step, a host copy per
   sample) against a bare loop of ``mjw.step`` over the same steps, no sampling, each the median of 3 runs
   after a warm-up; and MuJoCo C's.
3. Worlds: ``mjw.step`` on ``nworld`` copies of the pendulum at once (``mjw.put_data(nworld=...)``): the wall
   time of a step and the per-world throughput (steps of one world per second) against nworld.
4. Batch: the adapter's batches (``prepare_batch``/``run_batch``, every sample read back) of ``free_top_fast_spin``
   at 1, 8, 64 and 256 spins against one world's ``run`` (``benchmarks.batches``).

Every step launches its kernels one by one from Python (no CUDA graphs on the CPU), so the stepping cost is
Python's launch overhead more than arithmetic; the figures scale with how busy the machine is.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from dalembert import Settings
from dalembert.adapters import get_adapter
from dalembert.case import load_cases

REPEATS = 3
DT = 1e-3
INTEGRATORS = ("rk4",)
SECONDS = 1.0  # model time per case (``--seconds``): a step costs ~1.5-5 ms of Python (module docstring)
WORLDS = (1, 8, 64, 256)
WORLD_STEPS = 50  # steps timed per batch size


def canonical():
    return [f() for _, f in load_cases().items() if "canonical" in f.tags]


def span(case):
    """The case's samples within its first ``SECONDS`` (s)."""
    t = np.asarray(case.times, dtype=float)
    return t[t <= t[0] + SECONDS + 1e-12]


def parity():
    from dalembert.adapters.mujoco_warp.parity import horizon, one_step

    print(f"MuJoCo Warp {get_adapter('mujoco_warp').version()} (float32, CPU) vs MuJoCo C "
          f"{get_adapter('mujoco').version()}, dt = {DT:g}, first {SECONDS:g} s")
    print(f"{'case':<24}{'integrator':<14}{'1-step qpos':>12}{'1-step qvel':>12}{'attitude':>10}{'position':>10}"
          f"{'f32 floor':>10}")
    for case in canonical():
        for integ in INTEGRATORS:
            s = Settings(integ, dt=DT)
            one = one_step(case, s)
            h = horizon(case, s, span(case))
            print(f"{case.name:<24}{integ:<14}{one['qpos']:>12.1e}{one['qvel']:>12.1e}{h['orientation']:>10.1e}"
                  f"{h['position']:>10.1e}{h['float32_floor']:>10.1e}", flush=True)


def bare_loop(prepared):
    """All the run's steps as ``mjw.step`` calls, no sampling: what MuJoCo Warp costs bare (median, s)."""
    from dalembert.adapters.mujoco_warp.stepping import DEVICE, put_state, warp

    wp, mjw, _ = warp()
    p, n, walls = prepared, int(prepared.steps.sum()), []
    for _ in range(REPEATS):
        d = put_state(p.model, p.qpos0, p.qvel0, p.ctrl)
        with wp.ScopedDevice(DEVICE):
            t0 = time.perf_counter()
            for _ in range(n):
                mjw.step(p.mx, d)
            wp.synchronize_device(DEVICE)
            walls.append(time.perf_counter() - t0)
    return float(np.median(walls))


def cost():
    warp_adapter, mj = get_adapter("mujoco_warp"), get_adapter("mujoco")
    print(f"dt = {DT:g}, first {SECONDS:g} s; kernel compile or cache load (s), stepping per simulated second (ms)")
    print(f"{'case':<24}{'integrator':<14}{'compile':>9}{'adapter':>10}{'bare loop':>10}{'ratio':>7}{'MuJoCo C':>10}")
    for case in canonical():
        times = span(case)
        per_s = 1e3 / (times[-1] - times[0])
        for integ in INTEGRATORS:
            c = mj.prepare(case.scene, times, Settings(integ, dt=DT))
            mj.run(c)
            c_wall = np.median([mj.run(c).wall_s for _ in range(REPEATS)])
            p = warp_adapter.prepare(case.scene, times, Settings(integ, dt=DT))
            warp_adapter.run(p)
            ours = np.median([warp_adapter.run(p).wall_s for _ in range(REPEATS)])
            theirs = bare_loop(p)
            print(f"{case.name:<24}{integ:<14}{p.compile_s:>9.2f}{ours * per_s:>10.1f}{theirs * per_s:>10.1f}"
                  f"{ours / theirs:>7.2f}{c_wall * per_s:>10.2f}", flush=True)


def worlds():
    from dalembert.adapters.mujoco_warp.stepping import DEVICE, put_state, warp

    wp, mjw, _ = warp()
    case = next(f() for n, f in load_cases().items() if n == "pendulum")
    print(f"pendulum, {WORLD_STEPS} steps of dt = {DT:g} per batch size; wall per step (ms), world-steps per second")
    print(f"{'integrator':<14}{'nworld':>8}{'ms/step':>10}{'world-steps/s':>15}")
    for integ in INTEGRATORS:
        p = get_adapter("mujoco_warp").prepare(case.scene, span(case), Settings(integ, dt=DT))
        for n in WORLDS:
            d = put_state(p.model, p.qpos0, p.qvel0, p.ctrl, nworld=n)
            with wp.ScopedDevice(DEVICE):
                mjw.step(p.mx, d)  # a batch size's first step may compile kernels sized for it
                wp.synchronize_device(DEVICE)
                t0 = time.perf_counter()
                for _ in range(WORLD_STEPS):
                    mjw.step(p.mx, d)
                wp.synchronize_device(DEVICE)
                wall = (time.perf_counter() - t0) / WORLD_STEPS
            print(f"{integ:<14}{n:>8}{wall * 1e3:>10.2f}{n / wall:>15.0f}", flush=True)


def batch():
    from benchmarks.batches import throughput

    throughput("mujoco_warp")


def main(argv):
    global INTEGRATORS, SECONDS
    if "--all" in argv:
        INTEGRATORS = tuple(get_adapter("mujoco_warp").integrators)
        argv = [a for a in argv if a != "--all"]
    if "--seconds" in argv:
        i = argv.index("--seconds")
        SECONDS = float(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    parts = argv or ["parity", "cost", "worlds", "batch"]
    for name, part in (("parity", parity), ("cost", cost), ("worlds", worlds), ("batch", batch)):
        if name in parts:
            part()


if __name__ == "__main__":
    main(sys.argv[1:])
