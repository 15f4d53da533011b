"""Throughput of an engine's batches of worlds against its batch size, through the adapter; and a stability map
made batched against the same map probe by probe.

    python -m benchmarks.batches mujoco_warp        # or mjx; --sizes 1,8,64,256 --seconds 0.1
    python -m benchmarks.batches mujoco_warp --map "inertia=1,2,3;1,2.5,3"   # a swept parameter's map, both ways

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

``--map`` over a model parameter (MuJoCo Warp holds the fields it changes per world): ``python -m
benchmarks.batches mujoco_warp --map "inertia=1,2.2,3;1,2.6,3;1,2.9,3;1,3.1,3;1,3.4,3;1,3.8,3"`` (the
intermediate moment swept past the largest: the spin about body y goes from the unstable middle axis to the
largest) took 29 probes either way, the same keys, statuses and boundaries: 154 s batched (engine calls of 1 to
6 worlds, each world's ``body_inertia``, ``body_iquat``, ``body_invweight0`` and ``dof_invweight0`` its own)
against 458 s probe by probe, on 2 cores shared at a load of ~16-18.
"""

from __future__ import annotations

import argparse
import os
import tempfile
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


# The map ``--map`` makes: free_top_fast_spin over 1 s sampled every 0.1 s, RK4, its stable and finite step searched
# from 1e-3 to 1e-1 s to within a factor 1.5 (the map of ``dalembert.harness.batches``' measurement, over another
# parameter).
MAP = ["--case", "free_top_fast_spin", "--param", "t_final=1", "--param", "sample_interval=0.1", "--integrator",
       "rk4", "--search", "dt", "--dt", "1e-3,1e-1", "--resolution", "1.5", "--quick", "--jobs", "1"]


def batched_map(engine, sweep, out=None):
    """Make the map ``MAP`` over ``--param sweep`` (e.g. ``inertia=1,2,3;1,2.5,3``) on ``engine`` batched
    (``--batch``), then probe by probe, each into a store of its own under ``out`` (a temporary folder if None);
    print and return ``(batched s, probe by probe s, engine calls batched, probes)``. Raises AssertionError where
    the two maps' probes (keys), statuses or boundaries differ."""
    from dalembert.boundary import boundaries
    from dalembert.harness.cli import main
    from dalembert.store import Store

    out = out or tempfile.mkdtemp(prefix="batched_map_")
    walls, stores = {}, {}
    for name, extra in (("batched", ["--batch"]), ("probe by probe", [])):
        path = os.path.join(out, name.replace(" ", "_"))
        t0 = time.perf_counter()
        assert main(["run", *MAP, "--param", sweep, "--engine", engine, *extra, "--out", path]) == 0, name
        walls[name] = time.perf_counter() - t0
        stores[name] = Store(path).records()
        print(f"{name}: {walls[name]:.0f} s, {len(stores[name])} probes, 1-min load {os.getloadavg()[0]:.1f}",
              flush=True)
    one, batch = stores["probe by probe"], stores["batched"]
    assert sorted((r.key, r.status) for r in one) == sorted((r.key, r.status) for r in batch), "probes differ"
    assert [(b.stable, b.finite) for b in boundaries(one)] == [(b.stable, b.finite) for b in boundaries(batch)]
    calls = len({(r.settings.dt, r.cost.batch_wall_s) for r in batch})  # one batch: one step, one wall time
    print(f"the same {len(one)} probes, statuses and boundaries; {calls} engine calls batched "
          f"(largest {max(r.cost.batch_size for r in batch)} worlds); stores under {out}")
    for b in boundaries(batch):
        print(f"  {dict(b.params)}: stable {b.stable}, finite {b.finite}")
    return walls["batched"], walls["probe by probe"], calls, len(one)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("engine", choices=["mujoco_warp", "mjx"])
    p.add_argument("--sizes", default=",".join(map(str, SIZES)), help="batch sizes, comma-separated")
    p.add_argument("--seconds", type=float, default=SECONDS, help="model time per batch, s")
    p.add_argument("--map", metavar="KEY=VALUES", help="instead: the map over this --param sweep, batched and probe "
                   "by probe (batched_map)")
    p.add_argument("--out", help="with --map: where the two stores go (default: a temporary folder)")
    args = p.parse_args(argv)
    if args.map:
        batched_map(args.engine, args.map, args.out)
        return
    throughput(args.engine, tuple(int(x) for x in args.sizes.split(",")), args.seconds)


if __name__ == "__main__":
    main()
