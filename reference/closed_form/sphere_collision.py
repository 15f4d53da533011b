"""Two spheres meeting head-on in free space: their velocities after the impact.

Source: conservation of linear momentum with Newton's impact law (Marion & Thornton, *Classical Dynamics of
Particles and Systems*, 5th ed., chapter 9: inelastic collisions and the coefficient of restitution). Spheres of
masses ``m1``, ``m2`` moving on the line of their centres at ``v1 > v2`` meet when the gap between their surfaces closes, at ``t_c = gap / (v1 - v2)``; frictionless, no gravity, nothing turns. With
``M = m1 + m2`` and restitution ``e`` (the separation speed is ``e (v1 - v2)``):

    v1' = (m1 v1 + m2 v2 - m2 e (v1 - v2)) / M,    v2' = (m1 v1 + m2 v2 + m1 e (v1 - v2)) / M

The momentum ``m1 v1 + m2 v2`` is the same before and after, exactly; the kinetic energy drops by
``(1 - e^2) m1 m2 (v1 - v2)^2 / (2 M)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["HeadOnCollision"]


@dataclass(frozen=True)
class HeadOnCollision:
    """Closed-form motion of the two centres along their line.

    Parameters
    ----------
    m1, m2 : float — kg
    v1, v2 : float — initial speeds along the line, m/s, ``v1 > v2`` (they approach)
    x1, x2 : float — initial positions of the centres along the line, m, ``x1 < x2``
    r1, r2 : float — radii, m (``x2 - x1 >= r1 + r2``)
    restitution : float — in [0, 1]
    """

    m1: float
    m2: float
    v1: float
    v2: float
    x1: float
    x2: float
    r1: float
    r2: float
    restitution: float

    @property
    def impact_time(self):
        """``t_c = gap / (v1 - v2)`` (s)."""
        return (self.x2 - self.x1 - self.r1 - self.r2) / (self.v1 - self.v2)

    @property
    def velocities_after(self):
        """``(v1', v2')`` (m/s)."""
        M, p, du = self.m1 + self.m2, self.m1 * self.v1 + self.m2 * self.v2, self.v1 - self.v2
        return (p - self.m2 * self.restitution * du) / M, (p + self.m1 * self.restitution * du) / M

    @property
    def energy_lost(self):
        """``(1 - e^2) m1 m2 (v1 - v2)^2 / (2 M)`` (J)."""
        return (1.0 - self.restitution**2) * self.m1 * self.m2 * (self.v1 - self.v2) ** 2 / (2.0 * (self.m1 + self.m2))

    def velocities(self, t):
        """``(v1(t), v2(t))`` (m/s), each shape like ``t`` (s); at ``t_c`` the values after."""
        t = np.asarray(t, dtype=float)
        after = t >= self.impact_time
        a1, a2 = self.velocities_after
        return np.where(after, a1, self.v1), np.where(after, a2, self.v2)

    def positions(self, t):
        """``(x1(t), x2(t))`` (m)."""
        t = np.asarray(t, dtype=float)
        tc = self.impact_time
        before, after = np.minimum(t, tc), np.maximum(t - tc, 0.0)
        a1, a2 = self.velocities_after
        return self.x1 + self.v1 * before + a1 * after, self.x2 + self.v2 * before + a2 * after
