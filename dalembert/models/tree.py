"""A model file's kinematic tree, read but not yet a scene, and its turning into a ``Scene``.

Both readers (``dalembert.models.urdf``, ``dalembert.models.mjcf``) fill the same plain description: links
(mass, centre of mass and inertia in the link's own frame L) and joints (the joint frame's pose in the
parent link's frame and in the child link's frame, which coincide at zero joint coordinates). ``build_scene``
turns it into a ``Scene`` whose body frames sit at each link's COM with the link's axes:

* the inertia given about the COM in the inertial frame I is rotated into L, ``I_L = R_LI I_I R_LI^T``;
* a joint point known in L moves to the body frame B by ``x_B = x_L - c_L`` (``c_L``: the COM in L);
* ``fixed`` joints become welds, except where the child is not a rigid body on its own: a link without
  mass (a tool frame, a sensor mount: URDFs use them everywhere), or with a point mass, or with moments that
  break the triangle inequality (CAD exports), joined by a fixed joint is merged into its parent — its mass
  added (parallel-axis theorem), its frame composed into its children's joints. That is exactly the
  physics of the welded pair, and what Pinocchio's URDF reader does with every fixed joint. A massless
  subtree (frames only, whatever its joints) is left out; a massless link that carries massive links
  through a moving joint is refused, naming the link (its joint would have no inertia of its own);
* the root link is part of the world (``base="fixed"``: it does not move, so its mass acts on nothing that
  moves), with every link fixed to it, or free (``base="free"``; a root without mass, even with its fixed
  links merged in, is refused). A fixed-base scene so starts at its first moving joints.

Effects the file calls for beyond bodies and joints (damping, friction, armature, limits, springs,
actuators, transmissions, mimic joints) are collected in ``FileEffects`` and left out of the scene.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from dalembert import spatial
from dalembert.kinds import AXIS_KINDS, JOINT_KINDS
from dalembert.scene import INERTIA_REL_TOL, SINGULAR_INERTIA_RATIO, Body, Joint, Scene, SceneError

__all__ = ["ModelError", "FileEffect", "FileEffects", "LinkSpec", "JointSpec", "ImportedModel", "build_scene",
           "KINDS", "rpy_to_matrix"]

# The joint kinds a reader hands over, to the scene's joint kinds (``fixed`` is a weld or a merge).
KINDS = {"revolute": "revolute", "prismatic": "prismatic", "ball": "ball", "free": "free", "fixed": "weld"}


class ModelError(ValueError):
    """A model file dalembert cannot turn into a scene. ``reason`` is a short key (for counting files by
    why they fail); the message names the file, the element and the fix."""

    def __init__(self, message, reason):
        super().__init__(message)
        self.reason = reason


@dataclass(frozen=True)
class FileEffect:
    """One effect a model file calls for that the scene leaves out.

    Attributes
    ----------
    element : str — where, e.g. ``<joint name='elbow'>``
    kind : str — ``damping``, ``friction``, ``armature``, ``limit``, ``spring``, ``actuator``,
        ``transmission``, ``mimic``, ``merged`` (a massless link merged into its parent) or ``dropped``
        (a massless subtree left out)
    value : str — the file's values, as written
    """

    element: str
    kind: str
    value: str


@dataclass(frozen=True)
class FileEffects:
    """What the file calls for beyond the scene's bodies and joints ("the file calls for"), left out."""

    path: str
    effects: tuple = ()

    def kinds(self):
        """The kinds present, sorted."""
        return sorted({e.kind for e in self.effects})

    def __str__(self):
        if not self.effects:
            return f"{self.path}: the file calls for nothing beyond bodies and joints"
        counts = {k: sum(e.kind == k for e in self.effects) for k in self.kinds()}
        return (f"{self.path}: the file calls for (left out of the scene): "
                + ", ".join(f"{k} x{n}" for k, n in counts.items()))


@dataclass(frozen=True)
class LinkSpec:
    """A link as read: ``mass`` (kg), ``com`` (3,) the COM in the link frame L (m), ``R_LI`` (3, 3) the
    inertial frame's axes in L, ``inertia`` (3, 3) about the COM in the inertial frame (kg m^2)."""

    name: str
    mass: float
    com: tuple = (0.0, 0.0, 0.0)
    R_LI: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    inertia: tuple = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


@dataclass(frozen=True)
class JointSpec:
    """A joint as read: ``kind`` one of ``KINDS``; the joint frame J's pose in the parent link's frame
    (``p_PJ`` (3,) m, ``R_PJ`` (3, 3)) and in the child link's (``p_CJ``, ``R_CJ``); ``axis`` (3,) in J."""

    name: str
    kind: str
    parent: str
    child: str
    p_PJ: tuple
    R_PJ: tuple
    p_CJ: tuple = (0.0, 0.0, 0.0)
    R_CJ: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    axis: tuple | None = None


@dataclass(frozen=True)
class ImportedModel:
    """A model file's scene, what the file calls for besides, and the names that join the two.

    Attributes
    ----------
    scene : Scene
    effects : FileEffects
    joint_names : dict — the file's name of each moving joint -> the scene's joint (its child body's name)
    """

    scene: Scene
    effects: FileEffects
    joint_names: dict = field(default_factory=dict)

    @property
    def moving_joints(self):
        """The file's names of the joints with coordinates (revolute, prismatic, ball, free), in file order."""
        return tuple(self.joint_names)


def rpy_to_matrix(rpy):
    """URDF's fixed-axis roll, pitch, yaw (rad) as the rotation ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (3, 3)."""
    r, p, y = (float(v) for v in rpy)
    q = spatial.quat_multiply(spatial.quat_from_axis_angle([0.0, 0.0, 1.0], y),
                              spatial.quat_multiply(spatial.quat_from_axis_angle([0.0, 1.0, 0.0], p),
                                                    spatial.quat_from_axis_angle([1.0, 0.0, 0.0], r)))
    return spatial.quat_to_matrix(q)


def _pose(p, R):
    return np.asarray(p, dtype=float), np.asarray(R, dtype=float)


def _compose(a, b):
    """X_AC from X_AB = a and X_BC = b, each ``(p, R)``."""
    return a[0] + a[1] @ b[0], a[1] @ b[1]


def _is_body(mass, com, I):
    """Whether ``mass`` (kg) and ``I`` (3, 3, kg m^2) are a rigid body's as the scene's checks ask
    (``dalembert.scene_checks``: positive mass, positive moments, the triangle inequality)."""
    if not mass > 0.0 or not np.all(np.isfinite(I)):
        return False
    m = np.linalg.eigvalsh(0.5 * (I + I.T))
    return bool(m[0] > SINGULAR_INERTIA_RATIO * m[-1] > 0.0 and m[0] + m[1] >= m[2] * (1.0 - INERTIA_REL_TOL))


def _combine(a, b):
    """The mass properties of two bodies welded together, each ``(mass, com (3,), inertia about its COM (3, 3))``
    in one frame: masses add, the COM is the mass-weighted mean, inertias move to it by the parallel-axis
    theorem (Landau & Lifshitz, Mechanics, section 32)."""
    m = a[0] + b[0]
    c = (a[0] * a[1] + b[0] * b[1]) / m
    out = np.zeros((3, 3))
    for mi, ci, Ii in (a, b):
        d = ci - c
        out += Ii + mi * (d @ d * np.eye(3) - np.outer(d, d))
    return m, c, out


def build_scene(path, name, links, joints, effects, base="fixed", gravity=(0.0, 0.0, -9.81), positions=None,
                velocities=None, tag="link", locked=()):
    """The ``Scene`` of a model file's tree (see the module docstring).

    Parameters
    ----------
    path : str — the file, for messages
    name : str — the scene's name
    links : list of LinkSpec; joints : list of JointSpec (one per non-root link, a tree)
    effects : list of FileEffect — the file's extra effects; merges and drops are added here
    base : "fixed" or "free" — the root link part of the world (with every link fixed to it), or free
    gravity : 3 floats, m/s^2, world
    positions, velocities : dict — the file's joint name -> its initial coordinate (rad or m) and rate
        (rad/s or m/s), 0 where not given; for a free base, ``"base"`` -> the free joint's 7 coordinates /
        6 speeds (``JOINT_KINDS``; the position defaults to the root COM with the root frame at the origin)
    tag : str — the file's element for a link, in messages (``link``; MJCF's ``body``)
    locked : iterable of str — the file's names of moving joints to hold at their zero, as if fixed (a
        gripper's fingers, which slide without end when the file's limits are left out)

    Returns
    -------
    ImportedModel
    """
    positions, velocities, effects = dict(positions or {}), dict(velocities or {}), list(effects)
    locked = set(locked)
    missing = sorted(locked - {j.name for j in joints})
    if missing:
        raise ModelError(f"{path}: locked joints {missing} are not in the file — use its joint names", "bad argument")
    joints = [replace(j, kind="fixed") if j.name in locked else j for j in joints]
    effects += [FileEffect(f"<joint name='{n}'>", "locked", "held at 0 (asked for)") for n in sorted(locked)]
    if base not in ("fixed", "free"):
        raise ModelError(f"{path}: base={base!r} — use 'fixed' (the root is the world's) or 'free' (a floating base)",
                         "bad argument")
    if not links:
        raise ModelError(f"{path}: no links — the file defines no robot (a xacro macro file is expanded by xacro "
                         "first): give a file with <link> elements", "no links")
    by_name = {lk.name: lk for lk in links}
    children, parent_of = {lk.name: [] for lk in links}, {}
    for j in joints:
        for end in (j.parent, j.child):
            if end not in by_name:
                raise ModelError(f"{path}: <joint name='{j.name}'> names link '{end}', which the file does not "
                                 "define — add the link or fix the name", "broken tree")
        if j.child in parent_of:
            raise ModelError(f"{path}: link '{j.child}' is the child of two joints — a model is a tree: one "
                             "parent joint per link", "broken tree")
        parent_of[j.child] = j
        children[j.parent].append(j)
    roots = [lk.name for lk in links if lk.name not in parent_of]
    if len(roots) != 1:
        raise ModelError(f"{path}: {len(roots)} root links {roots[:5]} — a model is one tree with one root link",
                         "broken tree")
    root = roots[0]

    heavy = {}  # link -> whether its subtree has mass

    def has_mass(link):
        if link not in heavy:
            heavy[link] = by_name[link].mass > 0.0 or any(has_mass(j.child) for j in children[link])
        return heavy[link]

    order, stack = [], [root]
    while stack:  # parents first; a cycle cannot reach the root, so every link is seen once
        link = stack.pop()
        order.append(link)
        stack += [j.child for j in reversed(children[link])]
    if len(order) != len(links):
        raise ModelError(f"{path}: links {sorted(set(by_name) - set(order))[:5]} are not reached from the root "
                         f"'{root}' — every link hangs from the root by joints", "broken tree")

    # Pass 1: each link's place — the scene body it belongs to (itself, the parent it merges into, or the
    # world) and its frame's pose in that body's link frame — and each body's mass properties, merged ones
    # added in (mass kg, COM m and inertia kg m^2 about it, all in the owner's link frame).
    home, props, inner = {}, {}, {}
    for link in order:
        lk = by_name[link]
        I_L = np.asarray(lk.R_LI, float) @ np.asarray(lk.inertia, float) @ np.asarray(lk.R_LI, float).T
        mine = (lk.mass, np.asarray(lk.com, float), I_L)
        j = parent_of.get(link)
        if j is None:
            if base == "free":
                home[link], props[link] = (link, _pose(np.zeros(3), np.eye(3))), mine
            else:  # a fixed base does not move: it is part of the world (its mass acts on nothing that moves)
                home[link] = ("world", _pose(np.zeros(3), np.eye(3)))
                effects.append(FileEffect(f"<{tag} name='{link}'>", "merged", "into the world (the fixed root)"))
            continue
        if not has_mass(link):
            effects.append(FileEffect(f"<{tag} name='{link}'>", "dropped",
                                      f"massless subtree from <joint name='{j.name}'>"))
            continue
        owner, X_OP = home[j.parent]
        X_OJ = _compose(X_OP, _pose(j.p_PJ, j.R_PJ))
        inner[link] = (owner, X_OJ)
        if j.kind == "fixed" and (owner == "world" or not _is_body(*mine) or props[owner][0] <= 0.0):
            X_CJ = _pose(j.p_CJ, j.R_CJ)
            X_OC = _compose(X_OJ, (-X_CJ[1].T @ X_CJ[0], X_CJ[1].T))
            home[link] = (owner, X_OC)
            if owner != "world" and lk.mass > 0.0:  # (what is fixed to the world is the world's)
                props[owner] = _combine(props[owner], (lk.mass, X_OC[0] + X_OC[1] @ mine[1],
                                                       X_OC[1] @ I_L @ X_OC[1].T))
            effects.append(FileEffect(f"<{tag} name='{link}'>", "merged", "into the world (fixed to the fixed base)"
                                      if owner == "world" else f"into '{owner}' (fixed joint; mass {lk.mass:g} kg, "
                                      "not a body's inertia alone, or its parent has none)"))
            continue
        if lk.mass <= 0.0:
            raise ModelError(f"{path}: <{tag} name='{link}'> has no mass but moves on <joint name='{j.name}'> "
                             f"({j.kind}) and carries links with mass — give it an <inertial> with a mass "
                             "and inertia, or make the joint fixed", "massless moving link")
        home[link], props[link] = (link, _pose(np.zeros(3), np.eye(3))), mine

    # Pass 2: the bodies (at their COMs, the link's axes) and their joints.
    bodies, scene_joints, joint_names = [], [], {}
    for link in order:
        if link not in props:
            continue
        mass, com, I_L = props[link]
        if link == root and mass <= 0.0:
            raise ModelError(f"{path}: <{tag} name='{link}'> (the root) has no mass, nor the links fixed to it — a "
                             "floating base must be a body with mass: pass base='fixed', or give the root an "
                             "<inertial>", "massless floating root")
        if not _is_body(mass, com, I_L):
            raise ModelError(f"{path}: <{tag} name='{link}'> <inertial>: mass {mass:g} kg and principal moments "
                             f"{np.linalg.eigvalsh(I_L).tolist()} kg m^2 (links fixed to it merged in) are not a "
                             "rigid body's — a body needs a positive mass and moments that are positive and "
                             "meet the triangle inequality I1 + I2 >= I3: fix the <inertia>", "bad inertia")
        bodies.append(Body(link, mass, I_L))
        j = parent_of.get(link)
        if j is None:
            if base == "free":
                q0 = positions.get("base", (*com, 1.0, 0.0, 0.0, 0.0))
                scene_joints.append(Joint("free", "world", link, q0=q0, v0=velocities.get("base", (0.0,) * 6)))
                joint_names["base"] = link
            continue
        owner, X_OJ = inner[link]
        kind = KINDS[j.kind]
        if kind == "free" and owner != "world":
            raise ModelError(f"{path}: <joint name='{j.name}'> is floating but its parent '{j.parent}' moves — "
                             "dalembert frees a body only from the world: make it the root", "inner floating joint")
        p_OJ = X_OJ[0] - (props[owner][1] if owner != "world" else 0.0)
        quat_P = spatial.matrix_to_quat(X_OJ[1])
        p_CJ = np.asarray(j.p_CJ, float) - com
        quat_C = spatial.matrix_to_quat(np.asarray(j.R_CJ, float))
        nq, nv = JOINT_KINDS[kind]
        q0 = positions.get(j.name, (0.0,) * nq if kind != "ball" else (1.0, 0.0, 0.0, 0.0))
        v0 = velocities.get(j.name, (0.0,) * nv)
        if kind in ("revolute", "prismatic"):
            q0, v0 = np.atleast_1d(q0), np.atleast_1d(v0)
        if kind == "free":  # a floating joint from the world: the child's COM and attitude in the world
            R = X_OJ[1] @ np.asarray(j.R_CJ, float).T
            q0 = positions.get(j.name, (*(X_OJ[0] + R @ (com - np.asarray(j.p_CJ, float))),
                                        *spatial.matrix_to_quat(R)))
            scene_joints.append(Joint("free", "world", link, q0=q0, v0=v0))
        else:
            axis = j.axis if kind in AXIS_KINDS else None
            scene_joints.append(Joint(kind, owner, link, q0=q0, v0=v0, axis=axis, parent_point=p_OJ,
                                      parent_quat=quat_P, child_point=p_CJ, child_quat=quat_C))
        if kind != "weld":
            joint_names[j.name] = link
    unknown = sorted(k for k in set(positions) | set(velocities) if k not in joint_names and k != "base")
    if unknown:
        raise ModelError(f"{path}: initial coordinates for {unknown[:5]}, not moving joints of the model — use the "
                         f"file's joint names: {list(joint_names)[:8]}...", "bad argument")
    if not bodies:
        raise ModelError(f"{path}: nothing moves — with a fixed base the file has no moving joint (the whole robot "
                         "is one rigid body fixed to the world): pass base='free' for a floating base",
                         "no moving joints")
    try:
        scene = Scene(name, bodies, scene_joints, gravity)
    except SceneError as err:
        reason = "bad inertia" if any(".inertia" in p for p in err.problems) else "invalid scene"
        raise ModelError(f"{path}: the links make no valid scene — fix the file's <inertial> values:\n{err}",
                         reason) from None
    return ImportedModel(scene, FileEffects(path, tuple(effects)), joint_names)
