"""Independent truth for the torque-free top: a Taylor-series integrator of
Euler's equations and quaternion kinematics in 40-digit arithmetic (mpmath).

Both right-hand sides are quadratic, so the Taylor coefficients follow exactly
from Cauchy products: ``x_{n+1} = (f(x))_n / (n+1)``. With steps ``h`` such
that ``|w| h <= 0.25`` and 40 terms, the truncation error is far below 1e-30,
and 40 digits keep roundoff there too — well beyond double precision, which is
what a test of a closed form near the separatrix needs (a double-precision
integrator cannot get closer than ~1e-8 rad there: the motion amplifies
roundoff by ~1e8 over 20 s).
"""

from __future__ import annotations

import mpmath as mp
import numpy as np

DIGITS = 40
ORDER = 40
STEP_ANGLE = 0.25  # rad turned per step, bounds the series' ratio


def _conv(a, b, n):
    return mp.fsum(a[k] * b[n - k] for k in range(n + 1))


def integrate_top(moments, w0_B, q0_WB, times):
    """Attitude and body angular velocity of a torque-free body with diagonal inertia.

    Parameters
    ----------
    moments : (3,) principal moments (kg m^2), body axes principal
    w0_B : (3,) initial ``w_WB_B`` (rad/s)
    q0_WB : (4,) initial quaternion, scalar first
    times : (n,) increasing sample times (s), ``times[0] >= 0``

    Returns
    -------
    q : ndarray (n, 4), w : ndarray (n, 3)  (rounded to double)
    """
    with mp.workdps(DIGITS):
        I = [mp.mpf(float(x)) for x in moments]
        c = [(I[1] - I[2]) / I[0], (I[2] - I[0]) / I[1], (I[0] - I[1]) / I[2]]
        w = [mp.mpf(float(x)) for x in w0_B]
        q = [mp.mpf(float(x)) for x in q0_WB]
        h_max = STEP_ANGLE / max(mp.sqrt(sum(x * x for x in w)), mp.mpf(1))
        t = mp.mpf(0)
        out_q, out_w = [], []
        for target in times:
            target = mp.mpf(float(target))
            while t < target:
                h = min(h_max, target - t)
                w, q = _step(c, w, q, h)
                t += h
            out_q.append([float(x) for x in q])
            out_w.append([float(x) for x in w])
    return np.array(out_q), np.array(out_w)


def _step(c, w, q, h):
    W = [[x] for x in w]
    Q = [[x] for x in q]
    for n in range(ORDER):
        p = n + 1
        W[0].append(c[0] * _conv(W[1], W[2], n) / p)
        W[1].append(c[1] * _conv(W[2], W[0], n) / p)
        W[2].append(c[2] * _conv(W[0], W[1], n) / p)
        # q' = 1/2 q * (0, w)
        qw, qx, qy, qz = Q
        wx, wy, wz = W
        Q[0].append(-(_conv(qx, wx, n) + _conv(qy, wy, n) + _conv(qz, wz, n)) / (2 * p))
        Q[1].append((_conv(qw, wx, n) + _conv(qy, wz, n) - _conv(qz, wy, n)) / (2 * p))
        Q[2].append((_conv(qw, wy, n) - _conv(qx, wz, n) + _conv(qz, wx, n)) / (2 * p))
        Q[3].append((_conv(qw, wz, n) + _conv(qx, wy, n) - _conv(qy, wx, n)) / (2 * p))
    horner = lambda coef: mp.fsum(c * h**k for k, c in enumerate(coef))  # noqa: E731
    return [horner(x) for x in W], [horner(x) for x in Q]
