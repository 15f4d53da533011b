"""How stepping cost grows with the number of bodies, in every engine.

    python -m benchmarks.scaling [--sizes 2,4,8,16,32,64] [--budget 0.2] [--engine NAME ...]

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

MJX on XLA's CPU backend grows exponentially with the chain's depth (measured,
MJX 3.17 / JAX 0.10, a plain MJCF hinge chain: 1.4, 9.7 and 232 ms per Euler
step at 6, 7 and 8 bodies; ``smooth.kinematics`` alone 0.94 s at 8, every other
stage of the step ~1 ms). With XLA's CPU fusion emitters off
(``XLA_FLAGS=--xla_cpu_use_fusion_emitters=false``) the same step takes 0.12,
0.32 and 0.41 ms at 6, 8 and 16 bodies and kinematics 1.1 ms at 8, so the code
those emitters generate for MJX's body-by-body pose recursion is the cause (a
fused kernel that recomputes its producers, we suppose; the HLO was not read). So an engine whose cost passes
``MAX_COST`` at some N is not run at larger N (its row says where it stopped: a
blow-up of cost is a finding), and MJX is measured twice: as installed, and in
a fresh process with the fusion emitters off (XLA reads its flags once, when
JAX starts).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

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
# Stepping seconds per simulated second beyond which larger N are not run: 100 s/s is 0.1 s per step at DT, 10x
# the reference solver's Python Kane at N = 64; MJX as installed passes it at N = 8 (~230 s/s) and would take hours
# at N = 16.
MAX_COST = 100.0
# The largest N an engine is built for: MJX's XLA compilation of the chain (RK4, float32, fusion emitters off) took
# 11 s and 2.2 GB at N = 16, 42 s and 7.6 GB at N = 32 (measured: N^1.8 in memory), so N = 64 would need ~27 GB,
# more than these machines have (23 GB).
MAX_SIZE = {"mjx": 32}
# XLA's CPU fusion emitters off: MJX's kinematics no longer exponential in the depth (module docstring).
MJX_XLA_FLAGS = "--xla_cpu_use_fusion_emitters=false"


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


def row(name, sizes, budget):
    """The costs of engine ``name`` at ``sizes`` (NaN past the first beyond ``MAX_COST`` and past ``MAX_SIZE``) and
    the fitted exponents."""
    adapter, costs = get_adapter(name), []
    for n in sizes:
        run = (not costs or costs[-1] <= MAX_COST) and n <= MAX_SIZE.get(name, n)
        costs.append(cost(adapter, n, budget) if run else float("nan"))
    fit = [(n, c) for n, c in zip(sizes, costs) if np.isfinite(c)]
    big = [(n, c) for n, c in fit if n >= ASYMPTOTIC_FROM]
    p_all = exponent(*zip(*fit)) if len(fit) >= 2 else float("nan")
    p_big = exponent(*zip(*big)) if len(big) >= 2 else float("nan")
    return costs, p_all, p_big


def line(label, costs, p_all, p_big):
    cells = "".join(f"{c:>11.3g}" if np.isfinite(c) else f"{'not run':>11}" for c in costs)
    return f"{label:<13}" + cells + f"{p_all:>10.2f}{p_big:>10.2f}"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sizes", default=",".join(map(str, SIZES)), help="numbers of bodies, comma-separated")
    p.add_argument("--budget", type=float, default=0.2, help="least stepping time of one timed run (s)")
    p.add_argument("--engine", action="append", help="engines (default: every installed one)")
    p.add_argument("--row-only", metavar="LABEL", help=argparse.SUPPRESS)  # one engine's line (the MJX re-run)
    args = p.parse_args(argv)
    sizes = [int(x) for x in args.sizes.split(",")]
    if args.row_only:
        (name,) = args.engine
        print(line(args.row_only, *row(name, sizes, args.budget)))
        return
    engines = []
    for name in args.engine or adapter_names():
        if name not in INTEGRATORS:
            continue
        try:
            get_adapter(name).version()
            engines.append(name)
        except ImportError as e:
            print(f"{name}: not installed ({e})")
    print(f"stepping seconds per simulated second, dt = {DT:g} s, the chain case with N rods; "
          f"'not run': the cost passed {MAX_COST:g} s/s at a smaller N, or N is past what the engine can be built for "
          f"here ({', '.join(f'{k} {v}' for k, v in MAX_SIZE.items())}: MAX_SIZE)")
    print(f"{'engine':<13}" + "".join(f"{f'N={n}':>11}" for n in sizes) + f"{'p (all)':>10}{'p (N>=8)':>10}")
    for name in engines:
        print(line(name, *row(name, sizes, args.budget)), flush=True)
        if name == "mjx":  # again in a fresh process, XLA's fusion emitters off
            env = {**os.environ, "XLA_FLAGS": f"{os.environ.get('XLA_FLAGS', '')} {MJX_XLA_FLAGS}".strip()}
            out = subprocess.run([sys.executable, "-m", "benchmarks.scaling", "--engine", "mjx", "--sizes", args.sizes,
                                  "--budget", str(args.budget), "--row-only", "mjx, no fus."],
                                 env=env, capture_output=True, text=True, check=True)
            print(out.stdout.strip().splitlines()[-1])
    if "mjx" in engines:
        print(f"mjx, no fus.: MJX in a fresh process with XLA_FLAGS={MJX_XLA_FLAGS}")


if __name__ == "__main__":
    main()
