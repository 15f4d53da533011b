"""A solid sphere launched sliding on a level plane, with Coulomb friction, until it rolls.

Source: Newton's and Euler's equations for a rigid sphere with a Coulomb friction force at its contact point
(the classical billiard-ball problem: Routh, *A Treatise on the Dynamics of a System of Rigid Bodies*, elementary
part, the motion of a sphere on a rough plane; Kleppner & Kolenkow, *An Introduction to Mechanics*, the bowling
ball; any rigid-body text). The
sphere (mass m, radius R, moment ``I = 2/5 m R^2``) moves along world x with speed ``v`` and turns about world y
at ``w`` (the axis rolling would need): its contact point slips at ``u = v - w R``. While ``u != 0`` kinetic
friction ``mu m g`` opposes the slip, so with ``sigma = sign(u0)``

    v' = -sigma mu g,    w' = sigma 5 mu g / (2 R),    u' = -sigma 7 mu g / 2

and the slip vanishes at ``t* = 2 |u0| / (7 mu g)``, ``u0 = v0 - w0 R``. From then on static friction needs no
force to keep ``u = 0`` on a level plane: it rolls at ``v* = (5 v0 + 2 w0 R) / 7`` (the angular momentum about
the contact point, ``m R v + I w``, is conserved throughout since the friction acts at that point), ``w* = v* / R``.
The slip dissipates ``E0 - E*``, the kinetic energies before and after (``mu m g`` times the slip distance).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SlidingBall"]


@dataclass(frozen=True)
class SlidingBall:
    """Closed-form motion of the sphere.

    Parameters
    ----------
    v0 : float — initial speed along world x, m/s
    omega0 : float — initial spin about world y, rad/s (rolling along +x needs ``omega0 = v0 / R``)
    mu : float — Coulomb coefficient, > 0
    radius : float — m
    g : float — gravity's magnitude, m/s^2
    mass : float — kg
    """

    v0: float
    omega0: float
    mu: float
    radius: float
    g: float
    mass: float

    @property
    def initial_slip(self):
        """``u0 = v0 - omega0 R`` (m/s)."""
        return self.v0 - self.omega0 * self.radius

    @property
    def roll_time(self):
        """``t* = 2 |u0| / (7 mu g)`` (s), when rolling starts."""
        return 2.0 * abs(self.initial_slip) / (7.0 * self.mu * self.g)

    @property
    def roll_speed(self):
        """``v* = (5 v0 + 2 omega0 R) / 7`` (m/s), the rolling speed."""
        return (5.0 * self.v0 + 2.0 * self.omega0 * self.radius) / 7.0

    @property
    def inertia(self):
        """``2/5 m R^2`` (kg m^2)."""
        return 0.4 * self.mass * self.radius**2

    def _sliding(self, t):
        return np.minimum(np.asarray(t, dtype=float), self.roll_time)

    def speed(self, t):
        """``v(t)`` (m/s), shape like ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        ts = self._sliding(t)
        return self.v0 - np.sign(self.initial_slip) * self.mu * self.g * ts

    def spin(self, t):
        """``w(t)`` about world y (rad/s)."""
        ts = self._sliding(t)
        return self.omega0 + np.sign(self.initial_slip) * 2.5 * self.mu * self.g / self.radius * ts

    def slip(self, t):
        """``u(t) = v - w R`` (m/s)."""
        return self.speed(t) - self.spin(t) * self.radius

    def distance(self, t):
        """``x(t) - x(0)`` (m)."""
        t = np.asarray(t, dtype=float)
        ts = self._sliding(t)
        s = np.sign(self.initial_slip)
        return self.v0 * ts - 0.5 * s * self.mu * self.g * ts**2 + self.roll_speed * (t - ts)

    def angle(self, t):
        """The angle turned about world y since t = 0 (rad)."""
        t = np.asarray(t, dtype=float)
        ts = self._sliding(t)
        s = np.sign(self.initial_slip)
        return (self.omega0 * ts + 0.5 * s * 2.5 * self.mu * self.g / self.radius * ts**2
                + self.roll_speed / self.radius * (t - ts))

    def kinetic_energy(self, t):
        """``1/2 m v^2 + 1/2 I w^2`` (J)."""
        return 0.5 * self.mass * self.speed(t) ** 2 + 0.5 * self.inertia * self.spin(t) ** 2

    @property
    def dissipated_energy(self):
        """``E0 - E*`` (J): what the slip dissipates, all of it before ``t*``."""
        return float(self.kinetic_energy(0.0) - self.kinetic_energy(self.roll_time))
