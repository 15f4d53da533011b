"""Drake's stepping: a ``Simulator`` on the diagram, advanced from sample to sample.

Continuous mode: the integrator is chosen by Drake's own scheme name
(``ResetIntegratorFromFlags``), either in fixed-step mode (steps of exactly
``dt``; Drake lands on each sample time with one extra roundoff-sized step where
the accumulated time falls short of it — counted in its statistics, harmless to
the accuracy) or error-controlled (``set_target_accuracy(rtol)``: Drake has one
accuracy knob, its weighted error norm has no separate absolute tolerance; the
largest step is the horizon, and the samples are read from Drake's dense output,
so that the accuracy, not the sample interval, sets the steps: ``_dense``). Discrete mode: the plant's periodic update
of period ``dt``, whose update at ``t_n = n dt`` maps the state at ``t_n`` to the state at
``t_n + dt``; the simulator runs the updates triggered before the time it advances to. Sample
times carry roundoff (``linspace``: 0.30000000000000004 for 6 x 0.05) and Drake's update
times too, so advancing to ``t_k`` itself ran one update too many at some samples (measured
on the four-bar at dt = 1e-3: the crank one step ahead at t = 0.3, an error of its rate times
``dt``, 8e-3 rad); each sample is taken half a step before ``t_k``, where the discrete state is
already that of ``t_k``.

Fixed-step and discrete runs copy the state out after every ``AdvanceTo(t_k)``, ball joints in the
scene's chart (``charts``: their roll-pitch-yaw chart is moved at t = 0 and
whenever a sample, or in error-controlled runs a step, nears its singularity). A blow-up is data: the
first non-finite state, or a Drake exception raised on a non-finite state or
mentioning NaN, ends the run with NaN from that sample on and Drake's message
kept; any other Drake exception (e.g. an implicit integrator that fails to
converge at a fixed step) is raised with the time reached, and the run is
stored as failed.

``p`` is the ``DrakePrepared`` that ``DrakeAdapter.prepare`` returns.
"""

from __future__ import annotations

import time

import numpy as np

from dalembert.adapters.drake.charts import BallCharts

__all__ = ["simulate", "SCHEMES"]

# dalembert name -> Drake's scheme name (GetIntegrationSchemes()).
SCHEMES = {
    "explicit-euler": "explicit_euler", "semi-explicit-euler": "semi_explicit_euler",
    "rk2": "runge_kutta2", "rk3": "runge_kutta3", "rk5": "runge_kutta5", "bs3": "bogacki_shampine3",
    "implicit-euler": "implicit_euler", "velocity-implicit-euler": "velocity_implicit_euler",
    "radau1": "radau1", "radau3": "radau3",
}

# Error-controlled runs' first attempted step, as a fraction of the sample interval: Drake's default first
# attempt is a tenth of the largest step, which was the sample interval until the largest step became the
# horizon; a tenth of the horizon can start the error control where it never recovers (measured: the heavy
# top, 150 rad/s, at 1e-6 over 2 s: a first attempt of 0.2 s shrank to 2e-16 s and Drake stopped).
INITIAL_STEP_FRACTION = 0.1


def reset(p):
    """A fresh simulator at the initial state, with its integrator set up and its ball joints charted;
    ``(simulator, integrator or None, BallCharts)``."""
    from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator

    model, s = p.model, p.settings
    simulator = Simulator(model.diagram)
    context = simulator.get_mutable_context()
    context.SetTime(float(p.times[0]))
    plant_context = model.plant.GetMyMutableContextFromRoot(context)
    model.plant.SetPositionsAndVelocities(plant_context, np.concatenate([p.q0, p.v0]))
    charts = BallCharts(model, plant_context)
    if charts:
        charts.update(force=True)
    integrator = None
    if model.time_step == 0.0:
        name = p.scheme
        if s.dt is not None:
            integrator = ResetIntegratorFromFlags(simulator, name, float(s.dt))
            integrator.set_fixed_step_mode(True)
        else:  # the largest step is the horizon: the accuracy alone sets the steps (``_dense``)
            horizon = float(p.times[-1] - p.times[0])
            integrator = ResetIntegratorFromFlags(simulator, name, horizon)
            integrator.set_fixed_step_mode(False)
            integrator.request_initial_step_size_target(INITIAL_STEP_FRACTION * float(np.min(np.diff(p.times))))
            integrator.set_target_accuracy(float(s.rtol))
    simulator.Initialize()
    return simulator, integrator, charts


def simulate(p):
    """Step through ``p.times``: ``(X (n, nq + nv), wall s, steps, RHS evaluations, message, re-charts)``.

    ``X`` rows are the plant's ``(q, v)`` at each sample (the scene's charts), NaN from the first sample not
    reached. Error-controlled runs are sampled from Drake's dense output (``_dense``), the others by advancing
    to each sample (``_sample_by_sample``).
    """
    simulator, integrator, charts = reset(p)
    plant = p.model.plant
    plant_context = plant.GetMyContextFromRoot(simulator.get_context())  # the simulator's own, for all its steps
    x0 = charts.to_scene_chart(plant.GetPositionsAndVelocities(plant_context))
    X = np.full((len(p.times), len(x0)), np.nan)
    X[0] = x0
    loads = p.model.loads
    if loads is not None:
        loads.evaluations = 0
    # Discrete mode: stop half a step short of each sample, so that exactly round((t_k - t_0) / dt) updates
    # have run whatever the roundoff in t_k (module docstring)
    early = 0.5 * p.settings.dt if integrator is None else 0.0
    start = time.perf_counter()
    if integrator is not None and not integrator.get_fixed_step_mode():
        message = _dense(p, simulator, integrator, charts, X)
    else:
        message = _sample_by_sample(p, simulator, early, charts, X)
    wall = time.perf_counter() - start
    if integrator is not None:
        n_steps, n_rhs = integrator.get_num_steps_taken(), integrator.get_num_derivative_evaluations()
    else:  # discrete: one update, one evaluation of the dynamics per step
        n_steps = n_rhs = int(round((simulator.get_context().get_time() + early - p.times[0]) / p.settings.dt))
    return X, wall, int(n_steps), int(n_rhs), message, charts.recharts


def _advance(p, simulator, t):
    """``simulator.AdvanceTo(t)``: None, or the message of a blow-up (a Drake exception raised on a non-finite
    state or mentioning NaN: data); any other Drake exception is raised with the time reached."""
    context = simulator.get_context()
    try:
        simulator.AdvanceTo(t)
    except (RuntimeError, SystemExit) as e:  # pydrake raises SystemExit for a failed internal assertion
        plant = p.model.plant
        x = plant.GetPositionsAndVelocities(plant.GetMyContextFromRoot(context))
        if np.isfinite(x).all() and "nan" not in str(e).lower():
            raise RuntimeError(f"Drake stopped at t = {context.get_time():g} s of {p.times[-1]:g} s: {e}") from None
        return f"Drake at t = {context.get_time():g} s: {e}"
    return None


def _sample_by_sample(p, simulator, early, charts, X):
    """Fixed-step and discrete runs: ``AdvanceTo`` each sample time (``early`` s before it), the state copied
    into ``X[k]`` and the ball joints re-charted where due; the message of a blow-up, or ``""``."""
    times, plant = p.times, p.model.plant
    plant_context = plant.GetMyContextFromRoot(simulator.get_context())
    for k in range(1, len(times)):
        message = _advance(p, simulator, float(times[k]) - early)
        if message:
            return message
        x = plant.GetPositionsAndVelocities(plant_context)
        if not np.isfinite(x).all():
            return f"non-finite state at t = {times[k]:g} s"
        X[k] = charts.to_scene_chart(x)
        charts.update()
    return ""


def _dense(p, simulator, integrator, charts, X):
    """Error-controlled runs: one ``AdvanceTo`` the horizon, the samples read from Drake's dense output.

    Advancing to each sample instead truncates every step at the next sample: where the sample interval's
    error already meets the target accuracy, every accuracy gives the same steps (measured on the pendulum
    over 1 s, 0.01-s samples: rk5-adaptive at 1e-6 and 1e-9 bit for bit, 197 steps, 5.8e-11 rad). Drake's
    dense output (``StartDenseIntegration``) is its cubic Hermite interpolant of each step's end states and
    derivatives, so the sampled error includes that interpolant's (measured, same run: rk5-adaptive at 1e-9
    takes 67 steps, 5.0e-10 rad at the steps' ends, 2.5e-8 rad between them; at 1e-6 22 steps, 1.8e-5 and
    2.1e-5 rad): Drake's own continuous solution at that accuracy, as a Drake user sampling it would get.

    With ball joints a monitor ends the advance after a step that leaves a joint's ``|pitch|`` beyond
    ``charts.RECHART_PITCH``; the samples so far are read in the old charts, the joints re-charted there,
    and the advance resumes (the integrator keeps its step size). The message of a blow-up, or ``""``.
    """
    from pydrake.systems.framework import EventStatus

    times, plant = p.times, p.model.plant
    if charts:
        def monitor(root_context):
            if charts.due(plant.GetPositions(plant.GetMyContextFromRoot(root_context))):
                return EventStatus.ReachedTermination(None, "a ball joint's chart nears its singularity")
            return EventStatus.Succeeded()
        simulator.set_monitor(monitor)
    k, message = 1, ""  # k: the next sample to read
    while k < len(times):
        integrator.StartDenseIntegration()
        message = _advance(p, simulator, float(times[-1]))
        trajectory = integrator.StopDenseIntegration()
        if trajectory.get_number_of_segments() and trajectory.end_time() >= times[k]:
            reached = k + int(np.searchsorted(times[k:], trajectory.end_time(), side="right"))
            for j, x in enumerate(trajectory.vector_values(times[k:reached]).T, start=k):
                if not np.isfinite(x).all():
                    return f"non-finite state at t = {times[j]:g} s"
                X[j] = charts.to_scene_chart(x)
            k = reached
        if message or simulator.get_context().get_time() >= times[-1] or not charts:
            break
        charts.update()  # the monitor ended the advance: a chart is due
    return message or ""
