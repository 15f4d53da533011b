"""A block sliding on a plane inclined at ``angle``, with Coulomb friction (static = kinetic coefficient ``mu``).

Source: Coulomb's law of friction with Newton's second law along and normal to the slope (Marion & Thornton,
*Classical Dynamics of Particles and Systems*, 5th ed., chapter 2: the block on an inclined plane; any mechanics
text). The block does not turn and keeps its face on the plane, so the normal force balances gravity's normal
component, ``N = m g cos(angle)``. While it slides down the slope (speed ``v > 0`` along the downhill direction)
kinetic friction ``mu N`` acts uphill:

    v' = a = g (sin(angle) - mu cos(angle))

so ``s(t) = v0 t + a t^2 / 2``, ``v(t) = v0 + a t``. When ``tan(angle) < mu``, ``a < 0``: a block started at
``v0 > 0`` stops at ``t_stop = v0 / (-a)``, after ``s_stop = v0^2 / (-2 a)``, and then sticks for good: static
friction can hold it, since gravity's downhill pull ``m g sin(angle)`` is below ``mu N``; the friction force is
then exactly that pull. A block started at rest (``v0 = 0``) never moves. When ``tan(angle) >= mu`` it keeps
sliding (accelerating when ``>``). The energy the friction dissipates is ``mu N s``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SlidingBlock"]


@dataclass(frozen=True)
class SlidingBlock:
    """Closed-form motion of the block along the slope.

    Parameters
    ----------
    angle : float — the slope's inclination, rad, in [0, pi/2)
    mu : float — Coulomb coefficient, >= 0
    v0 : float — initial speed down the slope, m/s, >= 0
    g : float — gravity's magnitude, m/s^2
    mass : float — kg
    """

    angle: float
    mu: float
    v0: float
    g: float
    mass: float

    @property
    def sliding_acceleration(self):
        """``a = g (sin(angle) - mu cos(angle))`` (m/s^2) while it slides down."""
        return self.g * (np.sin(self.angle) - self.mu * np.cos(self.angle))

    @property
    def normal_force(self):
        """``N = m g cos(angle)`` (N), constant."""
        return self.mass * self.g * np.cos(self.angle)

    @property
    def stop_time(self):
        """When it stops (s): 0 for a block at rest that sticks, None when it never stops (it slides on)."""
        a = self.sliding_acceleration
        if a >= 0.0:
            return 0.0 if self.v0 == 0.0 and a == 0.0 else None
        return self.v0 / -a

    def speed(self, t):
        """Speed down the slope ``v(t)`` (m/s), shape like ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        stop = self.stop_time
        tt = t if stop is None else np.minimum(t, stop)
        return self.v0 + self.sliding_acceleration * tt

    def displacement(self, t):
        """Distance travelled down the slope ``s(t)`` (m), shape like ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        stop = self.stop_time
        tt = t if stop is None else np.minimum(t, stop)
        return self.v0 * tt + 0.5 * self.sliding_acceleration * tt * tt

    def sticks(self, t):
        """Whether the block is at rest and held by static friction at ``t`` (bool array)."""
        stop = self.stop_time
        t = np.asarray(t, dtype=float)
        return np.zeros(t.shape, bool) if stop is None else t >= stop

    def friction_force(self, t):
        """The friction force on the block along the slope, positive uphill (N): ``mu N`` while it slides, gravity's
        downhill pull ``m g sin(angle)`` once it sticks."""
        return np.where(self.sticks(t), self.mass * self.g * np.sin(self.angle), self.mu * self.normal_force)

    def dissipated_energy(self, t):
        """Energy friction has dissipated since t = 0 (J): ``mu N s(t)``."""
        return self.mu * self.normal_force * self.displacement(t)
