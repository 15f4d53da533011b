"""Drake: the adapter's stepping against a bare Simulator, and its world-frame angular velocity on
the intermediate-axis top side by side with the engines that carry it in body axes.

    python -m benchmarks.drake            # both parts
    python -m benchmarks.drake overhead   # part 1 only
    python -m benchmarks.drake tumble     # part 2 only
    python -m benchmarks.drake state      # part 3 only
    python -m benchmarks.drake loops      # part 4 only (not in the default run)

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
3. The state alone, without any engine: one Runge-Kutta tableau (Kutta's third order, Drake's
   ``runge_kutta3``) on the same top twice, once with the angular velocity in body axes (Euler's
   equations, ``q' = q (0, w_B) / 2``) and once in world axes as Drake carries it
   (``w_W' = I_W^-1 (-w_W x I_W w_W)``, ``I_W = R I_B R^T``, ``q' = (0, w_W) q / 2``): the attitude
   error at each dt, so the representation's share is seen apart from the method's order.
4. The parallelogram four-bar (``dalembert.cases.four_bar``, 0.5 s, its loop closed by two SAP
   ball constraints) with the ``discrete`` integrator: per dt, the crank's and the rocker's
   largest angle error against the closed form (rad), the worst loop residual at position (m)
   and velocity (m/s) level (``invariants.loop_residual``), the loop's reaction error (relative to
   the largest true reaction; all samples, and beyond 20 ms of the flat singular position), the
   steps and the stepping time (median of 3, s).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from benchmarks.bare import adapter_against_bare
from dalembert import Settings, make_case, spatial
from dalembert.adapters import get_adapter
from dalembert.case import load_cases
from dalembert.errors import trajectory_errors

REPEATS = 3
OVERHEAD_INTEGRATORS = ("rk3", "rk5", "implicit-euler", "discrete")
TUMBLE = [("drake", "rk3"), ("drake", "rk5"), ("drake", "bs3"), ("mujoco", "rk4"), ("pinocchio", "rk4")]
TUMBLE_DTS = (1e-2, 1e-3, 1e-4)


def bare(prepared):
    from dalembert.adapters.drake.stepping import reset

    simulator, _, _ = reset(prepared)
    t0 = time.perf_counter()
    simulator.AdvanceTo(float(prepared.times[-1]))
    return time.perf_counter() - t0


def overhead():
    adapter = get_adapter("drake")
    print(f"Drake {adapter.version()}, dt = 1e-3; stepping time per simulated second (ms)")
    cases = [f() for _, f in load_cases().items() if "canonical" in f.tags]
    adapter_against_bare(adapter, cases, OVERHEAD_INTEGRATORS, bare, repeats=REPEATS)


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


# Kutta's third-order tableau (Drake's RungeKutta3Integrator): c = (0, 1/2, 1).
KUTTA3_A = ((), (0.5,), (-1.0, 2.0))
KUTTA3_B = (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0)
STATE_DTS = (1e-2, 1e-3, 1e-4)


def _rk3(f, y, h, n):
    for _ in range(n):
        k = []
        for a in KUTTA3_A:
            k.append(f(y + h * sum((ai * ki for ai, ki in zip(a, k)), np.zeros_like(y))))
        y = y + h * sum(bi * ki for bi, ki in zip(KUTTA3_B, k))
    return y


def state():
    case = make_case("free_top_intermediate")
    I_B = case.scene.bodies[0].inertia_matrix
    I_B_inv = np.linalg.inv(I_B)
    q0, w0_B = np.array(case.scene.joints[0].q0[3:]), np.array(case.scene.joints[0].v0[3:])
    exact = case.exact(case.times).bodies["top"].quaternion

    def body(y):
        q, w = y[:4], y[4:]
        return np.concatenate([spatial.quat_derivative(q, w), I_B_inv @ np.cross(-w, I_B @ w)])

    def world(y):
        q, w = y[:4], y[4:]
        R = spatial.quat_to_matrix(q / np.linalg.norm(q))
        I_W = R @ I_B @ R.T
        return np.concatenate([0.5 * spatial.quat_multiply(np.concatenate([[0.0], w]), q),
                               np.linalg.solve(I_W, np.cross(-w, I_W @ w))])

    print("free_top_intermediate, 20 s: Kutta RK3 on the same top, w in body axes vs in world axes (as Drake)")
    print(f"{'dt':>8}{'body w':>12}{'world w':>12}")
    R0 = spatial.quat_to_matrix(q0)
    for dt in STATE_DTS:
        row = []
        for f, y0 in ((body, np.concatenate([q0, w0_B])), (world, np.concatenate([q0, R0 @ w0_B]))):
            n = int(round((case.times[1] - case.times[0]) / dt))
            y, worst = y0, 0.0
            for k in range(1, len(case.times)):
                y = _rk3(f, y, dt, n)
                worst = max(worst, float(spatial.rotation_angle(y[:4], exact[k])))
            row.append(worst)
        print(f"{dt:>8g}{row[0]:>12.2e}{row[1]:>12.2e}", flush=True)


LOOP_DTS = (1e-2, 1e-3, 1e-4, 1e-5)


def loops():
    from dalembert import invariants
    from dalembert.cases.four_bar import four_bar, parallelogram_pendulum
    from dalembert.reference.closed_form import RigidPendulum

    adapter = get_adapter("drake")
    case = four_bar()
    m, d, I, g, theta0, rate0 = parallelogram_pendulum()
    exact = RigidPendulum(m, d, I, g, theta0, rate0).angle(case.times) - np.pi / 2
    print(f"four_bar, {case.t_final:g} s, Drake {adapter.version()} discrete (SAP)")
    truth = case.exact(case.times)
    scale = max(np.abs(f).max() for k, f in truth.extras.items() if k.startswith("reaction_force:"))
    flat = case.times[np.argmin(np.abs(exact - np.pi))]  # the sample nearest the flat singular position
    far = np.abs(case.times - flat) > 0.02
    print(f"{'dt':>8}{'crank':>11}{'rocker':>11}{'loop pos':>11}{'loop vel':>11}{'react C':>11}{'(far)':>11}"
          f"{'steps':>8}{'stepping s':>12}")
    for dt in LOOP_DTS:
        prepared = adapter.prepare(case.scene, case.times, Settings("discrete", dt=dt))
        outcomes = [adapter.run(prepared) for _ in range(REPEATS)]
        traj = outcomes[0].trajectory
        crank, rocker = (np.abs(traj.joints[j].q[:, 0] - exact).max() for j in ("crank", "rocker"))
        pos, vel = (invariants.loop_residual(case.scene, traj, lv).max() for lv in ("position", "velocity"))
        wall = float(np.median([o.wall_s for o in outcomes]))
        react = np.linalg.norm(traj.extras["reaction_force:C"] - truth.extras["reaction_force:C"], axis=1) / scale
        print(f"{dt:>8g}{crank:>11.2e}{rocker:>11.2e}{pos:>11.2e}{vel:>11.2e}{react.max():>11.2e}"
              f"{react[far].max():>11.2e}{outcomes[0].n_steps:>8}{wall:>12.3f}", flush=True)


def main(argv):
    parts = argv or ["overhead", "tumble", "state"]
    if "loops" in parts:
        loops()
    if "overhead" in parts:
        overhead()
    if "tumble" in parts:
        tumble()
    if "state" in parts:
        state()


if __name__ == "__main__":
    main(sys.argv[1:])
