"""A rigid body swinging about a fixed horizontal axis under uniform gravity: the physical pendulum.

Source: E. T. Whittaker, *A Treatise on the Analytical Dynamics of Particles and
Rigid Bodies*, 4th ed. (1937), section 44 ("The simple pendulum"), and
Abramowitz & Stegun (1964) 16.1, 16.9. With ``theta`` the angle of the line from the
axis to the centre of mass below the downward vertical, ``d`` that distance, ``I_O``
the moment of inertia about the axis and ``w0^2 = m g d / I_O``::

    I_O theta'' = -m g d sin(theta)
    theta'^2 / 4 + w0^2 sin^2(theta / 2) = h w0^2          (the energy integral)

with ``h = sin^2(theta0 / 2) + (theta'0 / (2 w0))^2``. Then

* libration, ``h < 1`` (``k^2 = h = sin^2`` of half the amplitude)::

      sin(theta / 2) = k sn(u | k^2),  cos(theta / 2) = dn(u | k^2),  theta' = 2 k w0 cn(u | k^2),
      u = w0 t + u0,  period 4 K(k^2) / w0;

* rotation over the top, ``h > 1``::

      theta / 2 = am(v | 1/h),  theta' = 2 sqrt(h) w0 dn(v | 1/h),  v = sqrt(h) w0 t + v0,
      one turn per 2 K(1/h) / (sqrt(h) w0);

* the separatrix, ``h = 1``: ``sin(theta/2) = tanh(u)``, the libration formulas with ``k = 1``.

``theta`` is taken as ``2 atan2(k sn, dn)`` (never ``2 asin``, ill-conditioned at the turning
points), the complementary parameters ``1 - h = (cos(theta0/2) - r)(cos(theta0/2) + r)`` and
``(h - 1)/h`` with ``r = theta'0 / (2 w0)`` are formed without cancelling differences, and
``u0``, ``v0`` come from Carlson's ``R_F`` (``elliptic.inverse_amplitude``), so the angle is
exact to a few ulps of the phase ``w0 t`` at any amplitude, the separatrix's neighbourhood
included. Starts with ``theta'0 < 0`` use the mirror symmetry ``theta -> -theta``.

The pivot reaction follows from Newton's law for the body: the force the axis exerts ON
the body is ``R = m a_com - m g``, with ``a_com = d (theta'' t_hat - theta'^2 r_hat)``,
``r_hat`` from the axis to the centre of mass and ``t_hat`` the direction it moves for
increasing ``theta`` (plus the axial part, zero for a body symmetric about its swing plane).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dalembert.reference.closed_form.elliptic import amplitude, ellipj, ellipk, inverse_amplitude

__all__ = ["RigidPendulum"]


@dataclass(frozen=True, eq=False)
class RigidPendulum:
    """Closed-form motion of a physical pendulum.

    Parameters
    ----------
    mass : float — kg
    com_distance : float — from the axis to the centre of mass, ``d`` (m), positive
    inertia_pivot : float — moment of inertia about the axis, ``I_O`` (kg m^2)
    gravity : float — magnitude of the gravitational acceleration (m/s^2), positive
    theta0 : float — initial angle from the downward vertical (rad); any real number
    rate0 : float — initial rate ``theta'0`` (rad/s)
    down, swing : array_like, shape (3,) — world unit vectors: the direction of gravity, and the
        direction the centre of mass moves at ``theta = 0`` for increasing ``theta`` (the swing
        plane's horizontal); they place the motion in the world for the vector methods
    """

    mass: float
    com_distance: float
    inertia_pivot: float
    gravity: float
    theta0: float = 0.0
    rate0: float = 0.0
    down: tuple = (0.0, 0.0, -1.0)
    swing: tuple = (1.0, 0.0, 0.0)
    _s: dict = field(init=False, repr=False)

    def __post_init__(self):
        problems = [f"{name}: must be positive and finite, got {getattr(self, name)!r}"
                    for name in ("mass", "com_distance", "inertia_pivot", "gravity")
                    if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0.0)]
        if not (np.isfinite(self.theta0) and np.isfinite(self.rate0)):
            problems.append("theta0, rate0: must be finite")
        if problems:
            raise ValueError("RigidPendulum: " + "; ".join(problems))
        object.__setattr__(self, "_s", self._solve())

    @property
    def natural_frequency(self):
        """``w0 = sqrt(m g d / I_O)`` (rad/s): the small-amplitude angular frequency."""
        return float(np.sqrt(self.mass * self.gravity * self.com_distance / self.inertia_pivot))

    def _solve(self):
        w0 = self.natural_frequency
        sign = -1.0 if self.rate0 < 0.0 else 1.0  # mirror a start turning backwards
        theta0, rate0 = sign * self.theta0, sign * self.rate0
        # libration centre and half-angle within (-pi/2, pi/2]
        turns = np.round(theta0 / (2.0 * np.pi))
        half = 0.5 * (theta0 - 2.0 * np.pi * turns)
        s, c, r = np.sin(half), np.cos(half), rate0 / (2.0 * w0)
        h = s * s + r * r
        out = dict(w0=w0, sign=sign, h=h)
        if h == 0.0:
            return dict(out, regime="rest", centre=2.0 * np.pi * turns)
        if h <= 1.0:
            m1 = max((c - r) * (c + r), 0.0)
            if m1 == 0.0 and r == 0.0:  # balanced upside down: stays there
                return dict(out, regime="rest", centre=theta0)
            k = np.sqrt(h)
            u0 = inverse_amplitude(s / k, r / k, m1)
            return dict(out, regime="libration" if m1 > 0.0 else "separatrix", m1=m1, k=k, u0=u0,
                        centre=2.0 * np.pi * turns, period=4.0 * ellipk(m1) / w0 if m1 > 0.0 else np.inf)
        m1 = (r - c) * (r + c) / h  # rotation: parameter 1/h, complementary (h - 1)/h
        rate = np.sqrt(h) * w0  # dv/dt
        v0 = inverse_amplitude(s, c, m1) + 2.0 * ellipk(m1) * turns  # F(theta0/2 | 1/h): F(x + pi) = F(x) + 2K
        return dict(out, regime="rotation", m1=m1, rate=rate, v0=v0, period=2.0 * ellipk(m1) / rate)

    # ---------------------------------------------------------------- results
    @property
    def regime(self):
        """``'libration'``, ``'rotation'``, ``'separatrix'`` or ``'rest'``."""
        return self._s["regime"]

    @property
    def period(self):
        """Time of one swing back and forth (libration) or one full turn (rotation), s (inf on the
        separatrix, nan at rest)."""
        return self._s.get("period", np.nan)

    def angle(self, t):
        """``theta(t)`` (rad), shape like ``t`` (s); continuous (a rotation keeps counting turns)."""
        return self._state(t)[0]

    def rate(self, t):
        """``theta'(t)`` (rad/s)."""
        return self._state(t)[1]

    def angular_acceleration(self, t):
        """``theta''(t) = -w0^2 sin(theta)`` (rad/s^2)."""
        return -self._s["w0"] ** 2 * np.sin(self.angle(t))

    def _state(self, t):
        s, t = self._s, np.asarray(t, dtype=float)
        if s["regime"] == "rest":
            theta, rate = np.full(t.shape, s["centre"]), np.zeros(t.shape)
        elif s["regime"] == "rotation":
            v = s["rate"] * t + s["v0"]
            _, _, dn = ellipj(v, s["m1"])
            theta, rate = 2.0 * amplitude(v, s["m1"]), 2.0 * s["rate"] * dn
        else:
            sn, cn, dn = ellipj(s["w0"] * t + s["u0"], s["m1"])
            theta = s["centre"] + 2.0 * np.arctan2(s["k"] * sn, dn)
            rate = 2.0 * s["k"] * s["w0"] * cn
        return s["sign"] * theta, s["sign"] * rate

    def energy_parameter(self):
        """``h``: < 1 libration, 1 separatrix, > 1 rotation (dimensionless)."""
        return self._s["h"]

    # ------------------------------------------------------------ in the world
    def _frames(self, theta):
        down, swing = np.asarray(self.down, float), np.asarray(self.swing, float)
        c, s = np.cos(theta)[..., None], np.sin(theta)[..., None]
        return c * down + s * swing, -s * down + c * swing  # r_hat (axis -> COM), t_hat

    def com_position(self, t):
        """Centre of mass relative to the axis point, world (m), shape (n, 3)."""
        r_hat, _ = self._frames(self.angle(t))
        return self.com_distance * r_hat

    def com_velocity(self, t):
        """Centre-of-mass velocity, world (m/s), shape (n, 3)."""
        theta, rate = self._state(t)
        _, t_hat = self._frames(theta)
        return self.com_distance * rate[..., None] * t_hat

    def reaction_force(self, t):
        """Force the axis exerts ON the body, world (N), shape (n, 3): ``m a_com - m g``."""
        theta, rate = self._state(t)
        r_hat, t_hat = self._frames(theta)
        alpha = -self._s["w0"] ** 2 * np.sin(theta)
        a = self.com_distance * (alpha[..., None] * t_hat - (rate * rate)[..., None] * r_hat)
        return self.mass * (a - self.gravity * np.asarray(self.down, float))
