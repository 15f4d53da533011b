"""A solid sphere rolling without slipping down a plane inclined at ``angle``.

Source: Newton's and Euler's equations for a rigid sphere on a slope with a no-slip contact (Marion & Thornton,
*Classical Dynamics of Particles and Systems*, 5th ed., chapter 7: the disk rolling down an inclined plane, with the
sphere's moment ``I = 2/5 m R^2`` in place of the disk's). Along the
slope ``m a = m g sin(angle) - f`` and about the centre ``I a / R = f R``, so

    a = g sin(angle) / (1 + I / (m R^2)) = 5/7 g sin(angle),    f = 2/7 m g sin(angle)

and with the normal force ``N = m g cos(angle)`` the contact holds (no slip) where Coulomb's cone allows ``f``:
``mu >= f / N = 2/7 tan(angle)``. Released at rest, ``s(t) = a t^2 / 2``, ``v = a t``, ``w = v / R``; no work is
done at a contact that does not slip, so the energy ``1/2 m v^2 + 1/2 I w^2 - m g s sin(angle)`` is conserved.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["RollingBall"]


@dataclass(frozen=True)
class RollingBall:
    """Closed-form motion of the sphere along the slope, released at rest.

    Parameters
    ----------
    angle : float — the slope's inclination, rad
    mu : float — Coulomb coefficient (must reach ``min_mu`` for the closed form to hold)
    radius : float — m
    g : float — gravity's magnitude, m/s^2
    mass : float — kg
    """

    angle: float
    mu: float
    radius: float
    g: float
    mass: float

    @property
    def acceleration(self):
        """``5/7 g sin(angle)`` (m/s^2), down the slope."""
        return 5.0 / 7.0 * self.g * np.sin(self.angle)

    @property
    def min_mu(self):
        """``2/7 tan(angle)``: the least Coulomb coefficient that keeps it rolling."""
        return 2.0 / 7.0 * np.tan(self.angle)

    @property
    def friction_force(self):
        """``2/7 m g sin(angle)`` (N), up the slope."""
        return 2.0 / 7.0 * self.mass * self.g * np.sin(self.angle)

    @property
    def normal_force(self):
        """``m g cos(angle)`` (N)."""
        return self.mass * self.g * np.cos(self.angle)

    def distance(self, t):
        """``s(t)`` down the slope (m), shape like ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        return 0.5 * self.acceleration * t * t

    def speed(self, t):
        """``v(t)`` down the slope (m/s)."""
        return self.acceleration * np.asarray(t, dtype=float)

    def spin(self, t):
        """``w(t) = v / R`` (rad/s) about the axis ``normal x downhill``."""
        return self.speed(t) / self.radius

    def angle_turned(self, t):
        """``s(t) / R`` (rad)."""
        return self.distance(t) / self.radius
