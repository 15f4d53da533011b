"""The Pinocchio adapter's integrators, in Python, each evaluating the loads at every stage.

* ``euler``: semi-implicit (symplectic) Euler on the group;
* ``rk4``: Runge-Kutta-Munthe-Kaas with the classical tableau, the stage
  tangents corrected by the exact ``dexp^-1`` — Pinocchio's own
  ``dIntegrate(q, theta, ARG1)`` is the right Jacobian of ``integrate``, so
  ``theta' = dIntegrate^-1 v`` — and the configuration advanced by
  ``pin.integrate``. Fourth order on the group;
* ``rk4-naive``: RK4 on ``v`` with ``q`` advanced stagewise by
  ``integrate(q, c h v_i)`` and no ``dexp^-1`` correction (lower order on a
  non-commutative group: kept because the difference is a result);
* ``rk45``, ``dop853``: scipy's ``RK45`` and ``DOP853`` in local coordinates
  ``q = integrate(q_c, delta)`` about a chart centre ``q_c``: the state
  ``(delta, v)`` has no redundant component, so error control is not fooled by
  the quaternion's unit-norm constraint, and the quaternion never drifts. One
  solver runs over the whole horizon, its step size and error history carried
  from step to step (the tolerance decides the steps, never the sample
  interval), and the samples are read from its dense output; after every
  accepted step the chart is moved to the step's end (``delta = 0``), a change
  of coordinates between two steps, not of the motion (``adaptive``).

The fixed-step loops here are the readable specification of the compiled ones
(``native``, ``stepper.cpp``) and their fallback. ``pm`` is a
``PinocchioModel``; ``q0 (nq,)``, ``v0 (nv,)`` its coordinates at ``times[0]``.
"""

from __future__ import annotations

import numpy as np

from dalembert.settings import is_numerical_failure
from dalembert.stepping import march

__all__ = ["fixed_step", "adaptive", "STAGES"]

STAGES = {"euler": 1, "rk4": 4, "rk4-naive": 4}  # right-hand-side evaluations per fixed step


def fixed_step(pm, method, q0, v0, times, steps):
    """The Python loop of the fixed-step ``method`` (``STAGES``) with ``steps[k]`` steps per sample
    interval: ``(Q (n, nq), V (n, nv), steps taken, RHS evaluations)``, NaN after a non-finite
    state (``dalembert.stepping.march``)."""
    import pinocchio as pin

    model, acc = pm.model, pm.acceleration_function()
    integrate = pin.integrate
    dexpinv = pm.dexpinv_function()
    J_inv = dexpinv if dexpinv is not None else (lambda q, theta, vel: vel)

    def euler(q, v, h):
        v = v + h * acc(q, v)
        return integrate(model, q, h * v), v

    def rk4(q, v, h):  # Munthe-Kaas: stage tangents k_i, all from q
        hh = 0.5 * h
        a1 = acc(q, v)
        v2 = v + hh * a1
        th2 = hh * v
        k2 = J_inv(q, th2, v2)
        a2 = acc(integrate(model, q, th2), v2)
        v3 = v + hh * a2
        th3 = hh * k2
        k3 = J_inv(q, th3, v3)
        a3 = acc(integrate(model, q, th3), v3)
        v4 = v + h * a3
        th4 = h * k3
        k4 = J_inv(q, th4, v4)
        a4 = acc(integrate(model, q, th4), v4)
        h6 = h / 6.0
        return (integrate(model, q, h6 * (v + 2.0 * (k2 + k3) + k4)),
                v + h6 * (a1 + 2.0 * (a2 + a3) + a4))

    def rk4_naive(q, v, h):  # stagewise integrate, no dexp^-1
        hh = 0.5 * h
        a1 = acc(q, v)
        v2 = v + hh * a1
        a2 = acc(integrate(model, q, hh * v), v2)
        v3 = v + hh * a2
        a3 = acc(integrate(model, q, hh * v2), v3)
        v4 = v + h * a3
        a4 = acc(integrate(model, q, h * v3), v4)
        h6 = h / 6.0
        return (integrate(model, q, h6 * (v + 2.0 * (v2 + v3) + v4)),
                v + h6 * (a1 + 2.0 * (a2 + a3) + a4))

    step = {"euler": euler, "rk4": rk4, "rk4-naive": rk4_naive}[method]

    Q, V, n = march(lambda t, q, v, h: step(q, v, h), q0, v0, times, steps)
    return Q, V, n, n * STAGES[method]


def adaptive(pm, method, q0, v0, times, rtol, atol):
    """scipy's ``method`` (``"RK45"`` or ``"DOP853"``) in local coordinates over the whole horizon, sampled
    by its dense output: ``(Q (n, nq), V (n, nv), accepted steps, RHS evaluations)``, NaN from the first
    sample the solver does not reach.

    One solver object runs from ``times[0]`` to ``times[-1]``: its step size follows its error estimate
    alone (a solver restarted at every sample took the sample interval as its step wherever that already
    met the tolerance, so rtol 1e-6 and 1e-9 gave one trajectory, bit for bit). After each accepted step
    the chart is re-centred on the step's end: ``q_c <- integrate(q_c, delta)``, ``delta <- 0`` and the
    solver's first-same-as-last derivative ``f = (dexp^-1(q_c, delta, v), a)`` becomes ``(v, a)`` (``a`` is
    ``acc(q, v)``, and the move changes neither ``q`` nor ``v``), so the next step starts from the
    same state and derivative, in the new chart, with the step size the controller chose. The samples
    passed by a step are read from its dense output in the step's own chart, before the move.
    """
    import pinocchio as pin
    from scipy.integrate import DOP853, RK45

    model, nv = pm.model, pm.model.nv
    acc = pm.acceleration_function()
    dexpinv = pm.dexpinv_function() or (lambda q, theta, vel: vel)
    Q = np.full((len(times), model.nq), np.nan)
    V = np.full((len(times), nv), np.nan)
    Q[0], V[0] = q0, v0
    centre = [np.array(q0, dtype=float)]  # the chart's centre q_c, moved after every step

    def rhs(t, y):
        delta, vel = y[:nv], y[nv:]
        return np.concatenate([dexpinv(centre[0], delta, vel), acc(pin.integrate(model, centre[0], delta), vel)])

    solver_class = {"RK45": RK45, "DOP853": DOP853}[method]
    n_steps, k, solver = 0, 1, None  # k: the next sample to read
    try:
        solver = solver_class(rhs, float(times[0]), np.concatenate([np.zeros(nv), v0]), float(times[-1]),
                              rtol=rtol or 1e-8, atol=atol or 1e-8)
        while k < len(times) and solver.status == "running":
            if solver.step() is not None or not np.all(np.isfinite(solver.y)):
                break  # scipy's step failed (its step size fell below its minimum) or the state blew up
            n_steps += 1
            passed = k + int(np.searchsorted(times[k:], solver.t, side="right"))  # samples up to the step's end
            dense = solver.dense_output() if times[k] < solver.t else None  # (one interpolant per step)
            for j in range(k, passed):
                y = solver.y if times[j] == solver.t else dense(times[j])
                Q[j], V[j] = pin.integrate(model, centre[0], y[:nv]), y[nv:]
            k = passed
            # re-centre the chart on the step's end (docstring): same state, same derivative. scipy's Runge-Kutta
            # solvers take each step from their attributes y and f (scipy/integrate/_ivp/rk.py, RungeKutta._step_impl)
            centre[0] = pin.integrate(model, centre[0], solver.y[:nv])
            v = solver.y[nv:].copy()
            solver.y = np.concatenate([np.zeros(nv), v])
            solver.f = np.concatenate([v, solver.f[nv:]])
    except Exception as e:
        if not is_numerical_failure(e):
            raise
    return Q, V, n_steps, int(solver.nfev) if solver is not None else 0
