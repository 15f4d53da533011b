"""The collision vocabulary of a scene: geometry fixed in bodies (``Geom``: spheres and boxes), fixed planes in the
world (``Plane``: a ground), and the pairs that may touch (``ContactPair``). ``dalembert.scene`` holds them in a
``Scene`` (and re-exports them); ``dalembert.scene_checks`` validates them; ``dalembert.contact`` measures gaps
and slip on a motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert.kinds import CONTACT_EFFECT, FRICTION_EFFECT, RESTITUTION_EFFECT

__all__ = ["Geom", "Plane", "ContactPair", "floats"]


def floats(x, n=None):
    """``x`` (any array-like) as a flat tuple of floats; ``n``, the expected length, is checked by the scene's
    validation, not here (a wrong length is a problem reported with the others)."""
    return tuple(float(v) for v in np.ravel(np.asarray(x, dtype=float)))


@dataclass(frozen=True)
class Geom:
    """Collision geometry fixed in ``body``: a ``sphere`` or a ``box`` (``GEOM_KINDS``).

    Attributes
    ----------
    body : str — the body it moves with
    kind : str — ``"sphere"`` or ``"box"``
    size : tuple — m: a sphere's ``(radius,)``; a box's full edge lengths ``(sx, sy, sz)`` along the geom's axes
    point : tuple of 3 floats — the geom's centre in the body frame B (m)
    quat : tuple of 4 floats — the geom's axes in B (scalar first; a box's edges lie along them)
    name : str — default ``geom_<body>``; a ``ContactPair`` names it
    """

    body: str
    kind: str
    size: tuple
    point: tuple = (0.0, 0.0, 0.0)
    quat: tuple = (1.0, 0.0, 0.0, 0.0)
    name: str = ""

    def __post_init__(self):
        for name in ("size", "point", "quat"):
            object.__setattr__(self, name, floats(getattr(self, name)))
        if not self.name:
            object.__setattr__(self, "name", f"geom_{self.body}")


@dataclass(frozen=True)
class Plane:
    """A fixed plane in the world (a ground): the solid half-space lies behind it, against ``normal``.

    Attributes
    ----------
    name : str — a ``ContactPair`` names it
    normal : tuple of 3 floats — the outward normal, world axes (any non-zero length; made unit)
    point : tuple of 3 floats — a point of the plane, world (m)
    """

    name: str = "ground"
    normal: tuple = (0.0, 0.0, 1.0)
    point: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        for name in ("normal", "point"):
            object.__setattr__(self, name, floats(getattr(self, name)))

    @property
    def unit_normal(self):
        """The outward unit normal, ndarray (3,), world."""
        n = np.array(self.normal)
        return n / np.linalg.norm(n)


@dataclass(frozen=True)
class ContactPair:
    """Two geoms (or a geom and a plane), named by ``a`` and ``b``, that may touch: the only contacts a scene has.

    The contact is rigid and unilateral: the two never interpenetrate, and push apart only. ``friction`` is the
    Coulomb coefficient (static = kinetic: an ideal Coulomb cone at a point, no rolling or torsional
    resistance): the tangential force at the contact point is at most ``friction`` times the normal force, and
    opposes the slip while there is slip. ``restitution`` (None: the case states none, the contact stays
    closed once made) is Newton's coefficient: at an impact the normal approach speed ``u`` becomes a
    separation speed ``restitution u``.

    Attributes
    ----------
    a, b : str — names of a ``Geom`` or a ``Plane`` of the scene (at least one a geom)
    friction : float — Coulomb coefficient, >= 0 (0: frictionless)
    restitution : float or None — in [0, 1]
    name : str — default ``contact_<a>_<b>``
    """

    a: str
    b: str
    friction: float = 0.0
    restitution: float | None = None
    name: str = ""

    def __post_init__(self):
        object.__setattr__(self, "friction", float(self.friction))
        if self.restitution is not None:
            object.__setattr__(self, "restitution", float(self.restitution))
        if not self.name:
            object.__setattr__(self, "name", f"contact_{self.a}_{self.b}")

    @property
    def effects(self):
        """Its effect tags: ``contact``, with ``friction`` when ``friction > 0`` and ``restitution`` when given."""
        tags = {CONTACT_EFFECT}
        if self.friction > 0.0:
            tags.add(FRICTION_EFFECT)
        if self.restitution is not None:
            tags.add(RESTITUTION_EFFECT)
        return tags
