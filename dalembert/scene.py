"""Engine-neutral description of a multibody system: bodies, joints, loop closures, loads, springs, gravity.

Specs are frozen dataclasses holding plain tuples (arrays live only in
``Trajectory``). A ``Scene`` validates itself on construction: every problem is
collected and reported at once, each naming its field and the fix, before
anything runs (the checks: ``dalembert.scene_checks``; the kinds and effect tags:
``dalembert.kinds``; both re-exported here).

Frames: the body frame B of every body has its origin at the centre of mass;
``Body.inertia`` is the tensor about the COM expressed in B. A joint connects a
frame fixed in the parent (``parent_point``, ``parent_quat``, in parent body
coordinates, or world coordinates when the parent is ``"world"``) to a frame
fixed in the child (``child_point``, ``child_quat``, in child body coordinates).

The joints form a tree (the spanning tree every engine builds); closed kinematic loops are
a separate, explicit list of ``Loop`` closures between any two bodies (or a body and the
world), each adding constraint rows to the tree (``dalembert.closure``). An engine that
builds trees only declares loops unsupported through their effect tags (``loop:<kind>``).

Linear spring-dampers between two points (``Spring``) are a separate list too, with their own effect
tag (``spring_damper``), kept out of ``EFFECTS`` for the same reason: an engine declares them only once
its adapter builds them.

Contact is explicit: collision geometry fixed in bodies (``Geom``: spheres and boxes), fixed planes in the
world (``Plane``: a ground), and the list of pairs that may touch (``ContactPair``, each with its Coulomb
friction coefficient and, where the case calls for one, its coefficient of restitution). Nothing touches
that the scene does not name: two geoms without a pair pass through each other. Contact brings its own
effect tags (``contact``, ``friction``, ``restitution``: ``CONTACT_EFFECTS``), apart like the springs'.
The three types live in ``dalembert.collision`` and are re-exported here.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from dalembert import closure
from dalembert.collision import ContactPair, Geom, Plane, floats
from dalembert.kinds import (AXIS_KINDS, CONTACT_EFFECT, CONTACT_EFFECTS, EFFECTS, FRICTION_EFFECT, GEOM_KINDS,
                             JOINT_KINDS, LOAD_FRAMES, LOAD_KINDS, LOOP_EFFECTS, LOOP_KINDS, RESTITUTION_EFFECT,
                             SPRING_EFFECT, SPRING_EFFECTS, WORLD)
from dalembert.scene_checks import (INERTIA_REL_TOL, INITIAL_OVERLAP_TOL, LOOP_CLOSURE_TOL, QUAT_NORM_TOL,
                                    SINGULAR_INERTIA_RATIO, SceneError, scene_problems)

__all__ = ["WORLD", "JOINT_KINDS", "AXIS_KINDS", "LOOP_KINDS", "LOAD_KINDS", "LOAD_FRAMES", "EFFECTS", "LOOP_EFFECTS",
           "SPRING_EFFECT", "SPRING_EFFECTS", "GEOM_KINDS", "CONTACT_EFFECT", "FRICTION_EFFECT", "RESTITUTION_EFFECT",
           "CONTACT_EFFECTS", "Body", "Joint", "Loop", "Load", "Spring", "Geom", "Plane", "ContactPair", "Scene",
           "SceneError", "mass_properties", "QUAT_NORM_TOL", "INERTIA_REL_TOL", "SINGULAR_INERTIA_RATIO",
           "LOOP_CLOSURE_TOL", "INITIAL_OVERLAP_TOL"]


_vec = floats  # (the length of a tuple is checked by validate())


def mass_properties(masses, positions):
    """Total mass, centre of mass and inertia about it of a set of point masses.

    The inertia tensor (Landau & Lifshitz, Mechanics, section 32; any rigid-body text):
    ``A = sum_i m_i (|u_i|^2 1 - u_i u_i^T)``
    with ``u_i`` the position relative to the centre of mass.

    Parameters
    ----------
    masses : array_like, shape (n,)
        Point masses (kg).
    positions : array_like, shape (n, 3)
        Positions (m) in any frame F.

    Returns
    -------
    mass : float (kg)
    com : ndarray, shape (3,) — centre of mass in F (m)
    inertia : ndarray, shape (3, 3) — about the COM, axes of F (kg m^2)
    """
    m = np.asarray(masses, dtype=float)
    p = np.asarray(positions, dtype=float)
    total = float(m.sum())
    com = (m[:, None] * p).sum(axis=0) / total
    u = p - com
    inertia = np.einsum("i,ij,ik->jk", m, u, u)
    inertia = np.trace(inertia) * np.eye(3) - inertia
    return total, com, inertia


@dataclass(frozen=True)
class Body:
    """A rigid body.

    Attributes
    ----------
    name : str
    mass : float — kg
    inertia : tuple of 3 tuples of 3 floats — about the COM, in B (kg m^2)
    particles : tuple of (mass, (x, y, z)) — for bodies made of point masses:
        each particle's mass (kg) and position relative to the COM in B (m).
        Used by invariants (pairwise distances), not by the dynamics.
    """

    name: str
    mass: float
    inertia: tuple
    particles: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "mass", float(self.mass))
        I = np.asarray(self.inertia, dtype=float)
        object.__setattr__(self, "inertia", tuple(tuple(float(v) for v in row) for row in np.atleast_2d(I)))
        object.__setattr__(
            self, "particles", tuple((float(m), _vec(u, 3)) for m, u in self.particles)
        )

    @property
    def inertia_matrix(self):
        """Inertia about the COM in B, ndarray (3, 3), kg m^2."""
        return np.array(self.inertia, dtype=float)

    @classmethod
    def from_point_masses(cls, name, masses, positions):
        """Rigid body of point masses; returns ``(body, com)``.

        Parameters
        ----------
        masses : array_like, shape (n,) — kg
        positions : array_like, shape (n, 3) — m, in a frame F whose axes become B's

        Returns
        -------
        body : Body — body frame at the COM with the axes of F
        com : ndarray, shape (3,) — where the COM is in F (m)
        """
        mass, com, inertia = mass_properties(masses, positions)
        rel = np.asarray(positions, dtype=float) - com
        return cls(name, mass, inertia, tuple(zip(np.asarray(masses, float), rel))), com

    @classmethod
    def cylinder(cls, name, mass, length, radius, axis=0):
        """Solid cylinder (a rod when ``radius << length``) along body axis ``axis`` (0, 1, 2)."""
        I = np.full(3, mass * (3.0 * radius**2 + length**2) / 12.0)
        I[axis] = 0.5 * mass * radius**2
        return cls(name, mass, np.diag(I))

    @classmethod
    def box(cls, name, mass, size):
        """Solid cuboid with edge lengths ``size = (sx, sy, sz)`` (m) along the body axes."""
        sx, sy, sz = size
        return cls(name, mass, np.diag([sy**2 + sz**2, sx**2 + sz**2, sx**2 + sy**2]) * mass / 12.0)


@dataclass(frozen=True)
class Joint:
    """The joint of ``child`` to its ``parent`` (a body name or ``"world"``).

    See ``JOINT_KINDS`` for the coordinates ``q0``/``v0`` of each kind. ``axis``
    (revolute and prismatic only: the rotation axis, the sliding direction) is expressed in the
    joint frame and need not be unit length.
    """

    kind: str
    parent: str
    child: str
    q0: tuple = ()
    v0: tuple = ()
    axis: tuple | None = None
    parent_point: tuple = (0.0, 0.0, 0.0)
    parent_quat: tuple = (1.0, 0.0, 0.0, 0.0)
    child_point: tuple = (0.0, 0.0, 0.0)
    child_quat: tuple = (1.0, 0.0, 0.0, 0.0)

    def __post_init__(self):
        for name in ("q0", "v0", "parent_point", "parent_quat", "child_point", "child_quat"):
            object.__setattr__(self, name, _vec(getattr(self, name)))
        if self.axis is not None:
            object.__setattr__(self, "axis", _vec(self.axis))

    @property
    def name(self):
        """A joint is named after its child (every body has exactly one joint)."""
        return self.child


@dataclass(frozen=True)
class Loop:
    """A loop closure between ``body_a`` and ``body_b`` (body names, or ``"world"`` for one of them).

    It constrains a frame Ja fixed in body a (``point_a``, ``quat_a``: in a's body frame, or the
    world's when a is the world) against a frame Jb fixed in body b (``point_b``, ``quat_b``),
    like a joint's parent and child frames, but adds no coordinates: the tree's joints keep
    theirs, and the loop adds constraint rows (``dalembert.closure``). Kinds (``LOOP_KINDS``):

    * ``ball``: the points coincide;
    * ``revolute``: the points coincide and the ``axis`` (in the joint frames; any length) of Ja
      and of Jb stay on one line (the rotation about it is free, so the frames need not coincide);
    * ``distance``: the points stay ``length`` (m, positive) apart.

    ``name`` (default ``loop_<body_a>_<body_b>``) keys the loop's reaction force in a trajectory,
    ``reaction_force:<name>``: the force (N, world) the closure exerts ON body b at its point.
    """

    kind: str
    body_a: str
    body_b: str
    point_a: tuple = (0.0, 0.0, 0.0)
    point_b: tuple = (0.0, 0.0, 0.0)
    quat_a: tuple = (1.0, 0.0, 0.0, 0.0)
    quat_b: tuple = (1.0, 0.0, 0.0, 0.0)
    axis: tuple | None = None
    length: float | None = None
    name: str = ""

    def __post_init__(self):
        for name in ("point_a", "point_b", "quat_a", "quat_b"):
            object.__setattr__(self, name, _vec(getattr(self, name)))
        if self.axis is not None:
            object.__setattr__(self, "axis", _vec(self.axis))
        if self.length is not None:
            object.__setattr__(self, "length", float(self.length))
        if not self.name:
            object.__setattr__(self, "name", f"loop_{self.body_a}_{self.body_b}")

    @property
    def effect(self):
        """Effect tag, e.g. ``loop:revolute``."""
        return f"loop:{self.kind}"


@dataclass(frozen=True)
class Load:
    """A constant force or torque on ``body``.

    ``vector`` (N or N m) is expressed in ``frame``: ``"world"`` (fixed
    direction) or ``"body"`` (turns with the body: a follower load). ``point``
    is where a force acts, relative to the COM in body coordinates (m).
    """

    body: str
    kind: str
    vector: tuple
    frame: str
    point: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        object.__setattr__(self, "vector", _vec(self.vector))
        object.__setattr__(self, "point", _vec(self.point))

    @property
    def effect(self):
        """Effect tag, e.g. ``load:follower_force`` or ``load:world_torque``."""
        return f"load:{'follower' if self.frame == 'body' else 'world'}_{self.kind}"


@dataclass(frozen=True)
class Spring:
    """A linear spring-damper between a point of ``body_a`` and a point of ``body_b`` (body names, or
    ``"world"`` for one of them).

    ``point_a`` and ``point_b`` are the attachment points (m) in each body's frame (the world's for the
    world). With ``l`` the distance between them and ``l'`` its rate, the spring pulls the two points
    together with the tension ``stiffness (l - rest_length) + damping l'`` (N) along the line joining
    them: a force on each point, equal and opposite, which stores ``1/2 stiffness (l - rest_length)^2``
    (J) and dissipates ``damping l'^2`` (W) (``dalembert.springs``). The points must be apart at the
    initial state (where they coincide the line, and so the force's direction, is undefined).

    Attributes
    ----------
    body_a, body_b : str
    point_a, point_b : tuple of 3 floats — m, body frame (world frame for the world)
    stiffness : float — N/m, >= 0
    damping : float — N s/m, >= 0 (a spring with both zero is refused: it does nothing)
    rest_length : float — m, >= 0
    name : str — default ``spring_<body_a>_<body_b>``
    """

    body_a: str
    body_b: str
    point_a: tuple = (0.0, 0.0, 0.0)
    point_b: tuple = (0.0, 0.0, 0.0)
    stiffness: float = 0.0
    damping: float = 0.0
    rest_length: float = 0.0
    name: str = ""

    def __post_init__(self):
        for name in ("point_a", "point_b"):
            object.__setattr__(self, name, _vec(getattr(self, name)))
        for name in ("stiffness", "damping", "rest_length"):
            object.__setattr__(self, name, float(getattr(self, name)))
        if not self.name:
            object.__setattr__(self, "name", f"spring_{self.body_a}_{self.body_b}")

    @property
    def effect(self):
        """Effect tag: ``spring_damper`` (``SPRING_EFFECTS``)."""
        return SPRING_EFFECT


# The contact fields of a scene, each absent from its JSON and its case's version when empty (a scene
# without contact has the data it had before contact existed).
_CONTACT_FIELDS = ("geoms", "planes", "contacts")


@dataclass(frozen=True)
class Scene:
    """A multibody system. ``gravity`` (m/s^2, world) is required, never defaulted.

    Validated on construction (``SceneError`` lists every problem).
    """

    name: str
    bodies: tuple
    joints: tuple
    gravity: tuple
    loads: tuple = field(default=())
    loops: tuple = field(default=())
    springs: tuple = field(default=())
    geoms: tuple = field(default=())
    planes: tuple = field(default=())
    contacts: tuple = field(default=())

    def __post_init__(self):
        object.__setattr__(self, "bodies", tuple(self.bodies))
        object.__setattr__(self, "joints", tuple(self.joints))
        object.__setattr__(self, "loads", tuple(self.loads))
        object.__setattr__(self, "loops", tuple(self.loops))
        object.__setattr__(self, "springs", tuple(self.springs))
        for name in _CONTACT_FIELDS:
            object.__setattr__(self, name, tuple(getattr(self, name)))
        object.__setattr__(self, "gravity", _vec(self.gravity))
        self.validate()

    # -------------------------------------------------------------- data
    def to_json(self):
        """The scene as plain JSON data; ``from_json`` rebuilds it exactly (floats round-trip).

        ``loops``, ``springs`` and the contact fields (``geoms``, ``planes``, ``contacts``) appear only when there are
        some: a scene without them has the data it had before they existed."""
        data = asdict(self)
        for name in ("loops", "springs", *_CONTACT_FIELDS):
            if not data[name]:
                del data[name]
        return data

    @classmethod
    def from_json(cls, data):
        """Inverse of ``to_json`` (validated like any scene)."""
        return cls(data["name"], [Body(**b) for b in data["bodies"]], [Joint(**j) for j in data["joints"]],
                   data["gravity"], [Load(**ld) for ld in data["loads"]],
                   [Loop(**lp) for lp in data.get("loops", ())], [Spring(**sp) for sp in data.get("springs", ())],
                   [Geom(**g) for g in data.get("geoms", ())], [Plane(**p) for p in data.get("planes", ())],
                   [ContactPair(**c) for c in data.get("contacts", ())])

    # -------------------------------------------------------------- queries
    def body(self, name):
        """The body called ``name``."""
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)

    def geom(self, name):
        """The geom called ``name``."""
        for g in self.geoms:
            if g.name == name:
                return g
        raise KeyError(name)

    def plane(self, name):
        """The plane called ``name``."""
        for p in self.planes:
            if p.name == name:
                return p
        raise KeyError(name)

    def joint(self, child):
        """The joint whose child is ``child``."""
        for j in self.joints:
            if j.child == child:
                return j
        raise KeyError(child)

    @property
    def effects(self):
        """The physics this scene calls for, as a frozenset of tags.

        ``gravity`` when gravity is non-zero; ``joint:<kind>`` per joint kind
        present; ``load:{follower,world}_{force,torque}`` per load kind present;
        ``loop:<kind>`` per loop closure kind present (``LOOP_EFFECTS``); ``spring_damper`` when there
        are springs (``SPRING_EFFECTS``); ``contact``, ``friction``, ``restitution`` as the contact pairs call
        for them (``ContactPair.effects``, ``CONTACT_EFFECTS``).
        """
        tags = {f"joint:{j.kind}" for j in self.joints}
        tags |= {lp.effect for lp in self.loops}
        tags |= {sp.effect for sp in self.springs}
        for c in self.contacts:
            tags |= c.effects
        tags |= {ld.effect for ld in self.loads}
        if any(g != 0.0 for g in self.gravity):
            tags.add("gravity")
        return frozenset(tags)

    def topological_order(self):
        """Bodies ordered parents first (the scene must be valid)."""
        parent = {j.child: j.parent for j in self.joints}
        order, seen = [], {WORLD}
        pending = [b.name for b in self.bodies]
        while pending:
            ready = [n for n in pending if parent[n] in seen]
            order += ready
            seen |= set(ready)
            pending = [n for n in pending if n not in seen]
        return [self.body(n) for n in order]

    def loop_summary(self):
        """Loop count, constraint rows, the rank of their Jacobian in the tree's joint speeds and the
        residuals at the initial state (``dalembert.closure.ClosureSummary``; ``str()`` says it in a
        line). Redundant rows (rank below rows) are reported here, not refused: a mechanism moves
        despite them (the reference takes least-squares multipliers)."""
        return closure.summary(self)

    # -------------------------------------------------------------- checks
    def validate(self):
        """Raise ``SceneError`` listing every problem (``dalembert.scene_checks``), or return ``self``."""
        problems = scene_problems(self)
        if problems:
            raise SceneError(f"scene {self.name!r}", problems)
        return self
