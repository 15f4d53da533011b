"""A ball dropped on a level plane, bouncing with Newton's coefficient of restitution ``e``.

Source: free fall between impacts and Newton's impact law (the separation speed is ``e`` times the approach
speed): Goldsmith, *Impact*, 1960; Marion & Thornton, *Classical Dynamics of Particles and Systems*, 5th ed.,
chapter 9 (the coefficient of restitution). Dropped from rest with its lowest point at height ``h``, it first lands at
``t_1 = sqrt(2 h / g)`` with speed ``u_1 = sqrt(2 g h)``, and leaves each impact k at ``u_k e``, so

    u_(k+1) = e^k u_1,    t_(k+1) = t_k + 2 e^k u_1 / g,    apex after impact k: e^(2k) h at t_k + e^k u_1 / g.

For ``e < 1`` the impacts accumulate at ``t_inf = t_1 (1 + e) / (1 - e)`` (a convergent geometric series), after
which the ball rests on the plane; for ``e = 0`` it stops at its first impact. Energy is lost at each impact,
the fraction ``1 - e^2`` of the kinetic energy it lands with.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BouncingBall"]


@dataclass(frozen=True)
class BouncingBall:
    """Closed-form height of the ball's lowest point.

    Parameters
    ----------
    height : float — initial height of the lowest point above the plane, m (> 0)
    restitution : float — Newton's coefficient, in [0, 1]
    g : float — gravity's magnitude, m/s^2
    """

    height: float
    restitution: float
    g: float

    @property
    def first_impact(self):
        """``t_1 = sqrt(2 h / g)`` (s)."""
        return float(np.sqrt(2.0 * self.height / self.g))

    @property
    def landing_speed(self):
        """``u_1 = sqrt(2 g h)`` (m/s)."""
        return float(np.sqrt(2.0 * self.g * self.height))

    @property
    def rest_time(self):
        """``t_inf`` (s), when the bounces end; inf for ``e = 1``."""
        e = self.restitution
        return float("inf") if e >= 1.0 else self.first_impact * (1.0 + e) / (1.0 - e)

    def impacts(self, horizon):
        """The impact times up to ``horizon`` (s), ndarray (k,): ``t_1, t_2, ...`` (at most one impact for e = 0;
        a geometric series stopped where its terms fall below the double-precision resolution of ``horizon``)."""
        e, t, u = self.restitution, self.first_impact, self.landing_speed
        out = []
        while t <= horizon:
            out.append(t)
            u *= e
            dt = 2.0 * u / self.g
            if dt <= 4.0 * np.finfo(float).eps * max(t, 1.0):
                break
            t += dt
        return np.array(out)

    def apex_heights(self, count):
        """The first ``count`` apexes after impacts 1, 2, ...: ``e^(2k) h`` (m), ndarray (count,)."""
        return self.height * self.restitution ** (2.0 * np.arange(1, count + 1))

    def apex_times(self, count):
        """Their times ``t_k + e^k u_1 / g`` (s), ndarray (count,)."""
        e, t, u, out = self.restitution, self.first_impact, self.landing_speed, []
        for _ in range(count):
            u *= e
            out.append(t + u / self.g)
            t += 2.0 * u / self.g
        return np.array(out)

    def _phase(self, t):
        """Per time: ``(time since the last impact or the drop, the upward speed it left with, at rest)``."""
        t = np.asarray(t, dtype=float)
        hits = self.impacts(float(np.max(t, initial=0.0)))
        k = np.searchsorted(hits, t, side="right")  # impacts so far
        since = np.where(k == 0, t, t - hits[np.maximum(k - 1, 0)] if len(hits) else t)
        up = np.where(k == 0, 0.0, self.landing_speed * self.restitution ** np.maximum(k, 1).astype(float))
        rest = t >= self.rest_time
        return since, up, rest

    def height_at(self, t):
        """The lowest point's height ``z(t)`` (m), shape like ``t`` (s)."""
        since, up, rest = self._phase(t)
        z = np.where(up == 0.0, self.height, 0.0) + up * since - 0.5 * self.g * since**2
        return np.where(rest, 0.0, z)

    def vertical_velocity(self, t):
        """``z'(t)`` (m/s); at an impact instant, the speed it leaves with."""
        since, up, rest = self._phase(t)
        return np.where(rest, 0.0, up - self.g * since)
