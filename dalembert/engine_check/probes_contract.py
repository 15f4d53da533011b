"""Contract probes: the same run twice bit for bit (state reset), each fixed-step integrator's observed order
against its declaration, unsupported effects really refused, nothing printed on import, a minimum of supported
cases."""

from __future__ import annotations

import math

import numpy as np

from dalembert.engine_check import NotApplicable, Problem, probe, scenes

__all__ = ["ORDER_MARGIN", "ORDER_FLOOR", "ORDER_STEPS", "MIN_SUPPORTED_CASES", "CASE_SAMPLES", "observed_order"]

# The observed order log2(e(h) / e(h/2)) converges to the declared order as h shrinks, until roundoff takes over
# (in float32, MJX's default, already at the ladder's middle: its RK4 reads 4.91, 3.02, 0.05 down the ladder). The
# probe takes the highest order a triple of consecutive steps of ORDER_STEPS shows above ORDER_FLOOR: measured on its
# pendulum, every built-in fixed-step integrator's is at least p - 0.03 for its order p (RK4 4.91, Drake's rk2
# 2.85, rk3 3.03, rk5 4.94, Exudyn's rk67 6.63, the Euler variants 0.97-1.35), and a first-order method's at most
# 1.35 (its top triple, w h = 0.34). An order short by more than this margin is not the declared one: a first-order
# method declared second order shows 1.35 < 1.6.
ORDER_MARGIN = 0.4
# Differences between two runs below this (relative to the state's size, at least 1) are at double's roundoff: the
# order is not measured from them (an integrator exact on the probe claims none).
ORDER_FLOOR = 1e-11
# The fixed steps (s) of the order probe, each half the one before, over its 0.2 s horizon (w h from 0.34 down to
# 0.02 on its pendulum).
ORDER_STEPS = (0.04, 0.02, 0.01, 0.005, 0.0025)
# The built-in case the supported_cases probe runs is run this many samples (a start: the contract's sampling and
# bodies, not its accuracy, which the matrix judges).
CASE_SAMPLES = 3
# An adapter must run at least this many of the built-in cases (one that runs none passes every other probe
# vacuously, and the matrix stores nothing for it).
MIN_SUPPORTED_CASES = 1


def _arrays(traj):
    """Every array of a trajectory, by name: bodies' states, joints' coordinates, extras."""
    out = {}
    for name, b in traj.bodies.items():
        for f in ("position", "quaternion", "velocity", "angular_velocity"):
            out[f"bodies[{name!r}].{f}"] = getattr(b, f)
    for name, j in traj.joints.items():
        out[f"joints[{name!r}].q"], out[f"joints[{name!r}].v"] = j.q, j.v
    out.update({f"extras[{k!r}]": v for k, v in traj.extras.items()})
    return out


def _first_difference(a, b):
    """The first array that differs between trajectories ``a`` and ``b`` (not bit for bit), or None."""
    xa, xb = _arrays(a), _arrays(b)
    if set(xa) != set(xb):
        return f"the arrays differ: {sorted(set(xa) ^ set(xb))}"
    for key in xa:
        if not np.array_equal(np.asarray(xa[key]), np.asarray(xb[key]), equal_nan=True):
            return f"{key} (by up to {float(np.nanmax(np.abs(np.asarray(xa[key]) - np.asarray(xb[key])))):.3g})"
    return None


def _moving_scene(ctx):
    """The pendulum, else (an engine without hinges) the tilted spin: a scene whose every state moves."""
    for scene in (scenes.Pendulum(0.3).scene, scenes.tilted_spin()):
        try:
            ctx.adapter.check(scene, np.array([0.0, 0.1]), ctx.settings())
        except ValueError:
            continue
        if not ctx.adapter.unsupported(scene, ctx.settings()):
            return scene
    raise NotApplicable("runs neither the pendulum nor a free spin")


@probe("repeatable")
def repeatable(ctx):
    """The same run twice on one prepared model, and on a second prepare, gives the same numbers bit for bit."""
    from dalembert.engine_check.probes_motion import samples

    scene, times = _moving_scene(ctx), samples(0.2)
    _, (first, second) = ctx.simulate(scene, times, runs=2)
    _, (third,) = ctx.simulate(scene, times)
    problems = []
    for what, other in (("a second run of the same prepared model", second), ("a run of a second prepare", third)):
        diff = _first_difference(first.trajectory, other.trajectory)
        if diff:
            problems.append(Problem("repeatable", f"state not reset between runs: {what} differs from the first in "
                                    f"{diff} ({scene.name})", "run() starts from the initial state every time: keep "
                                    "it in prepare and copy it in run (never step the prepared model's own arrays); "
                                    "no state shared between prepared models (caches, warm starts, a global)"))
    return problems


def _final_state(traj):
    """Every body's final position, quaternion (sign as the first), velocity and angular velocity, one vector."""
    parts = []
    for name in sorted(traj.bodies):
        b = traj.bodies[name]
        q = b.quaternion[-1] * (1.0 if float(b.quaternion[-1] @ b.quaternion[0]) >= 0.0 else -1.0)
        parts += [b.position[-1], q, b.velocity[-1], b.angular_velocity[-1]]
    return np.concatenate(parts)


def observed_order(ctx, integrator, scene):
    """The highest ``log2(|x(h) - x(h/2)| / |x(h/2) - x(h/4)|)`` of ``scene``'s final state over consecutive
    triples of ``ORDER_STEPS`` whose differences are above ``ORDER_FLOOR``, or None where none is."""
    times = np.array([0.0, 0.2])
    finals = [_final_state(ctx.trajectory(scene, times, ctx.settings(dt, integrator))) for dt in ORDER_STEPS]
    floor = ORDER_FLOOR * max(float(np.linalg.norm(finals[-1])), 1.0)
    gaps = [float(np.linalg.norm(a - b)) for a, b in zip(finals, finals[1:])]
    orders = [math.log2(big / small) for big, small in zip(gaps, gaps[1:]) if small > floor]
    return max(orders) if orders else None


@probe("integrator_order", per_integrator=False)
def integrator_order(ctx):
    """Each fixed-step integrator's observed order (steps each half the last) against IntegratorSpec.order."""
    problems = []
    scene = None
    for candidate in (scenes.Pendulum(1.0).scene, scenes.asymmetric_body()):
        if not ctx.adapter.unsupported(candidate, ctx.settings()):
            scene = candidate
            break
    if scene is None:
        raise NotApplicable("runs neither the pendulum nor a free body")
    for integ in ctx.integrators:
        spec = ctx.adapter.integrators[integ]
        if not spec.fixed_step:
            continue
        try:
            order = observed_order(ctx, integ, scene)
        except NotApplicable as e:
            ctx.notes.append(f"{integ}: not measured ({e})")
            continue
        declared = getattr(spec, "order", None)
        if order is None:
            ctx.notes.append(f"{integ}: exact on {scene.name} to roundoff (order not measured)")
            continue
        ctx.notes.append(f"{integ}: observed order {order:.2f} on {scene.name}, declared "
                         f"{declared if declared is not None else 'none (IntegratorSpec.order)'}")
        if declared is not None and order < declared - ORDER_MARGIN:
            problems.append(Problem("integrator_order", f"integrator order lower than declared: {integ} shows order "
                                    f"{order:.2f} on {scene.name} (the highest over steps "
                                    f"{', '.join(f'{h:g}' for h in ORDER_STEPS)} s), "
                                    f"it declares {declared}", f"IntegratorSpec(order=...) of {integ!r}: declare the "
                                    "order the engine's method has (semi-implicit Euler: 1), or what in the stepping "
                                    "lowers it (a first-order update of the attitude, a constraint projection)"))
    return problems


@probe("refusals", per_integrator=False)
def refusals(ctx):
    """A scene with an effect the adapter does not declare is refused by unsupported() with a reason (not run)."""
    problems = []
    unknown = sorted(set(ctx.adapter.effects) - scenes.ALL_EFFECTS)
    if unknown:
        problems.append(Problem("refusals", f"declares effect tags no scene has: {unknown}",
                                "Adapter.effects: tags from dalembert.kinds (EFFECTS, LOOP_EFFECTS, SPRING_EFFECTS, "
                                "CONTACT_EFFECTS)"))
    for tag in sorted(scenes.ALL_EFFECTS - set(ctx.adapter.effects)):
        reason = ctx.adapter.unsupported(scenes.scene_needing(tag), ctx.settings())
        if not (isinstance(reason, str) and reason.strip()):
            problems.append(Problem("refusals", f"unsupported effect not refused: {ctx.name} does not declare {tag!r} "
                                    f"but unsupported() returns {reason!r} for a scene that needs it (the harness "
                                    "would run it: a silent approximation)", "unsupported(): start from "
                                    "super().unsupported(scene, settings), which names every effect not in effects"))
    refused = sorted(t for t in set(ctx.adapter.effects) & scenes.ALL_EFFECTS
                     if ctx.adapter.unsupported(scenes.scene_needing(t), ctx.settings()))
    if refused:
        ctx.notes.append(f"declares but refuses the probe scenes of {', '.join(refused)}")
    return problems


@probe("quiet", per_integrator=False)
def quiet(ctx):
    """Nothing printed on import and load, in a fresh interpreter (the other probes' runs are captured too)."""
    from dalembert.adapters import adapter_path
    from dalembert.engine_check.capture import import_output, printed_problem

    path = adapter_path(ctx.name)
    text, error = import_output(path)
    if error:
        return [Problem("quiet", f"importing {path} in a fresh interpreter fails: {error}",
                        "the adapter's module must import on its own (worker processes import it by this path)")]
    return [printed_problem(f"import of {path} (and load())", text)] if text else []


@probe("supported_cases", per_integrator=False)
def supported_cases(ctx):
    """The adapter accepts at least MIN_SUPPORTED_CASES of the built-in cases (an adapter that runs nothing fails),
    and the first of them runs its first CASE_SAMPLES samples: at exactly the case's times, every body of its scene."""
    from dalembert.adapters.contract import CONTRACT_TOL
    from dalembert.case import load_cases
    from dalembert.settings import Settings

    taken, every = [], load_cases()
    for name, factory in every.items():
        case = factory()
        interval = float(case.times[1] - case.times[0])
        for integ, spec in ctx.adapter.integrators.items():
            s = Settings(integ, dt=interval) if spec.fixed_step else Settings(integ, rtol=CONTRACT_TOL, atol=CONTRACT_TOL)
            if not ctx.adapter.unsupported(case.scene, s):
                taken.append((case, s))
                break
    ctx.notes.append(f"supports {len(taken)} of {len(every)} built-in cases")
    if len(taken) < MIN_SUPPORTED_CASES:
        return [Problem("supported_cases", f"supports none of the {len(every)} built-in cases (needs at least "
                        f"{MIN_SUPPORTED_CASES}): declares effects {sorted(ctx.adapter.effects) or 'none'}",
                        "Adapter.effects: declare the Scene.effects tags the adapter builds (EFFECTS: gravity, "
                        "joint:<kind>, load:<...>); unsupported() refuses the rest")]
    case, s = taken[0]
    times = case.times[:CASE_SAMPLES]
    traj = ctx.simulate(case.scene, times, s)[1][0].trajectory
    where = f"{case.name} ({s.label()}, its first {CASE_SAMPLES} samples)"
    problems = []
    if not np.array_equal(traj.t, times):
        problems.append(Problem("supported_cases", f"{where}: sampled at {traj.t.tolist()}, not at exactly the times "
                                f"asked, {times.tolist()}", "run() samples at exactly prepared.times (the engine's own "
                                "time may drift by roundoff: step whole intervals, and report the times asked)"))
    if set(traj.bodies) != {b.name for b in case.scene.bodies}:
        problems.append(Problem("supported_cases", f"{where}: the trajectory's bodies {sorted(traj.bodies)} are not "
                                f"the scene's {sorted(b.name for b in case.scene.bodies)}",
                                "the read-back gives every body of the scene, by its name"))
    return problems
