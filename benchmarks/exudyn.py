"""Benchmark of the Exudyn adapter: stepping cost per solver and the adapter's overhead.

    python -m benchmarks.exudyn

Per case and solver (fixed-step ones at dt = 1e-3, adaptive ones at rtol = atol =
1e-8; default node and joints), in the same process, each the best of 5 runs
after a warm-up, the adapter's and the bare ones interleaved (the best, as
``timeit`` advises, because a shared machine only ever adds time):

* ``solve``: Exudyn's stepping time per simulated second as the adapter measures
  it (``Outcome.wall_s``: ``SolveDynamic`` with sensors stored by Exudyn, or the
  per-sample ``SolveSteps`` loop of the adaptive solvers with its user functions);
* ``bare``: the same solve on a system built the same way, with no sensors
  stored and no user function: ``SolveDynamic``, or for the adaptive solvers the
  same per-sample ``SolveSteps`` loop (they have no dense output, so landing on
  every sample is part of the job, not overhead);
* ``overhead``: everything in ``adapter.run`` but the bare solve (building the
  system, sampling, user functions, read-back), as a fraction of the whole
  ``adapter.run``. Goal: <= 20% for runs over 50 ms, so that the cost the reports
  show is Exudyn's solve, not the adapter's bookkeeping (shorter runs are all
  fixed cost, building the system, and the fraction says nothing of the stepping).
"""

from __future__ import annotations

import time

import numpy as np

from dalembert.adapters import get_adapter
from dalembert.adapters.exudyn.adapter import ADAPTIVE
from dalembert.adapters.exudyn.model import build
from dalembert.adapters.exudyn.sampling import ON_TIME, solve_per_sample
from dalembert import Settings
from dalembert.case import load_cases

REPEATS = 5
LONG_RUN_S = 0.05  # the goal applies to runs longer than this (see the module docstring)
GOAL = 0.20


def bare_solve(adapter, prepared):
    """Seconds of Exudyn's solve alone on a system built as the adapter builds it (no sensors
    stored, no user function): ``SolveDynamic``, or the adapter's per-sample loop."""
    import exudyn as exu

    built = build(prepared.scene, prepared.settings)
    mbs, times = built.mbs, prepared.times
    settings = adapter._settings(prepared)
    console, exu.config.printToConsole = exu.config.printToConsole, False
    try:
        t0 = time.perf_counter()
        if prepared.settings.integrator in ADAPTIVE:
            tol = ON_TIME * settings.timeIntegration.minimumStepSize
            solve_per_sample(exu.MainSolverExplicit(), mbs, settings, times, tol)
        else:
            mbs.SolveDynamic(settings, solverType=settings.timeIntegration.solverType)
        return time.perf_counter() - t0
    finally:
        exu.config.printToConsole = console


def main():
    adapter = get_adapter("exudyn")
    print(f"Exudyn {adapter.version()}; stepping time per simulated second (ms); overhead = share of "
          f"adapter.run that is not Exudyn solving")
    print(f"{'case':<24}{'solver':<20}{'solve':>9}{'bare':>9}{'run':>9}{'overhead':>10}")
    shares = []
    for name, factory in load_cases().items():
        case = factory()
        if "hard" in factory.tags:
            continue
        for integ in adapter.integrators:
            s = Settings(integ, rtol=1e-8, atol=1e-8) if integ in ADAPTIVE else Settings(integ, dt=1e-3)
            if adapter.unsupported(case.scene, s):
                continue
            prepared = adapter.prepare(case.scene, case.times, s)
            adapter.run(prepared)
            runs, solves, bares = [], [], []
            for _ in range(REPEATS):
                t0 = time.perf_counter()
                out = adapter.run(prepared)
                runs.append(time.perf_counter() - t0)
                solves.append(out.wall_s)
                bares.append(bare_solve(adapter, prepared))
            bare, run = min(bares), min(runs)
            share = (run - bare) / run
            if run > LONG_RUN_S:
                shares.append(share)
            per_s = 1e3 / case.t_final
            print(f"{name:<24}{integ:<20}{min(solves) * per_s:>9.2f}{bare * per_s:>9.2f}{run * per_s:>9.2f}"
                  f"{100 * share:>9.1f}%")
    print(f"overhead for runs > {1e3 * LONG_RUN_S:.0f} ms: median {100 * np.median(shares):.1f}%, "
          f"max {100 * np.max(shares):.1f}% (goal <= {100 * GOAL:.0f}%)")


if __name__ == "__main__":
    main()
