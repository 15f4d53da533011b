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
* ``rk45``, ``dop853``: scipy ``solve_ivp`` in local coordinates
  ``q = integrate(q_k, delta)`` restarted at every sample ``q_k``: the state
  ``(delta, v)`` has no redundant component, so error control is not fooled by
  the quaternion's unit-norm constraint, and the quaternion never drifts.

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
    """scipy ``solve_ivp`` (``method``: ``"RK45"`` or ``"DOP853"``) in local coordinates, restarted
    at every sample: ``(Q (n, nq), V (n, nv), steps, RHS evaluations)``, NaN from the first sample
    the solver does not reach."""
    import pinocchio as pin
    from scipy.integrate import solve_ivp

    model, nv = pm.model, pm.model.nv
    acc = pm.acceleration_function()
    dexpinv = pm.dexpinv_function() or (lambda q, theta, vel: vel)
    Q = np.full((len(times), model.nq), np.nan)
    V = np.full((len(times), nv), np.nan)
    q, v = q0.copy(), v0.copy()
    Q[0], V[0] = q, v
    n_steps = n_rhs = 0
    for k in range(1, len(times)):
        q_ref = q

        def rhs(t, y):
            delta, vel = y[:nv], y[nv:]
            qq = pin.integrate(model, q_ref, delta)
            return np.concatenate([dexpinv(q_ref, delta, vel), acc(qq, vel)])

        try:
            sol = solve_ivp(rhs, (times[k - 1], times[k]), np.concatenate([np.zeros(nv), v]), method=method,
                            rtol=rtol or 1e-8, atol=atol or 1e-8)
        except Exception as e:
            if not is_numerical_failure(e):
                raise
            break
        n_steps += len(sol.t) - 1
        n_rhs += sol.nfev
        y = sol.y[:, -1]
        if not sol.success or not np.all(np.isfinite(y)):
            break
        q, v = pin.integrate(model, q_ref, y[:nv]), y[nv:]
        Q[k], V[k] = q, v
    return Q, V, n_steps, n_rhs
