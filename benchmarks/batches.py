"""Throughput of an engine's batches of worlds against its batch size, through the adapter.

    python -m benchmarks.batches mujoco_warp        # or mjx; --sizes 1,8,64,256 --seconds 0.1

``free_top_fast_spin`` at N spins from 5 to 500 rad/s (log-spaced: one model, N initial states), RK4 at
dt = 1e-3 over ``--seconds`` of model time sampled every 0.01 s: the adapter's ``prepare_batch`` (build,
once per size: kernels or JIT compilation) and ``run_batch`` (the median of 3 after a warm-up: every
world stepped, every sample copied to the host), against the adapter's ``run`` of one world. Printed per
size: the batch's wall time per step, its share per world, and world-steps per second. The engines here
launch their work from Python per step (MuJoCo Warp) or per sample interval (MJX), so on the CPU a
batch costs about one world's launches plus every world's arithmetic. Measured on 2 shared cores at a
load of ~2: MuJoCo Warp 4.85 ms a step for one world, 5.2 / 5.8 / 5.4 / 8.0 ms a batch step at 1 / 8 /
64 / 256 worlds (155x one world's throughput at 256); MJX 0.03 ms for one world, its batches 1.0 / 1.9 /
5.3 / 4.4x one world's throughput (arithmetic-bound on the CPU).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from dalembert import Settings, make_case
from dalembert.adapters import get_adapter

REPEATS = 3
DT = 1e-3
SIZES = (1, 8, 64, 256)
SECONDS = 0.1  # model time per batch: 100 steps of RK4 (MuJoCo Warp: ~1.5-5 ms a step on 2 busy cores)
SPINS = (5.0, 500.0)  # rad/s, the ends of the spins swept across a batch (the stability map's, cases/free_top.py)


def throughput(engine, sizes=SIZES, seconds=SECONDS, integrator="rk4"):
    """Print and return ``[(size, build s, batch wall s per step, world-steps per s)]`` for ``engine``'s batches,
    after one world's ``run`` (size 0 in the list: the adapter's single-world latency per step)."""
    adapter = get_adapter(engine)
    settings = Settings(integrator, dt=DT)
    one = make_case("free_top_fast_spin", spin=SPINS[0], t_final=seconds, sample_interval=0.01)
    p = adapter.prepare(one.scene, one.times, settings)
    adapter.run(p)
    single = float(np.median([adapter.run(p).wall_s for _ in range(REPEATS)])) / int(p.steps.sum())
    print(f"{engine} {adapter.version()}, free_top_fast_spin {integrator} dt = {DT:g}, {seconds:g} s per batch")
    print(f"one world's run: {single * 1e3:.2f} ms/step = {1 / single:.0f} steps/s")
    print(f"{'worlds':>8}{'build s':>9}{'ms/step':>10}{'ms/world-step':>15}{'world-steps/s':>15}{'x one':>7}",
          flush=True)
    out = [(0, float("nan"), single, 1 / single)]
    for n in sizes:
        cases = [make_case("free_top_fast_spin", spin=float(s), t_final=seconds, sample_interval=0.01)
                 for s in np.geomspace(*SPINS, n)]
        t0 = time.perf_counter()
        b = adapter.prepare_batch([c.scene for c in cases], cases[0].times, settings)
        build = time.perf_counter() - t0
        adapter.run_batch(b)
        wall = float(np.median([adapter.run_batch(b).wall_s for _ in range(REPEATS)]))
        steps = int(b.worlds[0].steps.sum())
        rate = n * steps / wall
        print(f"{n:>8}{build:>9.1f}{wall / steps * 1e3:>10.2f}{wall / steps / n * 1e3:>15.3f}{rate:>15.0f}"
              f"{rate * single:>7.1f}", flush=True)
        out.append((n, build, wall / steps, rate))
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("engine", choices=["mujoco_warp", "mjx"])
    p.add_argument("--sizes", default=",".join(map(str, SIZES)), help="batch sizes, comma-separated")
    p.add_argument("--seconds", type=float, default=SECONDS, help="model time per batch, s")
    args = p.parse_args(argv)
    throughput(args.engine, tuple(int(x) for x in args.sizes.split(",")), args.seconds)


if __name__ == "__main__":
    main()
