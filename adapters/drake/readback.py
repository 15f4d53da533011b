"""Drake's states in body terms: poses, velocities, joint coordinates and reactions.

Once per run, after stepping (never timed). Every Drake body frame is the
scene's body frame (``model``), so a free body's pose and velocity are read
straight from its quaternion floating joint's coordinates, for every sample at
once: ``q = (quaternion w x y z, COM position)``, ``v = (w_WB_W, v_WB_W)``.
Bodies on other joints are placed by the plant's kinematics, sample by sample.
Joint reactions come from the plant's ``reaction_forces`` output port: per
joint, ``F_CJc_Jc``, the force the joint exerts on the child at the origin of
the child joint frame Jc, in Jc axes; turned into world axes with ``R_WJc``.
Loop reactions (discrete mode) from the constraints' generalized force in the step
(``loops.LoopForces``), read in the same pass and context as the joints': the
reaction port and the acceleration port both come from the plant's one cached
discrete step at the sample's state, so each sample costs one step solve, not two.
Contact forces per scene pair (``contact.read_forces``, N, world, ON the pair's subject)
as the extras ``contact_force:<pair>``.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.drake.contact import read_forces
from dalembert.contact import FORCE_PREFIX

__all__ = ["read_back"]


def read_back(p, X):
    """The ``Trajectory`` of the sampled plant states ``X (n, nq + nv)`` (NaN rows stay NaN), with the
    reaction force on every revolute, prismatic, ball or welded child (N, world axes, on the child) as extras."""
    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    model, scene, times = p.model, p.scene, p.times
    plant = model.plant
    n, nq = len(times), plant.num_positions()
    Q, V = X[:, :nq], X[:, nq:]
    nan3 = lambda: np.full((n, 3), np.nan)  # noqa: E731
    bodies = {b.name: dict(p=nan3(), q=np.full((n, 4), np.nan), v=nan3(), w=nan3()) for b in scene.bodies}
    joints, jointed = {}, []
    for j in scene.joints:
        joint = model.joints[j.child]
        qj = Q[:, joint.position_start():joint.position_start() + joint.num_positions()]
        vj = V[:, joint.velocity_start():joint.velocity_start() + joint.num_velocities()]
        if j.kind == "free":  # the engine's own quaternion as integrated (its norm is data)
            b = bodies[j.child]
            b["q"], b["p"], b["w"], b["v"] = qj[:, :4], qj[:, 4:], vj[:, :3], vj[:, 3:]
            with np.errstate(over="ignore", invalid="ignore"):  # the last samples of a blow-up
                w_B = spatial.world_to_body(spatial.quat_normalize(qj[:, :4]), vj[:, :3])  # the scene's: body axes
            joints[j.child] = JointStates(np.concatenate([qj[:, 4:], qj[:, :4]], axis=1),
                                          np.concatenate([vj[:, 3:], w_B], axis=1))
            continue
        jointed.append(j)
        if j.kind in ("revolute", "prismatic"):  # Drake's coordinates are the scene's (model)
            joints[j.child] = JointStates(qj, vj)
        elif j.kind == "ball":  # rpy of R_FM -> quaternion q_JpJc; w_FM_F -> the child joint frame
            R_FM = _rpy_to_matrix(qj)
            joints[j.child] = JointStates(spatial.matrix_to_quat(R_FM), np.einsum("nji,nj->ni", R_FM, vj))
    reactions = {j.child: nan3() for j in jointed}
    reactions.update({lc.loop.name: nan3() for lc in model.loops})  # a loop's force ON its body b
    if reactions:
        _kinematics(p, X, bodies, jointed, reactions)
    traj_bodies = {name: BodyStates(b["p"], b["q"], b["v"], b["w"]) for name, b in bodies.items()}
    extras = {f"reaction_force:{c}": f for c, f in reactions.items()}
    forces = read_forces(model, times, X)
    if forces is not None:
        extras.update({FORCE_PREFIX + pair.name: forces[:, i] for i, pair in enumerate(scene.contacts)})
    return Trajectory(times, traj_bodies, joints, extras)


def _rpy_to_matrix(rpy):
    """``R = Rz(yaw) Ry(pitch) Rx(roll)`` for rows ``(roll, pitch, yaw)``, shape (n, 3) -> (n, 3, 3)."""
    r, p, y = rpy[:, 0], rpy[:, 1], rpy[:, 2]
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.stack([np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], -1),
                     np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], -1),
                     np.stack([-sp, cp * sr, cp * cr], -1)], -2)


def _kinematics(p, X, bodies, jointed, reactions):
    """Poses and velocities of the bodies on revolute, prismatic, ball and weld joints, the joints' reactions and
    the loops' (``loops.LoopForces``), from the plant sample by sample (the loads system is evaluated for the
    reactions, as in a step). The loop over samples only calls Drake and keeps its arrays; rotations, quaternions
    and the reactions' world axes are computed for all samples at once after it."""
    from dalembert.adapters.drake.loops import LoopForces
    from dalembert.closure import RANK_RTOL

    model = p.model
    plant = model.plant
    context = model.diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    port = plant.get_reaction_forces_output_port()
    names = [j.child for j in jointed]
    drake_bodies = [model.bodies[c] for c in names]  # each joint's child body
    # per joint: its index in the port's list and R_CJc, the child joint frame in the child's body frame
    ports = [int(model.joints[c].index()) for c in names]
    R_CJc = np.reshape([model.joints[c].frame_on_child().GetFixedPoseInBodyFrame().rotation().matrix()
                        for c in names], (-1, 3, 3))
    finite = np.flatnonzero(np.all(np.isfinite(X), axis=1))
    loops = LoopForces(model, RANK_RTOL) if model.loops else None
    m, nb = len(finite), len(names)
    X_WB = np.empty((m, nb, 3, 4))  # [R_WB | p_WB] per sample and body
    V_WB = np.empty((m, nb, 6))  # (w_WB_W, v_WB_W)
    f_Jc = np.empty((m, nb, 3))  # the joint's force on the child at Jc, Jc axes
    for i, k in enumerate(finite):
        context.SetTime(float(p.times[k]))
        plant.SetPositionsAndVelocities(plant_context, X[k])
        for b, body in enumerate(drake_bodies):
            X_WB[i, b] = plant.EvalBodyPoseInWorld(plant_context, body).GetAsMatrix34()
            V_WB[i, b] = plant.EvalBodySpatialVelocityInWorld(plant_context, body).get_coeffs()
        F = port.Eval(plant_context)
        for b, j in enumerate(ports):
            f_Jc[i, b] = F[j].translational()
        if loops:  # the same context: the step solved for F above is the one read here
            loops.add(context, plant_context)
    R_WB = X_WB[..., :3]
    f_W = ((R_WB @ R_CJc) @ f_Jc[..., None])[..., 0]  # R_WJc f_Jc
    quats = spatial.matrix_to_quat(R_WB)  # w >= 0, as every other engine's rotation
    for b, name in enumerate(names):
        out = bodies[name]
        out["p"][finite], out["q"][finite] = X_WB[:, b, :, 3], quats[:, b]
        out["w"][finite], out["v"][finite] = V_WB[:, b, :3], V_WB[:, b, 3:]
        reactions[name][finite] = f_W[:, b]
    if loops:
        for name, f in loops.forces().items():
            reactions[name][finite] = f
