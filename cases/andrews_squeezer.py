"""Andrews' squeezing mechanism: seven rigid bodies in the plane, closed in three loops at one point,
driven by a constant motor torque against a spring (the IFToMM benchmark A03; problem "andrews" of
the Test Set for IVP Solvers; E. Hairer and G. Wanner, Solving Ordinary Differential Equations II,
Springer 1996, sec. VII.7).

Sources (every number below comes from one of them):

* [TS-R] the Test Set's problem as the R package deTestSet ships it, file
  ``pkg/deTestSet/R/ex_andrews.R`` of the repository ``rforge/bvpsolve`` (commit 8ec2c2f03df2):
  the 42 parameters (masses m1..m7, inertias i1..i7 about the centres of mass, lengths, the fixed
  points xa ya xb yb xc yc, c0 = 4530 N/m, l0 = 0.07785 m, mom = 0.033 N m) and the consistent initial
  values of the seven angles (given there to 30 digits; the mechanism starts at rest);
* [TS-F] the same problem's Fortran, ``pkg/deTestSet/src/Ex_andrews.f`` of the same repository
  (commit 0007f922076d), "derived from the Test Set for IVP solvers" (F. Mazzia, C. Magherini,
  Univ. Bari; file ``andrews.F`` revision 1.2, 2006/10/02): the equations of motion (its mass matrix,
  forces and constraints, which fix the geometry below) and, in ``andsoln``, the reference solution
  at t = 0.03 s ("computed at Cray C90, using Cray double precision [...] PSIDE", tolerances 1e-14);
* [A03] the A03 statement as the IFToMM benchmark page of MBSbenchmarksInOpenSim reproduces it
  (http://rehabenggroup.github.io/MBSbenchmarksInOpenSim/benchmarks/A03_AndrewsMechanism.html): the
  body frames in which it gives each centre of mass (used for body 7, below) and the fixed points.
  Hairer and Wanner's book itself was not at hand: its numbers enter here through [TS-R] and [TS-F],
  which state that they take the problem from it.

Geometry (all in the world's x-y plane, every revolute axis along world z; [TS-F]'s constraints g1..g6
and mass matrix). O is the world origin; A = (xa, ya), B = (xb, yb), C = (xc, yc) are fixed. Each
tree joint's coordinate is one of the published angles, so the comparison with [TS-F] is direct
(``ANGLES``: angle -> the body whose joint it is):

    body1  crank, turns about O by beta; F = O + rr (cos beta, sin beta); COM ra from O towards F
    body2  joined to body1 at F by Theta (absolute angle beta + Theta); E = F - d (cos, sin)(beta + Theta);
           COM da from F towards E
    body3  triangle, turns about B by gamma; in its frame (rotated by gamma) E = B + (0, -ss),
           D = B + (sd, -sc), COM = B + (sb, -sa)
    body5  turns about A by delta; G = A + zt (cos delta, sin delta); COM = A + (ta, tb) in its frame
    body4  joined to body5 at G by Phi (absolute angle Phi + delta); E = G + e (sin, -cos)(Phi + delta);
           COM e - ea from G towards E
    body7  turns about A by epsilon; H = A + u (sin epsilon, -cos epsilon); COM at distance
           sqrt(ua^2 + ub^2) from A
    body6  joined to body7 at H by Omega (absolute angle Omega + epsilon);
           E = H + zf (cos, sin)(Omega + epsilon); COM zf - fa from H towards E

The three loops close at E, where bodies 2, 3, 4 and 6 meet: body2 against body3, body4 and body6
([TS-F]'s g1-g2, g3-g4, g5-g6), each a ``ball`` loop (the tree keeps every body in the plane, so a
ball at E is the planar revolute there, with one redundant row, the out-of-plane one, instead of a
revolute loop's three: 9 rows of rank 6 on 7 joint speeds, one degree of freedom). The spring
(stiffness c0, rest length l0, no damper) joins D on body3 to C; the motor's constant torque mom
turns body1 about +z. No gravity ([TS-F] has none).

Inertias. [TS-F] gives each body's moment about its COM for the in-plane rotation (i1..i7, kg m^2);
every body here is a lamina with that polar moment about z and half of it about the in-plane axes
(``diag(i/2, i/2, i)``: the perpendicular-axis theorem, a valid 3-D inertia). The out-of-plane moments
do not enter the motion: every body turns about z only.

Body 7's centre of mass. [TS-F] uses only its distance from A (body 7 turns about the fixed A, and
there is no gravity): m7 (ua^2 + ub^2). Its direction only moves body 7's reported COM and the
reaction at A; it is placed as [A03]'s table gives it, (-0.00449, -0.01228) = (-ub, -ua) m in a frame
at A with x along A -> H, as that table's rows for O -> F and A -> G are given.

The sign of one ground point ([A03] against [TS-R]). [A03] gives B = (+0.03635, 0.03273) m, [TS-R]
xb = -0.03635 m. Settled by experiment (``tests/test_andrews_squeezer.py``): with xb = -0.03635 the
published initial angles close the three loops to 1.4e-17 m and the motion reaches the published
angles at t = 0.03 s (below); with xb = +0.03635 they leave the loop at E open by 2 |xb| = 0.0727 m,
and no configuration closes at all (a least-squares search over the seven angles from 300 random
starts leaves at least 1.3e-2 m): the mechanism cannot be assembled. This case takes xb = -0.03635.

The published reference (``REFERENCE_T``, ``REFERENCE_ANGLES``, [TS-F] ``andsoln``, 16 digits).
Measured: this case's truth (the reference's Kane formulation with loop multipliers, DOP853 at 1e-12)
and, independently, [TS-F]'s own equations (index 1, scipy's DOP853 at 1e-12 to 1e-14) agree to 1e-11
rad at t = 0.03 s, and both differ from the published angles by up to 1.43e-9 rad (Theta; beta 1.14e-9,
gamma 1.1e-11, Phi and Omega 1.9e-11, delta 6e-13, epsilon 3e-13): 10 significant digits of beta and
Theta. The difference is a time shift: fitting (ours - published) = -rate dt over the seven angles gives
dt = 1.0e-12 s and leaves 2e-13 rad, so the published angles are the motion's at t = 0.03 s + 1.0e-12 s.
Its cause is not known here (an end time accumulated from the 1112 steps in the Cray's arithmetic would
carry an offset of this kind). The published rates and multipliers are less accurate than the angles
(1e-10 and 7e-8 relative against both formulations: algebraic variables of the index-3 DAE).

Not stiff for an explicit method: the truth's DOP853 takes ~310 steps at 1e-12 (~3700 evaluations), and
the reference's RK4 at dt = 1e-5 is within 3e-10 rad of it (deTestSet's manual page,
``pkg/deTestSet/man/ex_andrews.Rd`` of the same repository, calls it "a non-stiff second order
differential algebraic equation of index 3").
Its difficulty is speed: the crank turns 2.5 times in 30 ms (beta' reaches 1140 rad/s, Theta' 1424 rad/s)
and the accelerations reach 5.7e5 rad/s^2, so fixed steps of 1e-3 s or 1e-4 s are useless. An engine
whose adapter does not build both loop closures and spring-dampers declares it unsupported (issue 17);
every engine builds both (tests/test_<engine>_springs.py): MuJoCo and MJX with every integrator,
Pinocchio with every integrator, Exudyn with its two implicit solvers, Drake in discrete mode.
"""

from __future__ import annotations

import numpy as np

from dalembert import invariants, spatial
from dalembert.case import Case, Invariant, Tolerance, case, loop_closure_invariants
from dalembert.cases._sampling import sample_times
from dalembert.scene import Body, Joint, Load, Loop, Scene, Spring

# [TS-R]: the Test Set's parameters (SI units: kg, kg m^2, m, N/m, N m).
PARAMETERS = dict(
    m1=0.04325, m2=0.00365, m3=0.02373, m4=0.00706, m5=0.07050, m6=0.00706, m7=0.05498,
    i1=2.194e-6, i2=4.410e-7, i3=5.255e-6, i4=5.667e-7, i5=1.169e-5, i6=5.667e-7, i7=1.912e-5,
    xa=-0.06934, ya=-0.00227, xb=-0.03635, yb=0.03273, xc=0.014, yc=0.072,
    d=28e-3, da=115e-4, e=2e-2, ea=1421e-5, rr=7e-3, ra=92e-5, ss=35e-3, sa=1874e-5, sb=1043e-5,
    sc=18e-3, sd=2e-2, ta=2308e-5, tb=916e-5, u=4e-2, ua=1228e-5, ub=449e-5, zf=2e-2, zt=4e-2,
    fa=1421e-5, c0=4530.0, l0=7785e-5, mom=33e-3)
# [TS-R]: the consistent initial angles (rad; at rest), in the Test Set's order.
INITIAL_ANGLES = dict(beta=-0.0617138900142764496358948458001, Theta=0.0, gamma=0.455279819163070380255912382449,
                      Phi=0.222668390165885884674473185609, delta=0.487364979543842550225598953530,
                      Omega=-0.222668390165885884674473185609, epsilon=1.23054744454982119249735015568)
# The body whose (tree) joint coordinate each published angle is.
ANGLES = dict(beta="body1", Theta="body2", gamma="body3", Phi="body4", delta="body5", Omega="body6",
              epsilon="body7")
# [TS-F] andsoln: the reference solution at t = 0.03 s, angles (rad) and their rates (rad/s).
REFERENCE_T = 0.03
REFERENCE_ANGLES = dict(beta=0.1581077119629904e+2, Theta=-0.1575637105984298e+2, gamma=0.4082224013073101e-1,
                        Phi=-0.5347301163226948e+0, delta=0.5244099658805304e+0, Omega=0.5347301163226948e+0,
                        epsilon=0.1048080741042263e+1)
REFERENCE_RATES = dict(beta=0.1139920302151208e+4, Theta=-0.1424379294994111e+4, gamma=0.1103291221937134e+2,
                       Phi=0.1929337464421385e+2, delta=0.5735699284790808e+0, Omega=-0.1929337464421385e+2,
                       epsilon=0.3231791658026955e+0)

UNITS = dict(t_final="s", sample_interval="s")

# The mechanism's reach: body1 and body2 end to end, O to E at most (m); and its fastest point speed,
# that reach at the published fastest rate (|Theta'| = 1424 rad/s at 0.03 s): the scales of the closure
# residuals.
REACH = PARAMETERS["rr"] + PARAMETERS["d"]
SPEED = REACH * abs(REFERENCE_RATES["Theta"])

CLOSURE_TOL = Tolerance(1e-10, "relative to the reach (0.035 m; per s: to the reach times 1424 rad/s): the loops "
                               "close to roundoff on the truth (projection after every sample: ~1e-14 m); an "
                               "engine's closure drift is judged against it")
# Measured on the reference at the defaults against the truth (tests/test_andrews_squeezer.py): dop853 at rtol 1e-6
# (69 steps): 1.7e-6 rad, 1.3e-6 rad, 6.4e-9 m, 1.2e-5 m/s, 6.8e-4 rad/s, 1.6e-6 (joint, orientation, position,
# velocity, angular velocity, reaction); at 1e-9 (145 steps): 2.2e-9, 1.8e-9, 9.2e-12, 1.6e-8, 9.1e-7, 4.6e-9;
# rk4 at dt = 1e-5 (3000 steps): 3.1e-10, 2.5e-10, 1.0e-12, 2.2e-9, 1.3e-7, 3.9e-10.
ANGLE_TOL = Tolerance(1e-7, "rad over 30 ms (beta turns 16 rad, Theta 16 rad back): the reference's dop853 meets it "
                            "at rtol 1e-9 (2.2e-9 rad) but not at 1e-6 (1.7e-6 rad), its rk4 at dt = 1e-5 (3.1e-10); "
                            "70 times the published reference's own 1.4e-9 rad")
POSITION_TOL = Tolerance(4e-9, "m; levers of at most the reach, 0.035 m: ANGLE_TOL times the reach (dop853 rtol 1e-6: "
                               "6.4e-9 m, 1e-9: 9.2e-12 m)")
VELOCITY_TOL = Tolerance(1e-6, "m/s; the measured velocity errors are 7 m/s per rad of angle error (rates up to 1424 "
                               "rad/s on levers of centimetres): ANGLE_TOL times that, rounded up (dop853 rtol 1e-9: "
                               "1.6e-8 m/s)")
RATE_TOL = Tolerance(5e-5, "rad/s; the measured rate errors are ~400 rad/s per rad of angle error: ANGLE_TOL times "
                           "that, rounded up (dop853 rtol 1e-9: 9.1e-7 rad/s)")
REACTION_TOL = Tolerance(1e-6, "relative to the largest reaction (333 N at O): accelerations of the same motion, an "
                               "order looser than the angles for engines that take them from constraint forces "
                               "(dop853 rtol 1e-9: 4.6e-9)")
ENERGY_TOL = Tolerance(1e-8, "relative to the largest kinetic energy (1.5 J); exact: kinetic + spring energy - the "
                             "motor's work (the truth keeps it to 1.3e-13; the reference's dop853 to 3.5e-11 at "
                             "rtol 1e-9, not at 1e-6: 1.7e-7)")


def crank_angle(traj, body="body1"):
    """The crank's angle about world z (rad, ndarray (n,)) from its attitude in ``traj``, unwrapped: continuous
    while it turns less than pi between samples (at most 1.4 rad per 1-ms sample on the true motion)."""
    R = spatial.quat_to_matrix(spatial.quat_normalize(traj.bodies[body].quaternion))
    return np.unwrap(np.arctan2(R[:, 1, 0], R[:, 0, 0]))


def energy_with_motor_work(scene, traj):
    """Kinetic + spring energy minus the motor's work since t[0] (J, ndarray (n,)): conserved. The motor's
    torque is constant about the crank's fixed axis (world z), so its work is exactly torque times the angle
    turned, ``mom (beta - beta(0))``, with no quadrature (the built-in ``energy_balance`` integrates the
    sampled power by Simpson's rule: 1.2e-3 of the kinetic energy off on the 1-ms samples)."""
    (motor,) = [ld for ld in scene.loads if ld.body == "body1" and ld.kind == "torque"]  # world z, constant
    beta = crank_angle(traj, motor.body)
    return invariants.total_energy(scene, traj) - motor.vector[2] * (beta - beta[0])


ENERGY = Invariant("energy_with_motor_work", "kinetic + spring energy - the motor's work mom (beta - beta0), the "
                   "crank's angle beta unwrapped from its attitude (world z)", "J", 1.5, ENERGY_TOL,
                   energy_with_motor_work)


def lamina(name, mass, moment):
    """A planar body of ``mass`` (kg) with the polar moment ``moment`` (kg m^2) about its COM along body z:
    ``diag(moment/2, moment/2, moment)``, the perpendicular-axis theorem's lamina (a valid 3-D inertia)."""
    return Body(name, mass, np.diag([0.5 * moment, 0.5 * moment, moment]))


def squeezer_scene(parameters=None, angles=None, name="andrews_squeezer"):
    """The mechanism as a ``Scene`` (module docstring), at rest at ``angles`` (dict, rad; default
    ``INITIAL_ANGLES``) with ``parameters`` (dict; default ``PARAMETERS``)."""
    p = PARAMETERS if parameters is None else parameters
    q = INITIAL_ANGLES if angles is None else angles
    z = (0.0, 0.0, 1.0)
    com7 = np.array([-p["ua"], p["ub"], 0.0])  # [A03]'s (-ub, -ua) in a frame with x along A -> H (= -y here)
    h7 = np.array([0.0, -p["u"], 0.0]) - com7  # H in body7's frame

    def joint(parent, child, angle, parent_point, child_point):
        return Joint("revolute", parent, child, q0=[q[angle]], v0=[0.0], axis=z, parent_point=parent_point,
                     child_point=child_point)

    bodies = [lamina(f"body{k}", p[f"m{k}"], p[f"i{k}"]) for k in range(1, 8)]
    joints = [
        joint("world", "body1", "beta", (0.0, 0.0, 0.0), (-p["ra"], 0.0, 0.0)),  # at O
        joint("body1", "body2", "Theta", (p["rr"] - p["ra"], 0.0, 0.0), (p["da"], 0.0, 0.0)),  # at F
        joint("world", "body3", "gamma", (p["xb"], p["yb"], 0.0), (-p["sb"], p["sa"], 0.0)),  # at B
        joint("world", "body5", "delta", (p["xa"], p["ya"], 0.0), (-p["ta"], -p["tb"], 0.0)),  # at A
        joint("body5", "body4", "Phi", (p["zt"] - p["ta"], -p["tb"], 0.0), (0.0, p["e"] - p["ea"], 0.0)),  # at G
        joint("world", "body7", "epsilon", (p["xa"], p["ya"], 0.0), -com7),  # at A
        joint("body7", "body6", "Omega", h7, (p["fa"] - p["zf"], 0.0, 0.0)),  # at H
    ]
    e_body2 = (p["da"] - p["d"], 0.0, 0.0)
    loops = [Loop("ball", "body2", "body3", point_a=e_body2, point_b=(-p["sb"], p["sa"] - p["ss"], 0.0), name="E_body3"),
             Loop("ball", "body2", "body4", point_a=e_body2, point_b=(0.0, -p["ea"], 0.0), name="E_body4"),
             Loop("ball", "body2", "body6", point_a=e_body2, point_b=(p["fa"], 0.0, 0.0), name="E_body6")]
    spring = Spring("body3", "world", point_a=(p["sd"] - p["sb"], p["sa"] - p["sc"], 0.0), point_b=(p["xc"], p["yc"], 0.0),
                    stiffness=p["c0"], rest_length=p["l0"], name="spring_DC")
    motor = Load("body1", "torque", (0.0, 0.0, p["mom"]), "world")
    return Scene(name, bodies, joints, (0.0, 0.0, 0.0), loads=[motor], loops=loops, springs=[spring])


@case(tags=("variant", "jointed", "loops", "spring", "motor", "published", "iftomm"), units=UNITS,
      positive=("sample_interval",))
def andrews_squeezer(t_final=0.03, sample_interval=1e-3):
    """Andrews' squeezing mechanism (IFToMM A03; the Test Set's "andrews"): seven bodies, three loops
    closing at one point, a spring and a constant motor torque, from rest at the Test Set's consistent
    angles, over its 30 ms (the published reference is at t = 0.03 s). Out of the default matrix (tag
    ``variant``): run it by name. Sampled every ``sample_interval`` (the Test Set's own output grid, 1 ms).
    The energy is not conserved (the motor works on the crank), so the case lists no built-in conserved
    quantity; its declared invariant ``energy_with_motor_work`` (kinetic + spring energy - the motor's
    exact work) is conserved, and so are the loop closures (``loop_residual_position``, ``_velocity``)."""
    scene = squeezer_scene()
    tolerances = dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL, velocity=VELOCITY_TOL,
                      angular_velocity=RATE_TOL, reaction_force=REACTION_TOL)
    return Case("andrews_squeezer", scene, t_final, sample_times(t_final, sample_interval, "andrews_squeezer"),
                tolerances=tolerances,
                invariants=(ENERGY, *loop_closure_invariants("the three ball loops at E", REACH, SPEED, CLOSURE_TOL)))
