"""Pinocchio's states in body terms: poses, velocities, joint coordinates and reactions.

Once per run, after stepping (never timed). Poses and velocities of the scene's body
frames come from Pinocchio's frames (``PinocchioModel.frame_ids``: B, placed in each joint's
frame E) by forward kinematics, sample by sample; a free joint's coordinates are the
engine's own (its quaternion's norm is data). A joint's reaction is the force through
it from ``rnea`` at the sample's state and acceleration (``data.f``, the joint's LOCAL
frame), rotated to world axes; with constraints (loops, welds as constraints) the
sample loop keeps each ``constraintDynamics``' multipliers, frames and Jacobian, and
the constraints' forces and their share of the tree joints' reactions are resolved
after it for all samples at once (``PinocchioModel.minimum_norm``,
``constraint_forces``, ``carried_by``). A contact scene's pairs' forces, ON each pair's subject (N, world), are
the contact time-stepper's impulses over the step from each sample (``contact.read_forces``): the extras
``contact_force:<pair>``.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.pinocchio import contact, loops
from dalembert.contact import FORCE_PREFIX

__all__ = ["read_back", "REACTING"]

# The joint kinds whose reactions are read back (``reaction_force:<child>``): the force through the joint from
# ``rnea`` (``data.f``, the joint's LOCAL frame), rotated to world axes.
REACTING = ("revolute", "prismatic", "ball")


def read_back(p, Q, V):
    """The ``Trajectory`` of the sampled states ``Q (n, nq)``, ``V (n, nv)`` (Pinocchio's, quaternions
    ``(x, y, z, w)``; NaN rows stay NaN), with the reaction force on every revolute, prismatic or ball child
    and every loop's force on its body b (N, world axes) as extras ``reaction_force:<name>``, and each contact
    pair's force on its subject (N, world axes) as ``contact_force:<pair>``."""
    import pinocchio as pin

    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    pm, scene = p.pm, p.scene
    model, data = pm.model, pm.data
    n = len(p.times)
    bodies = {b.name: [np.full((n, 3), np.nan), None, np.full((n, 3), np.nan),
                       np.full((n, 3), np.nan)] for b in scene.bodies}
    R_WB = {b.name: np.full((n, 3, 3), np.nan) for b in scene.bodies}  # to quaternions once, below
    reacting = [j for j in scene.joints if j.kind in REACTING]
    reactions = {j.child: np.full((n, 3), np.nan) for j in reacting}
    loop_forces = {lc.loop.name: np.full((n, 3), np.nan) for lc in pm.loop_contacts}
    finite = np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1)  # once, not per sample
    # the constraints' multipliers and frames per sample (and their Jacobians, with loops), resolved after the
    # sample loop for all samples at once (``minimum_norm``, ``constraint_forces``)
    lams, R_Wc1, Js = [], [], []
    for k in np.flatnonzero(finite):
        q, v = Q[k], V[k]
        local = {}
        if reacting or loop_forces:  # rnea: data.f[joint] is the force through the joint
            a = pm.acceleration(q, v)
            if pm.constrained:  # from this constraintDynamics, before rnea overwrites data
                lam, R, J = pm.constraint_readout(q)
                lams.append(lam)
                R_Wc1.append(R)
                Js.append(J)
            if pm.has_forces:
                pin.rnea(model, data, q, v, a, pm.external_forces(q, v))
            else:
                pin.rnea(model, data, q, v, a)
            local = {j.child: data.f[pm.joint_ids[j.child]].linear.copy() for j in reacting}
        # rnea does not refresh data.oMi: rotate with this sample's forward kinematics
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        for child, f in local.items():
            reactions[child][k] = data.oMi[pm.joint_ids[child]].rotation @ f
        for name, arrs in bodies.items():
            fid = pm.frame_ids[name]
            X = data.oMf[fid]
            vel = pin.getFrameVelocity(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            arrs[0][k], arrs[2][k], arrs[3][k] = X.translation, vel.linear, vel.angular
            R_WB[name][k] = X.rotation
    if lams:
        lam = np.stack(lams)
        if pm.loop_contacts:
            lam = pm.minimum_norm(np.stack(Js), lam)
        forces = pm.constraint_forces(lam, np.stack(R_Wc1))  # (m, constraints, 3) on joint1's side, world
        for lc in pm.loop_contacts:
            loop_forces[lc.loop.name][finite] = loops.force_on_b(forces, lc)
        if reacting:  # the constraints' forces on the tree's joints (``carried_by``)
            S = pm.carried_by([pm.joint_ids[j.child] for j in reacting])
            for r, j in enumerate(reacting):
                reactions[j.child][finite] -= np.einsum("c,mci->mi", S[r], forces)
    for name, arrs in bodies.items():
        arrs[1] = spatial.matrix_to_quat(R_WB[name])
    joints = {}
    for j in scene.joints:
        if j.kind == "weld":
            continue
        jm = model.joints[pm.joint_ids[j.child]]
        qj, vj = Q[:, jm.idx_q:jm.idx_q + jm.nq], V[:, jm.idx_v:jm.idx_v + jm.nv]
        if j.kind == "free":  # the engine's own quaternion (its norm is data), scalar first
            quat = spatial.xyzw_to_wxyz(qj[:, 3:])
            bodies[j.child][1] = quat
            R = spatial.quat_to_matrix(spatial.quat_normalize(np.nan_to_num(quat, nan=1.0)))
            v_W = np.einsum("nij,nj->ni", R, vj[:, :3])
            joints[j.child] = JointStates(np.concatenate([qj[:, :3], quat], axis=1),
                                          np.concatenate([v_W, vj[:, 3:]], axis=1))
        elif j.kind == "ball":
            joints[j.child] = JointStates(spatial.xyzw_to_wxyz(qj), vj)
        else:
            joints[j.child] = JointStates(qj, vj)
    traj_bodies = {name: BodyStates(*arrs) for name, arrs in bodies.items()}
    extras = {f"reaction_force:{c}": f for c, f in reactions.items()}
    extras.update({f"reaction_force:{name}": f for name, f in loop_forces.items()})
    if p.contacts is not None:  # the contact time-stepper's impulses over the step from each sample
        forces = contact.read_forces(p, Q, V)
        extras.update({FORCE_PREFIX + pair.name: forces[:, i] for i, pair in enumerate(scene.contacts)})
    return Trajectory(p.times, traj_bodies, joints, extras)
