"""Benchmark of the Pinocchio adapter's integrators against bare ``pin.aba`` calls.

    python -m benchmarks.pinocchio

Per case and fixed-step integrator at dt = 1e-3 (over 2 s), for the compiled
loop (the default) and the Python one (``--option loop=python``): stepping time
per simulated second, and its ratio to the cost of the ``aba`` calls the method
needs (stages per step x steps x one bare ``pin.aba`` call from Python with the
same arguments, timed in a tight loop in the same process). Best of 3. Goal:
the Lie-group RK4 at most 3x four bare ``aba`` calls per step, i.e. the
``dexp^-1`` solves, ``integrate`` calls and loads of a step cost at most twice
its dynamics, so that the timings compare Pinocchio's dynamics and the methods,
not the loop around them.
"""

from __future__ import annotations

import time

import numpy as np

from dalembert.adapters import get_adapter
from dalembert import Settings
from dalembert.case import load_cases

STAGES = {"euler": 1, "rk4": 4, "rk4-naive": 4}


def bare_aba_seconds(pm, q, v, n=20000):
    import pinocchio as pin

    fext = pm.external_forces(q, v) if pm.has_forces else None
    args = (pm.model, pm.data, q, v, pm.tau) + ((fext,) if fext is not None else ())
    pin.aba(*args)
    t0 = time.perf_counter()
    for _ in range(n):
        pin.aba(*args)
    return (time.perf_counter() - t0) / n


def main():
    adapter = get_adapter("pinocchio")
    print(f"Pinocchio {adapter.version()}, dt = 1e-3, 2 s horizon")
    print(f"{'case':<24}{'integrator':<12}{'ms/sim s':>10}{'python':>9}{'aba us':>9}{'ratio':>8}{'python':>8}")
    rk4_ratios = []
    for name, factory in load_cases().items():
        case = factory(t_final=2.0)
        for integ, stages in STAGES.items():
            walls = {}
            for loop in ("native", "python"):
                prepared = adapter.prepare(case.scene, case.times, Settings(integ, dt=1e-3, options={"loop": loop}))
                adapter.run(prepared)
                walls[loop] = min(adapter.run(prepared).wall_s for _ in range(3))
            wall = walls["native"]
            aba = bare_aba_seconds(prepared.pm, prepared.q0, prepared.v0)
            n_steps = int(prepared.steps.sum())
            print(f"{name:<24}{integ:<12}{1e3 * wall / case.t_final:>10.2f}{1e3 * walls['python'] / case.t_final:>9.2f}"
                  f"{1e6 * aba:>9.2f}{wall / (stages * n_steps * aba):>8.2f}"
                  f"{walls['python'] / (stages * n_steps * aba):>8.2f}")
            if integ == "rk4":
                rk4_ratios.append(wall / (stages * n_steps * aba))
    print(f"rk4 (Lie group) per step / four bare aba calls: median {np.median(rk4_ratios):.2f}, "
          f"max {np.max(rk4_ratios):.2f} (goal <= 3)")


if __name__ == "__main__":
    main()
