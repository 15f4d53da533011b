"""Independent truths for the closed forms and the reference: Taylor-series integration in
40-digit arithmetic.

Every system here is written with a right-hand side that is quadratic in its state (extra
state variables make it so: ``sin`` and ``cos`` of the pendulum's angle, the Poisson vector of
a top), so the Taylor coefficients follow exactly from Cauchy products:
``x_{n+1} = (f(x))_n / (n + 1)``. With steps that turn at most ``STEP_ANGLE`` rad and ``ORDER``
terms, the truncation error is far below 1e-30, and 40 digits keep roundoff there too: well
beyond double precision, which is what a test of a closed form near a separatrix needs (a
double-precision integrator cannot get closer than ~1e-8 rad near the torque-free top's
separatrix: the motion amplifies roundoff by ~1e8 over 20 s). No formula is shared with the
elliptic-function solutions or with the reference solver.

The arithmetic is gmpy2's MPFR at ``PRECISION`` bits (mpmath's own backend, 20x faster from
Python than mpmath's objects).
"""

from __future__ import annotations

from operator import mul

import gmpy2
import numpy as np

DIGITS = 40
PRECISION = 136  # bits: 40 decimal digits (133 bits) and 3 guard bits
ORDER = 40
STEP_ANGLE = 0.25  # rad turned per step, bounds the series' ratio


def _conv(a, b, n):
    """The n-th coefficient of the product of two series."""
    return gmpy2.fsum(map(mul, a[: n + 1], reversed(b[: n + 1])))


def _mp(x):
    return gmpy2.mpfr(float(x))


def integrate(rhs, x0, times, h_max, order=ORDER):
    """Integrate ``x' = f(x)`` by Taylor series, sampled at ``times``.

    Parameters
    ----------
    rhs : callable ``(X, n) -> list`` — the n-th Taylor coefficient of each component of f(x(t)),
        given the coefficients ``X[k][0..n]`` of every component k (built from ``_conv``)
    x0 : sequence of float — initial state
    times : (m,) increasing sample times (s), ``times[0] >= 0``
    h_max : float — largest step (s)

    Returns
    -------
    ndarray (m, len(x0)) — the state at each sample, rounded to double
    """
    with gmpy2.context(gmpy2.get_context(), precision=PRECISION):
        x = [_mp(v) for v in x0]
        h_max = _mp(h_max)
        t = _mp(0.0)
        out = []
        for target in times:
            target = _mp(target)
            while t < target:
                h = min(h_max, target - t)
                X = [[v] for v in x]
                for n in range(order):
                    for series, coefficient in zip(X, rhs(X, n)):
                        series.append(coefficient / (n + 1))
                x = [_horner(series, h) for series in X]
                t += h
            out.append([float(v) for v in x])
    return np.array(out)


def _horner(coefficients, h):
    total = coefficients[-1]
    for c in reversed(coefficients[:-1]):
        total = total * h + c
    return total


def _quaternion_rate(Q, W, n):
    """``q' = 1/2 q (0, w)``, n-th coefficients (q scalar first, w in the body)."""
    qw, qx, qy, qz = Q
    wx, wy, wz = W
    return [-(_conv(qx, wx, n) + _conv(qy, wy, n) + _conv(qz, wz, n)) / 2,
            (_conv(qw, wx, n) + _conv(qy, wz, n) - _conv(qz, wy, n)) / 2,
            (_conv(qw, wy, n) - _conv(qx, wz, n) + _conv(qz, wx, n)) / 2,
            (_conv(qw, wz, n) + _conv(qx, wy, n) - _conv(qy, wx, n)) / 2]


def _cross(A, B, n):
    """n-th coefficients of ``a x b``."""
    return [_conv(A[1], B[2], n) - _conv(A[2], B[1], n),
            _conv(A[2], B[0], n) - _conv(A[0], B[2], n),
            _conv(A[0], B[1], n) - _conv(A[1], B[0], n)]


def integrate_top(moments, w0_B, q0_WB, times):
    """Attitude and body angular velocity of a torque-free body with diagonal inertia
    (Euler's equations and the quaternion kinematics).

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
    with gmpy2.context(gmpy2.get_context(), precision=PRECISION):
        I = [_mp(x) for x in moments]
        c = [(I[1] - I[2]) / I[0], (I[2] - I[0]) / I[1], (I[0] - I[1]) / I[2]]

    def rhs(X, n):
        W = X[:3]
        return [c[0] * _conv(W[1], W[2], n), c[1] * _conv(W[2], W[0], n), c[2] * _conv(W[0], W[1], n),
                *_quaternion_rate(X[3:], W, n)]

    h_max = STEP_ANGLE / max(float(np.linalg.norm(w0_B)), 1.0)
    x = integrate(rhs, [*w0_B, *q0_WB], times, h_max)
    return x[:, 3:], x[:, :3]


def integrate_pendulum(w0, theta0, rate0, times):
    """``theta'' = -w0^2 sin(theta)`` with ``s = sin(theta)``, ``c = cos(theta)`` carried along
    (``s' = c theta'``, ``c' = -s theta'``): angle (rad) and rate (rad/s), each ndarray (n,)."""
    with gmpy2.context(gmpy2.get_context(), precision=PRECISION):
        w2 = _mp(w0) ** 2
        s0, c0 = gmpy2.sin(_mp(theta0)), gmpy2.cos(_mp(theta0))

    def rhs(X, n):
        theta, rate, s, c = X
        return [rate[n], -w2 * s[n], _conv(c, rate, n), -_conv(s, rate, n)]

    # the rate stays below sqrt(rate0^2 + 4 w0^2) (energy); steps turn at most STEP_ANGLE rad
    h_max = STEP_ANGLE / max(float(np.hypot(rate0, 2.0 * w0)), 1.0)
    x = integrate(rhs, [theta0, rate0, s0, c0], times, h_max)
    return x[:, 0], x[:, 1]


def integrate_body_on_pivot(inertia_pivot, mgc_B, up_W, w0_B, q0_WB, times, w_max):
    """A rigid body turning about a fixed point under uniform gravity (the Euler-Poisson equations):
    ``I w' = (I w) x w + gamma x (m g c)``, ``gamma' = gamma x w``, ``q' = 1/2 q (0, w)``, with
    ``gamma`` the world's up direction in the body (dimensionless, unit).

    Parameters
    ----------
    inertia_pivot : (3, 3) inertia about the fixed point, body axes (kg m^2)
    mgc_B : (3,) ``m |g| c``: the weight times the centre of mass's position from the fixed point,
        body axes (N m)
    up_W : (3,) unit vector opposite to gravity, world
    w0_B : (3,) initial ``w_WB_B`` (rad/s); q0_WB : (4,) initial attitude, scalar first
    times : (n,) sample times (s)
    w_max : float — a bound on |w| over the horizon (rad/s), which sets the step

    Returns
    -------
    q : ndarray (n, 4), w : ndarray (n, 3), gamma : ndarray (n, 3)
    """
    with gmpy2.context(gmpy2.get_context(), precision=PRECISION):
        I = [[_mp(v) for v in row] for row in np.asarray(inertia_pivot, dtype=float)]
        Iinv = _inverse3(I)
        mgc = [_mp(v) for v in mgc_B]
        q0 = [_mp(v) for v in q0_WB]
        norm = gmpy2.sqrt(gmpy2.fsum(v * v for v in q0))
        q0 = [v / norm for v in q0]
        up = [_mp(v) for v in up_W]
        gamma0 = [gmpy2.fsum(R * u for R, u in zip(column, up)) for column in _columns(q0)]  # R^T up

    def rhs(X, n):
        W, G, Q = X[:3], X[3:6], X[6:]
        P = [[_conv(W[k], W[j], n) for j in range(3)] for k in range(3)]  # coefficients of w_k w_j
        Gn = [G[i][n] for i in range(3)]
        torque = []
        for i in range(3):
            i1, i2 = (i + 1) % 3, (i + 2) % 3
            gyro = gmpy2.fsum(I[i1][k] * P[k][i2] - I[i2][k] * P[k][i1] for k in range(3))  # ((I w) x w)_i
            torque.append(gyro + Gn[i1] * mgc[i2] - Gn[i2] * mgc[i1])
        w_dot = [gmpy2.fsum(Iinv[i][j] * torque[j] for j in range(3)) for i in range(3)]
        return [*w_dot, *_cross(G, W, n), *_quaternion_rate(Q, W, n)]

    x = integrate(rhs, [*w0_B, *gamma0, *q0], times, STEP_ANGLE / max(w_max, 1.0))
    return x[:, 6:], x[:, :3], x[:, 3:6]


def _columns(q):
    """Columns of R(q) (q scalar first, unit), as lists of mpfr."""
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)],
            [2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x)],
            [2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)]]


def _inverse3(A):
    """Inverse of a 3x3 matrix of mpfr by cofactors."""
    cof = [[A[(i + 1) % 3][(j + 1) % 3] * A[(i + 2) % 3][(j + 2) % 3]
            - A[(i + 1) % 3][(j + 2) % 3] * A[(i + 2) % 3][(j + 1) % 3] for j in range(3)] for i in range(3)]
    det = gmpy2.fsum(A[0][j] * cof[0][j] for j in range(3))
    return [[cof[j][i] / det for j in range(3)] for i in range(3)]
