"""Planar rod pivoted at one end, driven by a follower force at its tip.

Source: d'Alembert's principle (Kane & Levinson, *Dynamics: Theory and Applications*,
1985; Goldstein, *Classical Mechanics*, section 1.4) for the pivoted rod: with the tip
force perpendicular to the rod and of constant size F (a follower force),
``phi'' I_O = l F``, where ``I_O`` is the moment of inertia about the pivot
(``m l^2 / 3`` for a thin rod). Hence

    phi(t) = phi0 + w0 t + (l F / (2 I_O)) t^2      (= 3F/(2ml) t^2 for a thin rod at rest)

For the pivot reaction: the centre of mass, at ``d = l/2`` from the pivot,
accelerates as ``a = d (phi'' t_hat - phi'^2 r_hat)`` with ``r_hat`` along the
rod and ``t_hat`` perpendicular (in the plane of motion), and Newton's law for
the rod gives the force the pivot exerts ON the rod: ``R = m a - F t_hat``.
The work done by the force is ``W = l F (phi - phi0)`` (power ``F l phi'``),
which equals the kinetic energy gained, ``1/2 I_O (phi'^2 - w0^2)``.

The rod turns about world z in the x-y plane; ``phi`` is measured from world x.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FollowerForceRod"]


@dataclass(frozen=True)
class FollowerForceRod:
    """Closed-form motion of the rod.

    Parameters
    ----------
    mass : float — kg
    length : float — pivot to tip (m); the COM is at ``length / 2``
    inertia_pivot : float — about the pivot axis (kg m^2)
    force : float — tip force perpendicular to the rod, positive towards +phi (N)
    phi0, w0 : float — initial angle (rad) and rate (rad/s)
    """

    mass: float
    length: float
    inertia_pivot: float
    force: float
    phi0: float = 0.0
    w0: float = 0.0

    @property
    def angular_acceleration(self):
        """``phi''`` (rad/s^2), constant."""
        return self.length * self.force / self.inertia_pivot

    def angle(self, t):
        """``phi(t)`` (rad), shape like ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        return self.phi0 + self.w0 * t + 0.5 * self.angular_acceleration * t * t

    def rate(self, t):
        """``phi'(t)`` (rad/s)."""
        return self.w0 + self.angular_acceleration * np.asarray(t, dtype=float)

    def _frames(self, t):
        phi = self.angle(t)
        c, s, z = np.cos(phi), np.sin(phi), np.zeros_like(phi)
        return np.stack([c, s, z], -1), np.stack([-s, c, z], -1)

    def com_position(self, t):
        """COM in world (m), shape (n, 3)."""
        r_hat, _ = self._frames(t)
        return 0.5 * self.length * r_hat

    def com_velocity(self, t):
        """COM velocity in world (m/s), shape (n, 3)."""
        _, t_hat = self._frames(t)
        return 0.5 * self.length * self.rate(t)[..., None] * t_hat

    def reaction_force(self, t):
        """Force the pivot exerts ON the rod, world axes (N), shape (n, 3)."""
        r_hat, t_hat = self._frames(t)
        w = self.rate(t)[..., None]
        a = 0.5 * self.length * (self.angular_acceleration * t_hat - w * w * r_hat)
        return self.mass * a - self.force * t_hat

    def work(self, t):
        """Work done by the tip force since t = 0 (J)."""
        return self.length * self.force * (self.angle(t) - self.phi0)

    def kinetic_energy(self, t):
        """``1/2 I_O phi'^2`` (J)."""
        return 0.5 * self.inertia_pivot * self.rate(t) ** 2
