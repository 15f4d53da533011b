"""The planar four-bar linkage under gravity: the first closed kinematic loop (``Scene.loops``).

Not registered yet (a private module: ``@case`` would put it in the default matrix and the case
contract): the contract's second solution (scipy's LSODA) and the truth's DOP853 do not get past
the singular position at ``phi = 2 pi`` (see below), so a registered ``four_bar`` waits for the
adaptive integrators to handle it (issue 17). ``tests/test_loops.py`` checks the reference on it
against the closed form with RK4, which passes both singular positions.

Geometry (all bars ``length`` long, the ground too: a parallelogram), in the world's x-z plane
with z up and every joint axis along -y, so an angle turns x towards z:

    A = (0, 0, 0)  crank pivot (world)          D = (length, 0, 0)  rocker pivot (world)
    crank  A -> B,  coupler  B -> C,  rocker  D -> C;  tree: world-crank-coupler, world-rocker;
    loop closure: a revolute between the coupler's tip and the rocker's tip, at C.

Closed form of the parallelogram (derived here, checked in ``tests/test_loops.py``). With the
crank and the rocker equal and the coupler as long as the ground, ``ABCD`` stays a parallelogram:
the rocker turns with the crank (its angle ``phi``, from +x towards +z) and the coupler translates,
every point of it moving with the crank's tip, ``length * phi' (-sin phi, cos phi)``. With ``m`` the
mass of each bar and ``I_A = I_zz + m (length/2)^2`` the crank's (and rocker's) moment about its
pivot, the kinetic and potential energies are

    T = 1/2 (2 I_A + m length^2) phi'^2,        V = g length (m/2 + m/2 + m) sin(phi) = 2 m g length sin(phi)

so Lagrange's equation is that of a physical pendulum in ``theta = phi + pi/2`` (the angle from the
downward vertical):

    (2 I_A + m length^2) theta'' = -(2 m) g length sin(theta)

i.e. ``RigidPendulum(mass=2 m, com_distance=length, inertia_pivot=2 I_A + m length^2)``.

The singular position. At ``phi = pi`` (mod 2 pi) all four bars lie on the ground line; at
``phi = 0`` the coupler lies on the rocker. There the anti-parallelogram branch crosses the
parallelogram one and the loop's Jacobian loses a rank (2 -> 1 of its 5 rows: 3 rows of a 3-D
revolute closing a planar loop are redundant everywhere). From the default start (crank vertical,
6 rad/s) the crank turns over the top and reaches ``phi = pi`` at t = 0.23 s: the default horizon
(0.5 s) passes that singular position once. Longer horizons reach ``phi = 2 pi`` (t ~ 0.6 s), which
the reference's fixed-step integrators pass (RK4 at dt = 1e-3: 4e-12 rad from the closed form over
1 s) but at which scipy's adaptive DOP853, the truth's integrator, stalls (its steps shrink without
end): a horizon beyond 0.55 s is not served by the truth yet (issue 17).

Parameters. The IFToMM library's four-bar problem (A02) is a parallelogram of 1 m, 1 kg bars under
9.81 m/s^2 started from the crank vertical; its exact initial crank rate and horizon are not
verified here, so the defaults (6 rad/s, 0.5 s) are this case's own, not the library's.
"""

from __future__ import annotations

import numpy as np

from dalembert import invariants, spatial
from dalembert.case import Case, Invariant, Tolerance
from dalembert.cases._sampling import sample_times
from dalembert.scene import Body, Joint, Loop, Scene

UNITS = dict(length="m", mass="kg", radius="m", gravity="m/s^2", phi0="rad", rate0="rad/s", t_final="s",
             sample_interval="s")

# Joint frames: x along world x, y along world z, z (the revolute axis) along world -y.
R_WJ = np.column_stack([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

# Measured on the reference at the defaults against the closed form (tests/test_loops.py): RK4
# 4.9e-8 rad at dt = 1e-2 and 4.3e-12 at 1e-3 over 1 s; the truth (DOP853 at 1e-12) against LSODA.
ANGLE_TOL = Tolerance(1e-6, "rad over 0.5 s; the reference's rk4 meets it at dt = 1e-2 (~5e-8), a first-order "
                            "method does not")
POSITION_TOL = Tolerance(1e-6, "m; bars of 1 m: ANGLE_TOL times the largest lever")
VELOCITY_TOL = Tolerance(1e-5, "m/s; rates reach ~9 rad/s: ANGLE_TOL times the rate, with room")
RATE_TOL = Tolerance(1e-5, "rad/s; as VELOCITY_TOL")
REACTION_TOL = Tolerance(1e-5, "relative to the largest reaction; reactions are accelerations of the same motion "
                               "(multipliers and Newton's law), one order looser than the angle")
ENERGY_TOL = Tolerance(1e-7, "relative; exact, the reference's rk4 keeps 2e-8 at dt = 1e-2")
CLOSURE_TOL = Tolerance(1e-10, "the loop closes to roundoff on the truth (projection after every sample: ~1e-14); "
                               "an engine's closure drift is judged against it")


def _closure(level, scale, unit):
    return Invariant(f"loop_residual_{level}", f"largest loop-closure residual at {level} level (the coupler-rocker "
                     f"revolute at C; m, or the sine of the axes' tilt{'' if level == 'position' else ', per s'})",
                     unit, scale, CLOSURE_TOL, lambda scene, traj: invariants.loop_residual(scene, traj, level))


def four_bar(length=1.0, mass=1.0, radius=0.01, gravity=9.81, phi0=np.pi / 2, rate0=6.0, t_final=0.5,
             sample_interval=0.01):
    """A parallelogram four-bar (crank, coupler, rocker: uniform rods of ``length`` and ``mass``, ground
    ``length``) under gravity, the crank starting at ``phi0`` from the horizontal at ``rate0``; the
    coupler-rocker revolute closes the loop. See the module docstring for the closed form and the
    singular position it passes. The small ``radius`` gives every rod a positive definite inertia
    (the closed form includes it)."""
    rod = lambda name: Body.cylinder(name, mass, length, radius, axis=0)  # noqa: E731
    q_WJ = spatial.matrix_to_quat(R_WJ)
    half = 0.5 * length
    scene = Scene(
        "four_bar",
        bodies=[rod("crank"), rod("coupler"), rod("rocker")],
        joints=[Joint("revolute", "world", "crank", q0=[phi0], v0=[rate0], axis=[0, 0, 1], parent_quat=q_WJ,
                      child_point=[-half, 0, 0]),
                Joint("revolute", "crank", "coupler", q0=[-phi0], v0=[-rate0], axis=[0, 0, 1],
                      parent_point=[half, 0, 0], child_point=[-half, 0, 0]),
                Joint("revolute", "world", "rocker", q0=[phi0], v0=[rate0], axis=[0, 0, 1],
                      parent_point=[length, 0, 0], parent_quat=q_WJ, child_point=[-half, 0, 0])],
        gravity=[0.0, 0.0, -gravity],
        loops=[Loop("revolute", "coupler", "rocker", point_a=[half, 0, 0], point_b=[half, 0, 0], axis=[0, 0, 1],
                    name="C")],
    )
    tolerances = dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL, velocity=VELOCITY_TOL,
                      angular_velocity=RATE_TOL, reaction_force=REACTION_TOL, energy=ENERGY_TOL)
    return Case("four_bar", scene, t_final, sample_times(t_final, sample_interval, "four_bar"),
                conserved=("energy",), tolerances=tolerances,
                invariants=(_closure("position", length, "m"), _closure("velocity", length * max(abs(rate0), 1.0), "m/s")))


def parallelogram_pendulum(length=1.0, mass=1.0, radius=0.01, gravity=9.81, phi0=np.pi / 2, rate0=6.0):
    """The closed form's pendulum (module docstring): ``(mass, com_distance, inertia_pivot, gravity, theta0,
    rate0)`` for ``dalembert.reference.closed_form.RigidPendulum``, with ``theta = phi + pi/2``."""
    I_A = mass * (3 * radius**2 + length**2) / 12 + mass * (0.5 * length) ** 2
    return 2 * mass, length, 2 * I_A + mass * length**2, gravity, phi0 + np.pi / 2, rate0
