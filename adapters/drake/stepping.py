"""Drake's stepping: a ``Simulator`` on the diagram, advanced from sample to sample.

Continuous mode: the integrator is chosen by Drake's own scheme name
(``ResetIntegratorFromFlags``), either in fixed-step mode (steps of exactly
``dt``; Drake lands on each sample time with one extra roundoff-sized step where
the accumulated time falls short of it — counted in its statistics, harmless to
the accuracy) or error-controlled (``set_target_accuracy(rtol)``: Drake has one
accuracy knob, its weighted error norm has no separate absolute tolerance; the
largest step is the sample interval). Discrete mode: the plant's periodic update
of period ``dt``, whose update at ``t_n = n dt`` maps the state at ``t_n`` to the state at
``t_n + dt``; the simulator runs the updates triggered before the time it advances to. Sample
times carry roundoff (``linspace``: 0.30000000000000004 for 6 x 0.05) and Drake's update
times too, so advancing to ``t_k`` itself ran one update too many at some samples (measured
on the four-bar at dt = 1e-3: the crank one step ahead at t = 0.3, an error of its rate times
``dt``, 8e-3 rad); each sample is taken half a step before ``t_k``, where the discrete state is
already that of ``t_k``.

The state is copied out after every ``AdvanceTo(t_k)``, ball joints in the
scene's chart (``charts``: their roll-pitch-yaw chart is moved at t = 0 and
whenever a sample nears its singularity). A blow-up is data: the
first non-finite state, or a Drake exception raised on a non-finite state or
mentioning NaN, ends the run with NaN from that sample on and Drake's message
kept; any other Drake exception (e.g. an implicit integrator that fails to
converge at a fixed step) is raised with the time reached, and the run is
stored as failed.

``p`` is the dict ``DrakeAdapter.prepare`` returns.
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


def reset(p):
    """A fresh simulator at the initial state, with its integrator set up and its ball joints charted;
    ``(simulator, integrator or None, BallCharts)``."""
    from pydrake.systems.analysis import ResetIntegratorFromFlags, Simulator

    model, s = p["model"], p["settings"]
    simulator = Simulator(model.diagram)
    context = simulator.get_mutable_context()
    context.SetTime(float(p["times"][0]))
    plant_context = model.plant.GetMyMutableContextFromRoot(context)
    model.plant.SetPositionsAndVelocities(plant_context, np.concatenate([p["q0"], p["v0"]]))
    charts = BallCharts(model, plant_context)
    if charts:
        charts.update(force=True)
    integrator = None
    if model.time_step == 0.0:
        name = p["scheme"]
        if s.dt is not None:
            integrator = ResetIntegratorFromFlags(simulator, name, float(s.dt))
            integrator.set_fixed_step_mode(True)
        else:
            interval = float(np.min(np.diff(p["times"])))
            integrator = ResetIntegratorFromFlags(simulator, name, interval)
            integrator.set_fixed_step_mode(False)
            integrator.set_target_accuracy(float(s.rtol))
    simulator.Initialize()
    return simulator, integrator, charts


def simulate(p):
    """Step through ``p["times"]``: ``(X (n, nq + nv), wall s, steps, RHS evaluations, message, re-charts)``.

    ``X`` rows are the plant's ``(q, v)`` at each sample, NaN from the first sample not reached.
    """
    simulator, integrator, charts = reset(p)
    times = p["times"]
    context = simulator.get_context()
    plant = p["model"].plant
    plant_context = plant.GetMyContextFromRoot(context)  # the simulator's own, for all its steps
    x0 = charts.to_scene_chart(plant.GetPositionsAndVelocities(plant_context))
    X = np.full((len(times), len(x0)), np.nan)
    X[0] = x0
    message = ""
    loads = p["model"].loads
    if loads is not None:
        loads.evaluations = 0
    # Discrete mode: stop half a step short of each sample, so that exactly round((t_k - t_0) / dt) updates
    # have run whatever the roundoff in t_k (module docstring); continuous mode: the sample itself.
    early = 0.5 * p["settings"].dt if integrator is None else 0.0
    start = time.perf_counter()
    for k in range(1, len(times)):
        try:
            simulator.AdvanceTo(float(times[k]) - early)
        except (RuntimeError, SystemExit) as e:  # pydrake raises SystemExit for a failed internal assertion
            x = plant.GetPositionsAndVelocities(plant_context)
            if np.isfinite(x).all() and "nan" not in str(e).lower():
                raise RuntimeError(f"Drake stopped at t = {context.get_time():g} s of {times[-1]:g} s: {e}") from None
            message = f"Drake at t = {context.get_time():g} s: {e}"
            break
        x = plant.GetPositionsAndVelocities(plant_context)
        if not np.isfinite(x).all():
            message = f"non-finite state at t = {times[k]:g} s"
            break
        X[k] = charts.to_scene_chart(x)
        charts.update()
    wall = time.perf_counter() - start
    if integrator is not None:
        n_steps, n_rhs = integrator.get_num_steps_taken(), integrator.get_num_derivative_evaluations()
    else:  # discrete: one update, one evaluation of the dynamics per step
        n_steps = n_rhs = int(round((context.get_time() + early - times[0]) / p["settings"].dt))
    return X, wall, int(n_steps), int(n_rhs), message, charts.recharts
