"""Motion probes: effects the scene did not call for (damping, gravity not the scene's, a hinge held still, contact
where none was asked) and mass and inertia as the engine uses them, each from motion with a known answer."""

from __future__ import annotations

import numpy as np

from dalembert.engine_check import ROUNDOFF_REL_TOL, NotApplicable, Problem, probe, scenes

__all__ = ["ENERGY_REL_TOL", "GRAVITY_REL_TOL", "GROWING_ERROR_FRACTION", "FAR_APART", "HINGE_ACC_REL_TOL", "HELD_FRACTION", "PERIOD_REL_TOL",
           "FREE_FLIGHT_REL_TOL", "MASS_REL_TOL", "INERTIA_REL_TOL", "PRINCIPAL_REL_TOL", "samples", "start_rate"]

# A sphere-inertia body's spin, and a drift without spin, are exact solutions that keep their values step by step
# (no gyroscopic term, no force): any consistent integrator keeps the kinetic energy to roundoff. A damping rate
# as small as 1e-5 per second over the 0.5 s horizon shows.
ENERGY_REL_TOL = ROUNDOFF_REL_TOL
# Under constant gravity alone the COM velocity g t is integrated exactly by every Runge-Kutta method and by
# (semi-implicit) Euler: the error is roundoff (relative to |g| T).
GRAVITY_REL_TOL = ROUNDOFF_REL_TOL
# The hinge's angular acceleration at release, estimated by a 3-point forward difference over 2 probe steps:
# the difference's own error is O(h^2), and a first-order integrator's start shifts it by O(h) (measured at most
# 3.5e-5 of it on the built-in engines' Euler variants and RK4 at 1e-3 s); a motor or a joint damping moves it
# by 1e-1 or more within those two steps.
HINGE_ACC_REL_TOL = 2e-2
# A hinge whose start is below this fraction of gravity's drive is held (a motor, a limit), not mis-scaled.
HELD_FRACTION = 0.1
# The half period from the sign change of the swing's rate, linearly interpolated between 0.01 s samples:
# O(h^2 w^2) near the turning point, plus the integrator's phase error at 1e-3 s (measured at most 1e-4 on the
# built-in engines' Euler variants and RK4).
PERIOD_REL_TOL = 1e-2
# Two force-free bodies keep their velocities exactly (no force: every integrator's update is the identity on v).
FREE_FLIGHT_REL_TOL = 1e-9
# m: the passing bodies' centres this far apart (4 radii of their 0.05 m spheres) cannot touch.
FAR_APART = 0.2
# A constant force at the COM gives v = F t / m exactly (as gravity does): roundoff.
MASS_REL_TOL = ROUNDOFF_REL_TOL
# w'(0) from a 3-point forward difference of w over 2 probe steps; as HINGE_ACC_REL_TOL, the integrator's start
# shifts it by O(h |w|) (measured at most 3.0e-3 on Euler's equations, where |w| = 3.7 rad/s, and 4e-7 under a
# torque from rest, on the built-in engines' Euler variants at 1e-3 s); an inertia not the scene's moves it by 1e-1
# or more.
INERTIA_REL_TOL = 2e-2
# A spin about a principal axis is steady: w stays put to roundoff over the horizon (the spin is about the
# major axis, stable, so roundoff does not grow).
PRINCIPAL_REL_TOL = ROUNDOFF_REL_TOL

_HORIZON = 0.5  # s, the longest probe
_SAMPLE = 1e-2  # s, the probes' sample interval


def samples(horizon=_HORIZON, start=0, step=_SAMPLE):
    """Sample times (s): ``start`` samples one probe step apart from t = 0 (for rates at the start), then every
    ``step`` to ``horizon``; rounded to 12 decimals so that every interval is a whole number of probe steps."""
    from dalembert.engine_check import PROBE_DT

    coarse = np.arange(int(round(horizon / step)) + 1) * step
    if start:
        dense = np.arange(start) * PROBE_DT
        coarse = np.concatenate([dense, coarse[coarse > dense[-1] + 0.5 * PROBE_DT]])
    return np.round(coarse, 12)


def start_rate(t, x):
    """d x / d t at t[0] from the first three samples (equally spaced), 3-point forward difference, O(h^2)."""
    h = t[1] - t[0]
    return (-3.0 * x[0] + 4.0 * x[1] - x[2]) / (2.0 * h)


# A constant acceleration seen wrong by the same fraction from the first sample on is a wrong force or mass; one
# whose error grows with time (the first sample's below this fraction of the last's) comes from a force that grows
# with the speed: damping. Under a damping rate c the error grows as c t / 2, 20 times from 0.01 s to 0.2 s.
GROWING_ERROR_FRACTION = 0.2
_DAMPING_LOOK_AT = ("velocity damping the engine adds by default (free_spin sees it too): set it to zero in prepare")


def _slowed(t, v, a):
    """True when the velocities ``v`` (n, 3) of a body accelerated from rest at ``a`` (3,) part from ``a t`` by an
    error that grows with time (a velocity-dependent force), not by a constant fraction (a wrong ``a``)."""
    err = np.linalg.norm(v[1:] - t[1:, None] * a, axis=1) / (np.linalg.norm(a) * t[1:])
    return bool(err[-1] > 0.0 and err[0] < GROWING_ERROR_FRACTION * err[-1])


def _rel(a, b):
    return float(np.linalg.norm(np.asarray(a) - np.asarray(b)) / max(np.linalg.norm(b), 1e-300))


def _v(x):
    return np.array2string(np.asarray(x, dtype=float), precision=4, suppress_small=True, separator=", ")


@probe("free_spin")
def free_spin(ctx):
    """A spinning sphere-inertia body and a drifting one keep their kinetic energies (no damping)."""
    scene = scenes.spinning_sphere()
    traj = ctx.trajectory(scene, samples())
    problems = []
    for body, what, kind in ((scene.body("spinner"), "angular_velocity", "angular"),
                             (scene.body("drifter"), "velocity", "linear")):
        rate = getattr(traj.bodies[body.name], what)
        scale = body.inertia_matrix[0, 0] if kind == "angular" else body.mass
        energy = 0.5 * scale * np.sum(rate**2, axis=1)
        change = (energy - energy[0]) / energy[0]
        worst = int(np.argmax(np.abs(change)))
        if abs(change[worst]) <= ENERGY_REL_TOL:
            continue
        lost = change[worst] < 0
        problems.append(Problem("free_spin", f"a free body {'spinning' if kind == 'angular' else 'drifting'} with no "
                                f"force or torque {'loses' if lost else 'gains'} {abs(change[worst]):.3g} of its "
                                f"kinetic energy by t = {traj.t[worst]:g} s ({energy[0]:.6g} -> {energy[worst]:.6g} "
                                "J; it keeps it exactly)",
                                f"{kind} velocity damping the engine adds by default (or joint damping, armature, a "
                                "solver's regularisation): set it to zero in prepare" if lost else
                                "a force the scene does not have, or an integrator that adds energy"))
    return problems


@probe("free_fall")
def free_fall(ctx):
    """A body at rest falls with the scene's gravity, (1, -2, -8) m/s^2: v = g t; the audit reports that vector."""
    scene = scenes.falling_body()
    prepared, (outcome,) = ctx.simulate(scene, samples(0.2))
    traj = outcome.trajectory
    g = np.array(scene.gravity)
    v = traj.bodies["body"].velocity
    problems = []
    err = float(np.max(np.linalg.norm(v - traj.t[:, None] * g, axis=1)) / (np.linalg.norm(g) * traj.t[-1]))
    if not err <= GRAVITY_REL_TOL:
        a = v[-1] / traj.t[-1]
        if _slowed(traj.t, v, g):
            problems.append(Problem("free_fall", f"a free body falls slower and slower than g: {_v(a)} m/s^2 on "
                                    f"average over {traj.t[-1]:g} s, the scene's gravity is {_v(g)} m/s^2",
                                    _DAMPING_LOOK_AT))
        else:
            problems.append(Problem("free_fall", f"gravity is not the scene's: a free body falls with {_v(a)} m/s^2, "
                                    f"the scene's gravity is {_v(g)} m/s^2", "set the engine's gravity from "
                                    "Scene.gravity (world axes, m/s^2) in prepare, every component (never a default "
                                    "-9.81 z)"))
    audit = ctx.adapter.audit(prepared, outcome)
    if "gravity" not in audit:
        problems.append(Problem("free_fall", "the audit reports no gravity", "audit() returns {'gravity': the "
                                "vector read back from the engine's model, m/s^2, world}"))
    elif not np.allclose(np.asarray(audit["gravity"], dtype=float), g, rtol=0.0, atol=1e-12):
        problems.append(Problem("free_fall", f"the audit's gravity {audit['gravity']} is not the scene's {_v(g)}",
                                "gravity set in the engine's model (and audit() reading it back from there)"))
    return problems


@probe("hinge_swing")
def hinge_swing(ctx):
    """A rod on a hinge released at 0.3 rad starts with a = -m g l sin(theta0) / J and swings with the
    pendulum's exact period."""
    p = scenes.Pendulum(0.3)
    traj = ctx.trajectory(p.scene, samples(start=10))
    rate = traj.bodies["rod"].angular_velocity @ p.axis_W
    acc = start_rate(traj.t, rate)
    if abs(acc) < HELD_FRACTION * abs(p.acceleration0):
        return [Problem("hinge_swing", f"a hinge does not move under gravity: released at 0.3 rad it starts with "
                        f"{acc:.4g} rad/s^2, gravity drives it at {p.acceleration0:.4g}",
                        "what holds the joint: a default joint motor or actuator, a joint limit, joint damping or "
                        "friction the engine adds (set them to zero), or gravity not set (free_fall)")]
    if abs(acc - p.acceleration0) > HINGE_ACC_REL_TOL * abs(p.acceleration0):
        return [Problem("hinge_swing", f"released at 0.3 rad, the rod starts with {acc:.5g} rad/s^2 about its hinge, "
                        f"expected -m g l sin(theta0) / J = {p.acceleration0:.5g}",
                        "the joint's drive: a default motor, spring or damping on the joint; else gravity (free_fall) "
                        "or the rod's inertia about the pivot (torque_response)")]
    later = np.nonzero((traj.t > 0.05) & (rate >= 0.0))[0]
    if not len(later):
        return [Problem("hinge_swing", f"the rod does not swing back within {traj.t[-1]:g} s (half period "
                        f"{p.half_period:.4g} s)", "a default joint motor, limit or damping that holds the joint")]
    k = int(later[0])
    half = traj.t[k - 1] - rate[k - 1] * (traj.t[k] - traj.t[k - 1]) / (rate[k] - rate[k - 1])
    if abs(half - p.half_period) > PERIOD_REL_TOL * p.half_period:
        return [Problem("hinge_swing", f"the rod's half period is {half:.5g} s, the pendulum's is {p.half_period:.5g} "
                        "s (2 K(k^2) sqrt(J / (m g l)))",
                        "a joint spring, motor or damping, or armature added to the joint's inertia")]
    ctx.notes.append(f"hinge half period {half:.6g} s (exact {p.half_period:.6g} s)")
    return []


@probe("pass_through")
def pass_through(ctx):
    """Two bodies that fly through each other, with no contact pair, keep their velocities (no contact)."""
    try:
        scene = scenes.passing_bodies(geoms=True)
        traj = ctx.trajectory(scene, samples(0.4))
    except NotApplicable as e:  # an engine that maps no geometry: the same flight without the spheres
        ctx.notes.append(f"without geoms ({e})")
        scene = scenes.passing_bodies(geoms=False)
        traj = ctx.trajectory(scene, samples(0.4))
    problems = []
    close = np.linalg.norm(traj.bodies["a"].position - traj.bodies["b"].position, axis=1) <= FAR_APART
    before = slice(0, int(np.argmax(close)) if close.any() else len(close))  # the samples before they first near
    for name in ("a", "b"):
        v = traj.bodies[name].velocity
        change = float(np.max(np.linalg.norm(v - v[0], axis=1)) / np.linalg.norm(v[0]))
        early = float(np.max(np.linalg.norm(v[before] - v[0], axis=1)) / np.linalg.norm(v[0]))
        if not early <= FREE_FLIGHT_REL_TOL:  # slowed before the other came near: not contact
            problems.append(Problem("pass_through", f"a force-free body {name!r} changes velocity by {early:.3g} of it "
                                    f"before any other body comes within {FAR_APART:g} m", _DAMPING_LOOK_AT))
        elif not change <= FREE_FLIGHT_REL_TOL:
            problems.append(Problem("pass_through", f"contact where none was asked: body {name!r} changes velocity "
                                    f"by {change:.3g} of it passing through another body (no ContactPair names them)",
                                    "contact the engine adds by default: collision shapes on every body (default "
                                    "collision groups, contype/conaffinity, a shape made for the inertia); only a "
                                    "scene's ContactPair may touch"))
    return problems


@probe("force_response")
def force_response(ctx):
    """A body pushed by a known force accelerates at F / m (the mass the engine uses)."""
    scene = scenes.pushed_body()
    traj = ctx.trajectory(scene, samples(0.1))
    F, m = np.array(scene.loads[0].vector), scene.bodies[0].mass
    a = traj.bodies["body"].velocity[-1] / traj.t[-1]
    if _rel(a, F / m) > MASS_REL_TOL and _slowed(traj.t, traj.bodies["body"].velocity, F / m):
        return [Problem("force_response", f"pushed by {_v(F)} N, the body accelerates slower and slower than F/m = "
                        f"{_v(F / m)} m/s^2 ({_v(a)} on average over {traj.t[-1]:g} s)", _DAMPING_LOOK_AT)]
    if _rel(a, F / m) > MASS_REL_TOL:
        mass = np.linalg.norm(F) / max(np.linalg.norm(a), 1e-300)
        return [Problem("force_response", f"pushed by {_v(F)} N, the body accelerates at {_v(a)} m/s^2, expected F/m = "
                        f"{_v(F / m)} (as if its mass were {mass:.4g} kg, not {m:g})",
                        "the mass given to the engine (not one from geometry or density, a default, a unit), and the "
                        "force's frame (world) and point (the COM)")]
    return []


def _inertia_problem(probe_name, what, seen, expected):
    return Problem(probe_name, f"{what}: w' = {_v(seen)} rad/s^2 at t = 0, expected {_v(expected)}: the engine's "
                   "inertia is not the scene's", "the inertia tensor given to the engine (about the COM, in B, kg m^2: "
                   "all nine terms, off-diagonal ones included, principal axes turned into the engine's frame), not "
                   "one computed from collision shapes, a density or a default")


@probe("torque_response")
def torque_response(ctx):
    """A body at rest under a known torque starts turning at w' = I^-1 torque (its inertia, all nine terms)."""
    scene = scenes.twisted_body()
    traj = ctx.trajectory(scene, samples(0.01, start=3))
    expected = np.linalg.solve(scene.bodies[0].inertia_matrix, np.array(scene.loads[0].vector))
    seen = start_rate(traj.t, traj.bodies["body"].angular_velocity)
    if _rel(seen, expected) > INERTIA_REL_TOL:
        return [_inertia_problem("torque_response", "under a constant torque from rest", seen, expected)]
    return []


@probe("euler_rates")
def euler_rates(ctx):
    """A torque-free asymmetric body starts as Euler's equations say: w' = I^-1 ((I w) x w) across w (the inertia
    ratios)."""
    scene = scenes.asymmetric_body()
    traj = ctx.trajectory(scene, samples(0.01, start=3))
    inertia, w = scene.bodies[0].inertia_matrix, np.array(scene.joints[0].v0[3:])
    # compared across w only: a damping (along w) is free_spin's finding, not the inertia's
    across = np.eye(3) - np.outer(w, w) / (w @ w)
    expected = across @ np.linalg.solve(inertia, np.cross(inertia @ w, w))
    seen = across @ start_rate(traj.t, traj.bodies["body"].angular_velocity)
    if _rel(seen, expected) > INERTIA_REL_TOL:
        return [_inertia_problem("euler_rates", "a torque-free asymmetric body (across w)", seen, expected)]
    return []


@probe("principal_spin")
def principal_spin(ctx):
    """A spin about a principal axis of an inertia with off-diagonal terms in B is steady."""
    axis = scenes._Q_BP[:, 2]  # the major axis (0.13 kg m^2), in B; at the identity attitude, in the world too
    scene = scenes.asymmetric_body(tuple(4.0 * axis))
    traj = ctx.trajectory(scene, samples())
    w = traj.bodies["body"].angular_velocity
    drift = float(np.max(np.linalg.norm(w - 4.0 * axis, axis=1)) / 4.0)
    wobble = float(np.max(np.linalg.norm(w - np.outer(w @ axis, axis), axis=1)) / 4.0)  # off the axis
    if not drift <= PRINCIPAL_REL_TOL and wobble <= PRINCIPAL_REL_TOL:
        return [Problem("principal_spin", f"a steady spin about a principal axis slows: its rate changes by {drift:.3g} "
                        f"of it over {traj.t[-1]:g} s, about the same axis", _DAMPING_LOOK_AT)]
    if not drift <= PRINCIPAL_REL_TOL:
        return [Problem("principal_spin", f"a spin about a principal axis of the body's inertia wobbles: w moves by "
                        f"{drift:.3g} of it over {traj.t[-1]:g} s (it is steady)",
                        "the inertia tensor's off-diagonal terms (an engine that takes the diagonal only, or principal "
                        "moments without turning the body frame to their axes)")]
    return []
