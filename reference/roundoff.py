"""Roundoff floor: what double precision alone costs an integrator, by running it twice.

The same classical RK4, on Euler's equations and the quaternion kinematics of a
torque-free top, is run once in double and once in extended precision
(``numpy.longdouble``: 64-bit mantissa on x86-64 Linux, eps 1.1e-19). Their
truncation errors are the same; their difference is the roundoff a double
integrator accumulates over the horizon at that step, amplified by the motion's
own sensitivity (large near the separatrix of the intermediate axis, where the
time of each flip depends steeply on the energy). No double-precision integrator
taking as many steps can be expected to do better.

Checked (tests/test_roundoff.py) against truths that do not come from this
module: the extended run converges to the closed form (``TorqueFreeTop``, itself
checked against a 40-digit Taylor integration) at RK4's fourth order, so it is
RK4 on the right equations; and the floor scales with the unit roundoff of the
arithmetic (float32 against double is 2^29 times double against extended).
"""

from __future__ import annotations

import numpy as np

__all__ = ["EXTENDED", "rk4_top", "top_roundoff"]

# Extended precision where the platform has it (x86-64: 80-bit); None where
# ``longdouble`` is plain double (e.g. arm64 macOS), so no floor can be measured.
EXTENDED = np.longdouble if np.finfo(np.longdouble).eps < 1e-18 else None


def rk4_top(inertia, w0, times, dt, dtype=float, variant=0):
    """Classical RK4 on a torque-free top, in the scalar type ``dtype``.

    Parameters
    ----------
    inertia : (3,) principal moments about the COM, kg m^2 (body axes)
    w0 : (3,) initial angular velocity in body axes, rad/s (``w_WB_B``)
    times : (n,) sample times, s, from 0, evenly spaced; the attitude starts at identity
    dt : float — step, s (rounded so that it divides the sample interval)
    dtype : float, ``numpy.longdouble`` or ``numpy.float32`` — the arithmetic of every operation
    variant : 0, 1 or 2 — the order of the products in Euler's equations and of the sums in
        the kinematics: the same exact method with different rounding

    Returns
    -------
    (n, 4) ``q_WB`` scalar first, in ``dtype``, as integrated (not renormalized).
    """
    times = np.asarray(times, dtype=float)
    one, half = dtype(1), dtype(1) / dtype(2)
    I1, I2, I3 = (dtype(float(x)) for x in inertia)
    a1, a2, a3 = (I2 - I3) / I1, (I3 - I1) / I2, (I1 - I2) / I3

    def f0(w1, w2, w3, q0, q1, q2, q3):  # Euler's equations; q' = q (0, w) / 2
        return (a1 * w2 * w3, a2 * w3 * w1, a3 * w1 * w2,
                half * (-q1 * w1 - q2 * w2 - q3 * w3), half * (q0 * w1 + q2 * w3 - q3 * w2),
                half * (q0 * w2 + q3 * w1 - q1 * w3), half * (q0 * w3 + q1 * w2 - q2 * w1))

    def f1(w1, w2, w3, q0, q1, q2, q3):
        return (a1 * (w2 * w3), a2 * (w3 * w1), a3 * (w1 * w2),
                half * (-q3 * w3 - q2 * w2 - q1 * w1), half * (-q3 * w2 + q2 * w3 + q0 * w1),
                half * (-q1 * w3 + q3 * w1 + q0 * w2), half * (-q2 * w1 + q1 * w2 + q0 * w3))

    def f2(w1, w2, w3, q0, q1, q2, q3):
        return ((a1 * w3) * w2, (a2 * w1) * w3, (a3 * w2) * w1,
                half * (-q2 * w2 - q3 * w3 - q1 * w1), half * (q2 * w3 - q3 * w2 + q0 * w1),
                half * (q3 * w1 - q1 * w3 + q0 * w2), half * (q1 * w2 - q2 * w1 + q0 * w3))

    f = (f0, f1, f2)[variant]

    y = [dtype(float(x)) for x in w0] + [one, dtype(0), dtype(0), dtype(0)]
    out = np.empty((len(times), 4), dtype=dtype)
    out[0] = y[3:]
    for k in range(1, len(times)):
        n = max(1, int(round((times[k] - times[k - 1]) / dt)))
        h = (dtype(float(times[k])) - dtype(float(times[k - 1]))) / n
        h2, h6 = h / 2, h / 6
        for _ in range(n):
            k1 = f(*y)
            k2 = f(*[a + h2 * b for a, b in zip(y, k1)])
            k3 = f(*[a + h2 * b for a, b in zip(y, k2)])
            k4 = f(*[a + h * b for a, b in zip(y, k3)])
            y = [a + h6 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(y, k1, k2, k3, k4)]
        out[k] = y[3:]
    return out


def top_roundoff(inertia, w0, times, dt, working=float, extended=EXTENDED):
    """Largest attitude difference (rad) between RK4 in the ``working`` precision (its three
    ``variant``s) and the same RK4 in the ``extended`` one, on a torque-free top over ``times`` at
    step ``dt``; NaN where ``extended`` is None (the platform has no extended precision).

    The defaults, double against the platform's extended precision, give the floor of a
    double-precision integrator. Any pair works whose ``extended`` unit roundoff is far below the
    ``working`` one (the tests measure float32 against double).

    The roundoff is a random process amplified by the motion: one run is one sample (the three
    orderings give 4.1e-8 to 1.2e-7 rad in double on the 5 rad/s intermediate-axis top over 20 s at
    dt = 1e-3), so the floor is the largest of three.
    """
    from dalembert import spatial

    if extended is None:
        return float("nan")

    def unit(q):  # normalized in the extended precision: the comparison adds no rounding of the working one
        q = np.asarray(q, dtype=extended)
        return (q / np.sqrt(np.sum(q * q, axis=1))[:, None]).astype(float)

    reference = unit(rk4_top(inertia, w0, times, dt, extended))
    return max(float(np.max(spatial.rotation_angle(unit(rk4_top(inertia, w0, times, dt, working, v)), reference)))
               for v in range(3))
