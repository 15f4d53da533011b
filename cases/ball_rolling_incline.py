"""A solid sphere released on an inclined plane with enough friction to roll without slipping:
a = 5/7 g sin(angle), and its energy is conserved."""

from __future__ import annotations

import math

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case
from dalembert.cases._contact import TAGS, body_truth, normal_force_error, penetration, require, slip_speed
from dalembert.contact_residuals import residual_metrics
from dalembert.cases._sampling import sample_times
from dalembert.metrics import Metric
from dalembert.reference.closed_form import RollingBall
from dalembert.scene import Body, ContactPair, Geom, Joint, Plane, Scene

POSITION_TOL = Tolerance(2e-3, "m; 2 % of the 0.1-m radius after ~1.7 m of rolling: 0.1 %")
VELOCITY_TOL = Tolerance(1e-2, "m/s; the ball reaches ~2.4 m/s: 0.4 %")
ORIENTATION_TOL = Tolerance(2e-2, "rad; the ball turns ~17 rad: POSITION_TOL over the radius, doubled")
RATE_TOL = Tolerance(0.1, "rad/s; the spin reaches ~24 rad/s: VELOCITY_TOL over the radius")
ENERGY_TOL = Tolerance(1e-2, "relative to the largest kinetic energy; a contact that does not slip does no work, so "
                             "what is lost is the engine's (a yielding or slipping contact)")
SLIP_TOL = Tolerance(1e-3, "m/s; the contact point must not slip: 0.04 % of the final speed")
PENETRATION_TOL = Tolerance(1e-3, "m; 1 % of the 0.1-m radius")
# The normal force where the engine reports one (``_contact.normal_force_error``), relative to m g cos(angle).
NORMAL_FORCE_TOL = Tolerance(1e-2, "of m g cos(angle); the ball stays on the plane, so its contact carries the "
                                   "weight's normal part: 1 % more or less accelerates it off the plane at 0.1 m/s^2")
# ContactBench's residuals where the engine reports contact forces (``dalembert.contact_residuals``), over the load.
RESIDUAL_TOLS = dict(
    signorini_residual=Tolerance(1e-3, "m/s (W over the load in N); the load times the contact's normal speed: a "
                                       "loaded contact sinking or lifting at 1 mm/s leaves PENETRATION_TOL in 1 s"),
    cone_residual=Tolerance(1e-2, "of the load; friction 1 % of the normal force beyond Coulomb's cone"),
    dissipation_residual=Tolerance(1e-3, "m/s (W over the load in N); a rolling contact that slips at SLIP_TOL with "
                                         "friction short of the cone's edge, at full load"),
)


@case(tags=(*TAGS, "friction", "rolling"),
      units=dict(angle="rad", mu="1", radius="m", mass="kg", g="m/s^2", t_final="s", sample_interval="s"),
      positive=("radius", "mass", "g", "sample_interval"))
def ball_rolling_incline(angle=math.radians(20.0), mu=0.5, radius=0.1, mass=1.0, g=9.81, t_final=1.0,
                         sample_interval=0.01):
    """A solid sphere released at rest on a plane tilted by ``angle`` about world y (the plane is tilted, not
    gravity), with ``mu`` above ``2/7 tan(angle)``: it rolls without slipping, ``a = 5/7 g sin(angle)``, and
    conserves its energy. Judged on the motion, the energy, the slip and the penetration.
    """
    require("ball_rolling_incline", [
        (0.0 < angle < 0.5 * math.pi, f"angle: must lie in (0, pi/2) rad, got {angle!r} — the slope's inclination")])
    require("ball_rolling_incline", [
        (mu > 2.0 / 7.0 * math.tan(angle), f"mu: {mu!r} is at most 2/7 tan(angle) = {2.0 / 7.0 * math.tan(angle):.4g}, "
                                           "so the ball would slip — give a larger mu (or a gentler angle)")])
    normal = np.array([math.sin(angle), 0.0, math.cos(angle)])
    downhill = np.array([math.cos(angle), 0.0, -math.sin(angle)])
    axis = np.cross(normal, downhill)  # rolling down turns the ball about normal x downhill (world -y)
    p0 = radius * normal
    scene = Scene(
        "ball_rolling_incline", bodies=[Body("ball", mass, np.eye(3) * 0.4 * mass * radius**2)],
        joints=[Joint("free", "world", "ball", q0=[*p0, 1.0, 0.0, 0.0, 0.0], v0=[0.0] * 6)],
        gravity=[0.0, 0.0, -g], geoms=[Geom("ball", "sphere", (radius,))], planes=[Plane("slope", normal)],
        contacts=[ContactPair("geom_ball", "slope", mu)])
    exact = RollingBall(angle, mu, radius, g, mass)

    def truth(t):
        t = np.asarray(t, dtype=float)
        # the plane's force on the ball: the normal force, and static friction 2/7 m g sin(angle) up the slope
        force = np.tile(exact.normal_force * normal - exact.friction_force * downhill, (len(t), 1))
        return body_truth(t, "ball", p0 + exact.distance(t)[:, None] * downhill,
                          spatial.quat_from_axis_angle(axis, exact.angle_turned(t)),
                          exact.speed(t)[:, None] * downhill, exact.spin(t)[:, None] * axis,
                          {scene.contacts[0].name: force})

    slip = Metric("slip", "largest slip speed of the contact point (the closed form rolls: none)", "m/s", 1.0,
                  SLIP_TOL, lambda scene, traj: slip_speed(scene, traj), headline=True)
    return Case("ball_rolling_incline", scene, t_final, sample_times(t_final, sample_interval, "ball_rolling_incline"),
                exact=truth, conserved=("energy",),
                tolerances=dict(position=POSITION_TOL, velocity=VELOCITY_TOL, orientation=ORIENTATION_TOL,
                                angular_velocity=RATE_TOL, energy=ENERGY_TOL),
                invariants=(penetration(PENETRATION_TOL), slip, normal_force_error(exact.normal_force, NORMAL_FORCE_TOL),
                            *residual_metrics(0, exact.normal_force, RESIDUAL_TOLS)))
