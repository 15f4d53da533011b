"""A solid sphere launched sliding on a level plane: friction slows it and spins it up until it rolls, from
t* = 2 (v0 - omega0 R) / (7 mu g) on, at (5 v0 + 2 omega0 R) / 7."""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case
from dalembert.cases._contact import TAGS, body_truth, normal_force_error, penetration, require, slip_speed
from dalembert.contact_residuals import residual_metrics
from dalembert.cases._sampling import sample_times
from dalembert.invariants import kinetic_energy
from dalembert.metrics import Metric, constant, first_crossing
from dalembert.reference.closed_form import SlidingBall
from dalembert.scene import Body, ContactPair, Geom, Joint, Plane, Scene

POSITION_TOL = Tolerance(2e-3, "m; 2 % of the 0.1-m radius, after ~0.7 m of travel: an onset 10 ms late slides "
                               "~1 mm further")
VELOCITY_TOL = Tolerance(1e-2, "m/s; 1 % of the 1-m/s launch")
ORIENTATION_TOL = Tolerance(2e-2, "rad; the ball turns ~7 rad: POSITION_TOL over the radius, doubled")
RATE_TOL = Tolerance(0.1, "rad/s; the spin reaches ~7 rad/s: VELOCITY_TOL over the radius")
ONSET_TOL = Tolerance(5e-3, "s; the roll onset within 5 ms of t* (0.29 s for the defaults): 2 %")
ROLL_SPEED_TOL = Tolerance(1e-3, "m/s; 0.1 % of the 0.71-m/s rolling speed, which the angular momentum about the "
                                 "contact point fixes")
ENERGY_TOL = Tolerance(1e-2, "relative to the initial kinetic energy; the slip dissipates 2/7 of it for a ball "
                             "launched without spin: 1 % of what is left after it")
ROLL_SLIP_TOL = Tolerance(1e-3, "m/s; once rolling the contact point must not slip: 0.1 % of the launch speed")
PENETRATION_TOL = Tolerance(1e-3, "m; 1 % of the 0.1-m radius")
# The onset is located where the slip speed falls to this fraction of its initial value, in the run and in the
# closed form sampled alike (linear in t before t*: its crossing is exact between two samples).
ONSET_FRACTION = 0.01
# Rolling slip is measured from this long after t* (s): an onset late by less is ONSET_TOL's to judge.
ONSET_GRACE = 0.05
# The normal force where the engine reports one (``_contact.normal_force_error``), relative to m g.
NORMAL_FORCE_TOL = Tolerance(1e-2, "of m g; the ball stays on the level plane, so its contact carries its weight: "
                                   "1 % more or less accelerates it off the plane at 0.1 m/s^2")
# ContactBench's residuals where the engine reports contact forces (``dalembert.contact_residuals``), over m g.
RESIDUAL_TOLS = dict(
    signorini_residual=Tolerance(1e-3, "m/s (W over the weight in N); the weight times the contact's normal speed: "
                                       "a loaded contact sinking or lifting at 1 mm/s leaves PENETRATION_TOL in 1 s"),
    cone_residual=Tolerance(1e-2, "of the weight; friction 1 % of the normal force beyond Coulomb's cone"),
    dissipation_residual=Tolerance(1e-3, "m/s (W over the weight in N); a sliding contact whose friction falls short "
                                         "of mu m g, or a rolling one that slips, by ROLL_SLIP_TOL at full load"),
)


@case(tags=(*TAGS, "friction", "rolling"),
      units=dict(v0="m/s", omega0="rad/s", mu="1", radius="m", mass="kg", g="m/s^2", t_final="s",
                 sample_interval="s"),
      positive=("mu", "radius", "mass", "g", "sample_interval"))
def ball_slide_to_roll(v0=1.0, omega0=0.0, mu=0.1, radius=0.1, mass=1.0, g=9.81, t_final=1.0, sample_interval=0.01):
    """A solid sphere on a level plane, launched along world x at ``v0`` with spin ``omega0`` about world y (the
    axis rolling needs); Coulomb coefficient ``mu``. It slides, ``v = v0 - mu g t`` and the spin growing at
    ``5 mu g / (2 R)``, until it rolls from ``t* = 2 (v0 - omega0 R) / (7 mu g)`` at ``(5 v0 + 2 omega0 R) / 7``.

    The defaults are the issue's: t* = 0.2912 s. Judged on the motion, the onset time, the rolling speed, the
    energy after the slip, the slip once rolling and the penetration.
    """
    require("ball_slide_to_roll", [
        (v0 - omega0 * radius != 0.0, "v0: equals omega0 * radius, so the ball rolls from the start — launch it "
                                      "sliding (ball_rolling_incline covers rolling alone)"),
    ])
    scene = Scene(
        "ball_slide_to_roll", bodies=[Body("ball", mass, np.eye(3) * 0.4 * mass * radius**2)],
        joints=[Joint("free", "world", "ball", q0=[0.0, 0.0, radius, 1.0, 0.0, 0.0, 0.0],
                      v0=[v0, 0.0, 0.0, 0.0, omega0, 0.0])],
        gravity=[0.0, 0.0, -g], geoms=[Geom("ball", "sphere", (radius,))], planes=[Plane("ground")],
        contacts=[ContactPair("geom_ball", "ground", mu)])
    exact = SlidingBall(v0, omega0, mu, radius, g, mass)
    times = sample_times(t_final, sample_interval, "ball_slide_to_roll")

    def truth(t):
        t = np.asarray(t, dtype=float)
        n, zero = len(t), np.zeros(len(t))
        # the plane's force on the ball: its weight's reaction, and mu m g against the slip until it rolls
        friction = np.where(t < exact.roll_time, -np.sign(exact.initial_slip) * mu * mass * g, 0.0)
        force = np.stack([friction, zero, np.full(n, mass * g)], -1)
        return body_truth(t, "ball", np.stack([exact.distance(t), zero, np.full(n, radius)], -1),
                          spatial.quat_from_axis_angle([0.0, 1.0, 0.0], exact.angle(t)),
                          np.stack([exact.speed(t), zero, zero], -1), np.stack([zero, exact.spin(t), zero], -1),
                          {scene.contacts[0].name: force})

    metrics = [penetration(PENETRATION_TOL), normal_force_error(mass * g, NORMAL_FORCE_TOL),
               *residual_metrics(0, mass * g, RESIDUAL_TOLS)]
    t_star = exact.roll_time
    if t_star < t_final:
        level = ONSET_FRACTION * abs(exact.initial_slip)
        true_onset = first_crossing(times, np.abs(exact.slip(times)), level)
        rolling_energy = float(exact.kinetic_energy(t_final))

        def onset_error(scene, traj):
            found = first_crossing(traj.t, slip_speed(scene, traj), level)
            return constant(traj, (traj.t[-1] if found is None else found) - true_onset)

        metrics += [
            Metric("roll_onset_error", f"when the slip speed falls to {ONSET_FRACTION:g} of its initial value, "
                                       "against the closed form's (s)", "s", 1.0, ONSET_TOL, onset_error,
                   headline=True),
            Metric("roll_speed_error", "the speed at t_final against the rolling speed (5 v0 + 2 omega0 R) / 7", "m/s",
                   1.0, ROLL_SPEED_TOL,
                   lambda scene, traj: constant(traj, traj.bodies["ball"].velocity[-1, 0] - exact.roll_speed)),
            Metric("rolling_energy_error", "the kinetic energy at t_final against the closed form's after the slip, "
                                           "relative to the initial kinetic energy", "J",
                   float(exact.kinetic_energy(0.0)), ENERGY_TOL,
                   lambda scene, traj: constant(traj, kinetic_energy(scene, traj)[-1] - rolling_energy)),
            Metric("rolling_slip", f"largest slip speed of the contact point once rolling (from {ONSET_GRACE:g} s "
                                   "after t*)", "m/s", 1.0, ROLL_SLIP_TOL,
                   lambda scene, traj: np.where(traj.t >= t_star + ONSET_GRACE, slip_speed(scene, traj), 0.0)),
        ]
    return Case("ball_slide_to_roll", scene, t_final, times, exact=truth,
                tolerances=dict(position=POSITION_TOL, velocity=VELOCITY_TOL, orientation=ORIENTATION_TOL,
                                angular_velocity=RATE_TOL),
                invariants=tuple(metrics))
