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
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial

__all__ = ["read_back"]


def read_back(p, X):
    """The ``Trajectory`` of the sampled plant states ``X (n, nq + nv)`` (NaN rows stay NaN), with the
    reaction force on every revolute, prismatic, ball or welded child (N, world axes, on the child) as extras."""
    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    model, scene, times = p["model"], p["scene"], p["times"]
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
    reactions, as in a step)."""
    from dalembert.adapters.drake.loops import LoopForces
    from dalembert.closure import RANK_RTOL

    model = p["model"]
    plant = model.plant
    context = model.diagram.CreateDefaultContext()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    port = plant.get_reaction_forces_output_port()
    names = [j.child for j in jointed]
    drake_bodies = [model.bodies[c] for c in names]  # each joint's child body
    # per joint: its index in the port's list and R_CJc, the child joint frame in the child's body frame
    ports = [int(model.joints[c].index()) for c in names]
    R_CJc = [model.joints[c].frame_on_child().GetFixedPoseInBodyFrame().rotation().matrix() for c in names]
    finite = np.flatnonzero(np.all(np.isfinite(X), axis=1))
    loops = LoopForces(model, RANK_RTOL) if model.loops else None
    for k in finite:
        context.SetTime(float(p["times"][k]))
        plant.SetPositionsAndVelocities(plant_context, X[k])
        R_WB = []
        for name, body in zip(names, drake_bodies):
            X_WB = plant.EvalBodyPoseInWorld(plant_context, body)
            V_WB = plant.EvalBodySpatialVelocityInWorld(plant_context, body)
            b = bodies[name]
            R = X_WB.rotation()
            b["p"][k], b["q"][k] = X_WB.translation(), R.ToQuaternion().wxyz()
            b["w"][k], b["v"][k] = V_WB.rotational(), V_WB.translational()
            R_WB.append(R.matrix())
        F = port.Eval(plant_context)
        for name, i, R, R_CJ in zip(names, ports, R_WB, R_CJc):
            reactions[name][k] = (R @ R_CJ) @ F[i].translational()  # R_WJc f_Jc
        if loops:  # the same context: the step solved for F above is the one read here
            loops.add(context, plant_context)
    if loops:
        for name, f in loops.forces().items():
            reactions[name][finite] = f
    for name in names:  # w >= 0, as spatial.matrix_to_quat gives every other engine's rotation
        bodies[name]["q"] = spatial.quat_normalize(bodies[name]["q"])
