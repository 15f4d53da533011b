"""DART's states in body terms: poses, velocities, joint coordinates and reactions.

Once per run, after stepping (never timed). Every DART body frame is the scene's body frame B (``model``), so
for every sample the skeleton is set to the sampled positions and velocities, and each body node's world
transform (``R_WB``, ``p_WB``), the linear velocity of its origin (the COM) and its angular velocity, both in
world axes, are the scene's body states; the attitude is DART's rotation matrix (kept as ``rotation``, the
quaternion derived from it). The angular velocity is read from the body node, in world axes, never from a
``FreeJoint``'s velocities (body axes).

Joint reactions: DART's ``BodyNode.getBodyForce``, the spatial force the parent transmits to the node through
its joint, in the node's frame at its origin (the COM); its force part in world axes, ``R_WB f_B``, is the force
the joint exerts ON the child (checked on the pendulum: ``m a_COM - m g``). In a tree it is DART's forward dynamics'
(``computeForwardDynamics`` at the sampled state, with the loads applied as in a step). Where constraints act
(loops, contact) their impulses are part of it only in a step: one ``World.step`` is taken from each sampled
state and the force read after it (the force of the step that starts at the sample, first order in the step:
measured on the four-bar 9.0e-3 of the largest reaction at dt = 1e-3, 9.0e-4 at 1e-4). DART reports a loop's
constraint impulse only as the skeleton's generalized forces, so a loop's force is Newton's second law on one of
its bodies over that step (``_loop_forces``: 7.1e-3 and 7.1e-4 on the four-bar). Each contact pair's force, ON its
subject, N, world (``contact.read_forces``), is read after the same step: the extras ``contact_force:<pair>``.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.dart.contact import read_forces
from dalembert.adapters.dart.stepping import apply_loads
from dalembert.contact import FORCE_PREFIX
from dalembert.scene import WORLD

__all__ = ["read_back"]


def read_back(p, Q, V):
    """The ``Trajectory`` of the sampled skeleton states ``Q``, ``V`` (n, ndofs) (NaN rows stay NaN), with the
    reaction force on every revolute, prismatic, ball or welded child (N, world axes, on the child) and every contact
    pair's force on its subject (N, world axes, the step from the sample: ``contact.read_forces``) as extras."""
    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    model, scene, times = p.model, p.scene, p.times
    skeleton = model.skeleton
    n, names = len(times), [b.name for b in scene.bodies]
    nodes = [model.nodes[name] for name in names]
    jointed = [j.child for j in scene.joints if j.kind != "free"]  # reactions: every joint's but a free one's
    constrained = bool(scene.loops or scene.contacts)  # impulses in the step: read from one step (module docstring)
    R = np.full((n, len(names), 3, 3), np.nan)
    pos, vel, omega = (np.full((n, len(names), 3), np.nan) for _ in range(3))
    force = np.full((n, len(names), 3), np.nan)  # the joint's force on the body, body axes
    accel = np.full((n, len(names), 3), np.nan)  # constrained: the COM's acceleration over the step, world
    pair_force = np.full((n, len(scene.contacts), 3), np.nan)
    finite = np.flatnonzero(np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1))
    apply_loads(model)  # world loads in body axes are set again at each sample's pose below
    world_loads = any(ld.frame == "world" for ld in scene.loads)
    h = float(p.settings.dt)
    for k in finite:
        if constrained:
            model.reset()  # no impulse or warm start carried from the last sample's step
        skeleton.setPositions(Q[k])
        skeleton.setVelocities(V[k])
        if world_loads:
            apply_loads(model)
        for b, node in enumerate(nodes):
            T = node.getWorldTransform()
            R[k, b], pos[k, b] = T.rotation(), T.translation()
            vel[k, b], omega[k, b] = node.getLinearVelocity(), node.getAngularVelocity()
        if not (jointed or scene.loops or scene.contacts):
            continue
        if constrained:
            model.world.step(False)
            for b, node in enumerate(nodes):
                accel[k, b] = (node.getLinearVelocity() - vel[k, b]) / h
            if scene.contacts:
                pair_force[k] = read_forces(model)
                if not (jointed or scene.loops):
                    continue
        else:
            skeleton.computeForwardDynamics()
        for b, node in enumerate(nodes):
            force[k, b] = node.getBodyForce()[3:]
    quat = spatial.matrix_to_quat(R)
    bodies = {name: BodyStates(pos[:, b], quat[:, b], vel[:, b], omega[:, b], rotation=R[:, b])
              for b, name in enumerate(names)}
    order = {name: b for b, name in enumerate(names)}
    joints = {}
    for j in scene.joints:
        s = model.dofs[j.child]
        b = order[j.child]
        if j.kind == "free":
            joints[j.child] = JointStates(*spatial.free_joint_coordinates(pos[:, b], quat[:, b], vel[:, b],
                                                                          omega[:, b], R[:, b]))
        elif j.kind in ("revolute", "prismatic"):
            joints[j.child] = JointStates(Q[:, s], V[:, s])
        elif j.kind == "ball":  # rotation vector of R_JpJc -> quaternion; v is the scene's already
            with np.errstate(invalid="ignore"):
                R_J = np.stack([spatial.so3_exp(theta) if np.all(np.isfinite(theta)) else np.full((3, 3), np.nan)
                                for theta in Q[:, s]])
            joints[j.child] = JointStates(spatial.matrix_to_quat(R_J), V[:, s])
    on_child = {c: (R[:, order[c]] @ force[:, order[c], :, None])[..., 0] for c in jointed}  # world axes
    extras = {f"reaction_force:{c}": f for c, f in on_child.items()}
    extras.update(_loop_forces(scene, order, R, accel, on_child))
    extras.update({FORCE_PREFIX + pair.name: pair_force[:, i] for i, pair in enumerate(scene.contacts)})
    return Trajectory(times, bodies, joints, extras)


def _loop_forces(scene, order, R, accel, on_child):
    """Each loop's force ON its body b (N, world axes) by Newton's second law on the one body of the loop that no
    other loop holds (b, or a where b is the world or another loop's): its mass times its COM's acceleration over
    the step, less gravity, its force loads, its joint's force, plus its child joints' (each the opposite of the
    force on the child). A loop whose two bodies are both held by other loops too is left out."""
    held = {}
    for lp in scene.loops:
        for body in (lp.body_a, lp.body_b):
            held[body] = held.get(body, 0) + 1
    out = {}
    for lp in scene.loops:
        side = next((x for x in (lp.body_b, lp.body_a) if x != WORLD and held[x] == 1), None)
        if side is None:
            continue
        b = order[side]
        body, joint = scene.body(side), scene.joint(side)
        f = body.mass * (accel[:, b] - np.asarray(scene.gravity, dtype=float))
        for ld in scene.loads:
            if ld.body == side and ld.kind == "force":
                f = f - spatial.load_to_world(ld, R[:, b])
        if joint.kind != "free":
            f = f - on_child[side]
        for j in scene.joints:
            if j.parent == side:
                f = f + on_child[j.child]
        out[f"reaction_force:{lp.name}"] = f if side == lp.body_b else -f
    return out
