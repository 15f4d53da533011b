"""A box on an inclined plane with Coulomb friction: it slides with a = g (sin angle - mu cos angle), and where
tan(angle) < mu it stops and sticks (started at rest, it never moves)."""

from __future__ import annotations

import math

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case
from dalembert.cases._contact import TAGS, body_truth, normal_force_error, penetration, require
from dalembert.contact_residuals import residual_metrics
from dalembert.cases._sampling import sample_times
from dalembert.metrics import Metric, constant, first_crossing
from dalembert.reference.closed_form import SlidingBlock
from dalembert.scene import Body, ContactPair, Geom, Joint, Plane, Scene

# Agreement with the closed form. A rigid Coulomb contact holds the box on the plane exactly; engines' contacts
# yield (soft constraints, penalties), so these bounds are set by what the physics asks, not by roundoff.
POSITION_TOL = Tolerance(1e-3, "m; 1 % of the box's 0.1-m height: a contact that yields more, or a stop that "
                               "comes late enough to slide a mm further, is a different motion")
VELOCITY_TOL = Tolerance(1e-2, "m/s; the box reaches ~1 m/s when it slides: 1 %")
ORIENTATION_TOL = Tolerance(1e-2, "rad; the box must not tip (its 0.2-m base holds it up to tan(angle) = 2)")
RATE_TOL = Tolerance(0.1, "rad/s; the box does not turn: a rocking contact shows here")
# A box that must stick may not creep faster than this: 0.1 mm/s moves it 0.1 mm over the 1-s horizon, 1/1000 of
# its base (MuJoCo's default pyramidal cone creeps 1.8 mm/s on this very set-up: the issue that asked for contact).
CREEP_TOL = Tolerance(1e-4, "m/s; a sticking box creeping 0.1 mm/s moves 1/1000 of its 0.2-m base per second")
PENETRATION_TOL = Tolerance(1e-3, "m; 1 % of the box's 0.1-m height")
STOP_TOL = Tolerance(5e-3, "s; a stop 5 ms late, at the end of a deceleration of ~1 m/s^2, adds ~0.01 mm of travel: "
                           "well inside POSITION_TOL")
# A stop is located where the speed down the slope falls to this fraction of v0 (the closed form's speed is
# linear in t, so its crossing is exact between two samples): 1 %, above any engine's contact noise.
STOP_FRACTION = 0.01
# Creep is measured from this long after the stop (s; at rest from the start, after it): a stop late by less is
# STOP_TOL's to judge, and a compliant contact settles into its steady state (2.5 of MuJoCo's default 0.02-s time
# constants) — the creep is the steady rate, not the settling.
STOP_GRACE = 0.05
# The normal force where the engine reports one (``_contact.normal_force_error``), relative to m g cos(angle).
NORMAL_FORCE_TOL = Tolerance(1e-2, "of m g cos(angle); the box neither lifts nor tips, so its contact carries the "
                                   "weight's normal part: 1 % more or less accelerates it off the plane at 0.1 m/s^2")
# ContactBench's residuals where the engine reports contact forces (``dalembert.contact_residuals``), over the load.
RESIDUAL_TOLS = dict(
    signorini_residual=Tolerance(1e-3, "m/s (W over the load in N); the load times the contact's normal speed: a "
                                       "loaded contact sinking or lifting at 1 mm/s leaves PENETRATION_TOL in 1 s"),
    cone_residual=Tolerance(1e-2, "of the load; friction 1 % of the normal force beyond Coulomb's cone"),
    dissipation_residual=Tolerance(1e-4, "m/s (W over the load in N); slip short of full friction dissipates too "
                                         "little: at the cone's margin (mu cos - sin = 0.13 of the weight here) "
                                         "CREEP_TOL's slip gives 1.3e-5, the bound leaves 8x"),
)


@case(tags=(*TAGS, "friction"),
      units=dict(angle="rad", mu="1", v0="m/s", mass="kg", size="m", g="m/s^2", t_final="s", sample_interval="s"),
      positive=("mass", "size", "g", "sample_interval"))
def block_on_incline(angle=math.radians(20.0), mu=0.5, v0=0.0, mass=1.0, size=(0.2, 0.2, 0.1), g=9.81, t_final=1.0,
                     sample_interval=0.01):
    """A box (edges ``size``, the last one normal to the slope) on a plane tilted by ``angle`` about world y (the
    plane is tilted, not gravity), started sliding straight down the slope at ``v0``; Coulomb coefficient ``mu``.

    Slides with ``a = g (sin angle - mu cos angle)``; where ``tan(angle) < mu`` it stops at ``v0 / -a`` and then
    sticks (``v0 = 0``: it never moves). The defaults are the issue's: 1 kg, mu = 0.5 on 20 degrees, at rest.
    Judged on the motion, the creep while it must stick, the stop time and the penetration.
    """
    require("block_on_incline", [
        (0.0 <= angle < 0.5 * math.pi, f"angle: must lie in [0, pi/2) rad, got {angle!r} — the slope's inclination"),
        (mu >= 0.0, f"mu: must be >= 0, got {mu!r} — the Coulomb coefficient"),
        (v0 >= 0.0, f"v0: must be >= 0 (m/s, down the slope), got {v0!r} — start it at rest or sliding down"),
    ])
    normal = np.array([math.sin(angle), 0.0, math.cos(angle)])  # the plane's, tilted about world y
    downhill = np.array([math.cos(angle), 0.0, -math.sin(angle)])
    q = spatial.quat_from_axis_angle([0.0, 1.0, 0.0], angle)  # body z along the normal, body x downhill
    p0 = 0.5 * size[2] * normal  # the box's face on the plane, which passes through the origin
    scene = Scene(
        "block_on_incline", bodies=[Body.box("box", mass, size)],
        joints=[Joint("free", "world", "box", q0=[*p0, *q], v0=[*(v0 * downhill), 0.0, 0.0, 0.0])],
        gravity=[0.0, 0.0, -g], geoms=[Geom("box", "box", size)], planes=[Plane("slope", normal)],
        contacts=[ContactPair("geom_box", "slope", mu)])
    exact = SlidingBlock(angle, mu, v0, g, mass)
    times = sample_times(t_final, sample_interval, "block_on_incline")

    def truth(t):
        t = np.asarray(t, dtype=float)
        s, v = exact.displacement(t), exact.speed(t)
        # the plane's force on the box: the normal force, and friction up the slope (closed form's friction_force)
        force = exact.normal_force * normal - np.asarray(exact.friction_force(t))[:, None] * downhill
        return body_truth(t, "box", p0 + s[:, None] * downhill, np.tile(q, (len(t), 1)), v[:, None] * downhill,
                          np.zeros((len(t), 3)), {scene.contacts[0].name: force})

    def speed_down(traj):
        return traj.bodies["box"].velocity @ downhill

    metrics = [penetration(PENETRATION_TOL), normal_force_error(exact.normal_force, NORMAL_FORCE_TOL),
               *residual_metrics(0, exact.normal_force, RESIDUAL_TOLS)]
    stop = exact.stop_time
    if stop is not None and stop + STOP_GRACE < t_final:  # a phase that must stick
        begin = int(np.searchsorted(times, stop + STOP_GRACE))

        def creep(scene, traj):
            p = traj.bodies["box"].position
            moved = (p[-1] - p[begin]) - ((p[-1] - p[begin]) @ normal) * normal  # along the slope
            return constant(traj, np.linalg.norm(moved) / (traj.t[-1] - traj.t[begin]))

        metrics.append(Metric("creep", "mean speed of the box along the slope while the closed form sticks (its "
                                       f"displacement from {STOP_GRACE:g} s after the stop to t_final, over that time)",
                              "m/s", 1.0, CREEP_TOL, creep, headline=True))
    if stop is not None and 0.0 < stop < t_final:
        level = STOP_FRACTION * v0
        true_stop = first_crossing(times, exact.speed(times), level)

        def stop_error(scene, traj):
            found = first_crossing(traj.t, speed_down(traj), level)
            return constant(traj, (traj.t[-1] if found is None else found) - true_stop)

        metrics.append(Metric("stop_time_error", f"when the speed down the slope falls to {STOP_FRACTION:g} v0, "
                                                 "against the closed form's (s)", "s", 1.0, STOP_TOL, stop_error,
                              headline=not any(m.name == "creep" for m in metrics)))
    return Case("block_on_incline", scene, t_final, times, exact=truth,
                tolerances=dict(position=POSITION_TOL, velocity=VELOCITY_TOL, orientation=ORIENTATION_TOL,
                                angular_velocity=RATE_TOL),
                invariants=tuple(metrics))
