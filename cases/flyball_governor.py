"""The stiff flyball governor: a spinning shaft, a slider on it, two rods hinged at its top with a 5-kg ball at
each far end, and two stiff, strongly damped spring-dampers from the slider to the rods' middles (the IFToMM
library of computational benchmark problems, problem A05; Watt's governor with its coupler rods replaced by
spring-dampers).

Sources (every number below comes from one of them, or is marked as this case's own):

* [A05-CPP] the benchmark's OpenSim model in the repository RehabEngGroup/MBSbenchmarksInOpenSim,
  ``src/A05-FlyballGovernor/createModel.cpp`` and ``modelProperties.h``: gravity (0, 0, -9.81) m/s^2 (its
  ``setGravity``; the header's -y ``gravityVector`` is unused), density 3000 kg/m^3, the bodies, joints,
  initial coordinates and spring-dampers below, the shaft's initial rate 2 pi rad/s (``defaultSpeed``);
* [A05-OS] the same repository's ``help/benchmarks/A05_FlyballGovernor.rst`` (the table: shaft and rods
  1.0 x 0.01 x 0.01 m, slider 0.1 m cube, 5-kg point masses, K = 8e5 N/m, C = 4e4 N s/m, rest length 0.5 m,
  s = 0.5 m, alpha = 30 degrees, omega = 2 pi rad/s; a 10-s simulation) and its figure
  ``help/images/A05_kinematics.png``, OpenSim's s(t) over 10 s against the library's reference solution
  (curves only, no numbers; read below);
* [A05-SIM] ``data/A05-FlyballGovernor/simulationParameters.txt`` of the same repository: 10 s, reported every
  0.1 s (OpenSim's CPodes at accuracy 1e-6);
* the library's own specification, http://lim.ii.udc.es/mbsbenchmark/dist/A05/A05_specification.xml: only its
  header was readable, so no number here is taken from it directly.

Geometry ([A05-CPP]; world axes with z up, the shaft's axis). Bodies (every inertia a solid box of the given
edges, OpenSim's ``Inertia::brick`` of the half edges):

    shaft   1 x 0.01 x 0.01 m (long along z), 0.3 kg; revolute to the world about z at its bottom end, the
            world origin (its COM at z = 0.5 m), turning at 2 pi rad/s
    slider  0.1 m cube, 3 kg; prismatic on the shaft along z from the shaft's bottom end: s = 0.5 m puts its
            COM at z = 0.5 m; at rest relative to the shaft
    rod1    1 x 0.01 x 0.01 m, 0.3 kg, hinged to the shaft's top at (0.05, 0, 1) m about the shaft's -y axis
            (OpenSim's pin frame: the shaft frame turned by pi/2 about x), coordinate -2 pi / 3: the rod points
            outward along +x and 30 degrees below the horizontal (alpha); a 5-kg point mass welded at its far end
    rod2    its mirror image: hinged at (-0.05, 0, 1) m, coordinate +2 pi / 3, pointing along -x
    springs k = 8e5 N/m, c = 4e4 N s/m, rest length 0.5 m, from the slider's points (+-0.05, 0, 0) (its body
            frame) to each rod's middle: at the initial position both are exactly 0.5 m long (the pivot, the
            slider point and the rod's middle form an equilateral triangle of side 0.5 m with the shaft's line
            at 60 degrees), so they start at rest length and unloaded.

The joints' coordinates are [A05-CPP]'s own: the shaft's angle (rad), the slider's s (m), and each rod's pin
angle about the shaft's -y (rad, -2 pi / 3 and +2 pi / 3 at the start). [A05-CPP]'s spring-damper is an
``ExpressionBasedPointToPointForce`` of ``k (d - 0.5) + c d'`` (d the distance): OpenSim applies a positive
value as a tension (``ExpressionBasedPointToPointForce::computeForce``, opensim-core, pulls body 1's point
towards body 2's), the scene's ``Spring`` exactly.

The point masses, folded into their rods (this case's choice). [A05-CPP] welds a body of zero inertia to each
rod's far end; a weld makes one rigid body of the two, so each rod here is that body: 5.3 kg, its COM
``ROD_COM`` = 0.9717 m from the pivot along the rod, its inertia the bar's plus the point's by the
parallel-axis theorem (about the rod's own axis only the bar's 5e-6 kg m^2: positive definite). The motion is
the same; only the rod's reported COM is the union's, and no engine has to take a body of zero inertia.

The motion. The shaft's spin throws the balls out; the rods swing up, the stiff springs drag the slider up the
shaft, and the spin falls as the balls' moment of inertia grows (angular momentum about z is conserved: gravity
is along z and the world's revolute is about z). Measured on the truth over the library's 10 s: s swings
between 0.4999 m and 0.7436 m, peaks at 0.51, 1.54, 2.56, ..., 9.73 s (period 1.025 s), troughs at 1.02, 2.05,
..., 9.22 s, and the shaft's rate between 6.283 and 5.103 rad/s; the dampers take little energy (the springs
stretch by micrometres). The slider stays inside OpenSim's range [0, 1] m ([A05-CPP] clamps s there; the
scene's joint has no limits, and none is reached).

Stiffness. The equations linearised at the start decay at rates up to 8117 1/s (the dampers against the balls'
masses; ``reference.solver.decay_rate``), against the 7.3-rad/s governor motion: an explicit method's steps are
held below its stability bound (RK4: 2.8 / 8117 = 3.4e-4 s; the reference's rk4 at dt = 1e-3 diverges), and the
truth is the reference on Radau (``reference.solver.truth_settings``: Kane at rtol = atol = 1e-12).

Truth accuracy (measured): over 1 s, Radau at 1e-12 and DOP853 at 1e-12 (47513 evaluations, 4x Radau's) agree
to 3.1e-13 (coordinates, rad or m) and 1.3e-12 (rates); over the default 2 s, LSODA at 1e-12 (the contract's
second solution) is within 9.5e-11 (joints), 9.0e-11 m, 4.6e-10 m/s, and the reference's rk4 at dt = 2e-4 within
9.8e-12 (joints) and 6.9e-9 m/s (1e-4: 3.9e-13, 3.0e-10 m/s); the truth keeps L_z to 2.3e-13 relative and its
joints to 6e-16. ``tests/test_flyball_governor.py`` checks the convergence.

Against the published curve ([A05-OS]'s figure, read to its resolution: ~0.005 m and ~0.05 s; its polylines
join the 0.1-s reports of [A05-SIM], so a peak between reports is cut): s starts at 0.5 m, first peaks at ~0.745 m
at ~0.5 s (truth: 0.7432 m at 0.5 s), is back at ~0.50 m at ~1.0 s (0.5014 m), has a flat trough of ~0.505 m
over 2.0-2.1 s (0.5062, 0.5058 m) and another over 6.0-6.2 s (0.5062, 0.5068 m), ten peaks of 0.735-0.745 m in
the 10 s, the last near 9.7 s (9.73 s), and ends falling through ~0.62 m at 10 s (0.620 m): the truth lies on
the published curve everywhere it can be read. ``PUBLISHED_READINGS`` (the default horizon's) are checked in
``tests/test_flyball_governor.py``.

Reactions: judged relative to the largest true reaction of any joint (202 N, at the shaft's pivot). The
slider's joint carries no force at all: the springs pull it along the shaft and, by the mirror symmetry, their
pulls across it cancel (the truth's is 4e-15 N). Measured over 0.5 s against the truth (``dalembert.errors``):
the reference's rk4 at dt = 2e-4 5.4e-7, at 1e-4 2.4e-8; MuJoCo's and Exudyn's rk4 at 1e-4 2.4e-8.

Horizon. The library's 10 s is ``t_final=10`` (its truth takes minutes in the pure-Python reference); the default
2 s (this case's own: two governor cycles, the contract's ``HARD_HORIZON``) costs ~20 s of truth. Tagged
``hard`` (stiff: out of the default matrix; explicit fixed steps must be small).
"""

from __future__ import annotations

import numpy as np

from dalembert import invariants
from dalembert.case import Case, Invariant, Tolerance, case
from dalembert.cases._sampling import sample_times
from dalembert.scene import WORLD, Body, Joint, Scene, Spring

UNITS = dict(t_final="s", sample_interval="s")

# [A05-CPP] / [A05-OS]
DENSITY = 3000.0  # kg/m^3
BAR = (0.01, 0.01, 1.0)  # m: the shaft's and the rods' edges, long along their z
SLIDER_EDGE = 0.1  # m
BALL_MASS = 5.0  # kg
STIFFNESS, DAMPING, REST_LENGTH = 8e5, 4e4, 0.5  # N/m, N s/m, m
SPIN = 2.0 * np.pi  # rad/s: the shaft's initial rate
S0 = 0.5  # m: the slider's initial coordinate
ROD_ANGLE = 2.0 * np.pi / 3.0  # rad: the rods' pin coordinates -+ this (30 degrees below the horizontal)
PIVOT_X, PIVOT_Z = 0.05, 1.0  # m: the rods' pins on the shaft, world at the start (x: +-; z: the shaft's top)
GRAVITY = 9.81  # m/s^2, along -z

BAR_MASS = DENSITY * BAR[0] * BAR[1] * BAR[2]  # 0.3 kg
SLIDER_MASS = DENSITY * SLIDER_EDGE**3  # 3 kg
ROD_MASS = BAR_MASS + BALL_MASS  # 5.3 kg: a rod with its ball (module docstring)
ROD_COM = (BAR_MASS * 0.5 + BALL_MASS * 1.0) / ROD_MASS  # m from the pivot along the rod

# [A05-OS]'s figure read at report times of the default 2 s, (t in s, s in m): the first peak, the first
# trough, the flat second trough (tests/test_flyball_governor.py checks the truth against them).
PUBLISHED_READINGS = ((0.5, 0.745), (1.0, 0.50), (2.0, 0.505))
READING_TOL = 0.005  # m: the figure's resolution, a tenth of its 0.05-m ticks (~3 pixels)

# Tolerances. Measured on the reference against the truth over the default 2 s: LSODA at 1e-12 (the contract's
# second solution) 9.5e-11 (joints), 9.0e-11 m, 9.8e-11 rad, 4.6e-10 m/s, 3.2e-10 rad/s; LSODA at 1e-9 3.4e-8,
# 3.9e-8 m, 4.0e-8 rad, 2.1e-7 m/s, 1.3e-7 rad/s, L_z 1.0e-8; rk4 at dt = 2e-4 9.8e-12, 6.9e-9 m/s; rk4 at
# dt = 5e-4 diverges (its stability bound is 3.4e-4 s).
JOINT_TOL = Tolerance(1e-6, "rad or m over 2 s; the reference's lsoda at 1e-9 meets it (3.4e-8), its rk4 at "
                            "dt = 2e-4 (9.8e-12); at dt = 5e-4 rk4 diverges (stiff)")
POSITION_TOL = Tolerance(1e-6, "m; JOINT_TOL on levers of ~1 m (the balls are 0.92 m from the shaft)")
ORIENTATION_TOL = Tolerance(1e-6, "rad; as JOINT_TOL")
VELOCITY_TOL = Tolerance(1e-5, "m/s; the balls move at up to ~6 m/s: JOINT_TOL times the 7.3-rad/s governor rate, "
                               "with room")
RATE_TOL = Tolerance(1e-5, "rad/s; as VELOCITY_TOL")
BALANCE_TOL = Tolerance(1e-5, "relative to the largest energy; the dampers' dissipation is Simpson's rule on the "
                              "0.01-s samples of their power, 2.3e-6 off on the truth itself")
REACTION_TOL = Tolerance(1e-6, "relative to the largest reaction (202 N at the shaft's pivot): accelerations of "
                               "the same motion; the reference's rk4 at dt = 2e-4 keeps 5.4e-7 (docstring)")
MOMENTUM_TOL = Tolerance(1e-7, "relative to |L_z(0)|; exact (no moment about z): the truth keeps it to 2.3e-13, "
                                "the reference's lsoda at 1e-9 to 1.0e-8")


def vertical_angular_momentum(scene, traj):
    """The angular momentum about the world's z axis through the origin (kg m^2/s, ndarray (n,)): conserved."""
    return invariants.angular_momentum_about(scene, traj, (0.0, 0.0, 0.0))[:, 2]


def _rod(name):
    """A rod with its ball folded in (module docstring): body frame at the union's COM, z along the rod from the
    pivot to the ball."""
    bar = Body.box("bar", BAR_MASS, BAR).inertia_matrix  # about the bar's own COM
    transverse = bar[0, 0] + BAR_MASS * (ROD_COM - 0.5) ** 2 + BALL_MASS * (1.0 - ROD_COM) ** 2
    return Body(name, ROD_MASS, np.diag([transverse, transverse, bar[2, 2]]))


def governor_scene(name="flyball_governor"):
    """The governor (module docstring) at its initial state."""
    bodies = [Body.box("shaft", BAR_MASS, BAR), Body.box("slider", SLIDER_MASS, (SLIDER_EDGE,) * 3),
              _rod("rod1"), _rod("rod2")]
    half = 0.5 * BAR[2]
    pin_axis = (0.0, -1.0, 0.0)  # [A05-CPP]'s pin frames: the shaft's -y
    joints = [
        Joint("revolute", WORLD, "shaft", (0.0,), (SPIN,), axis=(0.0, 0.0, 1.0), child_point=(0.0, 0.0, -half)),
        Joint("prismatic", "shaft", "slider", (S0,), (0.0,), axis=(0.0, 0.0, 1.0), parent_point=(0.0, 0.0, -half)),
        Joint("revolute", "shaft", "rod1", (-ROD_ANGLE,), (0.0,), axis=pin_axis,
              parent_point=(PIVOT_X, 0.0, PIVOT_Z - half), child_point=(0.0, 0.0, -ROD_COM)),
        Joint("revolute", "shaft", "rod2", (ROD_ANGLE,), (0.0,), axis=pin_axis,
              parent_point=(-PIVOT_X, 0.0, PIVOT_Z - half), child_point=(0.0, 0.0, -ROD_COM)),
    ]
    middle = (0.0, 0.0, 0.5 - ROD_COM)  # the rod's middle in its body frame
    springs = [Spring("slider", rod, point_a=(x, 0.0, 0.0), point_b=middle, stiffness=STIFFNESS, damping=DAMPING,
                      rest_length=REST_LENGTH, name=f"spring_{rod}")
               for rod, x in (("rod1", PIVOT_X), ("rod2", -PIVOT_X))]
    return Scene(name, bodies, joints, (0.0, 0.0, -GRAVITY), springs=springs)


@case(tags=("hard", "jointed", "gravity", "prismatic", "spring", "stiff", "published", "iftomm"), units=UNITS,
      positive=("sample_interval",))
def flyball_governor(t_final=2.0, sample_interval=0.01):
    """The stiff flyball governor (IFToMM A05): a shaft spinning at 2 pi rad/s about the vertical, a slider on
    it (prismatic), two rods with 5-kg balls hinged at its top and two spring-dampers (8e5 N/m, 4e4 N s/m)
    from the slider to the rods' middles, released with the springs at rest length. The library simulates 10 s
    (``t_final=10``); the default 2 s is this case's own. The truth is the reference on Radau (stiff); see the
    module docstring for every number's source."""
    scene = governor_scene()
    L0 = abs(float(vertical_angular_momentum(scene, _initial_trajectory(scene))[0]))
    momentum = Invariant("vertical_angular_momentum", "angular momentum about the shaft's axis (world z through "
                         "the origin): no load has a moment about it", "kg m^2/s", L0, MOMENTUM_TOL,
                         vertical_angular_momentum)
    tolerances = dict(joint=JOINT_TOL, position=POSITION_TOL, orientation=ORIENTATION_TOL, velocity=VELOCITY_TOL,
                      angular_velocity=RATE_TOL, reaction_force=REACTION_TOL, energy_balance=BALANCE_TOL)
    return Case("flyball_governor", scene, t_final, sample_times(t_final, sample_interval, "flyball_governor"),
                conserved=("energy_balance",), tolerances=tolerances, invariants=(momentum,))


def _initial_trajectory(scene):
    """The scene's initial state as a one-sample ``Trajectory`` (for the invariants' scales)."""
    from dalembert import spatial
    from dalembert.trajectory import BodyStates, Trajectory

    states = spatial.initial_body_states(scene)
    return Trajectory(np.zeros(1), {name: BodyStates(s["p"][None], spatial.matrix_to_quat(s["R"])[None],
                                                     s["v"][None], s["w"][None]) for name, s in states.items()})
