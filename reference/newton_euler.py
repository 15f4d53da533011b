"""Newton-Euler equations for free rigid bodies (Landau & Lifshitz, Mechanics, sections 34 and 36).

For each body, with the centre of mass R in world and the attitude Q = R_WB::

    M R'' = F                                  (linear momentum, world)
    A w' + w x A w = tau                       (angular momentum about the COM, body frame)

with F and tau the resultant of the loads, gravity and spring-dampers (``dalembert.springs``) on the body.
    Q' = Q Omega,  Omega = skew(w)             (kinematics)

The attitude is either a unit quaternion (default) or a rotation
matrix (``attitude="matrix"``: 18 unknowns per body, whose orthonormality drift
under a vector-space integrator is one of the things the harness shows).
Only the terms the scene has are computed (no gravity unless declared).
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial, springs
from dalembert.trajectory import BodyStates, JointStates, Trajectory
from dalembert.reference.configuration import Block
from dalembert.reference.loads import BodyLoads

__all__ = ["NewtonEuler"]


class NewtonEuler:
    """A ``System`` (see ``integrators``) for a scene of free bodies.

    State per body: ``q = (p_WB (3), attitude (4 or 9))``,
    ``v = (v_WB_W (3), w_WB_B (3))`` — the free joint's own coordinates.

    Parameters
    ----------
    scene : Scene — every joint must be ``free``
    attitude : ``"quaternion"`` or ``"matrix"``
    """

    def __init__(self, scene, attitude="quaternion"):
        if attitude not in ("quaternion", "matrix"):
            raise ValueError(f"attitude: {attitude!r} — use 'quaternion' or 'matrix'")
        not_free = [j.child for j in scene.joints if j.kind != "free"]
        if not_free:
            raise ValueError(f"Newton-Euler handles free bodies only; {not_free} are jointed — use 'kane'")
        if scene.loops:
            raise ValueError("Newton-Euler handles free bodies without loop closures — use 'kane'")
        self.scene, self.attitude = scene, attitude
        na = 4 if attitude == "quaternion" else 9
        self.bodies = [scene.body(j.child) for j in scene.joints]
        blocks, q0, v0 = [], [], []
        for k, body in enumerate(self.bodies):
            j = scene.joint(body.name)
            qb, vb = k * (3 + na), 6 * k
            blocks += [Block("vector", slice(qb, qb + 3), slice(vb, vb + 3)),
                       Block("quat" if na == 4 else "rotmat", slice(qb + 3, qb + 3 + na), slice(vb + 3, vb + 6))]
            att = np.array(j.q0[3:]) if na == 4 else spatial.quat_to_matrix(j.q0[3:]).ravel()
            q0 += [np.array(j.q0[:3]), att]
            v0.append(np.array(j.v0))
        self.blocks = tuple(blocks)
        self.q0, self.v0 = np.concatenate(q0), np.concatenate(v0)
        self._I = [body.inertia_matrix for body in self.bodies]
        self._I_inv = [np.linalg.inv(I) for I in self._I]
        self._loads = [BodyLoads(scene, body) for body in self.bodies]

    def rotation(self, q_att):
        """``R_WB`` of an attitude block (the quaternion is normalized; a matrix is used as is)."""
        if self.attitude == "quaternion":
            return spatial.quat_to_matrix(q_att / np.linalg.norm(q_att))
        return q_att.reshape(3, 3)

    def _spring_wrenches(self, q, v):
        """The spring-dampers' wrench on each body (``dalembert.springs.wrenches``), from the bodies' states."""
        states = {"world": dict(R=np.eye(3), p=np.zeros(3), v=np.zeros(3), w=np.zeros(3))}
        for k, body in enumerate(self.bodies):
            pos, att = self.blocks[2 * k], self.blocks[2 * k + 1]
            R = self.rotation(q[att.q])
            states[body.name] = dict(R=R, p=q[pos.q], v=v[pos.v], w=R @ v[att.v])
        return springs.wrenches(self.scene.springs, states)

    def acceleration(self, t, q, v):
        """``(a_WB_W, dw_WB_B)`` per body, shape (nv,)."""
        out = np.empty_like(v)
        spring_wrenches = self._spring_wrenches(q, v) if self.scene.springs else {}
        for k, body in enumerate(self.bodies):
            att = self.blocks[2 * k + 1]
            R = self.rotation(q[att.q])
            w = v[att.v]
            F_W, tau_W = self._loads[k].resultant(R)
            if body.name in spring_wrenches:
                F_s, tau_s = spring_wrenches[body.name]
                F_W, tau_W = F_W + F_s, tau_W + tau_s
            I = self._I[k]
            out[6 * k:6 * k + 3] = F_W / body.mass
            out[att.v] = self._I_inv[k] @ (R.T @ tau_W - spatial.cross(w, I @ w))
        return out

    def trajectory(self, t, Q, V):
        """Sampled states ``Q (n, nq)``, ``V (n, nv)`` as a ``Trajectory``."""
        bodies, joints = {}, {}
        for k, body in enumerate(self.bodies):
            pos, att = self.blocks[2 * k], self.blocks[2 * k + 1]
            w_B = V[:, att.v]
            if self.attitude == "quaternion":
                quat, rot = Q[:, att.q], None
                R = spatial.quat_to_matrix(spatial.quat_normalize(quat))
            else:
                rot = Q[:, att.q].reshape(-1, 3, 3)
                finite = np.all(np.isfinite(rot), axis=(1, 2))
                quat = np.full((len(t), 4), np.nan)
                quat[finite] = spatial.matrix_to_quat(rot[finite])
                R = rot
            w_W = np.einsum("nij,nj->ni", R, w_B)
            bodies[body.name] = BodyStates(Q[:, pos.q], quat, V[:, pos.v], w_W, rot)
            joints[body.name] = JointStates(np.concatenate([Q[:, pos.q], quat], axis=1), V[:, 6 * k:6 * k + 6])
        return Trajectory(t, bodies, joints)
