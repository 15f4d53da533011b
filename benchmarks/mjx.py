"""MJX against MuJoCo C: parity at the same settings, and what the adapter's stepping costs.

    python -m benchmarks.mjx            # both parts
    python -m benchmarks.mjx parity     # part 1 only
    python -m benchmarks.mjx cost       # part 2 only
    python -m benchmarks.mjx batch      # part 3 only
    python -m benchmarks.mjx --all      # every MJX integrator, not only RK4

1. Parity (``dalembert.adapters.mjx.parity``), per canonical case, integrator and precision at
   dt = 1e-3: one step's largest ``qpos``/``qvel`` difference from MuJoCo C, the largest attitude
   (rad) and position (m) differences over the horizon, the case's double-precision floor and, for
   the torque-free tops, the float32 floor (RK4 in float32 against itself in double).
2. Cost, per canonical case at dt = 1e-3: the JIT compilation (build, once per model structure and
   precision) and the adapter's stepping per simulated second (``Outcome.wall_s``: the compiled
   scan, ``block_until_ready``) against a bare jitted ``mjx.step`` loop of ``jax.lax.scan`` over
   all steps without sampling, each the median of 3 runs after a warm-up; and MuJoCo C's.
3. Batch: the adapter's batches (``prepare_batch``/``run_batch``: ``jax.vmap`` of the rollout, every sample read
   back) of ``free_top_fast_spin`` at 1, 8, 64 and 256 spins against one world's ``run`` (``benchmarks.batches``).
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
# Every (case, integrator, precision) costs MJX a JIT compilation or two (5-25 s each on 2 busy
# cores): RK4 by default, every integrator with `--all`.
INTEGRATORS = ("rk4",)


def canonical():
    return [f() for _, f in load_cases().items() if "canonical" in f.tags]


def parity():
    from dalembert.adapters.mjx.parity import horizon, one_step

    print(f"MJX {get_adapter('mjx').version()} vs MuJoCo C {get_adapter('mujoco').version()}, dt = {DT:g}")
    print(f"{'case':<24}{'integrator':<14}{'precision':<10}{'1-step qpos':>12}{'1-step qvel':>12}"
          f"{'attitude':>10}{'position':>10}{'floor':>9}{'f32 floor':>10}")
    for case in canonical():
        for integ in INTEGRATORS:
            for prec in ("float32", "float64"):
                s = Settings(integ, dt=DT, options={"precision": prec})
                one = one_step(case, s)
                h = horizon(case, s)
                print(f"{case.name:<24}{integ:<14}{prec:<10}{one['qpos']:>12.1e}{one['qvel']:>12.1e}"
                      f"{h['orientation']:>10.1e}{h['position']:>10.1e}{h['floor']:>9.1e}{h['float32_floor']:>10.1e}",
                      flush=True)


def bare_scan(prepared):
    """All steps in one ``jax.lax.scan`` of ``mjx.step``, no sampling: what MJX costs bare."""
    import jax

    from dalembert.adapters.mjx.stepping import mjx, precision

    step = mjx().step
    n = int(prepared.steps.sum())
    with precision(prepared.precision):
        fn = jax.jit(lambda m, d: jax.lax.scan(lambda d, _: (step(m, d), None), d, None, length=n)[0].qpos)
        fn(prepared.mx, prepared.dx0).block_until_ready()  # compile
        walls = []
        for _ in range(REPEATS):
            t0 = time.perf_counter()
            fn(prepared.mx, prepared.dx0).block_until_ready()
            walls.append(time.perf_counter() - t0)
    return float(np.median(walls))


def cost():
    mjx, mj = get_adapter("mjx"), get_adapter("mujoco")
    print(f"dt = {DT:g}; JIT compile (s), stepping time per simulated second (ms)")
    print(f"{'case':<24}{'integrator':<14}{'precision':<10}{'compile':>9}{'adapter':>10}{'bare scan':>10}"
          f"{'ratio':>7}{'MuJoCo C':>10}")
    for case in canonical():
        for integ in INTEGRATORS:
            c = mj.prepare(case.scene, case.times, Settings(integ, dt=DT))
            mj.run(c)
            c_wall = np.median([mj.run(c).wall_s for _ in range(REPEATS)])
            for prec in ("float32", "float64"):
                p = mjx.prepare(case.scene, case.times, Settings(integ, dt=DT, options={"precision": prec}))
                mjx.run(p)
                ours = np.median([mjx.run(p).wall_s for _ in range(REPEATS)])
                theirs = bare_scan(p)
                per_s = 1e3 / case.t_final
                print(f"{case.name:<24}{integ:<14}{prec:<10}{p.compile_s:>9.1f}{ours * per_s:>10.2f}"
                      f"{theirs * per_s:>10.2f}{ours / theirs:>7.2f}{c_wall * per_s:>10.2f}", flush=True)


def main(argv):
    global INTEGRATORS
    if "--all" in argv:
        INTEGRATORS = tuple(get_adapter("mjx").integrators)
        argv = [a for a in argv if a != "--all"]
    parts = argv or ["parity", "cost", "batch"]
    if "parity" in parts:
        parity()
    if "cost" in parts:
        cost()
    if "batch" in parts:
        from benchmarks.batches import throughput

        throughput("mjx")


if __name__ == "__main__":
    main(sys.argv[1:])
