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
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "IDENTITY_QUAT",
    "skew",
    "cross",
    "quat_multiply",
    "quat_conjugate",
    "quat_normalize",
    "quat_to_matrix",
    "matrix_to_quat",
    "quat_rotate",
    "quat_exp",
    "quat_from_axis_angle",
    "frame_with_z",
    "quat_derivative",
    "so3_exp",
    "so3_dexpinv",
    "rotation_angle",
    "matrix_from_euler_zxz",
    "world_to_body",
    "body_to_world",
    "load_to_world",
    "wxyz_to_xyzw",
    "xyzw_to_wxyz",
    "joint_coordinates",
    "initial_body_states",
]

IDENTITY_QUAT = (1.0, 0.0, 0.0, 0.0)

# Below this rotation angle (rad), exp/dexpinv use Taylor series: the closed
# forms divide by the angle and lose precision; at 1e-4 the series' first
# omitted term is ~1e-20 relative.
_SMALL_ANGLE = 1e-4

_EYE3 = np.eye(3)  # never written to (each result is a new array): one allocation, not one per call
_EYE3.flags.writeable = False


def skew(v):
    """Cross-product matrix: ``skew(a) @ b == cross(a, b)``.

    Parameters
    ----------
    v : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    v = np.asarray(v, dtype=float)
    if v.ndim == 1:  # fast path for the integrators' inner loops
        # the entries as Python floats: the same IEEE products and sums as numpy scalars', bit for bit, and
        # a third of their cost (the reference solver's kinematics call this and ``cross`` millions of times)
        x, y, w = v.tolist()
        return np.array([[0.0, -w, y], [w, 0.0, -x], [-y, x, 0.0]])
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)],
        -2,
    )


def cross(a, b):
    """``a x b`` for shape (..., 3); faster than ``np.cross`` for single vectors."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.ndim == 1 and b.ndim == 1:  # (Python floats, as in ``skew``)
        a0, a1, a2 = a.tolist()
        b0, b1, b2 = b.tolist()
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    return np.cross(a, b)


def quat_multiply(q1, q2):
    """Hamilton product ``q1 * q2`` of scalar-first quaternions, shape (..., 4)."""
    q1 = np.asarray(q1, dtype=float)
    q2 = np.asarray(q2, dtype=float)
    if q1.ndim == 1 and q2.ndim == 1:  # (Python floats, as in ``skew``)
        w1, x1, y1, z1 = q1.tolist()
        w2, x2, y2, z2 = q2.tolist()
        return np.array([
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ])
    w1, x1, y1, z1 = np.moveaxis(q1, -1, 0)
    w2, x2, y2, z2 = np.moveaxis(q2, -1, 0)
    return np.stack(
        [
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        ],
        -1,
    )


def quat_conjugate(q):
    """Conjugate (inverse for a unit quaternion), shape (..., 4)."""
    q = np.array(q, dtype=float)
    q[..., 1:] *= -1.0
    return q


def quat_normalize(q):
    """Unit quaternion with a non-negative scalar part, shape (..., 4)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0.0, -q, q)


def quat_to_matrix(q):
    """Rotation matrix ``R_WB`` of quaternion ``q_WB``.

    The quaternion is used as given, not normalized: for ``|q| != 1`` the result
    is ``|q|^2`` times a rotation, so drift in the quaternion norm shows up as
    non-orthonormality (what ``invariants.orthonormality_error`` measures).

    Parameters
    ----------
    q : array_like, shape (..., 4), scalar first

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:  # (Python floats, as in ``skew``)
        w, x, y, z = q.tolist()
        return np.array([
            [w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z],
        ])
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z], -1),
        ],
        -2,
    )


def matrix_to_quat(R):
    """Unit quaternion (scalar first, ``w >= 0``) of rotation matrix ``R``.

    Uses the largest-diagonal branch (Shepperd's method), accurate to roundoff
    for every rotation. A matrix that is not exactly orthonormal is projected
    implicitly; measure its orthonormality before converting if that matters.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)

    Returns
    -------
    ndarray, shape (..., 4)
    """
    R = np.asarray(R, dtype=float)
    shape = R.shape[:-2]
    R = R.reshape(-1, 3, 3)
    tr = np.trace(R, axis1=1, axis2=2)
    diag = np.diagonal(R, axis1=1, axis2=2)
    cand = np.concatenate([tr[:, None], diag], axis=1)
    k = np.argmax(cand, axis=1)
    q = np.empty((R.shape[0], 4))
    for branch in range(4):
        sel = k == branch
        if not np.any(sel):
            continue
        r = R[sel]
        if branch == 0:
            s = 2.0 * np.sqrt(1.0 + tr[sel])
            q[sel] = np.stack(
                [0.25 * s, (r[:, 2, 1] - r[:, 1, 2]) / s, (r[:, 0, 2] - r[:, 2, 0]) / s, (r[:, 1, 0] - r[:, 0, 1]) / s],
                -1,
            )
        else:
            i = branch - 1
            j, m = (i + 1) % 3, (i + 2) % 3
            s = 2.0 * np.sqrt(1.0 + r[:, i, i] - r[:, j, j] - r[:, m, m])
            out = np.empty((r.shape[0], 4))
            out[:, 0] = (r[:, m, j] - r[:, j, m]) / s
            out[:, 1 + i] = 0.25 * s
            out[:, 1 + j] = (r[:, j, i] + r[:, i, j]) / s
            out[:, 1 + m] = (r[:, m, i] + r[:, i, m]) / s
            q[sel] = out
    q = np.where(q[:, :1] < 0.0, -q, q)
    return q.reshape(shape + (4,))


def quat_rotate(q, v):
    """Rotate vectors ``v_B`` into ``v_W = R(q_WB) v_B``; shapes (..., 4), (..., 3)."""
    return np.einsum("...ij,...j->...i", quat_to_matrix(q), np.asarray(v, dtype=float))


def body_to_world(q_WB, v_B):
    """Vector in body coordinates to world coordinates (e.g. ``w_WB_B -> w_WB_W``)."""
    return quat_rotate(q_WB, v_B)


def world_to_body(q_WB, v_W):
    """Vector in world coordinates to body coordinates (e.g. ``w_WB_W -> w_WB_B``)."""
    return quat_rotate(quat_conjugate(q_WB), v_W)


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


def quat_exp(theta):
    """Unit quaternion of the rotation vector ``theta`` (rad), shape (..., 3) -> (..., 4)."""
    theta = np.asarray(theta, dtype=float)
    if theta.ndim == 1:
        a = math.sqrt(theta @ theta)
        sinc = 0.5 - a * a / 48.0 if a < _SMALL_ANGLE else math.sin(0.5 * a) / a
        return np.array([math.cos(0.5 * a), sinc * theta[0], sinc * theta[1], sinc * theta[2]])
    a = np.linalg.norm(theta, axis=-1, keepdims=True)
    half = 0.5 * a
    small = a < _SMALL_ANGLE
    safe = np.where(small, 1.0, a)
    # sin(a/2)/a, with its series 1/2 - a^2/48 for small a
    sinc = np.where(small, 0.5 - a * a / 48.0, np.sin(half) / safe)
    return np.concatenate([np.cos(half), sinc * theta], axis=-1)


def quat_from_axis_angle(axis, angle):
    """Quaternion of a rotation by ``angle`` (rad) about the unit ``axis`` (3,)."""
    axis = np.asarray(axis, dtype=float)
    angle = np.asarray(angle, dtype=float)
    return quat_exp(axis / np.linalg.norm(axis) * angle[..., None])


def frame_with_z(z):
    """A rotation matrix (3, 3) whose third column is the unit vector along ``z`` (3,): a frame with a
    given z axis (a joint axis, the vertical), its x axis normal to ``z`` and to whichever of the x or y
    axes is farther from ``z``."""
    z = np.asarray(z, dtype=float) / np.linalg.norm(z)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def quat_derivative(q_WB, w_WB_B):
    """Time derivative ``dq/dt = 1/2 q * (0, w_B)`` of ``q_WB``, shape (..., 4)."""
    w = np.asarray(w_WB_B, dtype=float)
    if w.ndim == 1:
        return 0.5 * quat_multiply(q_WB, np.array([0.0, w[0], w[1], w[2]]))
    zero = np.zeros(w.shape[:-1] + (1,))
    return 0.5 * quat_multiply(q_WB, np.concatenate([zero, w], axis=-1))


def so3_exp(theta):
    """Rotation matrix ``exp(skew(theta))`` (Rodrigues), shape (..., 3) -> (..., 3, 3)."""
    theta = np.asarray(theta, dtype=float)
    if theta.ndim == 1:
        a = math.sqrt(theta @ theta)
        if not math.isfinite(a):  # a blown-up state (|theta| past 1e154 overflows): NaN, as numpy's path gives
            return np.full((3, 3), np.nan)
        if a < _SMALL_ANGLE:
            s1, s2 = 1.0 - a * a / 6.0, 0.5 - a * a / 24.0
        else:
            s1, s2 = math.sin(a) / a, (1.0 - math.cos(a)) / (a * a)
        K = skew(theta)
        return _EYE3 + s1 * K + s2 * (K @ K)
    a = np.linalg.norm(theta, axis=-1)[..., None, None]
    small = a < _SMALL_ANGLE
    safe = np.where(small, 1.0, a)
    s1 = np.where(small, 1.0 - a * a / 6.0, np.sin(safe) / safe)
    s2 = np.where(small, 0.5 - a * a / 24.0, (1.0 - np.cos(safe)) / (safe * safe))
    K = skew(theta)
    return np.eye(3) + s1 * K + s2 * (K @ K)


def so3_dexpinv(theta, k):
    """Inverse of the right-trivialized tangent of exp on SO(3).

    For ``R(t) = R0 exp(theta(t))`` with body angular velocity ``w``
    (``R' = R skew(w)``), ``theta' = so3_dexpinv(theta, w)``:
    ``w + theta x w / 2 + c(|theta|) theta x (theta x w)``,
    ``c = (1 - (a/2) cot(a/2)) / a^2`` (series ``1/12 + a^2/720``).

    Parameters
    ----------
    theta, k : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3)
    """
    theta = np.asarray(theta, dtype=float)
    k = np.asarray(k, dtype=float)
    if theta.ndim == 1:
        a = math.sqrt(theta @ theta)
        c = 1.0 / 12.0 + a * a / 720.0 if a < _SMALL_ANGLE else (1.0 - 0.5 * a / math.tan(0.5 * a)) / (a * a)
        tk = cross(theta, k)
        return k + 0.5 * tk + c * cross(theta, tk)
    a = np.linalg.norm(theta, axis=-1, keepdims=True)
    small = a < _SMALL_ANGLE
    safe = np.where(small, 1.0, a)
    c = np.where(small, 1.0 / 12.0 + a * a / 720.0, (1.0 - 0.5 * safe / np.tan(0.5 * safe)) / (safe * safe))
    tk = np.cross(theta, k)
    return k + 0.5 * tk + c * np.cross(theta, tk)


def rotation_angle(q1, q2):
    """Geodesic angle ``2 acos |<q1, q2>|`` (rad) between orientations, shape (...,).

    Computed as ``2 atan2(|vec(q1^* q2)|, |scalar(q1^* q2)|)``, which keeps full
    relative precision for small angles (``acos`` near 1 does not). Both inputs
    are normalized first, so norm drift is not counted as an orientation error.
    """
    d = quat_multiply(quat_conjugate(quat_normalize(q1)), quat_normalize(q2))
    return 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))


def matrix_from_euler_zxz(phi, theta, psi):
    """``Rz(phi) Rx(theta) Rz(psi)``: proper Euler angles z-x-z (rad), shape (...,) -> (..., 3, 3)."""
    phi, theta, psi = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (phi, theta, psi)))
    c1, s1 = np.cos(phi), np.sin(phi)
    c2, s2 = np.cos(theta), np.sin(theta)
    c3, s3 = np.cos(psi), np.sin(psi)
    return np.stack(
        [
            np.stack([c1 * c3 - s1 * c2 * s3, -c1 * s3 - s1 * c2 * c3, s1 * s2], -1),
            np.stack([s1 * c3 + c1 * c2 * s3, -s1 * s3 + c1 * c2 * c3, -c1 * s2], -1),
            np.stack([s2 * s3, s2 * c3, c2], -1),
        ],
        -2,
    )


def wxyz_to_xyzw(q):
    """Scalar-first to scalar-last (Pinocchio's storage), shape (..., 4)."""
    q = np.asarray(q, dtype=float)
    return np.concatenate([q[..., 1:], q[..., :1]], axis=-1)


def xyzw_to_wxyz(q):
    """Scalar-last (Pinocchio's storage) to scalar-first, shape (..., 4)."""
    q = np.asarray(q, dtype=float)
    return np.concatenate([q[..., 3:], q[..., :3]], axis=-1)


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
