"""Spring-dampers (``Scene.springs``) in Pinocchio: external forces per joint at every evaluation, and their
identification from the engine's own dynamics for the audit.

Pinocchio has no spring element. Each spring becomes a ``SpringElement``: its two ends as operational frames
of the model (``<name>:a``, ``<name>:b``; on the universe, joint 0, for a world end), placed at the scene's
points in the frame E of the joint that carries each body (``PinocchioModel.X_EB``), and its stiffness,
damping and rest length. At every right-hand-side evaluation, after ``forwardKinematics(q, v)``
(``data.oMi``, ``data.v``), ``add_forces`` computes each end's world position ``x = p_WE + R_WE p_E`` and
velocity ``x' = R_WE (v_E + w_E x p_E)`` (``data.v`` is the joint's spatial velocity in its LOCAL frame),
the length ``l``, the unit vector ``e`` from a's end to b's, the rate ``l' = e . (x_b' - x_a')``, the tension
``s = k (l - l0) + c l'`` (``dalembert.springs``), and adds ``-s e`` at b's end and ``+s e`` at a's end to
the joints' external forces, in the joint's LOCAL frame about its origin (``(f_E, p_E x f_E)``): what
``aba`` and ``rnea`` take. The universe's share is dropped (nothing moves it). The compiled loop
(``stepper.cpp``) does the same from the same arrays (``pack``).

The audit proves the springs from what the engine computes (``identify``): at the initial configuration,
the generalized force each spring adds to the dynamics the run used, with the spring and without it
(``M (a - a0)`` from the compiled or the Python right-hand side's accelerations; or the joint torques the
constraint dynamics is given), must be
``-s J_l^T``, ``J_l = e^T (J_b - J_a)`` the Jacobian of the length from the two end frames' Jacobians
(``getFrameJacobian``, LOCAL_WORLD_ALIGNED): the component of ``Q`` off ``J_l`` (``line_residual``) shows a
force off the line or at a wrong point; the tension ``s = -Q . J_l / |J_l|^2`` at two lengths (at rest)
gives the stiffness and the rest length, and at a velocity ``v = J_l^T`` (rate ``|J_l|^2``) the damping.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from dalembert import spatial
from dalembert.scene import WORLD

__all__ = ["SpringElement", "build", "add_forces", "pack", "mass_matrix", "identify", "IDENTIFY_STRETCH"]

# The identification's second length: the first end moved along the length's gradient by this fraction
# of the spring's length. The tension is exactly linear in the length, so the size only sets roundoff
# (Q is computed to ~1e-16 of the mass matrix times the accelerations; a 1e-3 stretch loses 3 digits).
IDENTIFY_STRETCH = 1e-3


@dataclass(frozen=True)
class SpringElement:
    """One spring as the model holds it.

    Attributes
    ----------
    name : str
    joint_a, joint_b : int — the joints that carry the ends (0: the universe, for the world)
    frame_a, frame_b : int — the ends' operational frames in ``model.frames``
    p_a, p_b : ndarray (3,) — the ends in their joints' frames E (m)
    stiffness : float — N/m
    damping : float — N s/m
    rest_length : float — m
    """

    name: str
    joint_a: int
    joint_b: int
    frame_a: int
    frame_b: int
    p_a: np.ndarray
    p_b: np.ndarray
    stiffness: float
    damping: float
    rest_length: float


def _end(pm, body, point):
    """``(joint id, point in its frame E)`` of a spring end on ``body`` (the world: the universe, 0)."""
    if body == WORLD:
        return 0, np.asarray(point, dtype=float)
    X_EB = pm.X_EB[body]
    return pm.carrier[body], X_EB.rotation @ np.asarray(point, dtype=float) + X_EB.translation


def build(pm, model):
    """Every spring of ``pm.scene`` as a ``SpringElement``, its ends added to ``model`` as operational frames
    (before ``model.createData()``). Returns a tuple."""
    import pinocchio as pin

    out = []
    for sp in pm.scene.springs:
        ends = []
        for side, body, point in (("a", sp.body_a, sp.point_a), ("b", sp.body_b, sp.point_b)):
            jid, p_E = _end(pm, body, point)
            fid = model.addFrame(pin.Frame(f"{sp.name}:{side}", jid, pin.SE3(np.eye(3), p_E), pin.FrameType.OP_FRAME))
            ends.append((jid, fid))
        # the element's numbers are read back from the model's frames, so the forces use what the model holds
        (ja, fa), (jb, fb) = ends
        out.append(SpringElement(sp.name, ja, jb, fa, fb, model.frames[fa].placement.translation.copy(),
                                 model.frames[fb].placement.translation.copy(), sp.stiffness, sp.damping,
                                 sp.rest_length))
    return tuple(out)


def _point(data, jid, p_E):
    """World position and velocity (m, m/s; (3,) each) of the point ``p_E`` of joint ``jid``'s frame, after
    ``forwardKinematics(q, v)``."""
    X, nu = data.oMi[jid], data.v[jid]
    R = X.rotation
    return X.translation + R @ p_E, R @ (nu.linear + spatial.cross(nu.angular, p_E))  # not np.cross: 10x slower here


def add_forces(elements, data, fext):
    """Add every spring's force to ``fext`` (``pin.StdVec_Force``, per joint, LOCAL frame about the joint's
    origin) at the state of the last ``forwardKinematics(model, data, q, v)``."""
    import pinocchio as pin

    for el in elements:
        x_a, xd_a = _point(data, el.joint_a, el.p_a)
        x_b, xd_b = _point(data, el.joint_b, el.p_b)
        d = x_b - x_a
        length = math.sqrt(d @ d)
        e = d / length
        tension = el.stiffness * (length - el.rest_length) + el.damping * (e @ (xd_b - xd_a))
        for jid, p_E, f_W in ((el.joint_a, el.p_a, tension * e), (el.joint_b, el.p_b, -tension * e)):
            if jid > 0:
                f_E = data.oMi[jid].rotation.T @ f_W
                fext[jid] = fext[jid] + pin.Force(f_E, spatial.cross(p_E, f_E))


def pack(elements):
    """The arrays the compiled loop takes: joints (n, 2) int32, points (n, 6) (``p_a``, ``p_b``, m) and
    parameters (n, 3) (stiffness, damping, rest length), C order; one zero row when there are none."""
    n = max(len(elements), 1)
    joints, points, params = np.zeros((n, 2), np.int32), np.zeros((n, 6)), np.zeros((n, 3))
    for i, el in enumerate(elements):
        joints[i] = el.joint_a, el.joint_b
        points[i] = *el.p_a, *el.p_b
        params[i] = el.stiffness, el.damping, el.rest_length
    return joints, points, params


def _length_jacobian(model, data, el, q):
    """``(l, J_l (nv,))``: the spring's length (m) at ``q`` and its Jacobian ``e^T (J_b - J_a)`` from the end
    frames' Jacobians (LOCAL_WORLD_ALIGNED: world axes, at the frame's origin)."""
    import pinocchio as pin

    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    d = data.oMf[el.frame_b].translation - data.oMf[el.frame_a].translation
    length = float(np.linalg.norm(d))
    e = d / length
    frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    J = (pin.getFrameJacobian(model, data, el.frame_b, frame)[:3]
         - pin.getFrameJacobian(model, data, el.frame_a, frame)[:3])
    return length, e @ J


def mass_matrix(model, data, q):
    """The joint-space mass matrix ``M (nv, nv)`` at ``q`` (``crba``, symmetrised)."""
    import pinocchio as pin

    M = pin.crba(model, data, q)
    return np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle


def identify(pm, el, forces, q0):
    """The spring ``el`` as the engine applies it, from its generalized force (module docstring).

    Parameters
    ----------
    pm : PinocchioModel
    el : SpringElement
    forces : callable (q (nq,), v (nv,), elements) -> (nv,) — what the run's right-hand side adds to the
        dynamics with the springs ``elements`` (a tuple of ``SpringElement``), up to a term that does not
        depend on them (e.g. ``M a``: the bias forces cancel): the spring's generalized force is the
        difference with and without ``el``
    q0 : ndarray (nq,) — the configuration to identify at

    Returns
    -------
    dict: ``stiffness`` (N/m), ``damping`` (N s/m), ``rest_length`` (m; None without stiffness),
    ``line_residual`` (the part of ``Q`` off the length's gradient, relative to ``|Q|``), ``frames`` (each
    end: its frame's name, joint and point in the joint's frame, read from the model); or ``note`` where the
    spring's ends move together (no generalized force to identify it from)
    """
    import pinocchio as pin

    model, data = pm.model, pm.data
    others = tuple(x for x in pm.springs if x is not el)
    frames = {side: f"{model.frames[fid].name} on joint {model.names[model.frames[fid].parentJoint]!r} at "
                    f"{np.round(model.frames[fid].placement.translation, 12).tolist()} m"
              for side, fid in (("a", el.frame_a), ("b", el.frame_b))}

    def tension(q, v):  # -Q . J_l / |J_l|^2, and the relative part of Q off J_l
        Q = forces(q, v, pm.springs) - forces(q, v, others)
        _, g = _length_jacobian(model, data, el, q)
        s = -float(Q @ g) / float(g @ g)
        return s, float(np.linalg.norm(Q + s * g) / max(np.linalg.norm(Q), np.finfo(float).tiny))

    length0, g0 = _length_jacobian(model, data, el, q0)
    gg = float(g0 @ g0)
    if gg == 0.0:
        return dict(frames=frames, note="its ends move together (one rigid joint): it exerts no generalized force")
    rest = np.zeros(model.nv)
    s0, residual = tension(q0, rest)
    # a second length: move along the gradient by IDENTIFY_STRETCH of the length
    q1 = pin.integrate(model, q0, (IDENTIFY_STRETCH * length0 / gg) * g0)
    length1, _ = _length_jacobian(model, data, el, q1)
    s1, _ = tension(q1, rest)
    stiffness = (s1 - s0) / (length1 - length0)
    # a rate: v = J_l^T stretches the spring at |J_l|^2 m/s
    s_moving, _ = tension(q0, g0)
    damping = (s_moving - s0) / gg
    return dict(frames=frames, stiffness=stiffness, damping=damping,
                rest_length=(length0 - s0 / stiffness) if stiffness != 0.0 else None, line_residual=residual)
