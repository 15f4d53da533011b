"""A chain of N uniform rods on parallel revolute joints under gravity: the double pendulum (N = 2)
and its longer kin, the scaling case."""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case
from dalembert.cases._sampling import sample_times
from dalembert.scene import Body, Joint, Scene, SceneError

UNITS = dict(n="links", length="m", mass="kg", radius="m", gravity="m/s^2", angle0="rad", bend0="rad",
             t_final="s", sample_interval="s")

# The joint frame of the first joint in the world: x down, z (the joint axis) along -y, so the
# chain hangs along -z at zero angles and swings in the x-z plane (as the pendulum does).
_Q_WJ = spatial.matrix_to_quat(np.column_stack([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]))


def chain_scene(name, n, length, mass, radius, gravity, angle0, bend0):
    """``n`` identical rods (``Body.cylinder`` along body x), each hanging from the tip of the one
    above on a revolute joint about the same horizontal axis; the first joint at the world origin
    turned ``angle0`` from the downward vertical, every following joint bent ``bend0`` relative to
    its parent, all at rest. Built in O(n): ``n = 64`` takes milliseconds."""
    if not (isinstance(n, int) and n >= 1):
        raise SceneError(f"case {name!r}", [f"n: must be a whole number of links >= 1, got {n!r}"])
    half = 0.5 * length
    names = [f"link{i}" for i in range(n)]
    rod = Body.cylinder(names[0], mass, length, radius, axis=0)
    bodies = [rod] + [Body(nm, rod.mass, rod.inertia) for nm in names[1:]]
    joints = [Joint("revolute", "world", names[0], q0=[angle0], v0=[0.0], axis=[0.0, 0.0, 1.0],
                    parent_quat=_Q_WJ, child_point=[-half, 0.0, 0.0])]
    joints += [Joint("revolute", names[i - 1], names[i], q0=[bend0], v0=[0.0], axis=[0.0, 0.0, 1.0],
                     parent_point=[half, 0.0, 0.0], child_point=[-half, 0.0, 0.0]) for i in range(1, n)]
    return Scene(name, bodies=bodies, joints=joints, gravity=(0.0, 0.0, -float(gravity)))


# No closed form: the truth is the reference at its truth settings (DOP853 at rtol = atol = 1e-12 on the
# planar formulation, reference.truth_settings), cross-checked by the second formulation, Kane's: over
# the 10 s of the defaults the two agree to 2.1e-11 rad with DOP853 at 1e-12 on both, 6.5e-11 rad with
# LSODA at 1e-12 on Kane's (the contract's second solution; tests/test_chain.py).
# Measured on the reference (Kane) at the defaults: rk4 3.2e-6, 2.5e-7, 1.7e-8, 4.4e-10 rad at dt =
# 1e-2, 5e-3, 2.5e-3, 1e-3 (13.2 and 14.8-fold per halving); dop853 5.2e-5, 4.3e-9 rad at rtol 1e-6,
# 1e-9; euler 1.8e-2, 1.8e-3 rad at 1e-3, 1e-4.
ANGLE_TOL = Tolerance(1e-6, "rad over 10 s: met by a 4th-order method from dt = 5e-3 (reference rk4: 2.5e-7 rad) "
                            "but not at 1e-2 (3.2e-6), by dop853 at rtol 1e-9 (4.3e-9); 5e4 times the truth's "
                            "own uncertainty (its two formulations agree to 2.1e-11 rad)")
POSITION_TOL = Tolerance(1e-6, "m; the links' COMs move on arcs of radius <= 1.5 m: ANGLE_TOL times that, rounded "
                               "down")
VELOCITY_TOL = Tolerance(1e-5, "m/s; rates reach ~4 rad/s: ANGLE_TOL times the rates, doubled (reference rk4 at "
                               "dt = 5e-3: 2.4e-7 m/s)")
RATE_TOL = Tolerance(1e-5, "rad/s; as VELOCITY_TOL (reference rk4 at dt = 5e-3: 1.0e-6 rad/s)")
REACTION_TOL = Tolerance(1e-6, "relative to the largest joint reaction; m a - m g of the same motion (reference "
                               "rk4 at dt = 5e-3: 1.8e-7)")
ENERGY_TOL = Tolerance(1e-8, "relative to max(|E(0)|, the largest kinetic energy); reference rk4 at dt = 5e-3: "
                             "1.5e-9, euler at 1e-4: 1.7e-4")


@case(tags=("canonical", "jointed", "gravity", "chain", "scaling"), units=UNITS, counts=("n",),
      positive=("length", "mass", "radius", "gravity", "sample_interval"))
def chain(n=2, length=1.0, mass=1.0, radius=0.01, gravity=9.81, angle0=0.5, bend0=0.5, t_final=10.0,
          sample_interval=0.01):
    """``n`` uniform rods in a revolute chain under gravity, released at rest with the first
    ``angle0`` from the vertical and each next one bent ``bend0`` further: the double pendulum by
    default, a regular (not chaotic) swing; ``n`` is the scaling parameter (``--param n=64``).

    No closed form: the truth is the reference at tight tolerance (``dalembert.reference.truth``),
    cross-checked by a second formulation (see ANGLE_TOL). At small amplitudes the motion tends to
    the linearised normal modes (``closed_form.NormalModes``) to within the amplitude cubed
    (tests/test_chain.py: 2.58 e^3 rad over 5 s for the double pendulum at ``angle0 = bend0 = e``).
    """
    scene = chain_scene("chain", n, length, mass, radius, gravity, angle0, bend0)
    return Case("chain", scene, t_final, sample_times(t_final, sample_interval, "chain"), conserved=("energy",),
                tolerances=dict(joint=ANGLE_TOL, orientation=ANGLE_TOL, position=POSITION_TOL,
                                velocity=VELOCITY_TOL, angular_velocity=RATE_TOL, reaction_force=REACTION_TOL,
                                energy=ENERGY_TOL))


# Released with both rods horizontal, the double pendulum is chaotic: two tight solutions part
# exponentially. Measured, the largest joint-angle difference over the horizon between the planar
# formulation at rtol 1e-13 and Kane's at 1e-12 and 1e-13: 1.4e-9 rad at 10 s, 2.5e-6 at 15 s, 5e-5 at
# 20 s, 0.17 at 30 s, O(1) by 35 s. So the horizon is 10 s, where the truth (planar, DOP853 at 1e-12)
# agrees with Kane's DOP853 at 1e-12 to 1.1e-9 rad and with Kane's LSODA at 1e-12 to 5.5e-8 rad
# (tests/test_chain.py); beyond ~20 s no double-precision solution is a truth.
CHAOTIC_ANGLE_TOL = Tolerance(1e-5, "rad over 10 s of chaos; 180 times the spread of three tight solutions (two "
                                    "formulations, two integrators: 5.5e-8 rad), 1e4 times that of the two "
                                    "formulations under one integrator (1.1e-9)")
CHAOTIC_RATE_TOL = Tolerance(1e-4, "rad/s (and m/s); CHAOTIC_ANGLE_TOL times the rates (up to ~10 rad/s)")
CHAOTIC_REACTION_TOL = Tolerance(1e-5, "relative to the largest joint reaction")
CHAOTIC_ENERGY_TOL = Tolerance(1e-7, "relative; energy is not sensitive to the chaos, only to the integrator")


@case(tags=("hard", "jointed", "gravity", "chain", "chaotic"), units=UNITS, counts=("n",),
      positive=("length", "mass", "radius", "gravity", "sample_interval"))
def chain_chaotic(n=2, length=1.0, mass=1.0, radius=0.01, gravity=9.81, angle0=np.pi / 2, bend0=0.0,
                  t_final=10.0, sample_interval=0.01):
    """The double pendulum released from the horizontal, both rods in line: chaotic. Over its
    10 s two tight reference solutions (two formulations, two tolerances) agree to 1.4e-9 rad;
    by 20 s only to 5e-5 rad, and by 30 s to 0.17 rad, so longer horizons have no truth (see
    CHAOTIC_ANGLE_TOL); tight horizons only."""
    scene = chain_scene("chain_chaotic", n, length, mass, radius, gravity, angle0, bend0)
    return Case("chain_chaotic", scene, t_final, sample_times(t_final, sample_interval, "chain_chaotic"),
                conserved=("energy",),
                tolerances=dict(joint=CHAOTIC_ANGLE_TOL, orientation=CHAOTIC_ANGLE_TOL, position=CHAOTIC_ANGLE_TOL,
                                velocity=CHAOTIC_RATE_TOL, angular_velocity=CHAOTIC_RATE_TOL,
                                reaction_force=CHAOTIC_REACTION_TOL, energy=CHAOTIC_ENERGY_TOL))
