"""PyBullet's states in body terms: poses, velocities, joint coordinates and reactions.

Once per run, after stepping (never timed), in the prepared model's scratch client (the same model
built twice: the run's client is left as the run left it). A floating base's pose and velocity are
the sampled row itself (PyBullet's COM, ``q_WE`` as integrated, ``v_W``, ``w_W``); a link's come from
``getLinkStates`` with forward kinematics and velocities at the sample's coordinates (its COM frame E:
PyBullet's link frame position and orientation are reported in single precision, E's in double).
The scene's body frame is ``R_WB = R_WE R_EB``; where E is B (a diagonal inertia) the quaternion is
PyBullet's own.

Reactions: PyBullet's joint force-torque sensor (``enableJointForceTorqueSensor``), read after one
step from the sample's state with the loads applied: it reports the force of the step's
articulated-body solve, computed from that state, in the child link's E axes, on the child; turned to
world axes with the sample's ``R_WE`` (the same numbers PyBullet gives in its world-space feedback mode,
checked on a 4-rod chain). What it reports is the engine's, and the harness shows where it is wrong
(measured against MuJoCo's Euler and the reference: right on a single hinge, 2e-14, and a single slider;
0.18 relative on the double pendulum and 0.67-0.78 on every joint of a 4-rod chain, the last included; 5/3
of the centripetal part on a bead sliding along a spinning rod; 160 N off along the axis of the heavy top's
ball joint at t = 0).

Contact forces: each pair's force ON its subject (N, world) over the step that starts at each sample, from a
replay of the run in a client of its own (``contact.read_forces``: Bullet's contact state outlives a reset of the
bodies' states), as the extras ``contact_force:<pair>``; the samples the replay matched bit for bit are the audit's
``contact_force_samples``.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.contact import FORCE_PREFIX
from dalembert.adapters.pybullet.contact import read_forces
from dalembert.adapters.pybullet.model import ball_from_bullet, engine
from dalembert.adapters.pybullet.stepping import apply_loads, write_state

__all__ = ["read_back"]


def _wxyz(q_xyzw):
    return spatial.xyzw_to_wxyz(np.asarray(q_xyzw, dtype=float))


def read_back(p, X):
    """The ``Trajectory`` of the sampled states ``X (n, state_size)`` (NaN rows stay NaN), with the reaction
    force on every revolute, prismatic, ball or welded child (N, world axes, on the child) and each contact pair's
    force on its subject (N, world axes: ``contact.read_forces``) as extras; and the figures the audit collects on
    the way (``max_motor_force``, ``contact_force_samples``)."""
    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    pb, scene, model = engine(), p.scene, p.scratch
    c, n = model.client, len(p.times)
    nan = lambda *shape: np.full((n, *shape), np.nan)  # noqa: E731
    com = {b.name: nan(3) for b in scene.bodies}
    q_WE = {b.name: nan(4) for b in scene.bodies}
    vel = {b.name: nan(3) for b in scene.bodies}
    omega = {b.name: nan(3) for b in scene.bodies}
    by_link = {(part.mb, part.link): part for part in model.parts.values()}
    jointed = [part for part in model.parts.values() if part.kind != "free"]
    force_E = {part.body: nan(3) for part in jointed}
    motor = 0.0
    # the row layout of stepping.read_state: floating bases first, then 7 numbers a link
    offset, k = {}, 13 * len(model.floating)
    for mb, links in model.links.items():
        for link in links:
            offset[(mb, link)] = k
            k += 7
    for i, mb in enumerate(model.floating):  # a base's states are its columns of X, every sample at once
        name = by_link[(mb, -1)].body
        s = X[:, 13 * i:13 * i + 13]
        com[name], q_WE[name], vel[name], omega[name] = s[:, :3], _wxyz(s[:, 3:7]), s[:, 7:10], s[:, 10:13]
    for row in np.flatnonzero(np.all(np.isfinite(X), axis=1)):
        write_state(pb, model, X[row])
        for mb, links in model.links.items():
            if not links:
                continue
            states = pb.getLinkStates(mb, list(links), computeLinkVelocity=1, computeForwardKinematics=1,
                                      physicsClientId=c)
            for link, s in zip(links, states):
                name = by_link[(mb, link)].body
                com[name][row], q_WE[name][row], vel[name][row], omega[name][row] = s[0], _wxyz(s[1]), s[6], s[7]
        if jointed:  # one step from the sample's state: the sensors' reactions of that state
            apply_loads(pb, c, p.loads)
            pb.stepSimulation(physicsClientId=c)
            for mb, links in model.links.items():
                if not links:
                    continue
                for link, (_, _, reaction, applied) in zip(links, pb.getJointStatesMultiDof(mb, list(links),
                                                                                          physicsClientId=c)):
                    force_E[by_link[(mb, link)].body][row] = reaction[:3]
                    motor = max(motor, float(np.max(np.abs(applied), initial=0.0)))
    bodies, joints, extras = {}, {}, {}
    for b in scene.bodies:
        part = model.parts[b.name]
        R_WE = spatial.quat_to_matrix(spatial.quat_normalize(q_WE[b.name]))
        if np.array_equal(part.R_EB, np.eye(3)):
            quat = q_WE[b.name]  # PyBullet's own, as integrated (its norm is data)
        else:
            quat = spatial.quat_multiply(q_WE[b.name], spatial.matrix_to_quat(part.R_EB))
        bodies[b.name] = BodyStates(com[b.name], quat, vel[b.name], omega[b.name])
        j = scene.joint(b.name)
        if j.kind == "free":
            joints[b.name] = JointStates(*spatial.free_joint_coordinates(com[b.name], quat, vel[b.name], omega[b.name],
                                                                         R_WE @ part.R_EB))
            continue
        a = offset[(part.mb, part.link)]
        if j.kind in ("revolute", "prismatic"):  # PyBullet's coordinates are the scene's (model)
            joints[b.name] = JointStates(X[:, a:a + 1].copy(), X[:, a + 4:a + 5].copy())
        elif j.kind == "ball":
            q_JpJc, w_Jc = ball_from_bullet(spatial.xyzw_to_wxyz(X[:, a:a + 4]), X[:, a + 4:a + 7], part.R_LE)
            joints[b.name] = JointStates(q_JpJc, w_Jc)
        extras[f"reaction_force:{b.name}"] = np.einsum("nij,nj->ni", R_WE, force_E[b.name])
    read = {"max_motor_force": motor}
    if scene.contacts:
        forces, read["contact_force_samples"] = read_forces(p, X)
        extras.update({FORCE_PREFIX + name: f for name, f in forces.items()})
    return Trajectory(p.times, bodies, joints, extras), read
