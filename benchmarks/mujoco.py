"""Benchmark of the MuJoCo adapter's stepping against a bare ``mujoco.rollout``.

    python -m benchmarks.mujoco

Per case and integrator at dt = 1e-3: the adapter's stepping time per simulated
second (``Outcome.wall_s``: the ``mj_step(nstep=k)`` loop with its per-sample
divergence checks and state copies) and a bare ``mujoco.rollout`` of the same
compiled model from the same initial state, in the same process, each the
median of 5 runs after a warm-up. Goal: ratio <= 1.2, so that what the reports
call MuJoCo's cost is MuJoCo's: the adapter's per-sample checks and copies may
add at most a fifth to it.
"""

from __future__ import annotations

import time

import numpy as np

from dalembert.adapters import get_adapter
from dalembert import Settings
from dalembert.case import load_cases

REPEATS = 5


def bare_rollout(prepared):
    import mujoco
    from mujoco import rollout

    model, data = prepared["model"], prepared["data"]
    mujoco.mj_resetData(model, data)
    data.qpos[:], data.qvel[:] = prepared["qpos0"], prepared["qvel0"]
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    control = np.ones((1, 1, model.nu))
    nstep = int(prepared["steps"].sum())
    t0 = time.perf_counter()
    rollout.rollout(model, data, state[None], control if model.nu else None, nstep=nstep)
    return time.perf_counter() - t0


def main():
    adapter = get_adapter("mujoco")
    print(f"MuJoCo {adapter.version()}, dt = 1e-3; stepping time per simulated second (ms)")
    print(f"{'case':<24}{'integrator':<14}{'adapter':>10}{'rollout':>10}{'ratio':>8}")
    ratios = []
    for name, factory in load_cases().items():
        case = factory()
        for integ in adapter.integrators:
            prepared = adapter.prepare(case.scene, case.times, Settings(integ, dt=1e-3))
            adapter.run(prepared)
            bare_rollout(prepared)
            ours = np.median([adapter.run(prepared).wall_s for _ in range(REPEATS)])
            bare = np.median([bare_rollout(prepared) for _ in range(REPEATS)])
            ratios.append(ours / bare)
            print(f"{name:<24}{integ:<14}{1e3 * ours / case.t_final:>10.2f}{1e3 * bare / case.t_final:>10.2f}"
                  f"{ours / bare:>8.2f}")
    print(f"overhead ratio: median {np.median(ratios):.2f}, max {np.max(ratios):.2f} (goal <= 1.2)")


if __name__ == "__main__":
    main()
