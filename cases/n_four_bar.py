"""The IFToMM A02 N-four-bar: ``n`` parallelogram four-bars in a row under gravity, one degree of freedom,
through its singular flat positions, where the loop Jacobian loses ``n`` rows and the mechanism ``n`` more
degrees of freedom; ``n`` is a parameter (the library's 40, a small default).

Sources (every number below comes from one of them, or is marked as this case's own):

* [A02-SPEC] the library's statement, http://lim.ii.udc.es/mbsbenchmark/dist/A02/A02_specification.xml (IFToMM
  library of computational benchmark problems, Univ. A Coruna, "N four-bar mechanism", M. Gonzalez Castro,
  2005-08-30; its text read through the ``search`` tool): "2N+1 links of 1 m length with a uniformly distributed
  mass of 1 kg", gravity "9.81 N/kg acting in the negative y direction", "a dynamic simulation with a duration of
  20 s", "particularized for N=40", "the velocity of the x-coordinate of point B0 is 1 m/s", and "when the
  mechanism reaches the horizontal position, the number of degrees of freedom instantaneously increases from 1
  to N+1". Its reference solution is the time history of B0's position and velocity in a data file,
  ``A02_solution_data.txt``, judged with 400 output steps to 1e-1 (low precision) or 1e-3 (high); that file
  was not found in any stored corpus, so no number of it is used here;
* [A02-OS] the same problem as RehabEngGroup/MBSbenchmarksInOpenSim reproduces it:
  ``help/images/2MBS_N-FourBar.png`` (the library's figure: the initial position, rockers ``A_i B_i`` vertical
  and couplers ``B_{i-1} B_i`` horizontal, the axes' origin at ``A_0``, x along the ground row, y up),
  ``src/A02-NFourBarMechanism/createModel.cpp`` and ``modelProperties.h`` (links of 1 m and 1 kg with the
  inertia of a slender rod, ``Inertia::cylinderAlongY(0, L/2)``, the first rocker's rate -1 rad/s about z,
  i.e. B0 moving along +x at 1 m/s, g = (0, -9.81, 0)), and ``help/images/A02_kinematics.png`` (B0's x
  position and x velocity over 10 s, an OpenSim run against a curve labelled the library's reference).

Geometry ([A02-OS]'s figure; world axes as the library's, x along the row and y up, no rotation to this
project's habit of z up). Rockers ``rocker0 .. rocker<n>`` pivot on the ground at ``A_i = (i L, 0, 0)``;
coupler ``coupler<i>`` (i = 1..n) hangs in the tree from rocker i-1's tip ``B_{i-1}`` and the loop ``B<i>`` (a
revolute about z) closes its far end on rocker i's tip ``B_i``. Every body frame has x along its link, every
joint axis is world z, so every rocker's joint angle is ``phi``, the angle from +x towards +y, and every
coupler's is ``-phi`` (it stays along +x). B0 is rocker0's tip, ``(L cos phi, L sin phi, 0)``.

Start ([A02-SPEC], [A02-OS]): ``phi = pi/2`` (rockers vertical), B0's x velocity ``vx0`` = 1 m/s, so
``phi' = -vx0 / L``.

The truth: the closed form (``cases._parallelogram``, derived there). Every window stays a parallelogram, the
rockers turn together and the couplers translate: a physical pendulum in ``theta = phi + pi/2`` with

    T = 1/2 ((n+1) I_A + n m L^2) phi'^2,   V = (3n+1)/2 m g L sin(phi),   I_A = m (3 r^2 + L^2)/12 + m L^2/4.

Measured on it (``scipy.optimize.brentq`` on its angle, defaults but ``n``): B0 reaches the first flat position
(``phi = 0``, every link on the ground line, B0 at x = 1 m) at t = 0.71436 s (n = 2), 0.71793 s (n = 4),
0.72159 s (n = 40), the second (``phi = -pi``, B0 at x = -1 m) at 1.22817, 1.23599, 1.24403 s; one turn takes
1.94253, 1.95391, 1.96561 s. The mechanism goes over the top every turn (it starts there, moving), so over
[A02-SPEC]'s 20 s it passes about 20 flat positions.

Defaults (this case's own): n = 2 ([A02-OS]'s N) and 1 s, which passes the first flat position (0.714 s). Not
further: the contract checks a closed form against the reference's DOP853 at rtol = 1e-12
(``testing.check_reference_agrees``), whose steps collapse at a flat position (as at ``four_bar``'s second,
``reference.integrators.MAX_STEPS_PER_INTERVAL``): measured, with n = 2 it passes the first and stalls at the
second (1.2282 s); with n = 4 it stalls at the first (0.7179 s). The truth is the closed form, so any horizon and
any n run through the harness (``--param n=40 --param t_final=20``); only the contract's check needs the default.

The slender rods. [A02-OS] gives every link the inertia of a line (no radius); engines need a positive definite
inertia, so each link is a cylinder of ``radius`` 0.01 m (this case's own, as ``four_bar``'s), which the
closed form includes. It lengthens a turn by 1.3e-5 s (n = 40) and moves B0 at 20 s by 2e-4 m from the
slender line's value (``radius=0`` is refused: a massless axis is not a rigid body every engine takes).

Redundancy and rank (``Scene.loop_summary``, tests/test_n_four_bar.py). Each loop's revolute gives 5 rows on
the tree's 2n+1 joint speeds; the 3 out-of-plane rows of each are redundant (a planar mechanism closed by 3-D
revolutes, as in ``four_bar``), and the 2n planar rows have full rank away from the flat positions: 5n rows, rank
2n, 3n redundant, 1 degree of freedom (Gruebler in the plane: 3 (2n+1) - 2 (3n+1) = 1). At a flat position
the rank drops to n: n+1 degrees of freedom, as [A02-SPEC] says.

Reactions. In the plane they are determined away from the flat positions, so the truth carries them
(``reaction_force:rocker<i>`` ON rocker i at its pivot, ``reaction_force:coupler<i>`` ON coupler i at
``B_{i-1}``, ``reaction_force:B<i>`` the loop's ON rocker i at ``B_i``; world, N). But for n >= 2 their
horizontal components grow as ``1 / sin(phi)`` near the flat positions (``cases._parallelogram``: the inner
rockers carry two couplers and the outer ones one, and only the couplers' horizontal forces, whose lever
vanishes there, can make them turn alike), so their size at a sample depends on how near it falls to a
singular instant, and any solver's multipliers there are ill-conditioned. A relative error "to the largest
true reaction" would then measure the sampling, not the engine: the case gives no ``reaction_force``
tolerance; reactions are stored and reported, not judged (``four_bar``, n = 1, judges its bounded ones).

Engines (measured: ``dalembert run --case n_four_bar``, defaults, every installed engine, integrator and
default step; the largest position error over 1 s, best run per engine): reference 4.6e-15 m (DOP853),
Pinocchio 5.2e-12 (RK45 at 1e-9), MJX 3.4e-8 (RK4, dt = 1e-3, float64), MuJoCo 8.1e-8 (RK4, dt = 1e-3), Exudyn
2.2e-6 (trapezoidal-index2, dt = 1e-3), Drake 3.8e-6 (discrete, dt = 1e-3). Every run that finished passed the
flat position on the parallelogram branch (rocker0 at -1.767 rad at 1 s, as the closed form); one run failed
there: Exudyn's generalized-alpha at dt = 1e-3 with ``joints=redundant node=ep`` stops at t = 0.714286 s, the
flat instant (0.71436 s), "SolveDynamic terminated". The library's n (``--param n=40 --engine reference --engine
pinocchio --integrator rk4 --dt 1e-2``, 1 s): both 4.95e-8 m from the closed form, through the flat position; the
reference's Kane formulation steps 81 bodies and 40 loops at ~65 s of wall time per simulated second, Pinocchio ~3 s.

[A02-OS]'s kinematics figure. Its black curve (the library's reference, by its legend) was compared with this
closed form drawn on the figure's own axes (its frame spans t = 0..10 s over pixels 100..720 and 2..-7 over
pixels 60..540): for each pixel column, the distance from the closed form's B0 x and x velocity to the nearest
black pixel. With n = 2 the median is 0.3 px (94 % of columns within 2 px, a pixel being 0.016 s or 0.019 m/s);
with n = 40, 4.9 px (28 %): the figure's reference is an n = 2 motion (its OpenSim model has 2 windows),
and says nothing of n = 40's. The figure is not a data source: no test reads it.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case, loop_closure_invariants
from dalembert.cases._parallelogram import ParallelogramChain, rod_pivot_inertia
from dalembert.cases._sampling import sample_times
from dalembert.scene import WORLD, Body, Joint, Loop, Scene, SceneError
from dalembert.trajectory import BodyStates, JointStates, Trajectory

UNITS = dict(n="windows", length="m", mass="kg", radius="m", gravity="m/s^2", vx0="m/s", t_final="s",
             sample_interval="s")

# [A02-SPEC]: the library's N.
LIBRARY_N = 40

# Measured on the reference at the defaults (n = 2, 1 s, the first flat position included) against the closed form
# (tests/test_n_four_bar.py): RK4 5.4e-8 rad at dt = 1e-2 and 3.4e-9 at 5e-3 (16-fold: its order), DOP853 at
# 1e-12 2.3e-14 rad; explicit Euler at dt = 1e-3 3.7e-6 rad and 5.7e-3 m/s.
ANGLE_TOL = Tolerance(1e-6, "rad over 1 s through a flat position; the reference's rk4 meets it at dt = 1e-2 "
                            "(5.4e-8), its euler at 1e-3 does not (3.7e-6)")
POSITION_TOL = Tolerance(1e-6, "m; links of 1 m: ANGLE_TOL times the largest lever")
VELOCITY_TOL = Tolerance(1e-5, "m/s; the rockers reach 6.8 rad/s: ANGLE_TOL times the rate, with room (reference "
                               "rk4 at dt = 1e-2: 3.7e-7 m/s)")
RATE_TOL = Tolerance(1e-5, "rad/s; as VELOCITY_TOL (reference rk4 at dt = 1e-2: 9.7e-8 rad/s)")
ENERGY_TOL = Tolerance(1e-7, "relative (|E(0)| = 35.8 J at n = 2); exact, the reference's rk4 keeps 1.6e-8 at "
                             "dt = 1e-2, its euler at 1e-3 2.5e-3")
CLOSURE_TOL = Tolerance(1e-10, "the loops close to roundoff on the truth and on the reference (projection after "
                               "every sample: ~1e-14 m); an engine's closure drift is judged against it")
# The fastest rocker rate (rad/s) over a turn, at the bottom: sqrt(2 (T0 + 2 V_top) / I), 6.93 (n = 1) to
# 6.73 (n = 40) for the library's start; the velocity closure's scale is the link length times it.
FASTEST_RATE = 7.0


def rockers(n):
    """The rockers' body (and joint) names, ``rocker0 .. rocker<n>``."""
    return [f"rocker{i}" for i in range(n + 1)]


def couplers(n):
    """The couplers' body (and joint) names, ``coupler1 .. coupler<n>``."""
    return [f"coupler{i}" for i in range(1, n + 1)]


def n_four_bar_scene(n, length=1.0, mass=1.0, radius=0.01, gravity=9.81, phi0=np.pi / 2, rate0=-1.0,
                     name="n_four_bar"):
    """The row of ``n`` windows (module docstring) with every rocker at ``phi0`` (rad, from +x towards +y)
    turning at ``rate0`` (rad/s), links of ``length`` (m), ``mass`` (kg) and ``radius`` (m), gravity
    ``gravity`` (m/s^2) along -y."""
    if not (isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 1):
        raise SceneError(f"case {name!r}", [f"n: must be a whole number of windows >= 1, got {n!r} — the library's "
                                            f"is {LIBRARY_N}"])
    n, half = int(n), 0.5 * length
    rod = Body.cylinder("rocker0", mass, length, radius, axis=0)  # along body x
    bodies = [Body(nm, rod.mass, rod.inertia) for nm in rockers(n) + couplers(n)]
    joints = [Joint("revolute", WORLD, r, q0=[phi0], v0=[rate0], axis=[0.0, 0.0, 1.0],
                    parent_point=[i * length, 0.0, 0.0], child_point=[-half, 0.0, 0.0])
              for i, r in enumerate(rockers(n))]
    joints += [Joint("revolute", f"rocker{i - 1}", f"coupler{i}", q0=[-phi0], v0=[-rate0], axis=[0.0, 0.0, 1.0],
                     parent_point=[half, 0.0, 0.0], child_point=[-half, 0.0, 0.0]) for i in range(1, n + 1)]
    loops = [Loop("revolute", f"coupler{i}", f"rocker{i}", point_a=[half, 0.0, 0.0], point_b=[half, 0.0, 0.0],
                  axis=[0.0, 0.0, 1.0], name=f"B{i}") for i in range(1, n + 1)]
    return Scene(name, bodies=bodies, joints=joints, gravity=(0.0, -float(gravity), 0.0), loops=loops)


def b0(traj, length=1.0):
    """[A02-SPEC]'s point B0 (rocker0's tip) in the world from ``traj``: position ndarray (k, 3), m."""
    s = traj.bodies["rocker0"]
    R_WB = spatial.quat_to_matrix(spatial.quat_normalize(s.quaternion))
    return s.position + R_WB @ np.array([0.5 * length, 0.0, 0.0])


@case(tags=("variant", "jointed", "gravity", "loop", "singular", "published", "iftomm", "scaling"), units=UNITS,
      counts=("n",), positive=("length", "mass", "radius", "gravity", "sample_interval"))
def n_four_bar(n=2, length=1.0, mass=1.0, radius=0.01, gravity=9.81, vx0=1.0, t_final=1.0, sample_interval=0.01):
    """IFToMM A02: ``n`` parallelogram four-bars in a row (``n + 1`` rockers, ``n`` couplers, every link a rod of
    ``length``, ``mass`` and ``radius``) under ``gravity`` along -y, started with the rockers vertical and B0 moving
    along +x at ``vx0``; it turns over the top and lies flat twice a turn. The library's n is 40 (``--param
    n=40``) and its horizon 20 s (``--param t_final=20``); the defaults (2, 1 s) are this case's own. The truth is
    the closed form (``cases._parallelogram``); the module docstring gives every number's source."""
    scene = n_four_bar_scene(n, length, mass, radius, gravity, np.pi / 2, -vx0 / length)
    exact = NFourBar(n, length, mass, radius, gravity, vx0)
    tolerances = dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL, velocity=VELOCITY_TOL,
                      angular_velocity=RATE_TOL, energy=ENERGY_TOL)  # no reaction_force: module docstring
    return Case("n_four_bar", scene, t_final, sample_times(t_final, sample_interval, "n_four_bar"),
                exact=exact.trajectory, conserved=("energy",), tolerances=tolerances,
                invariants=loop_closure_invariants(f"the {n} coupler-rocker revolutes B1..B{n}", length,
                                                   length * FASTEST_RATE, CLOSURE_TOL))


class NFourBar:
    """The row's motion in closed form (``cases._parallelogram.ParallelogramChain`` placed in the x-y plane):
    bodies, joints and reactions. Parameters are ``n_four_bar``'s (windows, m, kg, m, m/s^2, m/s)."""

    def __init__(self, n, length, mass, radius, gravity, vx0):
        self.n, self.length = int(n), float(length)
        self.chain = ParallelogramChain(self.n, length, mass, rod_pivot_inertia(length, mass, radius), gravity,
                                        np.pi / 2, -vx0 / length)

    def trajectory(self, t):
        """The ``Trajectory`` at times ``t`` (ndarray (k,), s): body states (world), joint coordinates and rates,
        and the reactions (module docstring; N, world)."""
        t = np.asarray(t, dtype=float)
        L, k = self.length, len(t)
        phi, rate = self.chain.angle(t), self.chain.rate(t)
        c, s, zero = np.cos(phi), np.sin(phi), np.zeros_like(phi)
        u, n_ = np.stack([c, s, zero], axis=1), np.stack([-s, c, zero], axis=1)
        q_rocker = spatial.quat_from_axis_angle([0.0, 0.0, 1.0], phi)
        w_rocker = np.stack([zero, zero, rate], axis=1)
        bodies, joints = {}, {}
        for i, name in enumerate(rockers(self.n)):
            bodies[name] = BodyStates(0.5 * L * u + [i * L, 0.0, 0.0], q_rocker, 0.5 * L * rate[:, None] * n_, w_rocker)
            joints[name] = JointStates(phi[:, None], rate[:, None])
        for i, name in enumerate(couplers(self.n), start=1):
            bodies[name] = BodyStates(L * u + [(i - 0.5) * L, 0.0, 0.0], np.tile([1.0, 0.0, 0.0, 0.0], (k, 1)),
                                      L * rate[:, None] * n_, np.zeros((k, 3)))
            joints[name] = JointStates(-phi[:, None], -rate[:, None])
        H, G, pivot = self.chain.pin_forces(t)
        to_world = lambda f: np.stack([f[:, 0], f[:, 1], zero], axis=1)  # noqa: E731  (h, v) -> (x, y, z)
        extras = {f"reaction_force:rocker{i}": to_world(pivot[:, i]) for i in range(self.n + 1)}
        for i in range(1, self.n + 1):
            extras[f"reaction_force:coupler{i}"] = to_world(G[:, i - 1])
            extras[f"reaction_force:B{i}"] = to_world(H[:, i - 1])
        return Trajectory(t, bodies, joints, extras)
