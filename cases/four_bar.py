"""The planar four-bar linkage under gravity: the first closed kinematic loop (``Scene.loops``).

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

Reactions (the case's truth carries them). With ``L = length``, ``u = (cos phi, 0, sin phi)`` along
the crank, ``n = (-sin phi, 0, cos phi)``, ``I = 2 I_A + m L^2`` and ``alpha = phi''``: the crank's
and rocker's COMs accelerate as ``a_rod = L/2 (alpha n - phi'^2 u)``, the coupler as
``a_cp = L (alpha n - phi'^2 u)``. Unknowns: ``F_B``, the force of the crank ON the coupler at B,
and ``F_C``, the loop's force ON the rocker at C (so ``-F_C`` on the coupler). The coupler does not
turn, so its moments about its COM give ``F_B,z = -F_C,z``, and its vertical balance
``F_C,z = -m (a_cp,z + g) / 2``. The rocker's moments about D give ``L (u x F_C) = I_A alpha +
m g (L/2) cos phi`` (planar cross product, positive from x to z), which with Lagrange's equation
(``alpha = -2 m g L cos(phi) / I``) is, free of the division by ``sin phi`` it seems to need,

    F_C,x = m L phi'^2 cos(phi) / 2 - m^2 g L^2 cos(phi) sin(phi) / I,

and the coupler's horizontal balance gives ``F_B,x = F_C,x + m a_cp,x``. Newton's law on the crank
and the rocker then gives the pivots' forces ON them: ``F_A = m a_rod + m g z + F_B``,
``F_D = m a_rod + m g z - F_C``. Nothing acts out of the plane (y), so every y component is zero.
At ``sin phi = 0`` exactly the split between ``F_B,x`` and ``F_C,x`` is not determined by the
mechanism (only their difference is); the formula is its continuous limit, which is what any
solver's reactions tend to on either side.

The singular positions. At ``phi = pi`` (mod 2 pi) all four bars lie on the ground line; at
``phi = 0`` the coupler lies on the rocker. There the anti-parallelogram branch crosses the
parallelogram one and the loop's Jacobian loses a rank (2 -> 1 of its 5 rows: 3 rows of a 3-D
revolute closing a planar loop are redundant everywhere). From the default start (crank vertical,
6 rad/s) the crank turns over the top and reaches ``phi = pi`` at t = 0.2376 s and ``phi = 2 pi``
at t = 0.6028 s (the closed form): the default horizon (0.5 s) passes the first once.

What the reference's integrators do there (measured, ``reference.integrators``, each sample
interval projected onto the constraint manifolds): the fixed-step ones pass both (RK4 at
dt = 1e-3: 4e-12 rad from the closed form over 1 s). The adaptive ones pass both at rtol = 1e-6 and
1e-9 (DOP853 and LSODA, over 1 s), but at rtol = 1e-12 their steps shrink without end near a
singular position: DOP853 passes ``phi = pi`` and stalls 2e-7 s short of ``phi = 2 pi``, LSODA stalls
6e-9 s short of ``phi = pi``. Such a run ends after a bounded number of steps as a divergence whose
message says so (``integrators.MAX_STEPS_PER_INTERVAL``). Hence the truth is the closed form, at
any horizon, and not the reference solver.

Parameters. The IFToMM library of computational benchmark problems, problem A02 ("N four-bar
mechanism", specification http://lim.ii.udc.es/mbsbenchmark/dist/A02/A02_specification.xml, read
through the ``search`` tool), is an assembly of N four-bar windows of 2N+1 links, each 1 m long
with a uniformly distributed mass of 1 kg, under 9.81 N/kg along -y, simulated for 20 s with N = 40,
the x velocity of point B0 starting at 1 m/s; its initial position is given in a figure that was
not read here. This case is its N = 1 window, with the library's link length, mass and gravity
(here along -z); the initial crank angle (vertical) and rate (6 rad/s) and the 0.5-s horizon are
this case's own, not the library's, and the library's reference solution (for N = 40) is not used.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case, loop_closure_invariants
from dalembert.cases._parallelogram import ParallelogramChain, rod_pivot_inertia
from dalembert.cases._sampling import sample_times
from dalembert.scene import Body, Joint, Loop, Scene
from dalembert.trajectory import BodyStates, JointStates, Trajectory

UNITS = dict(length="m", mass="kg", radius="m", gravity="m/s^2", phi0="rad", rate0="rad/s", t_final="s",
             sample_interval="s")

# Joint frames: x along world x, y along world z, z (the revolute axis) along world -y.
R_WJ = np.column_stack([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

# Measured on the reference at the defaults against the closed form (tests/test_loops.py): RK4
# 4.9e-8 rad at dt = 1e-2 and 4.3e-12 at 1e-3 over 1 s; DOP853 at 1e-12 2e-13 rad over 0.5 s.
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


@case(tags=("canonical", "jointed", "gravity", "loop", "singular"), units=UNITS,
      positive=("length", "mass", "radius", "gravity", "sample_interval"))
def four_bar(length=1.0, mass=1.0, radius=0.01, gravity=9.81, phi0=np.pi / 2, rate0=6.0, t_final=0.5,
             sample_interval=0.01):
    """A parallelogram four-bar (crank, coupler, rocker: uniform rods of ``length`` and ``mass``, ground
    ``length``) under gravity, the crank starting at ``phi0`` from the horizontal at ``rate0``; the
    coupler-rocker revolute closes the loop. See the module docstring for the closed form (the truth)
    and the singular positions it passes. The small ``radius`` gives every rod a positive definite
    inertia (the closed form includes it)."""
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
    exact = ParallelogramFourBar(length, mass, radius, gravity, phi0, rate0)
    tolerances = dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL, velocity=VELOCITY_TOL,
                      angular_velocity=RATE_TOL, reaction_force=REACTION_TOL, energy=ENERGY_TOL)
    return Case("four_bar", scene, t_final, sample_times(t_final, sample_interval, "four_bar"), exact=exact.trajectory,
                conserved=("energy",), tolerances=tolerances,
                invariants=loop_closure_invariants("the coupler-rocker revolute at C", length,
                                                   length * max(abs(rate0), 1.0), CLOSURE_TOL))


def parallelogram_pendulum(length=1.0, mass=1.0, radius=0.01, gravity=9.81, phi0=np.pi / 2, rate0=6.0):
    """The closed form's pendulum (module docstring): ``(mass, com_distance, inertia_pivot, gravity, theta0,
    rate0)`` for ``dalembert.reference.closed_form.RigidPendulum``, with ``theta = phi + pi/2``."""
    p = _chain(length, mass, radius, gravity, phi0, rate0).pendulum
    return p.mass, p.com_distance, p.inertia_pivot, p.gravity, p.theta0, p.rate0


def _chain(length, mass, radius, gravity, phi0, rate0):
    """The one-window ``ParallelogramChain`` (``cases._parallelogram``) of the four-bar's parameters."""
    return ParallelogramChain(1, length, mass, rod_pivot_inertia(length, mass, radius), gravity, phi0, rate0)


class ParallelogramFourBar:
    """The four-bar's motion in closed form (module docstring): bodies, joints and reactions, the one-window
    case of ``cases._parallelogram.ParallelogramChain`` placed in the x-z plane.

    Parameters are ``four_bar``'s (m, kg, m, m/s^2, rad, rad/s).
    """

    def __init__(self, length, mass, radius, gravity, phi0, rate0):
        self.length = float(length)
        self.chain = _chain(length, mass, radius, gravity, phi0, rate0)
        self.pendulum = self.chain.pendulum

    def angle(self, t):
        """Crank (and rocker) angle ``phi`` (rad) from +x towards +z, shape of ``t`` (s); continuous."""
        return self.chain.angle(t)

    def trajectory(self, t):
        """The ``Trajectory`` at times ``t`` (ndarray (n,), s): body states (world), the joints'
        coordinates and rates, and the reactions ``reaction_force:<joint>`` (ON the child) and
        ``reaction_force:C`` (the loop's, ON the rocker), N, world."""
        t = np.asarray(t, dtype=float)
        L = self.length
        phi, rate = self.chain.angle(t), self.chain.rate(t)
        c, s = np.cos(phi), np.sin(phi)
        zero = np.zeros_like(phi)
        u, n = np.stack([c, zero, s], axis=1), np.stack([-s, zero, c], axis=1)
        # joint frames (x along world x, z the axis along -y) turned by phi about their z
        q_rod = spatial.quat_multiply(spatial.matrix_to_quat(R_WJ), spatial.quat_from_axis_angle([0.0, 0.0, 1.0], phi))
        q_coupler = np.tile(spatial.matrix_to_quat(R_WJ), (len(t), 1))
        w_rod = np.stack([zero, -rate, zero], axis=1)  # about world -y
        bodies = {
            "crank": BodyStates(0.5 * L * u, q_rod, 0.5 * L * rate[:, None] * n, w_rod),
            "coupler": BodyStates(L * u + [0.5 * L, 0.0, 0.0], q_coupler, L * rate[:, None] * n, np.zeros((len(t), 3))),
            "rocker": BodyStates(0.5 * L * u + [L, 0.0, 0.0], q_rod, 0.5 * L * rate[:, None] * n, w_rod),
        }
        joints = {"crank": JointStates(phi[:, None], rate[:, None]),
                  "coupler": JointStates(-phi[:, None], -rate[:, None]),
                  "rocker": JointStates(phi[:, None], rate[:, None])}
        H, G, pivot = self.chain.pin_forces(t)
        to_world = lambda f: np.stack([f[:, 0], zero, f[:, 1]], axis=1)  # noqa: E731  (h, v) -> (x, y, z)
        extras = {"reaction_force:crank": to_world(pivot[:, 0]), "reaction_force:coupler": to_world(G[:, 0]),
                  "reaction_force:rocker": to_world(pivot[:, 1]), "reaction_force:C": to_world(H[:, 0])}
        return Trajectory(t, bodies, joints, extras)
