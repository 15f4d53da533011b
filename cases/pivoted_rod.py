"""A planar rod pivoted at one end, driven by a follower force at its tip (d'Alembert's principle for a rigid rod:
its moment of inertia about the pivot times phi'' equals the force's moment, l F)."""

from __future__ import annotations

import numpy as np

from dalembert.cases._sampling import sample_times
from dalembert import spatial
from dalembert.case import Case, Tolerance, case
from dalembert.scene import Body, Joint, Load, Scene
from dalembert.trajectory import BodyStates, JointStates, Trajectory
from dalembert.reference.closed_form import FollowerForceRod

# Agreement with the closed form. phi(t) is quadratic in t, so any Runge-Kutta
# method of order >= 2 is exact up to roundoff (~1e-14 rad over 12 rad); these
# bounds leave room for the conversion of engines' coordinates.
ANGLE_TOL = Tolerance(1e-9, "rad; 1e-10 of the ~12 rad turned, far above roundoff, far below any modelling error")
POSITION_TOL = Tolerance(1e-9, "m; the COM moves on a circle of 0.5 m: ANGLE_TOL times the radius, doubled")
VELOCITY_TOL = Tolerance(1e-8, "m/s; the COM speed reaches ~6 m/s: ~1e-9 relative")
RATE_TOL = Tolerance(1e-8, "rad/s; the rate reaches ~12 rad/s: ~1e-9 relative")
ENERGY_TOL = Tolerance(1e-8, "relative to the final kinetic energy; the sampled work quadrature (Simpson) is exact "
                             "for this linear power, so only integration error remains")
REACTION_TOL = Tolerance(1e-7, "relative to the largest reaction (m l w^2/2 ~ 72 N); reactions are second "
                               "derivatives, one order less accurate than the angle")


@case(tags=("canonical", "jointed", "follower-force"),
      units=dict(length="m", mass="kg", force="N", t_final="s", radius="m", sample_interval="s"),
      positive=("length", "mass", "radius", "sample_interval"))
def pivoted_rod(length=1.0, mass=1.0, force=2.0, t_final=2.0, radius=0.01, sample_interval=0.01):
    """Uniform rod pivoted at one end (revolute about z), a follower force of
    constant size perpendicular to the rod at its tip, no gravity.

    The small ``radius`` makes the inertia positive definite so every engine
    accepts it; it does not change the planar motion beyond its exact share
    ``m r^2 / 4`` of the moment about the pivot, which the closed form includes.
    """
    rod = Body.cylinder("rod", mass, length, radius, axis=0)  # axis along body x
    half = 0.5 * length
    scene = Scene(
        "pivoted_rod",
        bodies=[rod],
        joints=[Joint("revolute", "world", "rod", q0=[0.0], v0=[0.0], axis=[0.0, 0.0, 1.0],
                      child_point=[-half, 0.0, 0.0])],
        loads=[Load("rod", "force", [0.0, force, 0.0], frame="body", point=[half, 0.0, 0.0])],
        gravity=[0.0, 0.0, 0.0],
    )
    exact = FollowerForceRod(mass, length, rod.inertia[2][2] + mass * half**2, force)

    def truth(t):
        t = np.asarray(t, dtype=float)
        phi, rate = exact.angle(t), exact.rate(t)
        w = np.zeros((len(t), 3))
        w[:, 2] = rate
        body = BodyStates(exact.com_position(t), spatial.quat_from_axis_angle([0.0, 0.0, 1.0], phi),
                          exact.com_velocity(t), w)
        return Trajectory(t, {"rod": body}, {"rod": JointStates(phi[:, None], rate[:, None])},
                          {"reaction_force:rod": exact.reaction_force(t)})

    return Case(
        "pivoted_rod", scene, t_final, sample_times(t_final, sample_interval, "pivoted_rod"), exact=truth,
        conserved=("energy_balance",),
        tolerances=dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL, velocity=VELOCITY_TOL,
                        angular_velocity=RATE_TOL, energy_balance=ENERGY_TOL, reaction_force=REACTION_TOL),
    )


VIOLENT_ANGLE_TOL = Tolerance(1e-6, "rad after ~15000 rad: 1e-10 relative; phi stays quadratic in t, so RK methods "
                                    "of order >= 2 stay exact up to roundoff growing with the angle")
VIOLENT_REACTION_TOL = Tolerance(1e-6, "relative to the largest reaction (m l w^2 / 2 ~ 4.5e6 N)")
VIOLENT_ENERGY_TOL = Tolerance(1e-6, "relative; the energy balance of a rod spun to ~3000 rad/s")


@case(tags=("hard", "jointed", "follower-force", "fast-spin"),
      units=dict(length="m", mass="kg", force="N", t_final="s", radius="m", sample_interval="s"),
      positive=("length", "mass", "radius", "sample_interval"))
def pivoted_rod_violent(length=1.0, mass=1.0, force=100.0, t_final=10.0, radius=0.01, sample_interval=0.01):
    """The pivoted rod driven 50x harder for 10 s: its rate reaches ~3000 rad/s and
    the pivot reaction ~m l w^2 / 2 = 4.5e6 N."""
    made = pivoted_rod(length, mass, force, t_final, radius, sample_interval)
    tolerances = dict(made.tolerances, joint=VIOLENT_ANGLE_TOL, orientation=VIOLENT_ANGLE_TOL,
                      position=Tolerance(1e-6, "m; VIOLENT_ANGLE_TOL on the 0.5 m circle"),
                      velocity=Tolerance(1e-3, "m/s at 1500 m/s: 1e-6 relative"),
                      angular_velocity=Tolerance(1e-3, "rad/s at 3000 rad/s: 3e-7 relative"),
                      energy_balance=VIOLENT_ENERGY_TOL, reaction_force=VIOLENT_REACTION_TOL)
    return Case("pivoted_rod_violent", made.scene, made.t_final, made.sample_times, made.exact, made.conserved,
                tolerances)
