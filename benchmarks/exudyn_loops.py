"""Exudyn on the parallelogram four-bar (a closed loop): accuracy, closure and cost per solver.

    python -m benchmarks.exudyn_loops [t_final]

Per implicit solver (the explicit ones solve no constraints), joint formulation (the kinematic tree;
redundant coordinates on rotation-vector and on Euler-parameter nodes) and dt = 1e-2, 1e-3, 1e-4,
over the four-bar's default 0.5 s (through its singular position at t = 0.23 s):

* ``angle``: the largest error of the crank's and the rocker's angle against the closed form
  (``RigidPendulum``), rad;
* ``loop pos``, ``loop vel``: the worst closure residuals (``invariants.loop_residual``), m and m/s;
* ``F_C``: the largest error of the loop's reaction at C against the reference's (Kane with loop
  multipliers, DOP853 at 1e-12), relative to its largest value; ``F_C away`` the same on the samples
  0.1 rad or more from the flat (singular) position, where the reaction is sensitive to the state;
* ``wall``: the stepping time (``Outcome.wall_s``), best of 3 (a shared machine only adds time), s;
  ``steps`` and Newton iterations as Exudyn counts them.
"""

from __future__ import annotations

import sys

import numpy as np

from dalembert import invariants
from dalembert.adapters import get_adapter
from dalembert.cases.four_bar import four_bar, parallelogram_pendulum
from dalembert.reference import simulate
from dalembert.reference.closed_form import RigidPendulum
from dalembert.settings import Settings

REPEATS = 3
SOLVERS = ("generalized-alpha", "trapezoidal-index2")
VARIANTS = ({}, {"joints": "redundant"}, {"joints": "redundant", "node": "ep"})
STEPS = (1e-2, 1e-3, 1e-4)
AWAY = 0.1  # rad from the flat position, phi = pi (see ``F_C away``)


def main(t_final=0.5):
    case = four_bar(t_final=t_final)
    m, d, I, g, theta0, rate0 = parallelogram_pendulum()
    exact = RigidPendulum(m, d, I, g, theta0, rate0).angle(case.times) - np.pi / 2
    away = np.abs(np.angle(np.exp(1j * exact))) < np.pi - AWAY
    truth = simulate(case.scene, case.times, Settings("dop853", rtol=1e-12, atol=1e-12))[0]
    scale = np.abs(truth.extras["reaction_force:C"]).max()
    adapter = get_adapter("exudyn")
    print(f"four_bar over {t_final:g} s; F_C relative to its largest, {scale:.2f} N")
    print(f"{'solver':19s} {'variant':24s} {'dt':>6s} {'angle':>9s} {'loop pos':>9s} {'loop vel':>9s} "
          f"{'F_C':>8s} {'F_C away':>8s} {'wall s':>7s} {'steps':>6s} {'newton':>7s}")
    for solver in SOLVERS:
        for options in VARIANTS:
            name = ",".join(f"{k}={v}" for k, v in options.items()) or "joints=minimal"
            for dt in STEPS:
                try:
                    prepared = adapter.prepare(case.scene, case.times, Settings(solver, dt=dt, options=options))
                    outs = [adapter.run(prepared) for _ in range(REPEATS)]
                except RuntimeError as e:
                    print(f"{solver:19s} {name:24s} {dt:6.0e} failed: {str(e)[:110]}")
                    continue
                traj = outs[0].trajectory
                angle = max(np.abs(traj.joints[b].q[:, 0] - exact).max() for b in ("crank", "rocker"))
                force = np.abs(traj.extras["reaction_force:C"] - truth.extras["reaction_force:C"]).max(axis=1) / scale
                print(f"{solver:19s} {name:24s} {dt:6.0e} {angle:9.2e} "
                      f"{invariants.loop_residual(case.scene, traj).max():9.1e} "
                      f"{invariants.loop_residual(case.scene, traj, 'velocity').max():9.1e} "
                      f"{force.max():8.1e} {force[away].max():8.1e} {min(o.wall_s for o in outs):7.3f} "
                      f"{outs[0].n_steps:6d} {outs[0].info['newton_steps']:7d}")


if __name__ == "__main__":
    main(*(float(a) for a in sys.argv[1:]))
