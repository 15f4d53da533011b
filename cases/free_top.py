"""The torque-free asymmetric top (Euler's equations: Landau & Lifshitz, Mechanics, sections 36-37)."""

from __future__ import annotations

import numpy as np

from dalembert.cases._sampling import sample_times
from dalembert.case import Case, Tolerance, case
from dalembert.scene import Body, Joint, Scene
from dalembert.trajectory import BodyStates, Trajectory
from dalembert.reference.closed_form import TorqueFreeTop
from dalembert.maps import stability_map

# Agreement with the closed form over the horizon.
ORIENTATION_TOL = Tolerance(1e-7, "rad over 20 s; far above the double-precision floor of the stable spin "
                                  "(8e-13 rad at dt = 1e-3, top_floor), met by a 4th-order method at dt = 1e-3 "
                                  "(~5e-12 rad); a 2nd-order one needs dt ~1e-4")
RATE_TOL = Tolerance(1e-6, "rad/s; ORIENTATION_TOL times the spin rate (5 rad/s), doubled")
# The tumble amplifies every rounding: near the intermediate axis the floor is 1.2e-7 rad at
# dt = 1e-3 and 1.4e-7 at dt = 1e-4 (top_floor; the three orderings of the arithmetic spread
# over 4e-8..1.2e-7, one run being one sample of a random process), so 1e-7 would ask the impossible.
INTERMEDIATE_ORIENTATION_TOL = Tolerance(1e-6, "rad over 20 s; 8x the double-precision floor of this start "
                                               "(1.2e-7 rad at dt = 1e-3, 1.4e-7 at 1e-4), which every "
                                               "double-precision integrator pays, whatever its order")
INTERMEDIATE_RATE_TOL = Tolerance(1e-5, "rad/s; INTERMEDIATE_ORIENTATION_TOL times the spin rate (5 rad/s), "
                                        "doubled")
ENERGY_TOL = Tolerance(1e-10, "relative; a 4th-order method at dt = 1e-3 keeps energy to ~1e-12 over 20 s")
MOMENTUM_TOL = Tolerance(1e-10, "relative; as for energy: |L| in world is an exact invariant")
STILL_TOL = Tolerance(1e-12, "m and m/s; no force acts, the COM must not move at all")

UNITS = dict(inertia="kg m^2", omega0="rad/s", t_final="s", sample_interval="s")


def _top_case(name, inertia, omega0, t_final, sample_interval, orientation=ORIENTATION_TOL, rate=RATE_TOL):
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

    times = sample_times(t_final, sample_interval, name)
    return Case(
        name, scene, t_final, times, exact=truth,
        conserved=("energy", "angular_momentum", "linear_momentum"),
        tolerances=dict(orientation=orientation, angular_velocity=rate, position=STILL_TOL,
                        velocity=STILL_TOL, energy=ENERGY_TOL, angular_momentum=MOMENTUM_TOL,
                        linear_momentum=STILL_TOL),
        floor_fn=lambda: top_floor(inertia, omega0, times),
    )


@case(tags=("canonical", "free", "torque-free"), units=UNITS,
      positive=("inertia", "sample_interval"))
def free_top(inertia=(1.0, 2.0, 3.0), omega0=(0.1, 0.0, 5.0), t_final=20.0, sample_interval=0.01):
    """Torque-free asymmetric top (unit mass, principal moments ``inertia``),
    a stable spin near the axis of largest moment; ``omega0`` in the body frame."""
    return _top_case("free_top", inertia, omega0, t_final, sample_interval)


@case(tags=("canonical", "free", "torque-free", "intermediate-axis"), units=UNITS,
      positive=("inertia", "sample_interval"))
def free_top_intermediate(inertia=(1.0, 2.0, 3.0), omega0=(1e-3, 5.0, 1e-3), t_final=20.0, sample_interval=0.01):
    """The same top spinning 1e-3 rad/s off the intermediate axis: unstable, it flips."""
    return _top_case("free_top_intermediate", inertia, omega0, t_final, sample_interval,
                     INTERMEDIATE_ORIENTATION_TOL, INTERMEDIATE_RATE_TOL)


# ---------------------------------------------------------------- hard cases
# Stability bounds of the hard cases: a run that changes energy or |L| by more
# than this has stopped following the motion (it is adding or removing energy),
# whatever its phase accuracy.
STABILITY_ENERGY = Tolerance(1e-3, "relative; 0.1% of the energy gained or lost over the horizon is no longer "
                                   "roundoff or truncation but an integrator pumping or damping the motion")
STABILITY_MOMENTUM = Tolerance(1e-3, "relative; as STABILITY_ENERGY, for the world angular momentum")
HARD_ORIENTATION_TOL = Tolerance(1e-3, "rad; above the roundoff floor of every hard variant at its defaults for up "
                                       "to 2e5 steps (largest: the 50 rad/s fast spin, 7.7e-5 rad at dt = 1e-3, "
                                       "3.5e-4 at 1e-4), so a miss is the engine's, not the physics'")
HARD_RATE_TOL = Tolerance(1e-3, "relative to the spin rate; as HARD_ORIENTATION_TOL")
# The floor: what double precision alone costs an integrator on this motion — the same
# RK4 run in double and in extended precision (reference/roundoff.py), at FLOOR_DT (the
# default matrix's finer step; finer steps accumulate more roundoff: 7.7e-5 rad at 1e-3,
# 3.5e-4 rad at 1e-4 on the 50 rad/s fast spin). Never below the physics' own sensitivity:
# the spread of the closed form when each component of the initial angular velocity moves
# by FLOOR_ULPS ulps of |w0| (a lower bound: 1.6e-9 rad on that spin).
FLOOR_DT = 1e-3
FLOOR_ULPS = 2.0
# Horizons needing more steps than this at FLOOR_DT (~3 s per 1e5 in Python) get the
# sensitivity bound only: the long-horizon case (1e6 steps).
FLOOR_MAX_STEPS = 2e5


def top_floor(inertia, omega0, times):
    """Orientation floor (rad) of a torque-free top over ``times`` (see FLOOR_DT, FLOOR_ULPS)."""
    from dalembert import spatial
    from dalembert.reference.roundoff import top_roundoff

    I, w0 = np.diag(np.asarray(inertia, dtype=float)), np.asarray(omega0, dtype=float)
    base = TorqueFreeTop(I, w0).quaternion(times)
    h = FLOOR_ULPS * np.finfo(float).eps * np.linalg.norm(w0)
    spread = 0.0
    for k in range(3):
        for s in (-1.0, 1.0):
            w = w0.copy()
            w[k] += s * h
            spread = max(spread, float(np.max(spatial.rotation_angle(base, TorqueFreeTop(I, w).quaternion(times)))))
    roundoff = top_roundoff(inertia, w0, times, FLOOR_DT) if times[-1] / FLOOR_DT <= FLOOR_MAX_STEPS else 0.0
    return {"orientation": max(spread, roundoff) if np.isfinite(roundoff) else spread}


def _hard_top(name, inertia, omega0, t_final, sample_interval):
    made = _top_case(name, inertia, omega0, t_final, sample_interval)
    spin = float(np.linalg.norm(omega0))
    rate_tol = Tolerance(HARD_RATE_TOL.value * spin, f"rad/s; {HARD_RATE_TOL.value:g} of the {spin:g} rad/s spin")
    tolerances = dict(made.tolerances, orientation=HARD_ORIENTATION_TOL, angular_velocity=rate_tol,
                      energy=STABILITY_ENERGY, angular_momentum=STABILITY_MOMENTUM)
    return Case(name, made.scene, made.t_final, made.sample_times, made.exact, made.conserved, tolerances,
                floor_fn=made.floor_fn)


@case(tags=("hard", "free", "torque-free", "intermediate-axis", "fast-spin"),
      units=dict(UNITS, spin="rad/s", offset="rad/s"), positive=("inertia", "sample_interval"))
def free_top_fast_spin(inertia=(1.0, 2.0, 3.0), spin=50.0, offset=1e-3, t_final=20.0, sample_interval=0.01):
    """A fast spin ``spin`` rad/s about an axis ``offset`` rad/s off the intermediate
    axis: frequent flips (try spin=500, t_final=200 for the hardest variant)."""
    return _hard_top("free_top_fast_spin", inertia, (offset, spin, offset), t_final, sample_interval)


@case(tags=("hard", "free", "torque-free", "long-horizon"), units=UNITS,
      positive=("inertia", "sample_interval"))
def free_top_long_horizon(inertia=(1.0, 2.0, 3.0), omega0=(0.3, 0.2, 62.8), t_final=1000.0, sample_interval=0.1):
    """A generic asymmetric spin over 10^4 rotation periods (~0.1 s each): energy
    drift bounded for geometric integrators, secular for others (drift_rate)."""
    return _hard_top("free_top_long_horizon", inertia, omega0, t_final, sample_interval)


@case(tags=("hard", "free", "torque-free", "near-degenerate"), units=UNITS,
      positive=("inertia", "sample_interval"))
def free_top_near_symmetric(inertia=(1.0, 1.0 + 1e-6, 2.0), omega0=(0.3, 0.2, 5.0), t_final=20.0,
                            sample_interval=0.01):
    """Two principal moments 1e-6 apart: nearly axisymmetric."""
    return _hard_top("free_top_near_symmetric", inertia, omega0, t_final, sample_interval)


@case(tags=("hard", "free", "torque-free", "near-degenerate"), units=UNITS,
      positive=("inertia", "sample_interval"))
def free_top_slender(inertia=(1e-4, 1.0, 1.0), omega0=(5.0, 0.1, 0.2), t_final=20.0, sample_interval=0.01):
    """A slender body (moments 1e-4, 1, 1) spinning about its long axis while tumbling."""
    return _hard_top("free_top_slender", inertia, omega0, t_final, sample_interval)


def separatrix_omega(inertia, spin, gap):
    """Body angular velocity ``(x, spin, x)`` with ``2 E I2 / |L|^2 = 1 - gap`` exactly in the formulas."""
    I1, I2, I3 = inertia
    # M^2 - 2E I2 = gap M^2  with  w = (x, s, x):  x^2 (I3 (I3 - I2) - I1 (I2 - I1)) = gap (I2^2 s^2 + (I1^2 + I3^2) x^2)
    a = I3 * (I3 - I2) - I1 * (I2 - I1) - gap * (I1**2 + I3**2)
    return (float(np.sqrt(gap * I2**2 * spin**2 / a)), float(spin), float(np.sqrt(gap * I2**2 * spin**2 / a)))


@case(tags=("hard", "free", "torque-free", "separatrix"), units=dict(UNITS, spin="rad/s", gap="1"),
      positive=("inertia", "gap", "sample_interval"))
def free_top_separatrix(inertia=(1.0, 2.0, 3.0), spin=5.0, gap=1e-9, t_final=20.0, sample_interval=0.01):
    """Energy and momentum with ``2 E I2 / |L|^2 = 1 - gap``: a hair from the separatrix."""
    return _hard_top("free_top_separatrix", inertia, separatrix_omega(inertia, spin, gap), t_final, sample_interval)


stability_map(
    "fast_spin_map", case="free_top_fast_spin", parameter="spin", values="log:5,500,5", bracket=(1e-4, 1e-1),
    params=dict(t_final=2.0, sample_interval=0.1),
    reason="two decades of spin about the intermediate axis, each flip resolved at the finest step (500 rad/s "
           "turns 0.05 rad per 1e-4 s) and none at the coarsest; 2 s holds the first flips of the faster spins "
           "and ~20 probes per curve cost seconds; the 0.1-s samples let steps up to 0.1 s divide them")
