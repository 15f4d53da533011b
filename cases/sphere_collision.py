"""Two spheres of unequal mass meeting head-on in free space: their velocities after the impact follow from
momentum conservation and Newton's coefficient of restitution."""

from __future__ import annotations

import numpy as np

from dalembert.case import Case, Tolerance, case
from dalembert.cases._contact import TAGS, penetration, require
from dalembert.cases._sampling import sample_times
from dalembert.metrics import Metric, constant
from dalembert.reference.closed_form import HeadOnCollision
from dalembert.scene import Body, ContactPair, Geom, Joint, Scene
from dalembert.trajectory import BodyStates, Trajectory

POSITION_TOL = Tolerance(5e-3, "m; 5 % of the smaller radius: a contact that resolves the impact over a few ms "
                               "shifts the spheres by the approach speed times that")
VELOCITY_TOL = Tolerance(0.2, "m/s; the velocities jump at the impact by up to ~0.7 m/s: a sample during an "
                              "impact the engine spreads over a few ms differs by part of the jump")
MOMENTUM_TOL = Tolerance(1e-9, "relative to the total momentum; the contact forces are equal and opposite, so "
                               "any change is the engine's arithmetic")
AFTER_TOL = Tolerance(1e-2, "relative to the approach speed v1 - v2; the velocities after measure the restitution "
                            "(the separation speed is e times it): 1 %")
PENETRATION_TOL = Tolerance(2e-3, "m; 2 % of the 0.1-m radius, at a 1-m/s approach")


@case(tags=(*TAGS, "restitution", "impact", "free"),
      units=dict(restitution="1", m1="kg", m2="kg", r1="m", r2="m", v1="m/s", v2="m/s", gap="m", t_final="s",
                 sample_interval="s"),
      positive=("m1", "m2", "r1", "r2", "gap", "sample_interval"))
def sphere_collision(restitution=0.8, m1=1.0, m2=3.0, r1=0.1, r2=0.1, v1=1.0, v2=0.0, gap=0.3, t_final=0.6,
                     sample_interval=0.001):
    """Two solid spheres on world x, ``gap`` apart (surface to surface), sphere 1 at ``v1`` catching sphere 2 at
    ``v2``, frictionless, no gravity: they meet at ``gap / (v1 - v2)`` and leave with
    ``v1' = (m1 v1 + m2 v2 - m2 e (v1 - v2)) / M``, ``v2' = (m1 v1 + m2 v2 + m1 e (v1 - v2)) / M``.
    Momentum is conserved exactly. Judged on the motion, the momentum, the velocities after and the penetration.
    """
    require("sphere_collision", [
        (0.0 <= restitution <= 1.0, f"restitution: must lie in [0, 1], got {restitution!r} — Newton's coefficient"),
        (v1 > v2, f"v1: {v1!r} m/s does not exceed v2 = {v2!r} m/s, so the spheres never meet — make v1 > v2"),
    ])
    x2 = r1 + gap + r2
    scene = Scene(
        "sphere_collision",
        bodies=[Body("ball1", m1, np.eye(3) * 0.4 * m1 * r1**2), Body("ball2", m2, np.eye(3) * 0.4 * m2 * r2**2)],
        joints=[Joint("free", "world", "ball1", q0=[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], v0=[v1, 0, 0, 0, 0, 0]),
                Joint("free", "world", "ball2", q0=[x2, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0], v0=[v2, 0, 0, 0, 0, 0])],
        gravity=[0.0, 0.0, 0.0], geoms=[Geom("ball1", "sphere", (r1,)), Geom("ball2", "sphere", (r2,))],
        contacts=[ContactPair("geom_ball1", "geom_ball2", 0.0, restitution=restitution)])
    exact = HeadOnCollision(m1, m2, v1, v2, 0.0, x2, r1, r2, restitution)
    times = sample_times(t_final, sample_interval, "sphere_collision")

    def truth(t):
        t = np.asarray(t, dtype=float)
        n = len(t)
        bodies = {}
        for name, x, v in zip(("ball1", "ball2"), exact.positions(t), exact.velocities(t)):
            zero = np.zeros(n)
            bodies[name] = BodyStates(np.stack([x, zero, zero], -1), np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
                                      np.stack([v, zero, zero], -1), np.zeros((n, 3)))
        return Trajectory(t, bodies)

    metrics = [penetration(PENETRATION_TOL)]
    if exact.impact_time < t_final:
        after = exact.velocities_after

        def after_error(scene, traj):
            return constant(traj, max(abs(traj.bodies[name].velocity[-1, 0] - want)
                                      for name, want in zip(("ball1", "ball2"), after)))

        metrics.append(Metric("velocity_after_error", "largest error of the two velocities at t_final against "
                                                      "the closed form's after the impact, relative to v1 - v2",
                              "m/s", v1 - v2, AFTER_TOL, after_error, headline=True))
    return Case("sphere_collision", scene, t_final, times, exact=truth, conserved=("linear_momentum",),
                tolerances=dict(position=POSITION_TOL, velocity=VELOCITY_TOL, linear_momentum=MOMENTUM_TOL),
                invariants=tuple(metrics))
