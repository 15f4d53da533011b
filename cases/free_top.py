"""The torque-free asymmetric top (Euler's equations; seed 002, eqs. 27-29)."""

from __future__ import annotations

import numpy as np

from cases._sampling import sample_times
from dalembert.case import Case, Tolerance, case
from dalembert.scene import Body, Joint, Scene
from dalembert.trajectory import BodyStates, Trajectory
from reference.closed_form import TorqueFreeTop

# Agreement with the closed form over the horizon.
ORIENTATION_TOL = Tolerance(1e-7, "rad over 20 s; 5x the roundoff floor of a double-precision integrator on the "
                                  "intermediate-axis start (~2e-8 rad), so no engine is asked for the impossible")
RATE_TOL = Tolerance(1e-6, "rad/s; ORIENTATION_TOL times the spin rate (5 rad/s), doubled")
ENERGY_TOL = Tolerance(1e-10, "relative; a 4th-order method at dt = 1e-3 keeps energy to ~1e-12 over 20 s")
MOMENTUM_TOL = Tolerance(1e-10, "relative; as for energy: |L| in world is an exact invariant")
STILL_TOL = Tolerance(1e-12, "m and m/s; no force acts, the COM must not move at all")

UNITS = dict(inertia="kg m^2", omega0="rad/s", t_final="s", sample_interval="s")


def _top_case(name, inertia, omega0, t_final, sample_interval):
    moments = np.asarray(inertia, dtype=float)
    body = Body("top", 1.0, np.diag(moments))
    scene = Scene(
        name,
        bodies=[body],
        joints=[Joint("free", "world", "top", q0=[0, 0, 0, 1, 0, 0, 0], v0=[0, 0, 0, *omega0])],
        gravity=[0.0, 0.0, 0.0],
    )
    exact = TorqueFreeTop(np.diag(moments), np.asarray(omega0, dtype=float))

    def truth(t):
        t = np.asarray(t, dtype=float)
        zero = np.zeros((len(t), 3))
        return Trajectory(t, {"top": BodyStates(zero, exact.quaternion(t), zero, exact.angular_velocity_world(t))})

    return Case(
        name, scene, t_final, sample_times(t_final, sample_interval, name), exact=truth,
        conserved=("energy", "angular_momentum", "linear_momentum"),
        tolerances=dict(orientation=ORIENTATION_TOL, angular_velocity=RATE_TOL, position=STILL_TOL,
                        velocity=STILL_TOL, energy=ENERGY_TOL, angular_momentum=MOMENTUM_TOL,
                        linear_momentum=STILL_TOL),
    )


@case(tags=("canonical", "free", "torque-free"), units=UNITS)
def free_top(inertia=(1.0, 2.0, 3.0), omega0=(0.1, 0.0, 5.0), t_final=20.0, sample_interval=0.01):
    """Torque-free asymmetric top (unit mass, principal moments ``inertia``),
    a stable spin near the axis of largest moment; ``omega0`` in the body frame."""
    return _top_case("free_top", inertia, omega0, t_final, sample_interval)


@case(tags=("canonical", "free", "torque-free", "intermediate-axis"), units=UNITS)
def free_top_intermediate(inertia=(1.0, 2.0, 3.0), omega0=(1e-3, 5.0, 1e-3), t_final=20.0, sample_interval=0.01):
    """The same top spinning 1e-3 rad/s off the intermediate axis: unstable, it flips."""
    return _top_case("free_top_intermediate", inertia, omega0, t_final, sample_interval)
