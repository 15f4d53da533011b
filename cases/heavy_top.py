"""The heavy symmetric (Lagrange) top on a ball joint under gravity."""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.case import Case, Tolerance, case
from dalembert.cases._fixed_point import (body_spin, inertia_about_pivot, pivoted_scene, pivoted_truth, swing_scales,
                                          vertical_momentum)
from dalembert.cases._sampling import sample_times
from dalembert.reference.closed_form import LagrangeTop
from dalembert.scene import Body, SceneError

# The top frame T of the closed form (axis 3 = the symmetry axis) in the body frame B, whose y
# axis is the symmetry axis: T1 = B z, T2 = B x, T3 = B y.
R_BT = np.column_stack([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])

UNITS = dict(mass="kg", inertia="kg m^2", com_distance="m", gravity="m/s^2", tilt="rad", omega0="rad/s",
             t_final="s", sample_interval="s")


def _heavy_top(name, mass, inertia, com_distance, gravity, tilt, omega0, t_final, sample_interval, tolerances,
               invariant_tolerances):
    """The top: body y is its symmetry axis, the centre of mass ``com_distance`` along it from the
    pivot (the world origin); at t = 0 it is turned by ``tilt`` about world x from the body axes
    (``tilt > 0`` raises the axis) and spins at ``omega0`` (body axes)."""
    moments = np.asarray(inertia, dtype=float)
    if moments[0] != moments[2]:
        raise SceneError(f"case {name!r}", [f"inertia: {tuple(moments)} is not symmetric about body y — a "
                                            "Lagrange top needs I_x = I_z (the closed form covers that top only)"])
    body = Body("top", mass, np.diag(moments))
    c_B = (0.0, float(com_distance), 0.0)
    g = (0.0, 0.0, -float(gravity))
    R0_WB = spatial.so3_exp([float(tilt), 0.0, 0.0])
    w0 = np.asarray(omega0, dtype=float)
    scene = pivoted_scene(name, body, c_B, R0_WB, w0, g)
    I_O = inertia_about_pivot(body, c_B)
    exact = LagrangeTop(mass * gravity * com_distance, I_O[0, 0], I_O[1, 1], R0_WB @ R_BT, R_BT.T @ w0)

    def truth(t):
        t = np.asarray(t, dtype=float)
        return pivoted_truth(body, c_B, g, t, exact.rotation(t) @ R_BT.T, exact.angular_velocity_top(t) @ R_BT.T)

    momentum_tol, spin_tol = invariant_tolerances
    momentum_scale, rate_scale = swing_scales(body, c_B, g)
    return Case(name, scene, t_final, sample_times(t_final, sample_interval, name), exact=truth,
                conserved=("energy",), tolerances=tolerances,
                invariants=(vertical_momentum(g, I_O @ w0, momentum_tol, momentum_scale),
                            body_spin(body.name, (0.0, 1.0, 0.0), w0, spin_tol, rate_scale)))


# Agreement with the closed form (within 3e-15 rad of a 40-digit Taylor integration over the 0.2 s,
# tests/test_closed_forms.py). Measured on the reference at the defaults: rk4 3.6e-1, 3.0e-2, 1.9e-3,
# 4.9e-5 rad at dt = 1e-2, 5e-3, 2.5e-3, 1e-3 (the top turns 1.5 rad per step at 1e-2: 12-fold then
# 15.8-fold per halving); dop853 2.5e-6, 2.4e-9 rad at rtol 1e-6, 1e-9; euler 1.0e-1 rad at 1e-4.
ORIENTATION_TOL = Tolerance(1e-4, "rad over 0.2 s at 150 rad/s (30 rad turned): met by a 4th-order method at "
                                  "dt = 1e-3 (reference rk4: 4.9e-5 rad) but not at 2.5e-3 (1.9e-3 rad), and by "
                                  "adaptive ones at rtol 1e-6 (dop853: 2.5e-6 rad)")
RATE_TOL = Tolerance(1e-2, "rad/s at 150 rad/s: ORIENTATION_TOL times the spin, rounded down (reference rk4 at "
                           "dt = 1e-3: 6.3e-3 rad/s)")
POSITION_TOL = Tolerance(1e-4, "m; the COM is 1 m from the pivot: ORIENTATION_TOL times that distance")
VELOCITY_TOL = Tolerance(1e-3, "m/s; the COM moves at up to ~5 m/s: ORIENTATION_TOL times the rates, doubled "
                               "(reference rk4 at dt = 1e-3: 4.0e-4 m/s)")
REACTION_TOL = Tolerance(1e-4, "relative to the largest pivot reaction; m a - m g of the motion, as accurate as "
                               "the attitude (reference rk4 at dt = 1e-3: 6.4e-5)")
ENERGY_TOL = Tolerance(1e-6, "relative to the kinetic energy (5.3 kJ, mostly spin); reference rk4 at dt = 1e-3: "
                             "8.4e-7, dop853 at rtol 1e-6: 2.8e-7")
MOMENTUM_TOL = Tolerance(1e-4, "relative to |L| about the pivot (99 kg m^2/s); gravity's moment about the pivot is "
                               "horizontal, so the vertical part is exact (reference rk4 at dt = 1e-3: 5.1e-5)")
SPIN_TOL = Tolerance(1e-6, "relative to the initial angular speed; exact: for a symmetric top C w3' = 0 in body "
                           "axes, which the reference's integrators keep to 1e-15 at any step")


@case(tags=("canonical", "jointed", "gravity", "ball"), units=UNITS,
      positive=("mass", "inertia", "com_distance", "gravity", "sample_interval"))
def heavy_top(mass=15.0, inertia=(0.234375, 0.46875, 0.234375), com_distance=1.0, gravity=9.81, tilt=0.0,
              omega0=(0.0, 150.0, -4.61538), t_final=0.2, sample_interval=0.01):
    """The heavy-top benchmark of Terze, Mueller & Zlatar (Multibody System Dynamics 38, 2016),
    as Exudyn's test models run it (TestModels/explicitLieGroupIntegratorTest.py): 15 kg, inertia
    about the centre of mass ``inertia`` with the symmetry axis along body y, the centre of mass
    1 m from the fixed point along it, horizontal at t = 0, spinning at ``omega0`` (body axes).

    The truth is the closed form of the Lagrange top (``LagrangeTop``: cos(theta) in Jacobi elliptic
    functions, precession and spin by quadrature), pivot reaction included. Conserved: the energy,
    the angular momentum about the pivot along the vertical, and the spin about the symmetry axis
    (declared invariants). The -4.61538 rad/s about the vertical is within 4.6e-6 rad/s of
    -C w3 / A (A, C about the pivot), which sends the axis from the horizontal down to within
    7e-7 rad of the downward vertical at t = 0.37 s (``t_final=1`` to see it).
    """
    tolerances = dict(orientation=ORIENTATION_TOL, angular_velocity=RATE_TOL, position=POSITION_TOL,
                      velocity=VELOCITY_TOL, reaction_force=REACTION_TOL, energy=ENERGY_TOL)
    return _heavy_top("heavy_top", mass, inertia, com_distance, gravity, tilt, omega0, t_final, sample_interval,
                      tolerances, (MOMENTUM_TOL, SPIN_TOL))


# Measured on the reference at the nutating defaults (10 s, 7 nutations): rk4 4.7e-3, 1.4e-4, 6.6e-6,
# 1.6e-7 rad at dt = 1e-2, 5e-3, 2.5e-3, 1e-3; dop853 2.7e-4, 1.2e-7 rad at rtol 1e-6, 1e-9; euler diverges
# at 1e-3 and is 2.4 rad off at 1e-4.
NUTATING_ORIENTATION_TOL = Tolerance(1e-6, "rad over 10 s: met by a 4th-order method at dt = 1e-3 (reference rk4: "
                                           "1.6e-7 rad), not at 2.5e-3 (6.6e-6), and by dop853 at rtol 1e-9 "
                                           "(1.2e-7 rad)")
NUTATING_POSITION_TOL = Tolerance(1e-6, "m; the COM is 1 m from the pivot: NUTATING_ORIENTATION_TOL times that")
NUTATING_RATE_TOL = Tolerance(1e-5, "rad/s (and m/s for the COM) at rates up to ~20 rad/s: "
                                    "NUTATING_ORIENTATION_TOL times the rates (reference rk4 at dt = 1e-3: 1.9e-6)")
NUTATING_REACTION_TOL = Tolerance(1e-6, "relative to the largest pivot reaction (reference rk4 at dt = 1e-3: 7.0e-8)")
NUTATING_ENERGY_TOL = Tolerance(1e-8, "relative to the largest kinetic energy (reference rk4 at dt = 1e-3: 2.7e-9)")
NUTATING_MOMENTUM_TOL = Tolerance(1e-6, "relative to sqrt(I m g l) = 47 kg m^2/s, the momentum the swing reaches "
                                        "(reference rk4 at dt = 1e-3: 1.1e-8)")


@case(tags=("variant", "jointed", "gravity", "ball", "nutating"), units=UNITS,
      positive=("mass", "inertia", "com_distance", "gravity", "sample_interval"))
def heavy_top_nutating(mass=15.0, inertia=(0.234375, 0.46875, 0.234375), com_distance=1.0, gravity=9.81,
                       tilt=0.5, omega0=(0.0, 20.0, 0.0), t_final=10.0, sample_interval=0.01):
    """The same top spun slowly (20 rad/s about its axis, no precession) from 29 degrees above the
    horizontal: it falls and nutates strongly, its axis swinging between 29 degrees above the
    horizontal and 10 degrees from the downward vertical, over 7 nutation periods (1.375 s each,
    closed form)."""
    tolerances = dict(orientation=NUTATING_ORIENTATION_TOL, angular_velocity=NUTATING_RATE_TOL,
                      position=NUTATING_POSITION_TOL, velocity=NUTATING_RATE_TOL,
                      reaction_force=NUTATING_REACTION_TOL, energy=NUTATING_ENERGY_TOL)
    return _heavy_top("heavy_top_nutating", mass, inertia, com_distance, gravity, tilt, omega0, t_final,
                      sample_interval, tolerances, (NUTATING_MOMENTUM_TOL, SPIN_TOL))
