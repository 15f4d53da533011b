"""DART's states in body terms: poses, velocities, joint coordinates and reactions.

Once per run, after stepping (never timed). Every DART body frame is the scene's body frame B (``model``), so
for every sample the skeleton is set to the sampled positions and velocities, and each body node's world
transform (``R_WB``, ``p_WB``), the linear velocity of its origin (the COM) and its angular velocity, both in
world axes, are the scene's body states; the attitude is DART's rotation matrix (kept as ``rotation``, the
quaternion derived from it). The angular velocity is read from the body node, in world axes, never from a
``FreeJoint``'s velocities (body axes).

Joint reactions: DART's ``BodyNode.getBodyForce``, the spatial force the parent transmits to the node through
its joint, in the node's frame at its origin (the COM), as DART's forward dynamics computes it
(``computeForwardDynamics`` at the sampled state, with the loads applied as in a step); its force part in world
axes, ``R_WB f_B``, is the force the joint exerts ON the child (checked on the pendulum: ``m a_COM - m g``).
None in a scene with loops (``loops.REACTIONS_REASON``).
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.dart.stepping import apply_loads

__all__ = ["read_back"]


def read_back(p, Q, V):
    """The ``Trajectory`` of the sampled skeleton states ``Q``, ``V`` (n, ndofs) (NaN rows stay NaN), with the
    reaction force on every revolute, prismatic, ball or welded child (N, world axes, on the child) as extras."""
    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    model, scene, times = p.model, p.scene, p.times
    skeleton = model.skeleton
    n, names = len(times), [b.name for b in scene.bodies]
    nodes = [model.nodes[name] for name in names]
    # reactions: every joint's but a free one's, in a tree (``loops.REACTIONS_REASON``: none in a scene with loops)
    jointed = [] if scene.loops else [j.child for j in scene.joints if j.kind != "free"]
    R = np.full((n, len(names), 3, 3), np.nan)
    pos, vel, omega = (np.full((n, len(names), 3), np.nan) for _ in range(3))
    force = np.full((n, len(names), 3), np.nan)  # the joint's force on the body, body axes
    finite = np.flatnonzero(np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1))
    apply_loads(model)  # world loads in body axes are set again at each sample's pose below
    world_loads = any(ld.frame == "world" for ld in scene.loads)
    for k in finite:
        skeleton.setPositions(Q[k])
        skeleton.setVelocities(V[k])
        if world_loads:
            apply_loads(model)
        if jointed:
            skeleton.computeForwardDynamics()
        for b, node in enumerate(nodes):
            T = node.getWorldTransform()
            R[k, b], pos[k, b] = T.rotation(), T.translation()
            vel[k, b], omega[k, b] = node.getLinearVelocity(), node.getAngularVelocity()
            if jointed:
                force[k, b] = node.getBodyForce()[3:]
    quat = spatial.matrix_to_quat(R)
    bodies = {name: BodyStates(pos[:, b], quat[:, b], vel[:, b], omega[:, b], rotation=R[:, b])
              for b, name in enumerate(names)}
    order = {name: b for b, name in enumerate(names)}
    joints = {}
    for j in scene.joints:
        s = model.dofs[j.child]
        b = order[j.child]
        if j.kind == "free":  # the scene's: (p_WB, q_WB), (v_WB_W, w_WB_B)
            w_B = np.einsum("nji,nj->ni", R[:, b], omega[:, b])
            joints[j.child] = JointStates(np.concatenate([pos[:, b], quat[:, b]], axis=1),
                                          np.concatenate([vel[:, b], w_B], axis=1))
        elif j.kind in ("revolute", "prismatic"):
            joints[j.child] = JointStates(Q[:, s], V[:, s])
        elif j.kind == "ball":  # rotation vector of R_JpJc -> quaternion; v is the scene's already
            with np.errstate(invalid="ignore"):
                R_J = np.stack([spatial.so3_exp(theta) if np.all(np.isfinite(theta)) else np.full((3, 3), np.nan)
                                for theta in Q[:, s]])
            joints[j.child] = JointStates(spatial.matrix_to_quat(R_J), V[:, s])
    extras = {f"reaction_force:{c}": (R[:, order[c]] @ force[:, order[c], :, None])[..., 0] for c in jointed}
    return Trajectory(times, bodies, joints, extras)
