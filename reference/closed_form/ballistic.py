"""Centre of mass under uniform gravity: a parabola.

Source: Newton's second law for the centre of mass, ``M R'' = sum_i F_i``: the
centre of mass moves as a particle of the total mass under the total external
force (H. Goldstein, C. Poole, J. Safko, *Classical Mechanics*, 3rd ed., section
1.2; Landau & Lifshitz, *Mechanics*, section 34). Under uniform gravity the total force is ``M g`` (each of
the N particles carries ``(M/N) g``), so ``R'' = g`` — not ``g/N``, which giving
one particle's force to the whole mass would make it — and

    R(t) = R0 + V0 t + g t^2 / 2,    V(t) = V0 + g t.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Ballistic"]


@dataclass(frozen=True)
class Ballistic:
    """Parameters: ``p0`` (3,) m, ``v0`` (3,) m/s, ``gravity`` (3,) m/s^2, all world."""

    p0: tuple
    v0: tuple
    gravity: tuple

    def position(self, t):
        """COM position (m), shape (n, 3), at times ``t`` (s), shape (n,)."""
        t = np.asarray(t, dtype=float)[..., None]
        return np.asarray(self.p0) + np.asarray(self.v0) * t + 0.5 * np.asarray(self.gravity) * t * t

    def velocity(self, t):
        """COM velocity (m/s), shape (n, 3)."""
        t = np.asarray(t, dtype=float)[..., None]
        return np.asarray(self.v0) + np.asarray(self.gravity) * t
