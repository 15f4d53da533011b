"""Simbody's states in body terms: poses, velocities, joint coordinates and reactions.

Once per run, after stepping (never timed). Every OpenSim body frame is the scene's body frame B (``model``), so
for every sample a state is set to the sampled ``Y`` and realized, and each body's ground transform and spatial
velocity (of its origin, the COM; both in ground axes) are the scene's body states; the attitude is Simbody's
rotation matrix (kept as ``rotation``, the quaternion derived from it). Joint coordinates: a revolute or
prismatic joint's are its OpenSim coordinate's value and speed (the joint frames are turned so that the OpenSim
axis is the scene's, ``model``); a free or ball joint's (Euler-angle charts in the engine) are derived from the
bodies' motion (``dalembert.spatial.joint_coordinates``).

Joint reactions: OpenSim's ``Joint.calcReactionOnChildExpressedInGround`` at the state realized to accelerations
(Simbody's mobilizer reaction, loads included), its force part: the force the joint exerts ON the child, in ground
axes (the same at any point of the child).
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial

__all__ = ["read_back"]


def read_back(p, Y):
    """The ``Trajectory`` of the sampled Simbody states ``Y`` (n, ny) (NaN rows stay NaN), with the reaction force
    on every revolute, prismatic, ball or welded child (N, world axes, on the child) as extras."""
    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    model, scene, times = p.model, p.scene, p.times
    osim = model.osim
    n, names = len(times), [b.name for b in scene.bodies]
    bodies = [model.bodies[name] for name in names]
    jointed = [j.child for j in scene.joints if j.kind != "free"]
    one_dof = [j.child for j in scene.joints if j.kind in ("revolute", "prismatic")]
    R = np.full((n, len(names), 3, 3), np.nan)
    pos, vel, omega = (np.full((n, len(names), 3), np.nan) for _ in range(3))
    force = {c: np.full((n, 3), np.nan) for c in jointed}
    coord = {c: np.full((n, 2), np.nan) for c in one_dof}
    state = osim.State(model.state0)
    finite = np.flatnonzero(np.all(np.isfinite(Y), axis=1))
    for k in finite:
        state.setTime(float(times[k]))
        state.setY(osim.Vector.createFromMat(Y[k]))
        if jointed:
            model.model.realizeAcceleration(state)
        else:
            model.model.realizeVelocity(state)
        for b, body in enumerate(bodies):
            T = body.getTransformInGround(state)
            R[k, b] = _matrix(T.R())
            pos[k, b] = T.p().to_numpy()
            V = body.getVelocityInGround(state)
            omega[k, b], vel[k, b] = V.get(0).to_numpy(), V.get(1).to_numpy()
        for c in jointed:
            force[c][k] = model.joints[c].calcReactionOnChildExpressedInGround(state).get(1).to_numpy()
        for c in one_dof:
            co = model.joints[c].get_coordinates(0)
            coord[c][k] = co.getValue(state), co.getSpeedValue(state)
    quat = spatial.matrix_to_quat(R)
    states = {name: BodyStates(pos[:, b], quat[:, b], vel[:, b], omega[:, b], rotation=R[:, b])
              for b, name in enumerate(names)}
    order = {name: b for b, name in enumerate(names)}
    joints = {}
    for j in scene.joints:
        b = order[j.child]
        if j.kind == "free":
            joints[j.child] = JointStates(*spatial.free_joint_coordinates(pos[:, b], quat[:, b], vel[:, b],
                                                                          omega[:, b], R[:, b]))
        elif j.kind in ("revolute", "prismatic"):
            joints[j.child] = JointStates(coord[j.child][:, :1], coord[j.child][:, 1:])
        elif j.kind == "ball":
            if j.parent in order:
                R_P, w_P = R[:, order[j.parent]], omega[:, order[j.parent]]
            else:
                R_P, w_P = np.broadcast_to(np.eye(3), (n, 3, 3)), np.zeros((n, 3))
            with np.errstate(invalid="ignore"):
                q, v = spatial.joint_coordinates(j, R_P, R[:, b], w_P, omega[:, b])
            joints[j.child] = JointStates(q, v)
    extras = {f"reaction_force:{c}": f for c, f in force.items()}
    return Trajectory(times, states, joints, extras)


def _matrix(rot):
    """A ``SimTK::Rotation`` as an ndarray (3, 3)."""
    return np.array([[rot.get(i, k) for k in range(3)] for i in range(3)])
