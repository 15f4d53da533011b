"""The physical pendulum: one body on a revolute joint under gravity, at large amplitude or over the top."""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case
from dalembert.cases._sampling import sample_times
from dalembert.reference.closed_form import RigidPendulum
from dalembert.scene import Body, Joint, Scene
from dalembert.trajectory import BodyStates, JointStates, Trajectory
from dalembert.maps import stability_map

# Agreement with the closed form (Jacobi elliptic functions, within 1e-13 rad of a 40-digit Taylor
# integration over 10 s: tests/test_closed_forms.py). Measured on the reference at the defaults (1 rad,
# 10 s): rk4 4.0e-7, 2.7e-8, 1.7e-9, 4.4e-11 rad at dt = 1e-2, 5e-3, 2.5e-3, 1e-3 (fourth order: 15.2
# and 15.6-fold per halving); euler 1.8e-3 and 1.8e-4 rad at 1e-3 and 1e-4.
ANGLE_TOL = Tolerance(1e-7, "rad over 10 s; met by a 4th-order method from dt = 5e-3 (reference rk4: 2.7e-8 rad) "
                            "but not at 1e-2 (4.0e-7), never by a 1st-order one at dt >= 1e-4 (reference euler: "
                            "1.8e-4 rad); 1e6 times the closed form's own error")
POSITION_TOL = Tolerance(1e-7, "m; the COM moves on a circle of radius l/2 = 0.5 m: ANGLE_TOL times the radius, "
                               "doubled")
VELOCITY_TOL = Tolerance(1e-6, "m/s; rates reach ~4 rad/s: ANGLE_TOL times the largest rate, doubled")
RATE_TOL = Tolerance(1e-6, "rad/s; as VELOCITY_TOL")
REACTION_TOL = Tolerance(1e-6, "relative to the largest pivot reaction (~16 N at the bottom); the reaction is "
                               "m a - m g of the same motion, so it is as accurate as the angle (reference rk4 at "
                               "dt = 5e-3: 2.3e-8), with room for engines that take it from constraint forces")
ENERGY_TOL = Tolerance(1e-8, "relative to max(|E(0)|, the largest kinetic energy); the reference's rk4 keeps it "
                             "to 1.0e-9 at dt = 5e-3 and 6e-13 at 1e-3, its euler to 1.5e-4 at 1e-4")

UNITS = dict(length="m", mass="kg", radius="m", gravity="m/s^2", theta0="rad", rate0="rad/s", t_final="s",
             sample_interval="s")


def _pendulum_case(name, body, com_distance, down, axis, gravity, theta0, rate0, t_final, sample_interval,
                   tolerances):
    """A ``body`` whose frame x axis points from the pivot (at the world origin) to its COM,
    ``com_distance`` away, turning about the world ``axis`` (unit, horizontal) under gravity
    ``gravity`` (m/s^2) along the world unit vector ``down``; ``theta0``, ``rate0``: the angle
    from the downward vertical (rad) and its rate (rad/s) at t = 0.

    The joint frame J has x = ``down``, z = ``axis`` (the joint turns about J's z), so the joint
    angle is the pendulum's ``theta``: ``R_WB = R_WJ R_z(theta)``.
    """
    down, axis = np.asarray(down, dtype=float), np.asarray(axis, dtype=float)
    swing = np.cross(axis, down)  # where the COM moves at theta = 0 for increasing theta
    q_WJ = spatial.matrix_to_quat(np.column_stack([down, swing, axis]))
    scene = Scene(
        name,
        bodies=[body],
        joints=[Joint("revolute", "world", body.name, q0=[theta0], v0=[rate0], axis=[0.0, 0.0, 1.0],
                      parent_quat=q_WJ, child_point=[-com_distance, 0.0, 0.0])],
        gravity=tuple(gravity * down),
    )
    exact = RigidPendulum(body.mass, com_distance, body.inertia[2][2] + body.mass * com_distance**2, gravity,
                          theta0, rate0, tuple(down), tuple(swing))

    def truth(t):
        t = np.asarray(t, dtype=float)
        theta, rate = exact.angle(t), exact.rate(t)
        q = spatial.quat_multiply(q_WJ, spatial.quat_from_axis_angle([0.0, 0.0, 1.0], theta))
        states = BodyStates(exact.com_position(t), q, exact.com_velocity(t), rate[:, None] * axis)
        return Trajectory(t, {body.name: states}, {body.name: JointStates(theta[:, None], rate[:, None])},
                          {f"reaction_force:{body.name}": exact.reaction_force(t)})

    return Case(name, scene, t_final, sample_times(t_final, sample_interval, name), exact=truth,
                conserved=("energy",), tolerances=tolerances)


@case(tags=("canonical", "jointed", "gravity"), units=UNITS,
      positive=("length", "mass", "radius", "gravity", "sample_interval"))
def pendulum(length=1.0, mass=1.0, radius=0.01, gravity=9.81, theta0=1.0, rate0=0.0, t_final=10.0,
             sample_interval=0.01):
    """Uniform rod pivoted at one end, swinging under gravity from ``theta0`` (rad from the
    downward vertical) with rate ``rate0``: a libration of 57 degrees by default (period 1.747 s,
    6.6% longer than the small-amplitude one), up to any amplitude below pi (``theta0=3.1``), or
    over the top when ``rate0`` is large enough (``rate0=8``).

    At large amplitudes fourth-order methods need finer steps before their order shows (reference
    rk4 at ``theta0=2.5``: 32, 9, 12, 15-fold per halving from dt = 1e-2 to 6.25e-4, against 15.2,
    15.6, 15.8, 15.9 at the default).

    The truth is the closed form in Jacobi elliptic functions (``RigidPendulum``), pivot reaction
    included. The small ``radius`` makes the inertia positive definite for every engine and adds
    its exact share ``m r^2 / 4`` to the moment about the pivot, which the closed form includes.
    """
    rod = Body.cylinder("rod", mass, length, radius, axis=0)
    tolerances = dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL, velocity=VELOCITY_TOL,
                      angular_velocity=RATE_TOL, reaction_force=REACTION_TOL, energy=ENERGY_TOL)
    return _pendulum_case("pendulum", rod, 0.5 * length, (0.0, 0.0, -1.0), (0.0, -1.0, 0.0), gravity, theta0, rate0,
                          t_final, sample_interval, tolerances)


# The IFToMM benchmark library's A01 (M. Gonzalez, D. Dopico, U. Lugris, J. Cuadrado, "A benchmarking
# system for MBS simulation software", Multibody System Dynamics 16 (2006) 179-190; problem A01,
# lim.ii.udc.es/mbsbenchmark): a 1 kg lumped mass on a massless 1 m link, gravity 9.81 along -y,
# released at rest from the horizontal (P1 at x = +1 m), motion in the x-y plane; the library's
# horizon is 2000 s and its error bounds on P1's coordinates 1e-3 m (high precision) and 1e-1 m.
A01_SPHERE_RADIUS = 1e-3  # m: the lumped mass as a 1 mm solid ball (inertia 2/5 m r^2 = 4e-7 kg m^2)


@case(tags=("variant", "jointed", "gravity", "benchmark-library"), units=UNITS,
      positive=("length", "mass", "radius", "gravity", "sample_interval"))
def pendulum_a01(length=1.0, mass=1.0, radius=A01_SPHERE_RADIUS, gravity=9.81, theta0=np.pi / 2, rate0=0.0,
                 t_final=10.0, sample_interval=0.01):
    """The IFToMM library's simple pendulum A01 in its own frame (gravity along -y, swinging in the
    x-y plane from P1 = (1, 0, 0) m at rest), over 10 s (the library's horizon is 2000 s).

    Engines need a body with a positive definite inertia, so the library's point mass is a
    solid ball of ``radius`` 1 mm (2/5 m r^2 = 4e-7 kg m^2). That raises the moment about the
    pivot from m L^2 = 1 to 1.0000004 kg m^2 and lengthens the period by 2.0e-7 relative (of its
    2.3678 s; closed form): P1 lags the point mass by at most 8.7e-6 rad, i.e. 8.7e-6 m, over
    the 10 s (115 times below the library's high-precision bound, 1e-3 m), and by 1.8e-3 m over
    the library's 2000 s (``t_final=2000``: then above that bound, which the library's point-mass
    reference data would show). The truth here is the ball's own motion (closed form), exact for
    the body simulated; ``radius=0`` is refused (no engine accepts a zero inertia).
    """
    sphere = Body("mass", mass, np.eye(3) * 0.4 * mass * radius**2)
    tolerances = dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=Tolerance(1e-7, "m; P1 moves on a circle "
                      "of 1 m: ANGLE_TOL times the radius"), velocity=VELOCITY_TOL, angular_velocity=RATE_TOL,
                      reaction_force=REACTION_TOL, energy=ENERGY_TOL)
    return _pendulum_case("pendulum_a01", sphere, length, (0.0, -1.0, 0.0), (0.0, 0.0, 1.0), gravity, theta0, rate0,
                          t_final, sample_interval, tolerances)


stability_map(
    "pendulum_map", case="pendulum", parameter="theta0", values="lin:0.5,3.0,6", bracket=(1e-4, 1e-1),
    params=dict(t_final=5.0, sample_interval=0.1),
    reason="amplitudes from a near-linear swing (0.5 rad) to 0.14 rad below the top, where the period grows "
           "without bound; 5 s holds about three swings; the 0.1-s samples let steps up to 0.1 s divide them")
