"""The root-to-leaves pass of Kane's kinematics (``generalized.Kane.kinematics``) in scalar arithmetic: each
body's rotation, COM position, velocity and bias accelerations, and each generalized speed's motion (the
world axis it turns about, the translation it gives, the point its axis passes through), from which the
Jacobians follow at once.

Why scalars: the pass is a chain of 3-vector and 3x3 products, one body after the other. As numpy calls,
each of them cost about a microsecond of call overhead for 3 to 45 flops, and the pass ran in that overhead
(``benchmarks/reference_rhs.py``). Written on Python floats, the same formulas cost their flops. Written on
scalars, the code evaluates m states at once as well: every scalar is then an array of shape (m,) (numpy's
elementwise products and sums round as Python's floats do; its ``sin`` may differ from the math
module's in the last bit), so the stacked pass is the same one, not a twin.

The pass comes in two parts: ``positions`` (the poses and each speed's motion: all a projection onto loop closures
needs, and the mass matrix) and ``velocities`` (the bodies' velocities and bias accelerations, from the per-joint
terms ``positions`` leaves), so that one configuration's part serves several evaluations (``loops.ClosedLoops``:
the projection's last pass is the solve's); ``forward`` is the two in a row. Each formula is the one-piece pass's,
in its order: the split changes no bit.

Conventions: a rotation matrix is a 9-tuple, row-major; a vector a 3-tuple, world axes. Each body's state
is ``(R, p, w, v, a_bias, alpha_bias)``: ``R_WB``, COM position (m), angular velocity (rad/s), COM velocity
(m/s) and the accelerations' parts free of ``u'`` (m/s^2, rad/s^2). Each speed's motion is
``(omega, nu, o)``: the body it moves turns at ``omega`` per unit speed about an axis through the point
``o`` (m) while translating at ``nu``, so that a point ``x`` moving with it gets the velocity
``nu + omega x (x - o)`` (its column of the Jacobians: ``Kane.kinematics``).
"""

from __future__ import annotations

import math

import numpy as np

from dalembert import spatial
from dalembert.scalar3 import add, cross, mat, rot

__all__ = ["Step", "positions", "velocities", "forward", "FLOAT_MATH", "ARRAY_MATH"]

_I9 = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
_O3 = (0.0, 0.0, 0.0)
_E3 = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))

# sin and sqrt of a scalar: floats for one state, numpy's for m states at once
FLOAT_MATH = (math.sin, math.sqrt)
ARRAY_MATH = (np.sin, np.sqrt)


def _quat_matrix(w, x, y, z, sqrt):
    """``R`` of the quaternion ``(w, x, y, z)`` over its norm (``rotations.quat_to_matrix`` of the unit one)."""
    n = sqrt(w * w + x * x + y * y + z * z)
    if not isinstance(n, float):
        w, x, y, z = w / n, x / n, y / n, z / n
    elif n > 0.0:  # (a zero quaternion is NaN, as numpy's 0/0)
        w, x, y, z = w / n, x / n, y / n, z / n
    else:
        w = x = y = z = math.nan
    return (w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z)


class Step:
    """One joint of the pass, its constants as tuples: the joint's kind, its parent's slot in the pass's list of
    states (0: the world; a body's: its index in topological order plus 1), its first coordinate and speed,
    the joint frames (``R_PJ``; ``R_CJ^T`` and ``d = -R_CJ^T p_CJ``, the child's COM from its joint point in
    the child joint frame; None for an identity rotation) and the unit axis with its ``skew`` and square."""

    __slots__ = ("kind", "parent", "iq", "iv", "R_PJ", "p_PJ", "R_CJt", "d_C", "axis", "K", "K2")

    def __init__(self, kind, parent, iq, iv, R_PJ, p_PJ, R_CJ, p_CJ, axis):
        def nine(R):
            R = np.asarray(R, dtype=float)
            return None if np.array_equal(R, np.eye(3)) else tuple(R.ravel().tolist())

        self.kind, self.parent, self.iq, self.iv = kind, parent, iq, iv
        self.R_PJ, self.p_PJ = nine(R_PJ), tuple(np.asarray(p_PJ, dtype=float).tolist())
        self.R_CJt = nine(np.asarray(R_CJ, dtype=float).T)
        self.d_C = tuple((-(np.asarray(R_CJ, dtype=float).T @ np.asarray(p_CJ, dtype=float))).tolist())
        self.axis = self.K = self.K2 = None
        if axis is not None:
            a = np.asarray(axis, dtype=float)
            K = spatial.skew(a)
            self.axis, self.K, self.K2 = tuple(a.tolist()), tuple(K.ravel().tolist()), tuple((K @ K).ravel().tolist())


def positions(steps, q, fns):
    """The pass from the root to the leaves over the configuration only: what a projection onto the loop
    closures needs (the poses and the Jacobians), and what ``velocities`` needs to finish the pass.

    Parameters
    ----------
    steps : sequence of Step — the joints in topological order
    q : sequence of scalars — the generalized coordinates (floats, or (m,) arrays)
    fns : ``FLOAT_MATH`` or ``ARRAY_MATH`` — as the scalars

    Returns
    -------
    poses : list of ``(R, p)`` — one per body, in order (module docstring)
    motions : list of ``(omega, nu, o)`` — one per speed, in order
    links : list — one per body, the terms of its joint the velocities need: a free joint's ``R``; else
        ``(x, r_PJ, r_JC)``, the levers parent COM -> joint point (slid, for a prismatic joint) and joint point
        -> child COM (world) and ``x``: a revolute's world axis, a ball's ``R_WJc`` (9-tuple), a prismatic's
        world axis ``a_W``, None for a weld
    """
    sin, sqrt = fns
    poses, motions, links = [(_I9, _O3)], [], []
    for st in steps:
        kind = st.kind
        if kind == "free":  # (the joint's own coordinates, whatever its parent: world position and velocity)
            iq = st.iq
            R = _quat_matrix(q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6], sqrt)
            p = (q[iq], q[iq + 1], q[iq + 2])
            motions += [(_O3, e, p) for e in _E3]  # translation in world axes
            motions += [((R[0], R[3], R[6]), _O3, p), ((R[1], R[4], R[7]), _O3, p), ((R[2], R[5], R[8]), _O3, p)]
            poses.append((R, p))
            links.append(R)
            continue
        R_P, p_P = poses[st.parent]
        R_WJp = R_P if st.R_PJ is None else mat(R_P, st.R_PJ)
        r_PJ = rot(R_P, st.p_PJ)  # parent COM -> (parent's) joint point
        x = None
        if kind == "revolute":
            th, K, K2 = q[st.iq], st.K, st.K2
            try:
                s, h = sin(th), sin(0.5 * th)
            except ValueError:  # the math module's sin of an infinite angle (a blown-up state): NaN, as numpy's
                s = h = math.nan
            c = 2.0 * h * h  # 1 - cos(th), without its cancellation at small angles
            # R_J = exp(th skew(axis)) = I + sin(th) K + (1 - cos(th)) K^2 (Rodrigues; K's diagonal is zero)
            R_WJc = mat(R_WJp, (1.0 + c * K2[0], s * K[1] + c * K2[1], s * K[2] + c * K2[2],
                                 s * K[3] + c * K2[3], 1.0 + c * K2[4], s * K[5] + c * K2[5],
                                 s * K[6] + c * K2[6], s * K[7] + c * K2[7], 1.0 + c * K2[8]))
            x = rot(R_WJp, st.axis)
            motions.append((x, _O3, add(p_P, r_PJ)))
        elif kind == "ball":
            iq = st.iq
            R_WJc = x = mat(R_WJp, _quat_matrix(q[iq], q[iq + 1], q[iq + 2], q[iq + 3], sqrt))
            o = add(p_P, r_PJ)
            motions += [((R_WJc[0], R_WJc[3], R_WJc[6]), _O3, o), ((R_WJc[1], R_WJc[4], R_WJc[7]), _O3, o),
                        ((R_WJc[2], R_WJc[5], R_WJc[8]), _O3, o)]
        elif kind == "prismatic":
            # the child joint frame slides by d along a_W, fixed in the parent joint frame (the module docstring of
            # generalized): the lever gains the slide
            R_WJc = R_WJp
            x, d = rot(R_WJp, st.axis), q[st.iq]
            r_PJ = (r_PJ[0] + x[0] * d, r_PJ[1] + x[1] * d, r_PJ[2] + x[2] * d)
            motions.append((_O3, x, add(p_P, r_PJ)))
        else:  # weld
            R_WJc = R_WJp
        R = R_WJc if st.R_CJt is None else mat(R_WJc, st.R_CJt)
        r_JC = rot(R_WJc, st.d_C)  # joint point -> child COM
        poses.append((R, add(add(p_P, r_PJ), r_JC)))
        links.append((x, r_PJ, r_JC))
    return poses[1:], motions, links


def velocities(steps, links, u):
    """The pass from the root to the leaves over the speeds, at the configuration of ``positions``' ``links``.

    Parameters
    ----------
    steps : sequence of Step — the joints in topological order (``positions``')
    links : list — ``positions``' third output
    u : sequence of scalars — the generalized speeds (floats, or (m,) arrays, as ``positions``' ``q``)

    Returns
    -------
    list of ``(w, v, a_bias, alpha_bias)`` — one per body, in order (module docstring)
    """
    states = [(_O3, _O3, _O3, _O3)]
    for st, link in zip(steps, links):
        kind = st.kind
        if kind == "free":
            iv = st.iv
            states.append((rot(link, (u[iv + 3], u[iv + 4], u[iv + 5])), (u[iv], u[iv + 1], u[iv + 2]), _O3, _O3))
            continue
        w_P, v_P, a_P, al_P = states[st.parent]
        x, r_PJ, r_JC = link
        w, al, slide = w_P, al_P, None
        if kind == "revolute":
            ud = u[st.iv]
            w_rel = (x[0] * ud, x[1] * ud, x[2] * ud)
            w = add(w_P, w_rel)
            al = add(al_P, cross(w_P, w_rel))
        elif kind == "ball":
            iv = st.iv
            w_rel = rot(x, (u[iv], u[iv + 1], u[iv + 2]))  # u in the child joint frame
            w = add(w_P, w_rel)
            al = add(al_P, cross(w, w_rel))
        elif kind == "prismatic":
            # the velocity d' a_W, the bias the Coriolis 2 w_P x (d' a_W) (the module docstring of generalized)
            dd = u[st.iv]
            v_sl = (x[0] * dd, x[1] * dd, x[2] * dd)
            cw = cross(w_P, v_sl)
            slide = (v_sl, (2.0 * cw[0], 2.0 * cw[1], 2.0 * cw[2]))
        v = add(v_P, cross(w_P, r_PJ))
        a = add(add(a_P, cross(al_P, r_PJ)), cross(w_P, cross(w_P, r_PJ)))
        if slide is not None:
            v, a = add(v, slide[0]), add(a, slide[1])
        v = add(v, cross(w, r_JC))
        a = add(add(a, cross(al, r_JC)), cross(w, cross(w, r_JC)))
        states.append((w, v, a, al))
    return states[1:]


def forward(steps, q, u, fns):
    """The whole pass: ``positions``, then ``velocities``.

    Parameters
    ----------
    steps : sequence of Step — the joints in topological order
    q, u : sequence of scalars — the generalized coordinates and speeds (floats, or (m,) arrays)
    fns : ``FLOAT_MATH`` or ``ARRAY_MATH`` — as the scalars

    Returns
    -------
    states : list of ``(R, p, w, v, a_bias, alpha_bias)`` — one per body, in order (module docstring)
    motions : list of ``(omega, nu, o)`` — one per speed, in order
    """
    poses, motions, links = positions(steps, q, fns)
    return [pose + state for pose, state in zip(poses, velocities(steps, links, u))], motions
