"""Benchmark of the Simbody adapter's stepping against a bare OpenSim ``Manager`` loop.

    python -m benchmarks.simbody

Per case of the default matrix that Simbody runs (horizon cut to ``HORIZON``: OpenSim costs 10-100 us a step), at
dt = 1e-3 for the fixed-step integrators and at accuracy 1e-9 for the error-controlled ones: the adapter's
stepping time per simulated second (``Outcome.wall_s``: a ``Manager.integrate`` to every sample time, the state
copied out at each, the last call's summary captured for Simbody's statistics) and a bare ``Manager`` on the same
prepared model from the same initial state integrating to the horizon in one call, in the same process, each the
median of 5 runs after a warm-up. Goal: ratio <= 1.2, so that what the reports call Simbody's cost is Simbody's.
An error-controlled integrator may also take more steps in the adapter: each sample time ends a step.
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks.bare import adapter_against_bare
from dalembert import Settings
from dalembert.adapters import get_adapter
from dalembert.case import in_default_matrix, load_cases

REPEATS = 5
DT = 1e-3
RTOL = 1e-9
HORIZON = 2.0  # s


def bare_manager(prepared):
    """One ``Manager.integrate`` to the last sample time from the prepared initial state; its wall time, s."""
    from dalembert.adapters.simbody.stepping import manager

    osim = prepared.model.osim
    state = osim.State(prepared.model.state0)
    state.setTime(float(prepared.times[0]))
    mgr = manager(prepared)
    mgr.initialize(state)
    t0 = time.perf_counter()
    mgr.integrate(float(prepared.times[-1]))
    return time.perf_counter() - t0


def main():
    adapter = get_adapter("simbody")
    cases = [f(t_final=min(HORIZON, f.params["t_final"])) for _, f in load_cases().items() if in_default_matrix(f)]
    cases = [c for c in cases if adapter.unsupported(c.scene, Settings("verlet", dt=DT)) is None]
    fixed = [name for name, spec in adapter.integrators.items() if spec.fixed_step]
    adaptive = [name for name, spec in adapter.integrators.items() if not spec.fixed_step]
    print(f"Simbody (OpenSim {adapter.version()}), dt = {DT:g}; stepping time per simulated second (ms)")
    ratios = adapter_against_bare(adapter, cases, fixed, bare_manager, dt=DT, repeats=REPEATS, bare_label="manager")
    print(f"\nerror-controlled at rtol = {RTOL:g}; stepping time per simulated second (ms)")
    print(f"{'case':<24}{'integrator':<16}{'adapter':>10}{'manager':>10}{'ratio':>8}")
    for case in cases:
        for integ in adaptive:
            prepared = adapter.prepare(case.scene, case.times, Settings(integ, rtol=RTOL, atol=RTOL))
            adapter.run(prepared)
            bare_manager(prepared)
            ours = np.median([adapter.run(prepared).wall_s for _ in range(REPEATS)])
            theirs = np.median([bare_manager(prepared) for _ in range(REPEATS)])
            ratios.append(ours / theirs)
            print(f"{case.name:<24}{integ:<16}{1e3 * ours / case.t_final:>10.2f}{1e3 * theirs / case.t_final:>10.2f}"
                  f"{ours / theirs:>8.2f}", flush=True)
    print(f"overhead ratio, all: median {np.median(ratios):.2f}, max {np.max(ratios):.2f} (goal <= 1.2)")


if __name__ == "__main__":
    main()
