"""Bricard's mechanism: five rods and the ground closed in one loop by six revolute joints, a mechanism
that Gruebler's count makes rigid (6 bodies x 6 - 6 joints x 5 = 0 degrees of freedom with the ground)
and that moves with one (the IFToMM library of computational benchmark problems, problem A04).

Sources (every number below comes from one of them, or is marked as this case's own):

* [A04-OS] the A04 statement as MBSbenchmarksInOpenSim reproduces it (repository
  RehabEngGroup/MBSbenchmarksInOpenSim, ``help/benchmarks/A04_BricardsMechanism.rst``; the page
  http://rehabenggroup.github.io/MBSbenchmarksInOpenSim/benchmarks/A04_BricardsMechanism.html): five rods of
  1.0 m and 1.0 kg with a square cross section of 0.1 m, six revolute joints, gravity along -y, simulated for
  10 s; its figure ``help/images/4MBS_Bricard.png`` draws the initial position and names the point P3, and
  ``help/images/A04_kinematics.png`` plots P3's x, y, z over the 10 s against the library's reference solution
  (curves only, no numbers);
* [A04-CPP] the same repository's model, ``src/A04-BricardsMechanism/createModel.cpp`` and
  ``modelProperties.h``: g = (0, -9.81, 0) m/s^2, each rod's inertia that of a solid bar of the square section
  (``Inertia::brick``), the joints' places and axes (below), every coordinate's default value 0 and no initial
  speed (its default-speed line is commented out: the mechanism starts at rest, and the reference curves of
  [A04-OS]'s figure start with zero slope); ``simulate.cpp`` reports P3 as the point (0, -0.5, 0) of its
  ``Link_2`` (the far end of rod 2 here) and ``data/A04-BricardsMechanism/simulationParameters.txt`` gives the
  10-s horizon;
* the library's own specification, http://lim.ii.udc.es/mbsbenchmark/dist/A04/A04_specification.xml
  ("Bricard Mechanism", M. Gonzalez Castro, 2005): only its header was readable through the ``search`` tool,
  not its mechanism description nor its reference solution, so no number here is taken from it directly.

Geometry ([A04-CPP]; world axes with y up, as the library has it: no rotation to this project's habit of z up,
so P3 compares directly with the library's). The rods run along edges of a unit cube from joint 1 to joint 6,
the ground closing joint 6 back to joint 1 (1 m, along z), each joint's axis perpendicular to both members it
joins (points in m, world, at the initial position):

    joint  point          axis   joins
    1      (0, 0, 0)      y      world - rod1 (rod1 along +x)
    2      (1, 0, 0)      z      rod1 - rod2  (rod2 along -y)
    3      (1, -1, 0)     x      rod2 - rod3  (rod3 along +z)
    4      (1, -1, 1)     y      rod3 - rod4  (rod4 along -x)
    5      (0, -1, 1)     z      rod4 - rod5  (rod5 along +y)
    6      (0, 0, 1)      x      rod5 - world (the loop closure, named "joint6")

[A04-OS]'s P3 is the point where rods 2 and 3 meet, joint 3's (1, -1, 0): ``P3_POINT`` below. [A04-CPP] builds
rod 5 from two half rods (0.5 m, 0.5 kg each) welded at its middle; one rod of 1 m and 1 kg here is the same body.

Every joint's frame is the world's at the initial position and every rod's body frame too (the rods' long
axes are then x, y, z, x, y), so every joint angle starts at 0 and turns about the table's axis; the loop
at joint 6 closes rod5 to the world.

Inertia. [A04-CPP] gives each rod the inertia of a solid bar with a 0.1 m square section: ``Body.box`` of
(1.0, 0.1, 0.1) m along the rod. (A cylinder of radius 0.1/sqrt(3) m has exactly this inertia, axial moment
included: m a^2/6 both ways.)

Redundancy. The loop's revolute gives 5 rows (3 for the point, 2 for the axis) on the tree's 5 joint speeds;
at every position of the motion they have rank 4 (``Scene.loop_summary``): one row is redundant and one
degree of freedom is left, the motion Gruebler's count misses. The reference takes least-squares multipliers
(``reference.loops``), so the redundant row gets none.

Reactions: judged modulo the self-stress. A redundant row means a self-stress: multipliers ``lambda0`` with
``J^T lambda0 = 0`` (the left null vector of the loop's Jacobian), a set of loads the joints can carry without
moving anything, so any multiple of it can be added to every joint's reaction without changing the motion (the
mechanism is statically indeterminate, as a rigid model of it must be). The reference's truth takes the
least-squares (minimum-norm) multipliers; an engine may take any other. The truth carries the self-stress's
joint forces at every sample (``reference.loops.reaction_modes``) and the harness compares reactions modulo it
(``dalembert.errors``). Measured (``dalembert run --case bricard --engine mujoco --engine pinocchio --dt 1e-3
--param t_final=0.5``-style runs, RK4): the reactions differ from the truth's by 1.43 (Pinocchio) and 1.3 (MuJoCo)
of the largest reaction taken whole, and by 7.5e-9 (Pinocchio) and 1.5e-2 (MuJoCo's soft constraints) modulo the
self-stress; ``tests/test_bricard.py`` checks Pinocchio's.

The motion. Released at rest, the mechanism swings under gravity through a symmetric position, where P3 is
near (0, -0.866, -0.5) m, to its mirror position, P3 at (-1, -1, 0) m, at rest again, and back: periodic.
[A04-OS]'s figure of the library's reference solution shows exactly this (P3's x from 1 to -1 and back over
~5 s, its y rising from -1 to ~-0.87 and its z falling from 0 to -0.5 at a quarter period), read from the
figure to ~0.01 m and ~0.05 s: no published number is finer. Measured on this case's truth over the library's
10 s (DOP853 at 1e-12; ``t_final=10``): x(P3) crosses 0 at 1.2479 s and reaches -1 (to 2e-10 m) at
2.4959 s, +1 at 4.9917 s (the period), and P3 passes (0, -0.8660254, -0.4999999) at the quarter period;
energy kept to 7e-14 J of 29.43 J, the loop closed to 3e-15 m (and m/s). ``tests/test_bricard.py`` checks the
default horizon's truth against the figure and the reference's RK4.

Horizon. The library's 10 s is ``t_final=10`` (its truth takes ~50 s: 2836 evaluations per 2 s of DOP853 at
1e-12, each a few ms); the default 1.5 s (this case's own, not the library's) passes the symmetric position
at the quarter period and keeps the truth to ~8 s. Tagged
``variant`` (an IFToMM benchmark set-up, like ``pendulum_a01`` and ``andrews_squeezer``): out of the
default matrix, run by name.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case, loop_closure_invariants
from dalembert.cases._sampling import sample_times
from dalembert.scene import WORLD, Body, Joint, Loop, Scene

UNITS = dict(length="m", mass="kg", section="m", gravity="m/s^2", t_final="s", sample_interval="s")

# [A04-CPP]: the joints' points (world, m, in units of the rod length) and axes (world) at the initial position,
# from the ground pivot (joint 1) round to joint 6; rod k runs from point k-1 to point k, the ground from joint 6
# back to joint 1.
POINTS = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, -1.0, 0.0], [1.0, -1.0, 1.0], [0.0, -1.0, 1.0],
                   [0.0, 0.0, 1.0]])
AXES = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0],
                 [1.0, 0.0, 0.0]])
RODS = ("rod1", "rod2", "rod3", "rod4", "rod5")
# [A04-OS]'s P3: the far end of rod 2 (where rod 3 is hinged), in rod2's body frame (m per unit rod length).
P3_BODY, P3_POINT = "rod2", np.array([0.0, -0.5, 0.0])

# The truth keeps the closure at roundoff (measured in tests/test_bricard.py); an engine's drift is judged
# against this.
CLOSURE_TOL = Tolerance(1e-10, "the loop closes to roundoff on the truth (projection after every sample: ~1e-15); "
                               "an engine's closure drift is judged against it")
# Measured on the reference against the truth (DOP853 at 1e-12) over 2 s: rk4 at dt = 1e-2 2.0e-8 rad, 2.0e-8 m,
# 3.2e-8 m/s, 4.2e-8 rad/s, reactions 3.2e-8, energy 5.9e-9; at 5e-3 1.5e-9 rad; euler at 1e-3 1.3e-3 rad; lsoda at
# 1e-12 (the contract's second solution) 3.0e-10 rad.
ANGLE_TOL = Tolerance(1e-6, "rad over 1.5 s; the reference's rk4 meets it at dt = 1e-2 (2e-8), its euler at 1e-3 "
                            "does not (1.3e-3)")
POSITION_TOL = Tolerance(2e-6, "m; ANGLE_TOL times the largest lever (the mechanism spans sqrt(2) m from a pivot)")
VELOCITY_TOL = Tolerance(1e-5, "m/s; the rods' COMs move at up to 1.7 m/s and the joints turn at up to 2.2 "
                               "rad/s: ANGLE_TOL times them, with room")
RATE_TOL = Tolerance(1e-5, "rad/s; as VELOCITY_TOL")
REACTION_TOL = Tolerance(1e-6, "relative to the largest reaction, modulo the self-stress (module docstring): "
                               "accelerations of the same motion; the reference's rk4 at dt = 1e-2 keeps 3.2e-8")
ENERGY_TOL = Tolerance(1e-7, "relative (to |E(0)| = 29.43 J); exact (no dissipation: [A04-OS] judges runs by "
                             "the energy's variation), the reference's rk4 keeps 5.9e-9 at dt = 1e-2")
# The joints' fastest rate (rad/s; measured on the truth over 2 s, past the quarter period: 2.23): the velocity
# closure's scale is the rod length times it.
FASTEST_RATE = 2.2


def p3(traj, length=1.0):
    """[A04-OS]'s point P3 (the far end of rod 2) in the world, ndarray (n, 3), m, from ``traj``'s rod2."""
    states = traj.bodies[P3_BODY]
    R_WB = spatial.quat_to_matrix(spatial.quat_normalize(states.quaternion))
    return states.position + R_WB @ (P3_POINT * length)


def bricard_scene(length=1.0, mass=1.0, section=0.1, gravity=9.81, name="bricard"):
    """The mechanism (module docstring) at rest in its initial position: rods of ``length`` (m), ``mass`` (kg)
    and square ``section`` (m), gravity ``gravity`` (m/s^2) along -y."""
    points = POINTS * length
    coms = 0.5 * (points[:-1] + points[1:])  # rod k between points k-1 and k
    bodies = []
    for k, rod in enumerate(RODS):
        size = np.full(3, float(section))
        size[np.flatnonzero(points[k + 1] - points[k])[0]] = length  # the rod's long axis, a world axis
        bodies.append(Body.box(rod, mass, size))
    joints = [Joint("revolute", WORLD, RODS[0], q0=[0.0], v0=[0.0], axis=AXES[0], parent_point=points[0],
                    child_point=points[0] - coms[0])]
    joints += [Joint("revolute", RODS[k - 1], RODS[k], q0=[0.0], v0=[0.0], axis=AXES[k],
                     parent_point=points[k] - coms[k - 1], child_point=points[k] - coms[k]) for k in range(1, 5)]
    closure = Loop("revolute", WORLD, RODS[4], point_a=points[5], point_b=points[5] - coms[4], axis=AXES[5],
                   name="joint6")
    return Scene(name, bodies=bodies, joints=joints, gravity=(0.0, -float(gravity), 0.0), loops=[closure])


@case(tags=("variant", "jointed", "gravity", "loop", "redundant", "published", "iftomm"), units=UNITS,
      positive=("length", "mass", "section", "gravity", "sample_interval"))
def bricard(length=1.0, mass=1.0, section=0.1, gravity=9.81, t_final=1.5, sample_interval=0.01):
    """Bricard's mechanism (IFToMM A04): five rods of ``length`` and ``mass`` with a square ``section``,
    hinged end to end from the ground pivot at the origin round a unit cube's edges back to the ground,
    released at rest under ``gravity`` along -y. Six revolute joints on one loop: Gruebler's count says
    rigid, the loop's Jacobian (5 rows, rank 4) leaves one degree of freedom. The library simulates 10 s
    (``t_final=10``); the default 1.5 s is this case's own. The truth is the reference (Kane with
    least-squares loop multipliers, DOP853 at 1e-12); see the module docstring for every number's source."""
    scene = bricard_scene(length, mass, section, gravity)
    tolerances = dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL, velocity=VELOCITY_TOL,
                      angular_velocity=RATE_TOL, reaction_force=REACTION_TOL, energy=ENERGY_TOL)
    return Case("bricard", scene, t_final, sample_times(t_final, sample_interval, "bricard"), conserved=("energy",),
                tolerances=tolerances,
                invariants=loop_closure_invariants("the rod5-ground revolute at joint 6", length,
                                                   length * FASTEST_RATE, CLOSURE_TOL))
