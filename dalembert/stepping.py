"""The fixed-step march shared by the engines whose integrators are ours (the reference
solver, Pinocchio's Python loop): from sample to sample in whole steps, stopping at the
first non-finite state (divergence is a result, not an exception)."""

from __future__ import annotations

import numpy as np

from dalembert.settings import is_numerical_failure

__all__ = ["march"]


def march(step, q0, v0, times, steps):
    """Advance ``(q, v)`` through ``times`` with ``steps[k]`` equal steps between samples k and k + 1.

    Parameters
    ----------
    step : callable ``(t, q, v, h) -> (q, v)`` — one step of ``h`` s from time ``t`` (s)
    q0 : (nq,) initial configuration; v0 : (nv,) initial velocity (the engine's coordinates)
    times : (n,) sample times, s
    steps : (n - 1,) int — steps per sample interval

    Returns
    -------
    Q : (n, nq), V : (n, nv) — the state at each sample; NaN from the first sample whose
        state is non-finite or whose steps raised a numerical failure (``is_numerical_failure``)
    taken : int — steps taken up to the last finite sample
    """
    times = np.asarray(times, dtype=float)
    Q = np.full((len(times), len(q0)), np.nan)
    V = np.full((len(times), len(v0)), np.nan)
    q, v = np.array(q0, dtype=float), np.array(v0, dtype=float)
    Q[0], V[0] = q, v
    taken = 0
    for k, n in enumerate(steps):
        h = (times[k + 1] - times[k]) / n
        try:
            with np.errstate(over="ignore", invalid="ignore"):  # a blow-up is data, not a warning
                for i in range(n):
                    q, v = step(times[k] + i * h, q, v, h)
        except Exception as e:  # a blown-up state (e.g. a singular matrix): NaN from here on
            if not is_numerical_failure(e):
                raise
            break
        taken += n
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            break
        Q[k + 1], V[k + 1] = q, v
    return Q, V, taken
