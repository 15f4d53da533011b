"""Engine-neutral description of a multibody system: bodies, joints, loop closures, loads, springs, gravity.

Specs are frozen dataclasses holding plain tuples (arrays live only in
``Trajectory``). A ``Scene`` validates itself on construction: every problem is
collected and reported at once, each naming its field and the fix, before
anything runs.

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
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from dalembert import spatial
from dalembert.registry import suggest

__all__ = ["WORLD", "JOINT_KINDS", "AXIS_KINDS", "LOOP_KINDS", "EFFECTS", "LOOP_EFFECTS", "SPRING_EFFECTS",
           "Body", "Joint", "Loop",
           "Load", "Spring", "Scene", "SceneError", "mass_properties", "LOOP_CLOSURE_TOL"]

WORLD = "world"

# Per joint kind: (size of q0, size of v0). Coordinates:
#   free     q = (x, y, z, qw, qx, qy, qz): COM position (m) and attitude q_WB of
#            the child in world; v = (vx, vy, vz, wx, wy, wz): COM velocity in
#            world (m/s) and angular velocity w_WB_B in the child body frame (rad/s).
#   revolute q = (angle,) (rad) about `axis` in the joint frame; v = (rate,) (rad/s).
#   prismatic q = (displacement,) (m) of the child joint frame along the unit `axis` of the
#            parent joint frame (the two frames keep their relative attitude, identity; at
#            q = 0 they coincide); v = (rate,) (m/s).
#   ball     q = quaternion of the child joint frame in the parent joint frame;
#            v = relative angular velocity in the child joint frame (rad/s).
#   weld     no coordinates.
JOINT_KINDS = {"free": (7, 6), "revolute": (1, 1), "prismatic": (1, 1), "ball": (4, 3), "weld": (0, 0)}
# The kinds that take an ``axis`` (in the joint frame, any non-zero length).
AXIS_KINDS = ("revolute", "prismatic")
LOAD_KINDS = ("force", "torque")
LOAD_FRAMES = ("world", "body")
# Loop closures (``Loop``), per kind: the constraint rows in ``dalembert.closure.ROWS``.
#   ball      the two joint points coincide;
#   revolute  a ball whose frames also share the axis ``axis`` (given in the joint frames);
#   distance  the two points stay ``length`` apart (a massless rod with ball ends).
LOOP_KINDS = ("ball", "revolute", "distance")
# Every effect tag a tree scene can call for (``Scene.effects`` draws from these): what an
# adapter declares with ``effects = EFFECTS``.
EFFECTS = frozenset({"gravity"} | {f"joint:{k}" for k in JOINT_KINDS}
                    | {f"load:{w}_{k}" for w in ("follower", "world") for k in LOAD_KINDS})
# The tags of loop closures, apart: an adapter that closes loops declares them explicitly
# (``EFFECTS | LOOP_EFFECTS``), so one that builds trees only declares them unsupported.
LOOP_EFFECTS = frozenset(f"loop:{k}" for k in LOOP_KINDS)
# The tag of linear spring-dampers (``Spring``), apart for the same reason: an adapter that builds them
# declares ``EFFECTS | SPRING_EFFECTS``; every other one declares them unsupported.
SPRING_EFFECT = "spring_damper"
SPRING_EFFECTS = frozenset({SPRING_EFFECT})

# |q| may differ from 1 by this much (roundoff in user-typed decimals is ~1e-16;
# anything larger is a real mistake, not roundoff).
QUAT_NORM_TOL = 1e-9
# Inertia symmetry and the triangle inequality are checked to this relative
# tolerance: tensors computed from point masses carry roundoff of a few ulps.
INERTIA_REL_TOL = 1e-12
# A free body's smallest principal moment below this fraction of the largest is
# treated as singular: the rotation about that axis is then undetermined
# (all particles on one line: the rotator of Landau & Lifshitz, Mechanics, section 32, whose
# moment about that line is zero).
SINGULAR_INERTIA_RATIO = 1e-14
# An initial state whose loop closures are violated by more than this (m for points, the sine of
# the tilt for axes; m/s and rad/s for their rates) is refused: initial coordinates solved in
# double precision close a loop to ~1e-15, and anything beyond 1e-9 is a state the solver would
# have to move (the case's initial state would not be the one simulated).
LOOP_CLOSURE_TOL = 1e-9


class SceneError(ValueError):
    """A scene or case is invalid; ``problems`` lists every issue found."""

    def __init__(self, where, problems):
        self.problems = list(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        super().__init__(f"{where}: {len(self.problems)} problem(s)\n{lines}")


def _vec(x, n=None):
    t = tuple(float(v) for v in np.ravel(np.asarray(x, dtype=float)))
    if n is not None and len(t) != n:
        return t  # the length problem is reported by validate()
    return t


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

    def __post_init__(self):
        object.__setattr__(self, "bodies", tuple(self.bodies))
        object.__setattr__(self, "joints", tuple(self.joints))
        object.__setattr__(self, "loads", tuple(self.loads))
        object.__setattr__(self, "loops", tuple(self.loops))
        object.__setattr__(self, "springs", tuple(self.springs))
        object.__setattr__(self, "gravity", _vec(self.gravity))
        self.validate()

    # -------------------------------------------------------------- data
    def to_json(self):
        """The scene as plain JSON data; ``from_json`` rebuilds it exactly (floats round-trip).

        ``loops`` and ``springs`` appear only when there are some: a scene without them has the data
        it had before they existed."""
        data = asdict(self)
        for name in ("loops", "springs"):
            if not data[name]:
                del data[name]
        return data

    @classmethod
    def from_json(cls, data):
        """Inverse of ``to_json`` (validated like any scene)."""
        return cls(data["name"], [Body(**b) for b in data["bodies"]], [Joint(**j) for j in data["joints"]],
                   data["gravity"], [Load(**ld) for ld in data["loads"]],
                   [Loop(**lp) for lp in data.get("loops", ())], [Spring(**sp) for sp in data.get("springs", ())])

    # -------------------------------------------------------------- queries
    def body(self, name):
        """The body called ``name``."""
        for b in self.bodies:
            if b.name == name:
                return b
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
        are springs (``SPRING_EFFECTS``).
        """
        tags = {f"joint:{j.kind}" for j in self.joints}
        tags |= {lp.effect for lp in self.loops}
        tags |= {sp.effect for sp in self.springs}
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
        from dalembert import closure

        return closure.summary(self)

    # -------------------------------------------------------------- checks
    def validate(self):
        """Raise ``SceneError`` listing every problem, or return ``self``."""
        problems = []
        add = problems.append
        names = [b.name for b in self.bodies]
        if not self.bodies:
            add("bodies: empty — add at least one Body")
        for dup in sorted({n for n in names if names.count(n) > 1}):
            add(f"bodies: name {dup!r} used twice — give every body a unique name")
        if WORLD in names:
            add(f"bodies: {WORLD!r} is reserved for the fixed world frame — rename the body")
        if len(self.gravity) != 3 or not all(math.isfinite(g) for g in self.gravity):
            add(f"gravity: must be 3 finite numbers (m/s^2, world frame), got {self.gravity} — "
                "use (0, 0, 0) for none")
        free_bodies = {j.child for j in self.joints if j.kind == "free"}
        for b in self.bodies:
            problems += _body_problems(b, b.name in free_bodies)
        problems += self._joint_problems(set(names))
        for i, ld in enumerate(self.loads):
            problems += _load_problems(i, ld, set(names))
        for i, lp in enumerate(self.loops):
            problems += _loop_problems(i, lp, set(names))
        loop_names = [lp.name for lp in self.loops]
        for dup in sorted({n for n in loop_names if loop_names.count(n) > 1}):
            add(f"loops: name {dup!r} used twice — give each loop a unique name=")
        for clash in sorted(set(loop_names) & set(names)):
            add(f"loops: name {clash!r} is a body's (its joint's reactions are keyed by it) — rename the loop")
        for i, sp in enumerate(self.springs):
            problems += _spring_problems(i, sp, set(names))
        spring_names = [sp.name for sp in self.springs]
        for dup in sorted({n for n in spring_names if spring_names.count(n) > 1}):
            add(f"springs: name {dup!r} used twice — give each spring a unique name=")
        if self.loops and not problems:  # the closure needs valid names, joints and numbers
            problems += self._closure_problems()
        if self.springs and not problems:  # the initial lengths need valid names, joints and numbers
            problems += self._spring_length_problems()
        if problems:
            raise SceneError(f"scene {self.name!r}", problems)
        return self

    def _joint_problems(self, names):
        problems = []
        add = problems.append
        parents = {}
        for i, j in enumerate(self.joints):
            where = f"joints[{i}] ({j.kind} {j.parent!r} -> {j.child!r})"
            if j.kind not in JOINT_KINDS:
                add(f"{where}.kind: unknown {j.kind!r} — use one of {sorted(JOINT_KINDS)}")
                continue
            if j.child not in names:
                add(f"{where}.child: no body named {j.child!r}{_did_you_mean(j.child, names)}")
            if j.parent != WORLD and j.parent not in names:
                add(f"{where}.parent: no body named {j.parent!r}{_did_you_mean(j.parent, names | {WORLD})}")
            if j.parent == j.child:
                add(f"{where}: a body cannot be its own parent")
            if j.child in parents:
                add(f"bodies[{j.child!r}]: has two parents ({parents[j.child]!r} and {j.parent!r}) — "
                    "a scene is a tree: one joint per body")
            parents.setdefault(j.child, j.parent)
            nq, nv = JOINT_KINDS[j.kind]
            if len(j.q0) != nq:
                add(f"{where}.q0: {j.kind} needs {nq} numbers, got {len(j.q0)}")
            if len(j.v0) != nv:
                add(f"{where}.v0: {j.kind} needs {nv} numbers, got {len(j.v0)}")
            for field_name in ("q0", "v0", "parent_point", "child_point", "parent_quat", "child_quat"):
                if not all(math.isfinite(v) for v in getattr(j, field_name)):
                    add(f"{where}.{field_name}: contains NaN or inf")
            for field_name, n in (("parent_point", 3), ("child_point", 3), ("parent_quat", 4), ("child_quat", 4)):
                if len(getattr(j, field_name)) != n:
                    add(f"{where}.{field_name}: needs {n} numbers")
            quats = [("parent_quat", j.parent_quat), ("child_quat", j.child_quat)]
            if j.kind == "free" and len(j.q0) == 7:
                quats.append(("q0[3:7] (attitude)", j.q0[3:]))
            if j.kind == "ball" and len(j.q0) == 4:
                quats.append(("q0 (relative attitude)", j.q0))
            for label, q in quats:
                if len(q) == 4 and all(math.isfinite(v) for v in q):
                    norm = math.sqrt(sum(v * v for v in q))
                    if abs(norm - 1.0) > QUAT_NORM_TOL:
                        add(f"{where}.{label}: quaternion norm is {norm:.12g}, not 1 — "
                            "normalize it (scalar first: w, x, y, z)")
            if j.kind == "free":
                if j.parent != WORLD:
                    add(f"{where}.parent: a free joint connects a body to {WORLD!r}, got {j.parent!r}")
                frames = (j.parent_point, j.child_point, j.parent_quat, j.child_quat)
                if frames != ((0.0,) * 3, (0.0,) * 3, (1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)):
                    add(f"{where}: a free joint's q0 is the COM pose itself — leave the joint frames at identity")
            if j.kind in AXIS_KINDS:
                what = "rotation axis" if j.kind == "revolute" else "sliding direction"
                if j.axis is None or len(j.axis) != 3:
                    add(f"{where}.axis: a {j.kind} joint needs a 3-vector axis (its {what}, in the joint frame)")
                elif not all(math.isfinite(v) for v in j.axis):
                    add(f"{where}.axis: contains NaN or inf")
                elif math.sqrt(sum(v * v for v in j.axis)) == 0.0:
                    add(f"{where}.axis: zero length — give the {what}")
            elif j.axis is not None:
                add(f"{where}.axis: only {' and '.join(AXIS_KINDS)} joints take an axis")
        for b in sorted(names - set(parents)):
            add(f"bodies[{b!r}]: has no joint — give it one (a free body: Joint('free', 'world', {b!r}, ...))")
        # Cycles: follow parents up from every body; a path that never reaches the
        # world loops (only reachable when the parent names are all known).
        for start in sorted(parents):
            seen, node = set(), start
            while node in parents and node not in seen:
                seen.add(node)
                node = parents[node]
            if node in seen:
                add(f"joints: cycle through {sorted(seen)!r} — joints must form a tree rooted at {WORLD!r}")
                break
        return problems


    def _closure_problems(self):
        from dalembert import closure

        problems = []
        add = problems.append
        for i, (lp, r) in enumerate(zip(self.loops, closure.initial_rows(self))):
            where = f"loops[{i}] ({lp.kind} {lp.body_a!r} -> {lp.body_b!r})"
            for level, res, unit in (("position", r.phi, "m or the sine of a tilt"),
                                     ("velocity", r.velocity, "m/s or rad/s")):
                worst = float(np.max(np.abs(res))) if np.all(np.isfinite(res)) else float("nan")
                if not worst <= LOOP_CLOSURE_TOL:
                    add(f"{where}: the initial state violates the closure at {level} level by {worst:.3g} "
                        f"({unit}; row residuals {np.round(res, 12).tolist()}), above LOOP_CLOSURE_TOL = "
                        f"{LOOP_CLOSURE_TOL:g} — choose the tree joints' {'q0' if level == 'position' else 'v0'} "
                        "so that the loop closes")
        return problems

    def _spring_length_problems(self):
        from dalembert import closure, springs

        states = {**spatial.initial_body_states(self), WORLD: closure.world_state()}
        problems = []
        for i, sp in enumerate(self.springs):
            length = springs.state(sp, states[sp.body_a], states[sp.body_b]).length
            if not length > springs.MIN_LENGTH:
                problems.append(f"{_spring_where(i, sp)}: its points are {length:.3g} m apart at the initial state, "
                                f"below MIN_LENGTH = {springs.MIN_LENGTH:g} m (the force's direction, along the line "
                                "between them, is undefined) — move point_a or point_b, or the bodies")
        return problems


def _spring_where(i, sp):
    return f"springs[{i}] ({sp.name!r}: {sp.body_a!r} -> {sp.body_b!r})"


def _end_problems(where, element, names):
    """The problems naming ``element``'s two ends (``body_a``, ``body_b``: bodies of the scene or the world)."""
    return [f"{where}.{field_name}: no body named {b!r}{_did_you_mean(b, names | {WORLD})}"
            for field_name in ("body_a", "body_b") for b in [getattr(element, field_name)]
            if b != WORLD and b not in names]


def _numbers_problems(where, field_name, v, n, note=""):
    """The problem with ``v``, which must hold ``n`` finite numbers (``note``: what they are), as a list."""
    if len(v) != n:
        return [f"{where}.{field_name}: needs {n} numbers{note}, got {len(v)}"]
    if not _finite(v):
        return [f"{where}.{field_name}: contains NaN or inf"]
    return []


def _spring_problems(i, sp, names):
    where = _spring_where(i, sp)
    problems = []
    add = problems.append
    problems += _end_problems(where, sp, names)
    if sp.body_a == sp.body_b:
        add(f"{where}: joins a body to itself — a spring joins two different bodies (or a body and {WORLD!r})")
    for field_name in ("point_a", "point_b"):
        problems += _numbers_problems(where, field_name, getattr(sp, field_name), 3, " (m, in the body's frame)")
    for field_name, unit in (("stiffness", "N/m"), ("damping", "N s/m"), ("rest_length", "m")):
        v = getattr(sp, field_name)
        if not (math.isfinite(v) and v >= 0.0):
            add(f"{where}.{field_name}: must be finite and >= 0 ({unit}), got {v!r}")
    if sp.stiffness == 0.0 and sp.damping == 0.0:
        add(f"{where}: stiffness and damping are both zero, so it exerts no force — give one of them, or drop the spring")
    return problems


def _loop_problems(i, lp, names):
    where = f"loops[{i}] ({lp.kind} {lp.body_a!r} -> {lp.body_b!r})"
    problems = []
    add = problems.append
    if lp.kind not in LOOP_KINDS:
        add(f"{where}.kind: unknown {lp.kind!r} — use one of {list(LOOP_KINDS)}")
    problems += _end_problems(where, lp, names)
    if lp.body_a == lp.body_b:
        add(f"{where}: closes a body on itself — a loop joins two different bodies (or a body and {WORLD!r})")
    for field_name, n in (("point_a", 3), ("point_b", 3), ("quat_a", 4), ("quat_b", 4)):
        v = getattr(lp, field_name)
        shape = _numbers_problems(where, field_name, v, n)
        problems += shape
        if not shape and n == 4 and abs(math.sqrt(sum(x * x for x in v)) - 1.0) > QUAT_NORM_TOL:
            add(f"{where}.{field_name}: quaternion norm is {math.sqrt(sum(x * x for x in v)):.12g}, not 1 — "
                "normalize it (scalar first: w, x, y, z)")
    if lp.kind == "revolute":
        if lp.axis is None or len(lp.axis) != 3:
            add(f"{where}.axis: a revolute loop needs a 3-vector axis (in the joint frames)")
        elif not _finite(lp.axis) or math.sqrt(sum(v * v for v in lp.axis)) == 0.0:
            add(f"{where}.axis: must be finite and non-zero — give the rotation axis direction")
    elif lp.axis is not None:
        add(f"{where}.axis: only revolute loops take an axis")
    if lp.kind == "distance":
        if lp.length is None or not (math.isfinite(lp.length) and lp.length > 0.0):
            add(f"{where}.length: a distance loop needs a positive finite length (m), got {lp.length!r} — "
                "for coincident points use a ball loop")
    elif lp.length is not None:
        add(f"{where}.length: only distance loops take a length")
    return problems


def _finite(x):
    return all(math.isfinite(v) for v in np.ravel(x))


def _body_problems(b, is_free):
    where = f"bodies[{b.name!r}]"
    problems = []
    add = problems.append
    if not (math.isfinite(b.mass) and b.mass > 0.0):
        add(f"{where}.mass: must be positive and finite, got {b.mass!r} — give the mass in kg")
    I = np.asarray(b.inertia, dtype=float)
    if I.shape != (3, 3):
        add(f"{where}.inertia: must be 3x3 (kg m^2 about the COM, body frame), got shape {I.shape}")
        return problems
    if not _finite(I):
        add(f"{where}.inertia: contains NaN or inf")
        return problems
    scale = max(np.abs(I).max(), np.finfo(float).tiny)
    if np.abs(I - I.T).max() > INERTIA_REL_TOL * scale:
        add(f"{where}.inertia: not symmetric (max |I - I^T| = {np.abs(I - I.T).max():.3g}) — "
            "an inertia tensor is symmetric")
        return problems
    moments = np.linalg.eigvalsh(I)
    if moments[0] < 0.0 or moments[-1] <= 0.0:
        add(f"{where}.inertia: not positive definite (principal moments {moments.tolist()}) — "
            "principal moments must be positive")
    elif moments[0] <= SINGULAR_INERTIA_RATIO * moments[-1]:
        if is_free:
            add(f"{where}.inertia: singular (principal moments {moments.tolist()}): all mass lies on "
                "one line — a rotator (Landau & Lifshitz, Mechanics, section 32) — so the spin about that line is "
                "undetermined; a free body needs three positive principal moments (give the body a "
                "thickness)")
        else:
            add(f"{where}.inertia: not positive definite (principal moments {moments.tolist()}) — "
                "give the body a finite thickness")
    elif moments[0] + moments[1] < moments[2] * (1.0 - INERTIA_REL_TOL):
        add(f"{where}.inertia: principal moments {moments.tolist()} violate the triangle inequality "
            "I1 + I2 >= I3 — no mass distribution has them")
    for k, (m, u) in enumerate(b.particles):
        if not (math.isfinite(m) and m > 0.0) or len(u) != 3 or not _finite(u):
            add(f"{where}.particles[{k}]: needs a positive finite mass and 3 finite coordinates")
    return problems


def _load_problems(i, ld, names):
    where = f"loads[{i}] ({ld.kind} on {ld.body!r})"
    problems = []
    add = problems.append
    if ld.body not in names:
        add(f"{where}.body: no body named {ld.body!r}{_did_you_mean(ld.body, names)}")
    if ld.kind not in LOAD_KINDS:
        add(f"{where}.kind: unknown {ld.kind!r} — use one of {list(LOAD_KINDS)}")
    if ld.frame not in LOAD_FRAMES:
        add(f"{where}.frame: unknown {ld.frame!r} — use 'body' (a follower load) or 'world'")
    for field_name in ("vector", "point"):
        problems += _numbers_problems(where, field_name, getattr(ld, field_name), 3)
    if ld.kind == "torque" and any(ld.point):
        add(f"{where}.point: a torque has no point of application — leave point at (0, 0, 0)")
    return problems


def _did_you_mean(name, candidates):
    return suggest(name, candidates)
