"""Rotations: quaternions, rotation matrices, the SO(3) exponential and the geodesic angle between
attitudes, and the engines' quaternion layouts.

Conventions (docs/DESIGN.md; ``dalembert.spatial`` re-exports every name here, the one import path
of every conversion):

* Quaternions are scalar first, ``(w, x, y, z)``, and rotate body vectors into
  the world: ``v_W = R(q_WB) v_B``.
* Rotation matrices ``R_AB`` map coordinates in frame B to frame A.
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
    "IDENTITY_QUAT", "skew", "cross", "quat_multiply", "quat_conjugate", "quat_normalize", "quat_to_matrix",
    "matrix_to_quat", "quat_rotate", "quat_exp", "quat_from_axis_angle", "frame_with_z", "quat_derivative",
    "so3_exp", "so3_dexpinv", "rotation_angle", "matrix_from_euler_zxz", "world_to_body", "body_to_world",
    "wxyz_to_xyzw", "xyzw_to_wxyz",
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
    q = np.asarray(q_WB, dtype=float)
    if w.ndim == 1 and q.ndim == 1:  # (Python floats: ``quat_multiply``'s products and sums with w2 = 0, bit for bit;
        w1, x1, y1, z1 = q.tolist()  # the reference's qdot asks this per quaternion block per right-hand side)
        x2, y2, z2 = w.tolist()
        w2 = 0.0
        return np.array([0.5 * (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2), 0.5 * (w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2),
                         0.5 * (w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2), 0.5 * (w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)])
    if w.ndim == 1:
        return 0.5 * quat_multiply(q, np.array([0.0, w[0], w[1], w[2]]))
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
