"""Drake: the adapter's stepping against a bare Simulator, and its world-frame angular velocity on
the intermediate-axis top side by side with the engines that carry it in body axes.

    python -m benchmarks.drake            # both parts
    python -m benchmarks.drake overhead   # part 1 only
    python -m benchmarks.drake tumble     # part 2 only

1. Per canonical case and a few integrators at dt = 1e-3: the adapter's stepping time per
   simulated second (``Outcome.wall_s``: ``AdvanceTo`` each sample time and a state copy) and a
   bare ``Simulator.AdvanceTo(t_final)`` of the same diagram from the same state, each the median
   of 3 runs after a warm-up. Goal: ratio <= 1.2.
2. ``free_top_intermediate`` (20 s, 1e-3 rad/s off the intermediate axis): Drake's quaternion
   floating joint integrates ``w_WB_W`` (world axes) where MuJoCo and Pinocchio integrate
   ``w_WB_B``. Per engine, integrator and dt: the largest attitude error (rad), angular velocity
   error in world axes and in body axes (rad/s; body axes through each engine's own attitude),
   the drift of |L| and of the energy (relative), and the first time the attitude leaves the case's
   tolerance — against the case's double-precision floor.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from dalembert import Settings, make_case, spatial
from dalembert.adapters import get_adapter
from dalembert.case import load_cases
from dalembert.errors import trajectory_errors

REPEATS = 3
OVERHEAD_INTEGRATORS = ("rk3", "rk5", "implicit-euler", "discrete")
TUMBLE = [("drake", "rk3"), ("drake", "rk5"), ("drake", "bs3"), ("mujoco", "rk4"), ("pinocchio", "rk4"),
          ("reference", "rkmk4")]
TUMBLE_DTS = (1e-2, 1e-3, 1e-4)


def bare(prepared):
    from dalembert.adapters.drake.stepping import reset

    simulator, _ = reset(prepared)
    t0 = time.perf_counter()
    simulator.AdvanceTo(float(prepared["times"][-1]))
    return time.perf_counter() - t0


def overhead():
    adapter = get_adapter("drake")
    print(f"Drake {adapter.version()}, dt = 1e-3; stepping time per simulated second (ms)")
    print(f"{'case':<24}{'integrator':<16}{'adapter':>10}{'bare':>10}{'ratio':>8}")
    ratios = []
    for name, factory in load_cases().items():
        if "canonical" not in factory.tags:
            continue
        case = factory()
        for integ in OVERHEAD_INTEGRATORS:
            prepared = adapter.prepare(case.scene, case.times, Settings(integ, dt=1e-3))
            adapter.run(prepared)
            ours = np.median([adapter.run(prepared).wall_s for _ in range(REPEATS)])
            theirs = np.median([bare(prepared) for _ in range(REPEATS)])
            ratios.append(ours / theirs)
            print(f"{name:<24}{integ:<16}{1e3 * ours / case.t_final:>10.2f}{1e3 * theirs / case.t_final:>10.2f}"
                  f"{ours / theirs:>8.2f}")
    print(f"overhead ratio: median {np.median(ratios):.2f}, max {np.max(ratios):.2f} (goal <= 1.2)")


def tumble():
    from dalembert import invariants

    case = make_case("free_top_intermediate")
    exact = case.exact(case.times)
    tol = case.tolerances["orientation"].value
    q_exact = exact.bodies["top"].quaternion
    w_exact_W = exact.bodies["top"].angular_velocity
    w_exact_B = spatial.world_to_body(q_exact, w_exact_W)
    print(f"free_top_intermediate, 20 s; floor {case.floor().get('orientation', float('nan')):.1e} rad, "
          f"tolerance {tol:g} rad")
    print(f"{'engine':<10}{'integrator':<12}{'dt':>8}{'attitude':>11}{'w world':>10}{'w body':>10}{'|L| drift':>11}"
          f"{'E drift':>10}{'leaves tol':>11}")
    for engine, integ in TUMBLE:
        adapter = get_adapter(engine)
        for dt in TUMBLE_DTS:
            traj = adapter.run(adapter.prepare(case.scene, case.times, Settings(integ, dt=dt))).trajectory
            e = trajectory_errors(traj, exact)
            b = traj.bodies["top"]
            w_B = spatial.world_to_body(b.quaternion, b.angular_velocity)
            drifts = invariants.summary(case.scene, traj, case.conserved).drifts
            angle = spatial.rotation_angle(b.quaternion, q_exact)
            out = np.flatnonzero(~(angle <= tol))
            leaves = f"{traj.t[out[0]]:.2f} s" if len(out) else "never"
            print(f"{engine:<10}{integ:<12}{dt:>8g}{e['orientation'][0]:>11.2e}{e['angular_velocity'][0]:>10.2e}"
                  f"{np.nanmax(np.abs(w_B - w_exact_B)):>10.2e}{drifts.get('angular_momentum', np.nan):>11.2e}"
                  f"{drifts.get('energy', np.nan):>10.2e}{leaves:>11}", flush=True)


def main(argv):
    parts = argv or ["overhead", "tumble"]
    if "overhead" in parts:
        overhead()
    if "tumble" in parts:
        tumble()


if __name__ == "__main__":
    main(sys.argv[1:])
