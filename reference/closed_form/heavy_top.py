"""The heavy symmetric (Lagrange) top: a body symmetric about an axis through a fixed point and
its centre of mass, under uniform gravity.

Source: H. Goldstein, C. Poole, J. Safko, *Classical Mechanics*, 3rd ed. (2002), section 5.7
("The heavy symmetrical top with one point fixed"); Whittaker (1937), section 71. In the top
frame T (origin at the fixed point, axis 3 the symmetry axis towards the centre of mass, at
distance ``l``), with moments ``A`` (transverse) and ``C`` (axial) about the fixed point, and
z-x-z Euler angles ``R_VT = Rz(phi) Rx(theta) Rz(psi)`` relative to a frame V whose z points up,
the integrals are the spin ``w3 = psi' + phi' cos(theta)``, the vertical angular momentum about
the fixed point ``L_z = A phi' sin^2(theta) + C w3 cos(theta)`` and the energy. With
``u = cos(theta)``, ``a = C w3 / A``, ``b = L_z / A``, ``beta = 2 m g l / A``::

    u'^2 = f(u) = (1 - u^2)(alpha - beta u) - (b - a u)^2          (a cubic)
    phi' = (b - a u) / (1 - u^2),    psi' = w3 - u phi'

``f`` has roots ``u1 <= u2`` in [-1, 1] and ``u3 >= 1``; with ``u3 - u1 = x3 - x1`` etc.::

    u(t) = u1 + (u2 - u1) sn^2(lam t + tau0 | k^2),  k^2 = (u2 - u1)/(u3 - u1),
    lam = sqrt(beta (u3 - u1)) / 2                                   (substitute and compare)

Precession and spin are quadratures of the rates: with the partial fractions
``phi' = (b - a)/(2(1 - u)) + (b + a)/(2(1 + u))`` and ``psi' = w3 - a - (b - a)/(2(1 - u)) +
(b + a)/(2(1 + u))``, the attitude needs only ``sigma = phi + psi`` and ``delta = phi - psi``::

    q_VT = (cos(theta/2) cos(sigma/2), sin(theta/2) cos(delta/2),
            sin(theta/2) sin(delta/2), cos(theta/2) sin(sigma/2))

    sigma = sigma0 + (w3 - a) t + (b + a) int dt/(1 + u),  delta = delta0 - (w3 - a) t + (b - a) int dt/(1 - u)

Numerics, exact to roundoff (checked against a 40-digit Taylor integration of the
Euler-Poisson equations, tests/test_closed_forms.py):

* the cubic is expanded about the initial ``u0`` with coefficients formed from the initial rates
  (``f(u0) = (sin(theta0) theta'0)^2`` exactly), its large root ``x3`` found by safeguarded
  Newton, and the pair ``x1 <= 0 <= x2`` by deflation, ``x^2 + p x + q`` with ``q <= 0``: no
  cancellation, however small the nutation; a root near a pole is refined on the cubic
  expanded about that pole, so ``1 + u1`` (``1 - u2``) keeps its relative precision;
* ``1 +- u = (1 + u1) + (u2 - u1) sn^2`` and ``(1 - u2) + (u2 - u1) cn^2`` are sums of terms of
  one sign, and ``b +- a`` come from the initial state directly;
* the two integrals ``int dt/(1 +- u)`` are ``quadrature.PeriodicIntegral`` in ``tau`` over one
  period ``2K``, graded towards ``tau = 0`` and ``K`` where the axis passes near the lower or upper
  vertical (the rate's singularity is then ``sqrt((1 + u1)/(u2 - u1))`` off the real axis: 7e-7
  for the heavy-top benchmark's start);
* where the axis passes exactly through a pole (``b + a = 0`` with ``u1 = -1``, or ``b - a = 0``
  with ``u2 = 1``), ``cos(theta/2)`` (``sin(theta/2)``) takes the sign of ``sn`` (``cn``): the axis
  goes through the vertical instead of bouncing off it.

The start must have the symmetry axis off the vertical (``0 < theta0 < pi``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dalembert import spatial
from dalembert.reference.closed_form.elliptic import ellipj, ellipk, inverse_amplitude
from dalembert.reference.closed_form.quadrature import PeriodicIntegral, graded_edges

__all__ = ["LagrangeTop"]

_PANEL = 0.5  # largest quadrature panel in tau (quadrature.py)
_NEAR_POLE = 0.5  # refine a root closer than this to -1 or +1 on the cubic expanded about that pole
_NEWTON_STEPS = 60


def _cubic_about(one_minus_c2, minus_2c, alpha_minus_beta_c, beta, b_minus_a_c, a):
    """Coefficients ``k0..k3`` of ``f(c + y)`` from the data at the centre ``c``."""
    A0, A1, A2 = one_minus_c2, minus_2c, -1.0
    B0, B1 = alpha_minus_beta_c, -beta
    C0, C1 = b_minus_a_c, -a
    return [A0 * B0 - C0 * C0, A0 * B1 + A1 * B0 - 2.0 * C0 * C1, A1 * B1 + A2 * B0 - C1 * C1, A2 * B1]


def _horner(k, y):
    return ((k[3] * y + k[2]) * y + k[1]) * y + k[0]


def _newton(k, y, lo, hi):
    """A root of the cubic ``k`` in ``[lo, hi]`` (it changes sign there) from ``y``: Newton, with
    bisection whenever a step leaves the bracket."""
    f_lo = _horner(k, lo)
    for _ in range(_NEWTON_STEPS):
        f = _horner(k, y)
        if f == 0.0:
            return y
        if (f < 0.0) == (f_lo < 0.0):
            lo, f_lo = y, f
        else:
            hi = y
        d = (3.0 * k[3] * y + 2.0 * k[2]) * y + k[1]
        step = f / d if d != 0.0 else np.inf
        y_next = y - step
        if not lo < y_next < hi:
            y_next = 0.5 * (lo + hi)
        if y_next == y or hi - lo <= 4.0 * np.finfo(float).eps * max(abs(lo), abs(hi)):
            return y_next
        y = y_next
    return y


@dataclass(frozen=True, eq=False)
class LagrangeTop:
    """Closed-form motion of a heavy symmetric top about its fixed point.

    Parameters
    ----------
    mgl : float — weight times the distance from the fixed point to the centre of mass, ``m g l`` (N m), > 0
    A, C : float — transverse and axial moments of inertia about the fixed point (kg m^2)
    R0_WT : array_like (3, 3) — initial attitude of the top frame T (axis 3: the symmetry axis,
        from the fixed point towards the centre of mass)
    w0_T : array_like (3,) — initial angular velocity ``w_WT_T`` in T (rad/s)
    up : array_like (3,) — world direction opposite to gravity
    """

    mgl: float
    A: float
    C: float
    R0_WT: np.ndarray
    w0_T: np.ndarray
    up: tuple = (0.0, 0.0, 1.0)
    _s: dict = field(init=False, repr=False)

    def __post_init__(self):
        problems = [f"{k}: must be positive and finite, got {getattr(self, k)!r}" for k in ("mgl", "A", "C")
                    if not (np.isfinite(getattr(self, k)) and getattr(self, k) > 0.0)]
        if problems:
            raise ValueError("LagrangeTop: " + "; ".join(problems))
        object.__setattr__(self, "R0_WT", np.asarray(self.R0_WT, dtype=float))
        object.__setattr__(self, "w0_T", np.asarray(self.w0_T, dtype=float))
        object.__setattr__(self, "_s", self._solve())

    # ------------------------------------------------------------------ set-up
    def _solve(self):
        A, C, w = self.A, self.C, self.w0_T
        R_WV = spatial.frame_with_z(self.up)
        R_VT = R_WV.T @ self.R0_WT
        e3 = R_VT[:, 2]  # the symmetry axis in V
        s0_sq = e3[0] ** 2 + e3[1] ** 2  # sin^2(theta0), without cancellation
        if not s0_sq > 0.0:
            raise ValueError("LagrangeTop: the symmetry axis starts vertical (theta0 = 0 or pi), where the "
                             "Euler angles of this solution are undefined — tilt it")
        u0, s0 = e3[2], np.sqrt(s0_sq)
        one_plus_u0 = 1.0 + u0 if u0 >= 0.0 else s0_sq / (1.0 - u0)  # 1 + u0 = s0^2 / (1 - u0)
        one_minus_u0 = 1.0 - u0 if u0 < 0.0 else s0_sq / (1.0 + u0)
        phi0, psi0 = np.arctan2(e3[0], -e3[1]), np.arctan2(R_VT[2, 0], R_VT[2, 1])
        c, s = np.cos(psi0), np.sin(psi0)
        theta_rate = w[0] * c - w[1] * s  # theta'0
        phi_rate_s = w[0] * s + w[1] * c  # phi'0 sin(theta0)
        w3 = w[2]
        a, beta = C * w3 / A, 2.0 * self.mgl / A
        P0 = theta_rate**2 + phi_rate_s**2  # alpha - beta u0
        Q0 = phi_rate_s * s0  # b - a u0
        b_plus_a, b_minus_a = Q0 + a * one_plus_u0, Q0 - a * one_minus_u0
        # the cubic about u0 (x = u - u0): f(u0) = (sin(theta0) theta'0)^2 exactly
        k = _cubic_about(s0_sq, -2.0 * u0, P0, beta, Q0, a)
        k[0] = (s0 * theta_rate) ** 2
        # the large root u3 >= 1, i.e. x3 >= 1 - u0, where f(1) = -(b - a)^2 <= 0
        lo = one_minus_u0
        top_is_u3 = b_minus_a == 0.0 and (3.0 * k[3] * lo + 2.0 * k[2]) * lo + k[1] > 0.0
        if top_is_u3:  # f(1) = 0 rising: u = 1 is the largest root itself
            x3 = lo
        else:
            while _horner(k, lo) >= 0.0:  # (f(1) = 0 falling: u2 = 1; u3 lies above)
                lo = np.nextafter(lo, np.inf) if lo else np.finfo(float).tiny
            hi = lo + 1.0
            while _horner(k, hi) <= 0.0:
                hi = lo + 2.0 * (hi - lo)
            x3 = _newton(k, hi, lo, hi)
        # the pair by deflation: x^2 + p x + q, q = x1 x2 <= 0
        p = k[2] / k[3] + x3
        q = -k[0] / (k[3] * x3)
        root = np.sqrt(p * p - 4.0 * q)
        if p > 0.0:
            x1 = -0.5 * (p + root)
            x2 = q / x1 if x1 != 0.0 else 0.0
        else:
            x2 = 0.5 * (root - p)
            x1 = q / x2 if x2 != 0.0 else 0.0
        delta = root  # u2 - u1
        s = dict(R_WV=R_WV, A=A, C=C, w3=w3, a=a, b_plus_a=b_plus_a, b_minus_a=b_minus_a,
                 sigma0=phi0 + psi0, delta0=phi0 - psi0, u0=u0)
        if delta == 0.0:  # steady precession: u stays u0
            s.update(kind="steady", phi_rate=phi_rate_s / s0, one_plus=one_plus_u0, one_minus=one_minus_u0,
                     theta_rate=0.0)
            return s
        # 1 + u1 and 1 - u2 to full relative precision near a pole
        v1 = one_plus_u0 + x1
        if v1 < _NEAR_POLE:
            kv = _cubic_about(0.0, 2.0, P0 + beta * one_plus_u0, beta, b_plus_a, a)  # f(-1 + v)
            kv[0] = -b_plus_a**2
            v1 = 0.0 if b_plus_a == 0.0 else _newton(kv, max(v1, 0.0), 0.0, one_plus_u0)
        w2 = one_minus_u0 - x2
        if w2 < _NEAR_POLE and not top_is_u3:
            kw = _cubic_about(0.0, 2.0, P0 - beta * one_minus_u0, -beta, b_minus_a, -a)  # f(1 - w)
            kw[0] = -b_minus_a**2
            w2 = 0.0 if b_minus_a == 0.0 else _newton(kw, max(w2, 0.0), 0.0, one_minus_u0)
        m1 = (x3 - x2) / (x3 - x1)  # 1 - k^2 = (u3 - u2)/(u3 - u1)
        lam = 0.5 * np.sqrt(beta * (x3 - x1))
        # tau0: sn^2 = (u0 - u1)/delta, sn >= 0; sn cn has the sign of u'0 = -sin(theta0) theta'0
        sn0 = np.sqrt(max(-x1, 0.0) / delta)
        cn0 = np.sqrt(max(x2, 0.0) / delta) * (-1.0 if theta_rate > 0.0 else 1.0)
        tau0 = inverse_amplitude(sn0, cn0, m1)
        K = ellipk(m1)
        s.update(kind="nutating", v1=v1, w2=w2, delta=delta, m1=m1, lam=lam, tau0=tau0, K=K,
                 cn_sign=np.sign(cn0) or 1.0)
        # Each integral over the period centred on its near-singular point, graded towards it: 1/(1 + u) at
        # tau = 0 (u = u1; singular sqrt(v1/delta) off the axis), 1/(1 - u) at tau = K (u = u2), integrated in
        # r = tau - K with cn(K + r)^2 = m1 sd(r)^2 (A&S 16.8.2; singular sqrt(w2/(delta m1)) off the axis).
        # Centred so that sn, sd are evaluated at small arguments, to full relative precision where
        # the rate peaks (sn(2K - e) would carry an absolute error of an ulp of pi).
        def edges(d):
            return np.concatenate([graded_edges(-K, 0.0, _PANEL, None, d), graded_edges(0.0, K, _PANEL, d, None)[1:]])

        # (an integral whose coefficient b +- a is zero is not needed: the axis then goes through that pole,
        # where the integrand is singular on the real axis)
        if b_plus_a != 0.0:
            d = np.sqrt(v1 / delta) if v1 > 0.0 else None
            s["plus"] = PeriodicIntegral(lambda r: self._one_plus_inverse(s, r), 2.0 * K, -K, edges(d))
        if b_minus_a != 0.0:
            d = np.sqrt(w2 / (delta * m1)) if m1 > 0.0 else None
            s["minus"] = PeriodicIntegral(lambda r: self._one_minus_inverse(s, r), 2.0 * K, -K, edges(d))
        return s

    @staticmethod
    def _one_plus_inverse(s, tau):
        """``1 / (1 + u)`` at ``tau``, shape like ``tau``."""
        sn, _, _ = ellipj(tau, s["m1"])
        return 1.0 / (s["v1"] + s["delta"] * sn * sn)

    @staticmethod
    def _one_minus_inverse(s, r):
        """``1 / (1 - u)`` at ``tau = K + r``, shape like ``r``."""
        sn, _, dn = ellipj(r, s["m1"])
        sd = sn / dn
        return 1.0 / (s["w2"] + s["delta"] * s["m1"] * sd * sd)

    # ---------------------------------------------------------------- results
    @property
    def regime(self):
        """``'nutating'`` or ``'steady'`` (uniform precession)."""
        return self._s["kind"]

    @property
    def nutation_period(self):
        """Period of ``cos(theta)`` (s); inf for a steady precession."""
        s = self._s
        return 2.0 * s["K"] / s["lam"] if s["kind"] == "nutating" else np.inf

    def _angles(self, t):
        """``cos(theta/2)``, ``sin(theta/2)``, ``sigma``, ``delta``, ``theta'``, ``phi' sin(theta)``, each (n,)."""
        s, t = self._s, np.asarray(t, dtype=float)
        if s["kind"] == "steady":
            n = np.ones_like(t)
            spin = s["w3"] - s["a"]
            sigma = s["sigma0"] + (spin + s["b_plus_a"] / s["one_plus"]) * t
            delta = s["delta0"] + (-spin + s["b_minus_a"] / s["one_minus"]) * t
            s0 = np.sqrt(s["one_plus"] * s["one_minus"])
            return (np.sqrt(0.5 * s["one_plus"]) * n, np.sqrt(0.5 * s["one_minus"]) * n, sigma, delta,
                    0.0 * n, s["phi_rate"] * s0 * n)
        tau = s["lam"] * t + s["tau0"]
        sn, cn, dn = ellipj(tau, s["m1"])
        one_plus = s["v1"] + s["delta"] * sn * sn
        one_minus = s["w2"] + s["delta"] * cn * cn
        half_cos = np.sqrt(0.5 * one_plus)
        half_sin = np.sqrt(0.5 * one_minus)
        if s["v1"] == 0.0:  # through the lower pole: cos(theta/2) changes sign with sn
            half_cos = np.sqrt(0.5 * s["delta"]) * sn
        if s["w2"] == 0.0:  # through the upper pole
            half_sin = np.sqrt(0.5 * s["delta"]) * cn * s["cn_sign"]
        spin = s["w3"] - s["a"]
        sigma = s["sigma0"] + spin * t
        delta = s["delta0"] - spin * t
        if "plus" in s:  # + (b + a) int_0^t dt / (1 + u)
            sigma = sigma + s["b_plus_a"] * (s["plus"](tau) - s["plus"](s["tau0"])) / s["lam"]
        if "minus" in s:
            delta = delta + s["b_minus_a"] * (s["minus"](tau - s["K"]) - s["minus"](s["tau0"] - s["K"])) / s["lam"]
        # sin(theta) = 2 sin(theta/2) cos(theta/2); theta' = -u' / sin(theta), u' = 2 delta lam sn cn dn
        sin_theta = 2.0 * half_sin * half_cos
        with np.errstate(invalid="ignore", divide="ignore"):
            theta_rate = np.where(sin_theta != 0.0, -2.0 * s["delta"] * s["lam"] * sn * cn * dn / sin_theta, 0.0)
            # phi' sin(theta) = (b - a u)/sin(theta), b - a u = ((b - a)(1 + u) + (b + a)(1 - u))/2
            phi_rate_s = 0.5 * (s["b_minus_a"] * one_plus + s["b_plus_a"] * one_minus) / sin_theta
        return half_cos, half_sin, sigma, delta, theta_rate, phi_rate_s

    def quaternion_vertical(self, t):
        """``q_VT`` (scalar first) at times ``t`` (s), shape (n,) -> (n, 4); V: z up."""
        hc, hs, sigma, delta, _, _ = self._angles(t)
        return np.stack([hc * np.cos(0.5 * sigma), hs * np.cos(0.5 * delta), hs * np.sin(0.5 * delta),
                         hc * np.sin(0.5 * sigma)], -1)

    def rotation(self, t):
        """``R_WT`` at times ``t`` (s), shape (n,) -> (n, 3, 3)."""
        return self._s["R_WV"] @ spatial.quat_to_matrix(self.quaternion_vertical(t))

    def quaternion(self, t):
        """``q_WT`` (scalar first), shape (n, 4)."""
        return spatial.quat_multiply(spatial.matrix_to_quat(self._s["R_WV"]), self.quaternion_vertical(t))

    def cos_theta(self, t):
        """``u = cos(theta)``: the symmetry axis's component along ``up``, shape (n,)."""
        hc, hs, _, _, _, _ = self._angles(t)
        return hc * hc - hs * hs

    def angular_velocity_top(self, t):
        """``w_WT_T`` (rad/s) in the top frame, shape (n, 3)."""
        hc, hs, sigma, delta, theta_rate, phi_rate_s = self._angles(t)
        psi = 0.5 * (sigma - delta)
        c, s = np.cos(psi), np.sin(psi)
        w3 = np.full(np.shape(c), self._s["w3"])
        return np.stack([phi_rate_s * s + theta_rate * c, phi_rate_s * c - theta_rate * s, w3], -1)

    def angular_velocity_world(self, t):
        """``w_WT_W`` (rad/s), world axes, shape (n, 3)."""
        return np.einsum("nij,nj->ni", self.rotation(t), self.angular_velocity_top(t))
