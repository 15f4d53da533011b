"""How stepping cost grows with the number of bodies, in every engine.

    python -m benchmarks.scaling [--sizes 2,4,8,16,32,64] [--budget 1.0]

The ``chain`` case (N uniform rods in a revolute chain under gravity, released
from rest at its default angles) is stepped by each installed engine's fourth-order fixed-step integrator at
dt = 1e-3 (the reference solver: Kane's equations with RK4; MuJoCo RK4;
Pinocchio's Lie-group RK4, compiled; Exudyn RK44 on its kinematic tree; Drake's
RK5 at a fixed step, its only fixed-step method of order four or more; MJX RK4
in float32, compiled once per N in ``prepare``, never timed). For
each N the horizon grows tenfold from 0.01 s until one run takes at least
``--budget`` seconds (or 10 s of simulated time is reached), so every figure is
a stepping time well above the timer's resolution; the cost is printed as
stepping seconds per simulated second, the median of ``REPEATS`` runs after a
warm-up. Then, per engine, the exponent p of cost ~ N^p fitted by least squares
on log-log axes, over all N and over N >= 8 (where fixed per-step costs no longer
dominate). Recursive O(N) algorithms (ABA in Pinocchio and MuJoCo's ``mj_step``
up to its dense factorization) should show p near 1 at small N; a generalized-
coordinate mass-matrix method p near 2 to 3.

Timings are taken on whatever else the machine is doing; the exponents are
ratios within one invocation.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from dalembert import Settings
from dalembert.adapters import adapter_names, get_adapter
from dalembert.case import make_case

SIZES = (2, 4, 8, 16, 32, 64)
# each engine's fourth-order fixed-step integrator (Drake has none at a fixed step: its RK5)
INTEGRATORS = {"reference": "rk4", "mujoco": "rk4", "pinocchio": "rk4", "exudyn": "rk44", "drake": "rk5", "mjx": "rk4"}
DT = 1e-3
REPEATS = 3
MAX_HORIZON_S = 10.0
# Fits over the sizes where the per-step fixed costs (calls, Python) no longer dominate.
ASYMPTOTIC_FROM = 8


def cost(adapter, n, budget):
    """Stepping seconds per simulated second of the ``n``-rod chain (median of ``REPEATS``)."""
    settings = Settings(INTEGRATORS[adapter.name], dt=DT)
    horizon = 0.01
    while True:
        case = make_case("chain", n=n, t_final=horizon, sample_interval=horizon)
        prepared = adapter.prepare(case.scene, case.times, settings)
        adapter.run(prepared)  # warm-up
        walls = [adapter.run(prepared).wall_s for _ in range(REPEATS)]
        if np.median(walls) >= budget or horizon >= MAX_HORIZON_S:
            return float(np.median(walls)) / horizon
        horizon = min(10.0 * horizon, MAX_HORIZON_S)


def exponent(sizes, costs):
    """Least-squares slope of log(cost) against log(N)."""
    return float(np.polyfit(np.log(sizes), np.log(costs), 1)[0])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sizes", default=",".join(map(str, SIZES)), help="numbers of bodies, comma-separated")
    p.add_argument("--budget", type=float, default=0.2, help="least stepping time of one timed run (s)")
    args = p.parse_args(argv)
    sizes = [int(x) for x in args.sizes.split(",")]
    engines = []
    for name in adapter_names():
        if name not in INTEGRATORS:
            continue
        try:
            get_adapter(name).version()
            engines.append(name)
        except ImportError as e:
            print(f"{name}: not installed ({e})")
    print(f"stepping seconds per simulated second, dt = {DT:g} s, the chain case with N rods")
    print(f"{'engine':<11}" + "".join(f"{f'N={n}':>11}" for n in sizes) + f"{'p (all)':>10}{'p (N>=8)':>10}")
    for name in engines:
        adapter = get_adapter(name)
        costs = []
        for n in sizes:
            costs.append(cost(adapter, n, args.budget))
        big = [(n, c) for n, c in zip(sizes, costs) if n >= ASYMPTOTIC_FROM]
        p_big = exponent(*zip(*big)) if len(big) >= 2 else float("nan")
        print(f"{name:<11}" + "".join(f"{c:>11.3g}" for c in costs) + f"{exponent(sizes, costs):>10.2f}{p_big:>10.2f}")


if __name__ == "__main__":
    main()
