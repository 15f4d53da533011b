"""How stepping cost grows with the number of bodies, in every engine, and what real robots cost beside the chain.

    python -m benchmarks.scaling [--sizes 2,4,8,16,32,64] [--budget 0.2] [--engine NAME ...] [--robots ur5,panda,...]

The ``chain`` case (N uniform rods in a revolute chain under gravity, released
from rest at its default angles) is stepped by each installed engine's fourth-order fixed-step integrator at
dt = 1e-3 (the reference solver: Kane's equations with RK4; MuJoCo RK4;
Pinocchio's Lie-group RK4, compiled; Exudyn RK44 on its kinematic tree; Drake's
RK5 at a fixed step, its only fixed-step method of order four or more; MJX RK4
in float32, compiled once per N in ``prepare``, never timed; DART, PyBullet and Simbody have no fixed-step
method of order four: DART's and PyBullet's semi-implicit Euler, Simbody's Verlet). For
each N the horizon grows tenfold from 0.01 s until one run takes at least
``--budget`` seconds (or 10 s of simulated time is reached), so every figure is
a stepping time well above the timer's resolution; the cost is printed as
stepping seconds per simulated second, the median of ``REPEATS`` runs after a
warm-up. Then, per engine, the exponent p of cost ~ N^p fitted by least squares
on log-log axes, over all N and over N >= 8 (where fixed per-step costs no longer
dominate). Recursive O(N) algorithms (ABA in Pinocchio and MuJoCo's ``mj_step``
up to its dense factorization) should show p near 1 at small N; a generalized-
coordinate mass-matrix method p near 2 to 3.

Real robots beside the chain (``ROBOTS``, from example-robot-data: ``pip install dalembert[robots]``): the
robot cases at the same step and integrators, their cost against their degrees of freedom (UR5 6 and Panda 7
on ``robot_arm``, Solo12's 18 in ``robot_free_fall``, Talos's 32 in ``robot_tree``), each beside the chain's
cost at as many joints (its log-log line between the sizes run, where they bracket it): a ratio near 1 says
the engine's cost is its number of joints; a branched tree (Talos, Solo) or a floating base may cost otherwise.
A robot an engine refuses (``unsupported``) is marked with its reason.

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
INTEGRATORS = {"reference": "rk4", "mujoco": "rk4", "pinocchio": "rk4", "exudyn": "rk44", "drake": "rk5", "mjx": "rk4",
               "dart": "euler", "pybullet": "euler", "simbody": "verlet"}
# Real robots: (label, case, parameters); their degrees of freedom are read from each case's scene.
ROBOTS = (("ur5", "robot_arm", {"model": "ur5"}), ("panda", "robot_arm", {"model": "panda"}),
          ("solo12", "robot_free_fall", {}), ("talos", "robot_tree", {}))
# Where an engine's default refuses a robot's welds, the integrator and options that run them (its cell is starred):
# Exudyn's kinematic tree has single-axis joints only; its redundant coordinates take welds, as an index-3 DAE
# that only its implicit integrators solve.
ROBOT_FALLBACK = {"exudyn": ("generalized-alpha", {"joints": "redundant"})}
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


def cost(adapter, n, budget, case_name="chain", integrator=None, options=None, **params):
    """Stepping seconds per simulated second of the ``n``-rod chain (median of ``REPEATS``), or of case ``case_name``
    with ``params`` (``n`` unused), with ``integrator`` (default ``INTEGRATORS``'s) and engine ``options``."""
    settings = Settings(integrator or INTEGRATORS[adapter.name], dt=DT, options=options or {})
    horizon = 0.01
    if case_name == "chain":
        params = dict(params, n=n)
    while True:
        case = make_case(case_name, t_final=horizon, sample_interval=horizon, **params)
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


def robot_dofs(robots):
    """Degrees of freedom of each robot of ``robots`` (``ROBOTS`` rows): ``{label: int}``."""
    return {label: sum(len(j.v0) for j in make_case(name, **params).scene.joints) for label, name, params in robots}


def robot_row(name, robots, budget):
    """Engine ``name``'s cost of each robot: ``{label: (cost s/s or NaN, the refusal, or "*" where it ran with
    ``ROBOT_FALLBACK``, or "")}``."""
    adapter, out = get_adapter(name), {}
    for label, case_name, params in robots:
        case = make_case(case_name, **params)
        integrator, options = INTEGRATORS[name], {}
        why = adapter.unsupported(case.scene, Settings(integrator, dt=DT))
        if why and name in ROBOT_FALLBACK:
            integrator, options = ROBOT_FALLBACK[name]
            why = adapter.unsupported(case.scene, Settings(integrator, dt=DT, options=options))
        if why:
            out[label] = (float("nan"), why)
            continue
        try:
            out[label] = (cost(adapter, 0, budget, case_name, integrator, options, **params), "*" if options else "")
        except RuntimeError as e:  # the engine stopped (its solver failed): a finding, in the row's note
            out[label] = (float("nan"), f"{integrator} {options or ''} stopped: {e}")
    return out


def at_size(sizes, costs, n):
    """The chain's cost at ``n`` joints on its log-log line between the sizes run that bracket it, or NaN."""
    pts = [(s, c) for s, c in zip(sizes, costs) if np.isfinite(c)]
    for (a, ca), (b, cb) in zip(pts, pts[1:]):
        if a <= n <= b:
            return float(np.exp(np.interp(np.log(n), [np.log(a), np.log(b)], [np.log(ca), np.log(cb)])))
    return float("nan")


def robot_line(label, robots, found, chain_sizes, chain_costs, dofs):
    """Two printed lines: the robots' costs, and each against the chain's at as many joints."""
    cells, ratios = "", ""
    for r, _, _ in robots:
        c, why = found[r]
        cells += (f"{c:>13.3g}" + (why or " ")) if np.isfinite(c) else \
            f"{'stopped' if ' stopped: ' in why else 'refused':>14}"
        ratio = c / at_size(chain_sizes, chain_costs, dofs[r]) if np.isfinite(c) else float("nan")
        ratios += f"{ratio:>14.2f}" if np.isfinite(ratio) else f"{'-':>14}"
    refusals = "; ".join(f"{r}: {found[r][1]}" for r, _, _ in robots if found[r][1] and found[r][1] != "*")
    return f"{label:<13}{cells}\n{'  / chain':<13}{ratios}" + (f"\n  ({refusals})" if refusals else "")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sizes", default=",".join(map(str, SIZES)), help="numbers of bodies, comma-separated")
    p.add_argument("--budget", type=float, default=0.2, help="least stepping time of one timed run (s)")
    p.add_argument("--engine", action="append", help="engines (default: every installed one)")
    p.add_argument("--robots", default=",".join(r[0] for r in ROBOTS),
                   help="real robots beside the chain, comma-separated (of ur5, panda, solo12, talos; '' for none)")
    p.add_argument("--row-only", metavar="LABEL", help=argparse.SUPPRESS)  # one engine's lines (the MJX re-run)
    args = p.parse_args(argv)
    sizes = [int(x) for x in args.sizes.split(",")]
    robots = [r for r in ROBOTS if r[0] in args.robots.split(",")]
    unknown = sorted(set(filter(None, args.robots.split(","))) - {r[0] for r in ROBOTS})
    if unknown:
        p.error(f"--robots: unknown {unknown} — use some of {', '.join(r[0] for r in ROBOTS)}")
    if args.row_only:
        (name,) = args.engine
        found = row(name, sizes, args.budget)
        print(line(args.row_only, *found))
        if robots:
            print(robot_line(args.row_only, robots, robot_row(name, robots, args.budget), sizes, found[0],
                             robot_dofs(robots)))
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
    chains = {}
    for name in engines:
        chains[name] = row(name, sizes, args.budget)
        print(line(name, *chains[name]), flush=True)
        if name == "mjx":  # again in a fresh process, XLA's fusion emitters off
            env = {**os.environ, "XLA_FLAGS": f"{os.environ.get('XLA_FLAGS', '')} {MJX_XLA_FLAGS}".strip()}
            out = subprocess.run([sys.executable, "-m", "benchmarks.scaling", "--engine", "mjx", "--sizes", args.sizes,
                                  "--budget", str(args.budget), "--row-only", "mjx, no fus.", "--robots", args.robots],
                                 env=env, capture_output=True, text=True, check=True)
            mjx_lines = out.stdout.strip().splitlines()
            print(mjx_lines[0 if robots else -1])
    if "mjx" in engines:
        print(f"mjx, no fus.: MJX in a fresh process with XLA_FLAGS={MJX_XLA_FLAGS}")
    if not robots:
        return
    dofs = robot_dofs(robots)
    print(f"\nreal robots: stepping seconds per simulated second at dt = {DT:g} s, the same integrators; "
          "'/ chain': against the chain's cost at as many joints (its line between the sizes run; '-' outside them); "
          "*: " + ", ".join(f"{k} {i} with {o}" for k, (i, o) in ROBOT_FALLBACK.items())
          + " (ROBOT_FALLBACK: the default refuses the robot's welds)")
    print(f"{'engine':<13}" + "".join(f"{f'{r} ({dofs[r]})':>14}" for r, _, _ in robots))
    for name in engines:
        if name == "mjx":
            print(robot_line("mjx", robots, robot_row(name, robots, args.budget), sizes, chains[name][0], dofs))
            print("\n".join(mjx_lines[1:]))
            continue
        print(robot_line(name, robots, robot_row(name, robots, args.budget), sizes, chains[name][0], dofs), flush=True)


if __name__ == "__main__":
    main()
