"""Benchmark of the DART adapter's stepping against a bare ``World.step`` loop.

    python -m benchmarks.dart

Per case DART runs (``unsupported`` is None) at dt = 1e-3: the adapter's stepping time per simulated second
(``Outcome.wall_s``: ``World.step(False)`` per step, and per sample interval the state copied out, checked
finite and DART's captured console checked for its non-finite warning) and a bare loop of ``World.step(False)``
on the same prepared world from the same initial state (world-frame loads set again before every step, as the
physics needs), in the same process, each the median of 5 runs after a warm-up. Cases whose run diverges at
that step are left out (the adapter stops at the first flagged sample, a bare loop does not). Goal: ratio <= 1.2, so that
what the reports call DART's cost is DART's.
"""

from __future__ import annotations

import time

from benchmarks.bare import adapter_against_bare
from dalembert import Settings
from dalembert.adapters import get_adapter
from dalembert.case import load_cases

REPEATS = 5
DT = 1e-3


def bare_loop(prepared):
    from dalembert.adapters.dart.stepping import EngineLog, apply_loads

    with EngineLog():  # DART's warnings, if any, kept off the console as the adapter keeps them
        return _bare_loop(prepared, apply_loads)


def _bare_loop(prepared, apply_loads):
    model = prepared.model
    model.reset()
    apply_loads(model)
    step, nstep = model.world.step, int(prepared.steps.sum())
    every_step = any(ld.frame == "world" for ld in model.scene.loads)
    t0 = time.perf_counter()
    if every_step:
        for _ in range(nstep):
            apply_loads(model)
            step(False)
    else:
        for _ in range(nstep):
            step(False)
    return time.perf_counter() - t0


def main():
    adapter = get_adapter("dart")
    cases = [f() for _, f in load_cases().items()]
    cases = [c for c in cases if adapter.unsupported(c.scene, Settings("euler", dt=DT)) is None]
    # a run that blows up stops at its first flagged sample, a bare loop does not: no comparison there
    diverged = [c for c in cases
                if not adapter.run(adapter.prepare(c.scene, c.times, Settings("euler", dt=DT))).trajectory.is_finite()]
    if diverged:
        print(f"left out, diverged at dt = {DT:g}: {', '.join(c.name for c in diverged)}")
    cases = [c for c in cases if c not in diverged]
    print(f"DART {adapter.version()}, dt = {DT:g}; stepping time per simulated second (ms)")
    adapter_against_bare(adapter, cases, adapter.integrators, bare_loop, dt=DT, repeats=REPEATS,
                         bare_label="bare")


if __name__ == "__main__":
    main()
