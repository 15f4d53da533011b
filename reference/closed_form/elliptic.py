"""Jacobi elliptic functions and integrals of the first kind, to roundoff,
parametrized by the complementary parameter ``m1 = 1 - m``.

Why not ``scipy.special.ellipj``: it takes ``m`` itself, so near the separatrix
of the torque-free top (``m1`` ~ 1e-8) the rounding of ``m`` alone destroys
half of the digits of ``m1`` and hence of the period, and its documentation
says it switches to an approximation for ``m1 < 1e-9``. Here ``m1`` is carried
exactly from the physical data, and every formula avoids cancellation:

* ``sn, cn``: descending Landen / arithmetic-geometric mean, Abramowitz &
  Stegun (1964) 16.4, started from ``b0 = sqrt(m1)`` and with
  ``c_{n+1} = c_n^2 / (4 a_{n+1})`` instead of the cancelling ``(a - b)/2``;
* ``dn = sqrt(cn^2 + m1 sn^2)`` (A&S 16.9.1 rewritten without ``1 - m sn^2``);
* ``F(phi|m) = sin(phi) R_F(cos^2 phi, cos^2 phi + m1 sin^2 phi, 1)`` and
  ``K(m) = R_F(0, m1, 1)``: Carlson's symmetric integral, DLMF 19.25.5 and
  19.25.1, evaluated by ``scipy.special.elliprf`` (Carlson 1995, relative error
  a few ulps).
"""

from __future__ import annotations

import numpy as np

__all__ = ["ellipk", "ellipj", "amplitude", "inverse_amplitude"]

# The AGM stops when c_n/a_n falls below this; one ulp of 1.0.
_AGM_TOL = np.finfo(float).eps
_AGM_MAX_ITER = 64  # converges quadratically; 64 is unreachable for m1 >= 1e-300


def ellipk(m1):
    """Complete elliptic integral of the first kind ``K(m)``, ``m = 1 - m1``.

    Parameters
    ----------
    m1 : float
        Complementary parameter, ``0 <= m1 <= 1``. ``m1 = 0`` gives ``inf``.
    """
    if m1 == 0.0:
        return np.inf
    from scipy.special import elliprf  # here, not at the top: scipy.special is ~0.2 s of a process's start

    return float(elliprf(0.0, m1, 1.0))


def ellipj(u, m1):
    """Jacobi elliptic functions ``sn, cn, dn`` of ``u`` for parameter ``m = 1 - m1``.

    Parameters
    ----------
    u : array_like, shape (n,)
        Argument (dimensionless). Reduced modulo ``4K`` internally.
    m1 : float
        Complementary parameter, ``0 <= m1 <= 1``.

    Returns
    -------
    sn, cn, dn : ndarray, shape (n,)
    """
    u = np.asarray(u, dtype=float)
    if not 0.0 <= m1 <= 1.0:
        raise ValueError(f"m1 must lie in [0, 1], got {m1!r}")
    if m1 == 0.0:  # m = 1: the separatrix, hyperbolic functions (A&S 16.6.1-3)
        sech = 1.0 / np.cosh(u)
        return np.tanh(u), sech, sech
    K = ellipk(m1)
    # Reduce to |u| <= 2K (sn, cn have period 4K): keeps the amplitude small.
    phi = _agm_amplitude(u - 4.0 * K * np.round(u / (4.0 * K)), m1)
    sn, cn = np.sin(phi), np.cos(phi)
    dn = np.sqrt(cn * cn + m1 * sn * sn)
    return sn, cn, dn


def amplitude(u, m1):
    """Jacobi amplitude ``am(u | m)``, ``m = 1 - m1``, continuous in ``u`` (unbounded: ``am(u + 2K) =
    am(u) + pi``), so that ``sn = sin am`` and ``cn = cos am``.

    Parameters
    ----------
    u : array_like, shape (n,) — argument (dimensionless)
    m1 : float — complementary parameter, ``0 <= m1 <= 1``; ``m1 = 0`` gives the Gudermannian
        ``atan(sinh u)`` (A&S 16.6.1)

    Returns
    -------
    ndarray, shape (n,) — rad
    """
    u = np.asarray(u, dtype=float)
    if not 0.0 <= m1 <= 1.0:
        raise ValueError(f"m1 must lie in [0, 1], got {m1!r}")
    if m1 == 0.0:
        return np.arctan(np.sinh(u))
    K = ellipk(m1)
    turns = np.round(u / (2.0 * K))  # reduce to |u| <= K, where the amplitude lies in [-pi/2, pi/2]
    return _agm_amplitude(u - 2.0 * K * turns, m1) + np.pi * turns


def _agm_amplitude(u, m1):
    """``am(u | 1 - m1)`` for ``|u| <= 2K`` by the descending Landen transformation (A&S 16.4),
    from ``b0 = sqrt(m1)`` with ``c_{n+1} = c_n^2 / (4 a_{n+1})`` (no cancelling difference)."""
    a, b, c = 1.0, np.sqrt(m1), np.sqrt(1.0 - m1)
    ratios = []
    while c > _AGM_TOL * a:
        if len(ratios) == _AGM_MAX_ITER:
            raise RuntimeError(f"AGM did not converge for m1={m1!r}")
        a_next = 0.5 * (a + b)
        c = c * c / (4.0 * a_next)
        b = np.sqrt(a * b)
        a = a_next
        ratios.append(c / a)
    phi = (2.0 ** len(ratios)) * a * u
    for r in reversed(ratios):
        phi = 0.5 * (phi + np.arcsin(r * np.sin(phi)))
    return phi


def inverse_amplitude(sn, cn, m1):
    """The ``u`` in ``(-2K, 2K]`` with ``sn(u) = sn`` and ``cn(u) = cn``.

    Parameters
    ----------
    sn, cn : float
        A point on the unit circle (normalized here).
    m1 : float
        Complementary parameter, ``0 <= m1 <= 1``. For ``m1 = 0`` the point
        must have ``cn > 0`` (the separatrix never reaches ``cn <= 0``).
    """
    r = np.hypot(sn, cn)
    s, c = sn / r, cn / r
    if m1 == 0.0:
        if c <= 0.0:
            raise ValueError("on the separatrix (m1 = 0) cn must be positive")
        return float(np.arctanh(s))
    from scipy.special import elliprf  # lazily, as in ellipk

    # F(phi) for |phi| <= pi/2 from Carlson's R_F; F(pi - phi) = 2K - F(phi).
    f = s * elliprf(c * c, c * c + m1 * s * s, 1.0)
    if c >= 0.0:
        return float(f)
    return float(np.copysign(2.0 * ellipk(m1), s) - f)
