"""Benchmark of the PyBullet adapter's stepping against a bare ``stepSimulation`` loop.

    python -m benchmarks.pybullet

Per case PyBullet runs (loops and springs refused) at dt = 1e-3: the adapter's stepping time per
simulated second (``Outcome.wall_s``: its step loop with the loads applied before each step, the state copied
out at every sample and checked for a blow-up) and a bare loop of the same steps on the same prepared model from
the same initial state (the loads applied as PyBullet requires, before every step, and nothing else), in the same
process, each the median of 5 runs after a warm-up. Goal: ratio <= 1.2, so that what the reports call PyBullet's
cost is PyBullet's.
"""

from __future__ import annotations

import time

from benchmarks.bare import adapter_against_bare
from dalembert import Settings
from dalembert.adapters import get_adapter
from dalembert.adapters.pybullet.model import engine, rebuild
from dalembert.adapters.pybullet.stepping import apply_loads
from dalembert.case import load_cases

REPEATS = 5
DT = 1e-3  # s


def bare_loop(prepared):
    """``stepSimulation`` as many times as the run steps, loads applied before each; its wall time, s."""
    pb = engine()
    model, plan = prepared.model, prepared.loads
    if prepared.scene.contacts:  # as the adapter's run: a fresh world (model.rebuild)
        rebuild(model, prepared.scene, prepared.settings)
    else:
        model.state0(prepared.scene)
    c, step, n = model.client, pb.stepSimulation, int(prepared.steps.sum())
    t0 = time.perf_counter()
    if plan:
        for _ in range(n):
            apply_loads(pb, c, plan)
            step(physicsClientId=c)
    else:
        for _ in range(n):
            step(physicsClientId=c)
    return time.perf_counter() - t0


def main():
    adapter = get_adapter("pybullet")
    cases = [f() for _, f in load_cases().items()]
    cases = [c for c in cases if adapter.unsupported(c.scene, Settings("euler", dt=DT)) is None]
    print(f"PyBullet {adapter.version()}, dt = {DT:g}; stepping time per simulated second (ms)")
    adapter_against_bare(adapter, cases, adapter.integrators, bare_loop, dt=DT, repeats=REPEATS,
                         bare_label="loop")


if __name__ == "__main__":
    main()
