"""The scene as Newton's ``Model``: bodies at their centres of mass, joints in their frames, nothing added.

Frames: each Newton body's frame is the scene's body frame B (origin at the COM: ``com = 0``; its full 3x3
inertia tensor about the COM in B, off-diagonal terms included), so ``X_EB`` is the identity and Newton's
``body_q`` is ``(p_WB, q_WB)`` (quaternion x, y, z, w), its ``body_qd`` ``(v_WB_W, w_WB_W)``. A joint's anchor
frames are the scene's Jp (``parent_xform``: ``parent_point``, ``parent_quat`` in the parent's B, or the world)
and Jc (``child_xform``), its axis in Jp as the scene gives it. Each tree is one Newton articulation, its joints
added root first (Newton requires an articulation's joints contiguous).

Nothing the scene does not call for: joint armature, damping, stiffness, friction and limit gains 0, limits
open (Newton's defaults leave limit gains at 1e4 and 10 on ±1e10 limits: never reached, set to 0 anyway), no
shapes (no contact), inertia taken as given (``balance_inertia`` off, ``lock_inertia``); the built mass and
inertia are checked against the scene's (``check_mass_properties``). Gravity is the scene's vector, stored by
Newton in float32.

The initial state: every body's world pose and velocity at the joints' ``q0``, ``v0``
(``spatial.initial_body_states``), turned into joint coordinates by Newton's own inverse kinematics
(``newton.eval_ik``), then forward kinematics (``newton.eval_fk``), so the joint-coordinate solvers
(Featherstone, Steel) and the body-coordinate ones (semi-implicit, XPBD, VBD) start from the same float32 state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import spatial
from dalembert.adapters.newton.engine import DEVICE, engine
from dalembert.scene import WORLD

__all__ = ["STEEL_DAMPING", "NewtonModel", "build", "build_worlds", "model_text", "why_not", "check_mass_properties",
           "summary"]

# Compiled mass properties must be the scene's to float32's rounding: Newton stores mass and inertia in float32
# (relative error 2^-24 = 6e-8 each), so 4x that.
MASS_PROPERTY_REL_TOL = 4 * 2.0 ** -24
# Steel's per-body angular damping, a model attribute (``SolverSteel.register_custom_attributes``)
STEEL_DAMPING = "steel:rigid_body_angular_damping"


@dataclass(frozen=True, eq=False)
class NewtonModel:
    """A finalized Newton model of a scene.

    Attributes
    ----------
    model : newton.Model — on a Warp device (``model.device``: the CPU unless option ``device`` says), float32
    index : dict body name -> int — the body's index in Newton's arrays
    joint_index : dict joint name -> int
    body_q0 : ndarray (nbody, 7) float32 — the initial ``body_q``, ``(p_WB, q_WB x y z w)``, m, of every body of
        every world of ``model`` (world k's rows at its ``index``)
    body_qd0 : ndarray (nbody, 6) float32 — the initial ``body_qd``, ``(v_WB_W, w_WB_W)``, m/s, rad/s
    joint_q0 : ndarray (ncoord,) float32 — the initial joint coordinates (``eval_ik`` of the body states)
    joint_qd0 : ndarray (ndof,) float32
    world : int — this world's index in ``model`` (0 for a single run)
    worlds : int — how many worlds ``model`` holds (1 for a single run; a batch's size)
    """

    model: object
    index: dict
    joint_index: dict
    body_q0: np.ndarray
    body_qd0: np.ndarray
    joint_q0: np.ndarray
    joint_qd0: np.ndarray
    world: int = 0
    worlds: int = 1

    @property
    def local(self):
        """dict body name -> int: the body's index within its world (its row in a world's samples)."""
        per_world = len(self.index)
        return {n: i - self.world * per_world for n, i in self.index.items()}


def why_not(scene):
    """What Newton's model here cannot hold of ``scene`` (beyond the effects the adapter lacks), or None."""
    floating = sorted(j.child for j in scene.joints if j.kind == "free" and j.parent != WORLD)
    if floating:
        return (f"Newton's free joint here joins a body to the world only: {', '.join(floating)} float on another "
                "body (not mapped)")
    return None


def model_text(scene):
    """What Newton's model of ``scene`` is built from, as text: the scene but its joints' initial coordinates
    (``q0``, ``v0``), which only the initial state takes; scenes of equal text share one model (``build_worlds``)."""
    from dataclasses import fields

    joints = tuple(tuple((f.name, getattr(j, f.name)) for f in fields(j) if f.name not in ("q0", "v0"))
                   for j in scene.joints)
    rest = tuple((f.name, getattr(scene, f.name)) for f in fields(scene) if f.name not in ("name", "joints"))
    return repr((joints, rest))


def _transform(wp, p, q_wxyz):
    x, y, z, w = spatial.wxyz_to_xyzw(np.asarray(q_wxyz, dtype=float) / np.linalg.norm(q_wxyz))
    return wp.transform(wp.vec3(*(float(v) for v in p)), wp.quat(float(x), float(y), float(z), float(w)))


def _trees(scene):
    """The bodies grouped by tree, each root first, in topological order: [[body, ...], ...]."""
    root = {}
    order = list(scene.topological_order())
    for b in order:
        j = scene.joint(b.name)
        root[b.name] = b.name if j.parent == WORLD else root[j.parent]
    trees = {}
    for b in order:
        trees.setdefault(root[b.name], []).append(b)
    return list(trees.values())


def _builder(newton, wp, scene, steel_angular_damping, balance_inertia):
    """A ``ModelBuilder`` holding ``scene`` (its bodies at their initial poses) and the bodies' and joints' indices in
    it: ``(builder, {body: index}, {joint: index})``."""
    start = spatial.initial_body_states(scene)
    b = newton.ModelBuilder(gravity=tuple(float(g) for g in scene.gravity))
    b.balance_inertia = bool(balance_inertia)
    extra = None
    if steel_angular_damping is not None:
        newton.solvers.SolverSteel.register_custom_attributes(b)
        extra = {STEEL_DAMPING: float(steel_angular_damping)}
    free = dict(armature=0.0, damping=0.0, stiffness=0.0, friction=0.0, limit_ke=0.0, limit_kd=0.0)
    index, joint_index = {}, {}
    for tree in _trees(scene):
        ids = []
        for body in tree:
            s = start[body.name]
            index[body.name] = b.add_link(xform=_transform(wp, s["p"], spatial.matrix_to_quat(s["R"])),
                                          mass=body.mass, inertia=wp.mat33(*body.inertia_matrix.ravel().tolist()),
                                          label=body.name, lock_inertia=True, custom_attributes=extra)
        for body in tree:
            j = scene.joint(body.name)
            parent, child = (-1 if j.parent == WORLD else index[j.parent]), index[j.child]
            frames = dict(parent_xform=_transform(wp, j.parent_point, j.parent_quat),
                          child_xform=_transform(wp, j.child_point, j.child_quat), label=j.name)
            if j.kind == "free":
                jid = b.add_joint_free(child, label=j.name)
            elif j.kind == "revolute":
                jid = b.add_joint_revolute(parent, child, axis=wp.vec3(*j.axis), **frames, **free)
            elif j.kind == "prismatic":
                jid = b.add_joint_prismatic(parent, child, axis=wp.vec3(*j.axis), **frames, **free)
            elif j.kind == "ball":
                jid = b.add_joint_ball(parent, child, armature=0.0, friction=0.0, **frames)
            elif j.kind == "weld":
                jid = b.add_joint_fixed(parent, child, **frames)
            else:
                raise ValueError(f"joints[{j.name!r}].kind: Newton's adapter has no {j.kind!r} joint")
            joint_index[j.name] = jid
            ids.append(jid)
        b.add_articulation(ids, label=tree[0].name)
    return b, index, joint_index


def build(scene, color=False, steel_angular_damping=None, balance_inertia=False, device=DEVICE):
    """The Newton model of ``scene`` (``NewtonModel``) on Warp's ``device`` (``cpu``, ``cuda:0``). ``color``: the
    body graph coloured (``ModelBuilder.color``), which VBD requires. ``steel_angular_damping`` (1/s, or None: not
    for Steel): Steel's per-body angular damping of free bodies, a model attribute
    (``steel:rigid_body_angular_damping``) that Steel otherwise takes as 0.05 (PhysX's default), registered and set
    on every body. ``balance_inertia``: Newton's correction of inertias that violate the triangle inequality (its
    default on; off here unless asked: a scene's inertia is as given, and ``check_mass_properties`` then says where
    Newton changed one)."""
    return build_worlds([scene], color, steel_angular_damping, balance_inertia, device)[0]


def build_worlds(scenes, color=False, steel_angular_damping=None, balance_inertia=False, device=DEVICE):
    """One Newton model of ``len(scenes)`` worlds, each a copy of ``scenes[0]``'s bodies and joints
    (``ModelBuilder.replicate``: the scenes share one model, ``batch.same_model``) started from its own scene's
    initial state: one ``NewtonModel`` per world, all on the one ``model`` (arguments as ``build``'s). A single
    scene is built as one world without replication."""
    wp, newton, _ = engine()
    one, index, joint_index = _builder(newton, wp, scenes[0], steel_angular_damping, balance_inertia)
    if len(scenes) == 1:
        b = one
    else:
        b = newton.ModelBuilder(gravity=tuple(float(g) for g in scenes[0].gravity))
        if steel_angular_damping is not None:
            newton.solvers.SolverSteel.register_custom_attributes(b)
        b.replicate(one, len(scenes))
    if color:
        b.color()
    model = b.finalize(device=device)
    nb, nj = len(index), len(joint_index)
    with wp.ScopedDevice(device):
        state = model.state()
        bq, bqd = state.body_q.numpy(), state.body_qd.numpy()  # host copies on a CUDA device: written back below
        for k, scene in enumerate(scenes):
            start = spatial.initial_body_states(scene)
            for body in scene.bodies:
                s, i = start[body.name], k * nb + index[body.name]
                bq[i, :3], bq[i, 3:] = s["p"], spatial.wxyz_to_xyzw(spatial.matrix_to_quat(s["R"]))
                bqd[i, :3], bqd[i, 3:] = s["v"], s["w"]
        state.body_q.assign(bq)
        state.body_qd.assign(bqd)
        newton.eval_ik(model, state, state.joint_q, state.joint_qd)
        newton.eval_fk(model, state.joint_q, state.joint_qd, state)
    body_q, body_qd = state.body_q.numpy().copy(), state.body_qd.numpy().copy()
    joint_q, joint_qd = state.joint_q.numpy().copy(), state.joint_qd.numpy().copy()
    return [NewtonModel(model, {n: k * nb + i for n, i in index.items()},
                        {n: k * nj + i for n, i in joint_index.items()}, body_q, body_qd, joint_q, joint_qd,
                        world=k, worlds=len(scenes)) for k in range(len(scenes))]


def check_mass_properties(nm, scene):
    """Newton's mass and inertia of every body against the scene's (RuntimeError naming the body)."""
    mass, inertia = nm.model.body_mass.numpy(), nm.model.body_inertia.numpy()
    com = nm.model.body_com.numpy()
    for body in scene.bodies:
        i = nm.index[body.name]
        I = body.inertia_matrix
        if (abs(mass[i] - body.mass) > MASS_PROPERTY_REL_TOL * body.mass
                or np.abs(inertia[i] - I).max() > MASS_PROPERTY_REL_TOL * np.abs(I).max()
                or np.any(com[i] != 0.0)):
            raise RuntimeError(f"Newton built body {body.name!r} with mass {mass[i]}, inertia {inertia[i].tolist()} "
                               f"and COM offset {com[i].tolist()}; the scene has {body.mass}, "
                               f"{I.tolist()} and 0")


def summary(nm):
    """Newton's model as text, read back from its arrays (``dalembert show-model``)."""
    newton, m = engine()[1], nm.model
    names = {i: n for n, i in nm.index.items()}
    lines = [f"newton.Model on {m.device}: {m.body_count} bodies, {m.joint_count} joints, "
             f"{m.articulation_count} articulations, gravity {m.gravity.numpy()[0].tolist()} m/s^2 (float32)"]
    steel = getattr(getattr(m, "steel", None), "rigid_body_angular_damping", None)
    if steel is not None:
        lines.append(f"steel:rigid_body_angular_damping {float(steel.numpy().max(initial=0.0)):g} 1/s (every body)")
    mass, inertia = m.body_mass.numpy(), m.body_inertia.numpy()
    for i in range(m.body_count):
        lines.append(f"body {names[i]}: mass {mass[i]:.9g} kg, inertia about the COM "
                     f"{np.round(inertia[i], 9).tolist()} kg m^2")
    jtype, parent, child = m.joint_type.numpy(), m.joint_parent.numpy(), m.joint_child.numpy()
    X_p, X_c = m.joint_X_p.numpy(), m.joint_X_c.numpy()
    axis, start = m.joint_axis.numpy(), m.joint_qd_start.numpy()
    armature = m.joint_armature.numpy()
    for k in range(m.joint_count):
        kind = newton.JointType(int(jtype[k])).name
        dofs = range(int(start[k]), int(start[k + 1]))
        lines.append(f"joint {kind} {names.get(int(parent[k]), 'world')} -> {names[int(child[k])]}: "
                     f"X_p {np.round(X_p[k], 9).tolist()}, X_c {np.round(X_c[k], 9).tolist()}, axes "
                     f"{[np.round(axis[d], 9).tolist() for d in dofs]}, armature {[float(armature[d]) for d in dofs]}")
    return "\n".join(lines)
