"""CPU of the reference's closed-loop formulation (``reference.loops.ClosedLoops``) on every registered case with
loops: per truth (``dalembert.reference.truth``: the integration, the read-back and the self-stresses), per
right-hand side (``acceleration`` at the case's own states moved 1e-10 off the manifolds, a step's drift: one
Gauss-Newton iteration each, as in a run), and the share of that right-hand side that is the formulation's own
(the same calls with the tree's ``positions`` and ``velocities`` memoized, so that only the projection, the rows,
the metric and the solve are timed).

    python -m benchmarks.reference_loops [--repeats 3]

Process CPU time (``time.process_time``: another process's load does not count), the least of ``--repeats``.
Measured on 2 shared cores (load average 6.7) against the code before the formulation's rows were written in
floats and assembled as one G (40b4c4a's modules imported under other names, old and new alternating in one
process, least of 5; CPU s per truth, old -> new): andrews_squeezer 5.16 -> 4.17, bricard 2.23 -> 1.86,
four_bar 0.016 -> 0.013, n_four_bar 0.056 -> 0.049 (all four 7.46 -> 6.09, 1.23x); per right-hand side
1.18-1.43x; its own share 1.66-2.08x (andrews_squeezer 627 -> 378 us). The rest of a right-hand side was the
tree's ``Kane.kinematics``: three full passes (the state, the projected configuration, the projected state).
Split into ``positions`` and ``velocities`` (the projection's passes on the configuration only, the solve's
velocities at the projection's last positions; results unchanged to the last bit), against 80c169b's modules (a copy
on ``PYTHONPATH``, old and new processes alternating, two rounds, least of 3 each; load average ~5; old -> new):
per right-hand side andrews_squeezer 462 -> 358 us (1.29x), bricard 331 -> 269 (1.23x), four_bar 282 -> 238
(1.18x), n_four_bar 366 -> 312 (1.17x); per truth andrews_squeezer 1.72 -> 1.45 s (1.19x), bricard 0.78 -> 0.64 s
(1.21x), all four 2.54 -> 2.13 s (1.19x; four_bar's and n_four_bar's truths are closed forms).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from dalembert.case import load_cases
from dalembert.reference import configuration as cfg, truth
from dalembert.reference.loops import ClosedLoops

# The states' distance from the manifolds (rad or m): a step's drift on a truth run (its tolerances ~1e-12 over a
# step), so that each right-hand side projects by one Gauss-Newton iteration, as the truth's do.
DRIFT = 1e-10
STATES = 8  # per case, along its truth
CALLS = 40  # right-hand sides per state per repeat


def _cpu(f):
    start = time.process_time()
    f()
    return time.process_time() - start


def _memoized(system):
    """``system`` with its tree kinematics memoized by state: ``positions`` by ``q``, ``velocities`` by the positions
    and ``u`` (each call gets its own body entries: the solve writes into them)."""
    memo, positions, velocities = {}, system.positions, system.velocities

    def cached_positions(q):
        key = q.tobytes()
        if key not in memo:
            memo[key] = positions(q)
        return memo[key]

    def cached_velocities(pos, u):
        key = (id(pos), u.tobytes())
        if key not in memo:
            memo[key] = velocities(pos, u)
        return {body: dict(entry) for body, entry in memo[key].items()}

    system.positions, system.velocities = cached_positions, cached_velocities
    return system


def measure(case, repeats):
    """CPU s per truth, per right-hand side, and per right-hand side with ``Kane.kinematics`` memoized."""
    truth_s = min(_cpu(lambda: truth(case)) for _ in range(repeats))
    traj = truth(case)
    system = ClosedLoops(case.scene)
    Q = np.concatenate([traj.joints[jd["joint"].child].q for jd in system.joints], axis=1)
    V = np.concatenate([traj.joints[jd["joint"].child].v for jd in system.joints], axis=1)
    rng = np.random.default_rng(0)
    states = [(cfg.retract(system.blocks, Q[i], DRIFT * rng.standard_normal(system.nv)),
               V[i] + DRIFT * rng.standard_normal(system.nv)) for i in np.linspace(0, len(Q) - 1, STATES).astype(int)]
    calls = lambda s: [s.acceleration(0.0, q, v) for _ in range(CALLS) for q, v in states]  # noqa: E731
    rhs_s = min(_cpu(lambda: calls(system)) for _ in range(repeats)) / (CALLS * STATES)
    own = _memoized(ClosedLoops(case.scene))
    calls(own)  # (fills the memo)
    own_s = min(_cpu(lambda: calls(own)) for _ in range(repeats)) / (CALLS * STATES)
    return truth_s, rhs_s, own_s


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    cases = load_cases()
    names = [name for name in sorted(cases) if cases[name]().scene.loops]
    print(f"{'case':<20}{'truth CPU s':>12}{'RHS CPU us':>12}{'own us':>10}")
    total = 0.0
    for name in names:
        truth_s, rhs_s, own_s = measure(cases[name](), args.repeats)
        total += truth_s
        print(f"{name:<20}{truth_s:>12.3f}{1e6 * rhs_s:>12.1f}{1e6 * own_s:>10.1f}", flush=True)
    print(f"{'all truths':<20}{total:>12.3f}")


if __name__ == "__main__":
    main()
