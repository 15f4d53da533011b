"""Every quaternion and frame conversion in dalembert, and nowhere else.

Conventions (docs/DESIGN.md):

* Quaternions are scalar first, ``(w, x, y, z)``, and rotate body vectors into
  the world: ``v_W = R(q_WB) v_B``.
* Rotation matrices ``R_AB`` map coordinates in frame B to frame A; the pose
  ``X_AB`` of frame B in frame A (monogram notation) is ``(p_AB, R_AB)``, the
  position of B's origin in A and ``R_AB``: ``x_A = p_AB + R_AB x_B``.
* Angular velocity ``w_WB_W`` is expressed in the world, ``w_WB_B`` in the body;
  ``w_WB_W = R_WB w_WB_B``.
* Orientation error is the geodesic angle ``2 acos |<q1, q2>|`` (sign-blind).

All functions accept a single item or a stack: arrays of shape ``(..., 4)`` for
quaternions, ``(..., 3)`` for vectors and ``(..., 3, 3)`` for matrices.

The rotations themselves (quaternions, matrices, SO(3) exponential, geodesic angle) are in
``dalembert.rotations``, re-exported here; this module adds the frames of a scene: loads in world
axes, joint coordinates from the bodies' motion, and the bodies' initial states from the joints'.
"""

from __future__ import annotations

import numpy as np

from dalembert.rotations import (IDENTITY_QUAT, body_to_world, cross, frame_with_z, matrix_from_euler_zxz,
                                 matrix_to_quat, quat_conjugate, quat_derivative, quat_exp, quat_from_axis_angle,
                                 quat_multiply, quat_normalize, quat_rotate, quat_to_matrix, rotation_angle, skew,
                                 so3_dexpinv, so3_exp, world_to_body, wxyz_to_xyzw, xyzw_to_wxyz)

__all__ = [
    "IDENTITY_QUAT", "skew", "cross", "quat_multiply", "quat_conjugate", "quat_normalize", "quat_to_matrix",
    "matrix_to_quat", "quat_rotate", "quat_exp", "quat_from_axis_angle", "frame_with_z", "quat_derivative",
    "so3_exp", "so3_dexpinv", "rotation_angle", "matrix_from_euler_zxz", "world_to_body", "body_to_world",
    "wxyz_to_xyzw", "xyzw_to_wxyz", "load_to_world", "free_joint_coordinates", "joint_coordinates",
    "initial_body_states",
]


def load_to_world(load, R_WB):
    """The vector of ``load`` in world axes: force (N) or torque (N m).

    A follower load (``load.frame == "body"``, vector in body axes) turns with
    its body, ``v_W = R_WB v_B``; a world-frame load is as given, repeated once
    per rotation. The point of application is not used (it stays in body
    coordinates).

    Parameters
    ----------
    load : dalembert.scene.Load
    R_WB : array_like, shape (3, 3) or (n, 3, 3)
        Rotation(s) of the loaded body, body to world.

    Returns
    -------
    ndarray, shape (3,) or (n, 3)
        A new array, world axes.
    """
    R_WB = np.asarray(R_WB, dtype=float)
    vector = np.asarray(load.vector, dtype=float)
    if load.frame == "body":
        return R_WB @ vector
    return np.broadcast_to(vector, R_WB.shape[:-1]).copy()


def free_joint_coordinates(p_WB, q_WB, v_WB_W, w_WB_W, R_WB):
    """A free joint's coordinates (``Joint`` conventions) from its body's motion.

    Parameters
    ----------
    p_WB : ndarray (n, 3) — COM position, world, m
    q_WB : ndarray (n, 4) — attitude, scalar-first unit quaternion (as the engine gave it)
    v_WB_W : ndarray (n, 3) — COM velocity, world axes, m/s
    w_WB_W : ndarray (n, 3) — angular velocity, world axes, rad/s
    R_WB : ndarray (n, 3, 3) — attitude as a matrix (turns ``w_WB_W`` into body axes)

    Returns
    -------
    q : ndarray (n, 7) — ``(p_WB, q_WB)``
    v : ndarray (n, 6) — ``(v_WB_W, w_WB_B)``: the angular velocity in body axes
    """
    return (np.concatenate([p_WB, q_WB], axis=1),
            np.concatenate([v_WB_W, np.einsum("nji,nj->ni", R_WB, w_WB_W)], axis=1))


def joint_coordinates(joint, R_WP, R_WC, w_WP_W, w_WC_W, p_WP=None, p_WC=None, v_WP_W=None, v_WC_W=None):
    """A joint's coordinates (``Joint`` conventions) from its parent's and child's motion.

    For engines that simulate bodies in redundant coordinates. A revolute angle
    is unwrapped and shifted by whole turns to start at ``joint.q0``. A prismatic
    joint's slide needs the bodies' positions and velocities too: it is the child
    joint point's offset from the parent's along the axis, ``d = a_W . r`` with
    ``r = p_Jc - p_Jp`` and ``a_W = R_WJp a``, and its rate ``a_W . (r' - w_WP x r)``
    (``a_W`` turns with the parent).

    Parameters
    ----------
    joint : dalembert.scene.Joint — revolute, prismatic, ball or weld
    R_WP, R_WC : array_like (n, 3, 3) or (3, 3) — parent and child body rotations
        ``R_WB`` (world: the identity)
    w_WP_W, w_WC_W : array_like (n, 3) — their angular velocities, world axes, rad/s
    p_WP, p_WC : array_like (n, 3) or (3,), optional — parent and child COM positions,
        world, m (world: the origin); prismatic joints only
    v_WP_W, v_WC_W : array_like (n, 3) or (3,), optional — their COM velocities, world
        axes, m/s (world: zero); prismatic joints only

    Returns
    -------
    q : ndarray (n, nq) — angle (rad), displacement (m), scalar-first quaternion
        ``q_JpJc``, or (n, 0)
    v : ndarray (n, nv) — rate about the axis (rad/s), rate along it (m/s),
        ``w_JpJc`` in the child joint frame (rad/s), or (n, 0)
    """
    w_rel = np.asarray(w_WC_W, dtype=float) - np.asarray(w_WP_W, dtype=float)
    n = len(w_rel)
    if joint.kind == "weld":
        return np.zeros((n, 0)), np.zeros((n, 0))
    R_WJp = np.asarray(R_WP, dtype=float) @ quat_to_matrix(joint.parent_quat)
    R_WJc = np.asarray(R_WC, dtype=float) @ quat_to_matrix(joint.child_quat)
    if joint.kind == "prismatic":
        missing = [k for k, v in (("p_WP", p_WP), ("p_WC", p_WC), ("v_WP_W", v_WP_W), ("v_WC_W", v_WC_W)) if v is None]
        if missing:
            raise ValueError(f"joint_coordinates.{missing[0]}: a prismatic joint's slide needs the parent's and "
                             "child's COM positions and velocities — pass p_WP, p_WC, v_WP_W, v_WC_W")
        R_WP_n = np.broadcast_to(np.asarray(R_WP, dtype=float), (n, 3, 3))
        R_WC_n = np.broadcast_to(np.asarray(R_WC, dtype=float), (n, 3, 3))
        w_P = np.broadcast_to(np.asarray(w_WP_W, dtype=float), (n, 3))
        w_C = np.broadcast_to(np.asarray(w_WC_W, dtype=float), (n, 3))
        # the joint points in world (lever from each COM, world axes) and their velocities
        rho_P = R_WP_n @ np.asarray(joint.parent_point, dtype=float)
        rho_C = R_WC_n @ np.asarray(joint.child_point, dtype=float)
        r = (np.asarray(p_WC, dtype=float) + rho_C) - (np.asarray(p_WP, dtype=float) + rho_P)  # Jp -> Jc, (n, 3)
        r_dot = (np.asarray(v_WC_W, dtype=float) + cross(w_C, rho_C)) - (np.asarray(v_WP_W, dtype=float)
                                                                         + cross(w_P, rho_P))
        a_W = np.broadcast_to(R_WJp, (n, 3, 3)) @ (np.asarray(joint.axis, dtype=float) / np.linalg.norm(joint.axis))
        slide = np.einsum("ni,ni->n", a_W, r)
        rate = np.einsum("ni,ni->n", a_W, r_dot - cross(w_P, r))
        return slide[:, None], rate[:, None]
    R_J = np.broadcast_to(np.swapaxes(R_WJp, -1, -2) @ R_WJc, (n, 3, 3))
    if joint.kind == "ball":
        return matrix_to_quat(R_J), np.einsum("nji,nj->ni", np.broadcast_to(R_WJc, (n, 3, 3)), w_rel)
    if joint.kind != "revolute":
        raise ValueError(f"joint.kind: no joint coordinates for {joint.kind!r} here")
    a = np.asarray(joint.axis, dtype=float) / np.linalg.norm(joint.axis)
    # R_J = exp(angle skew(a)): R - R^T = 2 sin(angle) skew(a), trace = 1 + 2 cos(angle)
    vee = np.stack([R_J[:, 2, 1] - R_J[:, 1, 2], R_J[:, 0, 2] - R_J[:, 2, 0], R_J[:, 1, 0] - R_J[:, 0, 1]], -1)
    angle = np.unwrap(np.arctan2(0.5 * vee @ a, 0.5 * (np.trace(R_J, axis1=1, axis2=2) - 1.0)))
    if n and np.isfinite(angle[0]):
        angle += 2.0 * np.pi * np.round((joint.q0[0] - angle[0]) / (2.0 * np.pi))
    rate = np.einsum("ni,ni->n", np.broadcast_to(R_WJp @ a, (n, 3)), w_rel)
    return angle[:, None], rate[:, None]


def initial_body_states(scene, velocities=None):
    """World pose and velocity of every body at the joints' ``q0``, ``v0`` (forward kinematics).

    For engines that take body states rather than joint coordinates (redundant
    coordinates). Joint conventions as in ``dalembert.scene.JOINT_KINDS``.
    ``velocities`` (dict joint name -> (nv,) array), when given, replaces the joints'
    ``v0`` (missing joints at rest): body velocities are linear in them, so unit
    velocities give the columns of the tree's Jacobian (``dalembert.closure``).

    Returns
    -------
    dict body name -> dict with ``R`` (3, 3) ``R_WB``, ``p`` (3,) COM position (m),
    ``v`` (3,) COM velocity (m/s), ``w`` (3,) angular velocity ``w_WB_W`` (rad/s)
    """
    zero = np.zeros(3)
    out = {"world": dict(R=np.eye(3), p=zero, v=zero, w=zero)}
    for body in scene.topological_order():
        j = scene.joint(body.name)
        q0, v0 = np.asarray(j.q0, dtype=float), np.asarray(j.v0, dtype=float)
        if velocities is not None:
            v0 = np.asarray(velocities.get(j.name, np.zeros(len(v0))), dtype=float)
        if j.kind == "free":
            R = quat_to_matrix(q0[3:] / np.linalg.norm(q0[3:]))
            out[body.name] = dict(R=R, p=q0[:3].copy(), v=v0[:3].copy(), w=R @ v0[3:])
            continue
        P = out[j.parent]
        R_WJp = P["R"] @ quat_to_matrix(j.parent_quat)
        # The child joint frame relative to the parent's: rotation, and the slide (world axes)
        R_J, w_rel, d_W, d_rate_W = np.eye(3), zero, zero, zero
        if j.kind == "revolute":
            a = np.asarray(j.axis, dtype=float) / np.linalg.norm(j.axis)
            R_J, w_rel = so3_exp(a * q0[0]), R_WJp @ a * v0[0]
        elif j.kind == "prismatic":
            a_W = R_WJp @ (np.asarray(j.axis, dtype=float) / np.linalg.norm(j.axis))
            d_W, d_rate_W = a_W * q0[0], a_W * v0[0]
        elif j.kind == "ball":
            R_J = quat_to_matrix(q0 / np.linalg.norm(q0))
            w_rel = R_WJp @ R_J @ v0  # v0 in the child joint frame
        R = R_WJp @ R_J @ quat_to_matrix(j.child_quat).T
        r_PJ = P["R"] @ np.asarray(j.parent_point, dtype=float) + d_W  # parent COM -> child joint point
        r_JC = -R @ np.asarray(j.child_point, dtype=float)  # joint point -> child COM
        w = P["w"] + w_rel
        out[body.name] = dict(R=R, p=P["p"] + r_PJ + r_JC, w=w,
                              v=P["v"] + cross(P["w"], r_PJ) + d_rate_W + cross(w, r_JC))
    del out["world"]
    return out
