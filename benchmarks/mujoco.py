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

from benchmarks.bare import adapter_against_bare
from dalembert.adapters import get_adapter
from dalembert.case import load_cases

REPEATS = 5


def bare_rollout(prepared):
    import mujoco
    from mujoco import rollout

    model, data = prepared.model, prepared.data
    mujoco.mj_resetData(model, data)
    data.qpos[:], data.qvel[:] = prepared.qpos0, prepared.qvel0
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    control = np.ones((1, 1, model.nu))
    nstep = int(prepared.steps.sum())
    t0 = time.perf_counter()
    rollout.rollout(model, data, state[None], control if model.nu else None, nstep=nstep)
    return time.perf_counter() - t0


def main():
    adapter = get_adapter("mujoco")
    print(f"MuJoCo {adapter.version()}, dt = 1e-3; stepping time per simulated second (ms)")
    adapter_against_bare(adapter, [f() for _, f in load_cases().items()], adapter.integrators, bare_rollout,
                         repeats=REPEATS, bare_label="rollout")


if __name__ == "__main__":
    main()
