"""Lagrange's equations of a planar serial chain in absolute angles: a second formulation of the
reference for revolute chains whose axes are all parallel (pendulums, the multi-link chain).

Nothing is shared with Kane's formulation (``generalized.py``) but the scene: the coordinates are
the links' absolute angles ``phi_i`` about the common axis ``a`` (the joint angles summed from the
root), the kinematics are 2-D rotations in the plane normal to ``a``, and the mass matrix and the
forces are written out in closed form (Goldstein, Poole & Safko, *Classical Mechanics*, 3rd ed.,
section 1.4, the Lagrangian of a system of particles, applied to rigid links). With, in the plane
and at the current angles, ``D_i`` the vector from joint i to joint i+1, ``C_i`` from joint i to
the centre of mass of link i, ``mu_i`` the mass beyond link i and ``E_i = m_i C_i + mu_i D_i``::

    M_ii = I_i + m_i |C_i|^2 + mu_i |D_i|^2,    M_ij = D_i . E_j  (i < j)
    (M phi'')_j = E_j x g + sum_{i<j} (E_j x D_i) phi_i'^2 + sum_{i>j} (D_j x E_i) phi_i'^2

(``x``: the planar cross product about ``a``; ``I_i``: link i's moment about the axis through its
centre of mass). Forces from the scene's gravity only: a scene with loads, other joints, branches
or non-parallel axes is not planar here (``why_not``). The joint reactions follow from Newton's
law per link, from the tip back to the root.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.scene import WORLD
from dalembert.trajectory import BodyStates, JointStates, Trajectory
from dalembert.reference.configuration import Block

__all__ = ["PlanarChain", "why_not"]

# Joint axes are parallel when their world directions differ by less than this angle (rad):
# directions built from rounded decimals agree to ~1e-16.
PARALLEL_TOL = 1e-12


def _links(scene):
    """The chain's bodies from the root, or a reason why the scene is not a planar chain."""
    if scene.loops:
        return None, "the planar formulation takes serial chains only, no loop closures"
    if scene.loads:
        return None, "the planar formulation takes gravity only, no loads"
    if scene.springs:
        return None, "the planar formulation takes gravity only, no spring-dampers"
    if any(j.kind != "revolute" for j in scene.joints):
        return None, "the planar formulation takes revolute joints only"
    children = {}
    for j in scene.joints:
        children.setdefault(j.parent, []).append(j.child)
    if len(children.get(WORLD, [])) != 1 or any(len(c) > 1 for c in children.values()):
        return None, "the planar formulation takes one serial chain from the world (no branches)"
    order = [children[WORLD][0]]
    while order[-1] in children:
        order.append(children[order[-1]][0])
    return order, None


def why_not(scene):
    """Why ``scene`` is not a planar chain (a sentence), or None when it is."""
    order, reason = _links(scene)
    if reason:
        return reason
    axes = _axes_at_zero(scene, order)[0]
    a = axes[0]
    if any(np.arccos(min(1.0, abs(float(b @ a)))) > PARALLEL_TOL for b in axes[1:]):
        return "the planar formulation needs every joint axis parallel"
    return None


def _axes_at_zero(scene, order):
    """World joint axes and body rotations ``R_WB`` with every joint angle zero."""
    R, axes, rotations = {WORLD: np.eye(3)}, [], []
    for name in order:
        j = scene.joint(name)
        R_WJp = R[j.parent] @ spatial.quat_to_matrix(j.parent_quat)
        axes.append(R_WJp @ (np.asarray(j.axis, float) / np.linalg.norm(j.axis)))
        R[name] = R_WJp @ spatial.quat_to_matrix(j.child_quat).T
        rotations.append(R[name])
    return axes, rotations


def _cross2(u, v):
    """Planar cross product ``u_x v_y - u_y v_x`` of stacks (..., 2)."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _rotate2(phi, v):
    """``v`` (..., 2) turned by ``phi`` (...) in the plane."""
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]], -1)


class PlanarChain:
    """A ``System`` (``integrators``) for a planar serial chain: ``q`` = absolute angles ``phi`` (rad),
    ``v = phi'`` (rad/s), one entry per link from the root.

    Parameters
    ----------
    scene : Scene — a serial chain of revolute joints with parallel axes, gravity only
        (``why_not`` says why a scene is not)
    """

    def __init__(self, scene):
        reason = why_not(scene)
        if reason:
            raise ValueError(f"formulation 'planar': {reason} — use 'kane'")
        self.scene = scene
        order, _ = _links(scene)
        self.names = order
        axes, R0 = _axes_at_zero(scene, order)
        a = axes[0]
        self.a, self.E = a, spatial.frame_with_z(a)[:, :2]  # E: the plane's basis e1, e2 with e1 x e2 = a (3, 2)
        joints = [scene.joint(n) for n in order]
        bodies = [scene.body(n) for n in order]
        n = len(order)
        self.m = np.array([b.mass for b in bodies])
        self.I = np.array([a @ (R @ b.inertia_matrix @ R.T) @ a for b, R in zip(bodies, R0)])
        self.mu = np.concatenate([np.cumsum(self.m[::-1])[::-1][1:], [0.0]])  # mass beyond each link
        # at zero angles, world vectors: joint i -> COM i (c3), joint i -> joint i+1 (d3)
        self.c3 = np.array([-R @ np.asarray(j.child_point, float) for j, R in zip(joints, R0)])
        self.d3 = np.zeros((n, 3))
        for i in range(n - 1):
            self.d3[i] = self.c3[i] + R0[i] @ np.asarray(joints[i + 1].parent_point, float)
        self.c2, self.d2 = self.c3 @ self.E, self.d3 @ self.E
        self.root = np.asarray(joints[0].parent_point, float)  # joint 1, world (its parent is the world)
        self.R0 = np.array(R0)
        self.g3 = np.asarray(scene.gravity, float)
        self.g2 = self.g3 @ self.E
        self.blocks = (Block("vector", slice(0, n), slice(0, n)),)
        self.q0 = np.cumsum([j.q0[0] for j in joints])
        self.v0 = np.cumsum([j.v0[0] for j in joints])
        self.upper = np.triu(np.ones((n, n), dtype=bool), 1)  # i < j

    def _terms(self, phi):
        C, D = _rotate2(phi, self.c2), _rotate2(phi, self.d2)
        Ev = self.m[:, None] * C + self.mu[:, None] * D
        return C, D, Ev

    def acceleration(self, t, q, v):
        """``phi''`` (n,), rad/s^2."""
        C, D, Ev = self._terms(q)
        DE = D @ Ev.T  # [i, j] = D_i . E_j
        M = np.where(self.upper, DE, 0.0)
        M = M + M.T + np.diag(self.I + self.m * np.einsum("ik,ik->i", C, C) + self.mu * np.einsum("ik,ik->i", D, D))
        X = np.where(self.upper.T, _cross2(Ev[:, None, :], D[None, :, :]), 0.0)  # [j, i] = E_j x D_i, i < j
        X += np.where(self.upper, _cross2(D[:, None, :], Ev[None, :, :]), 0.0)  # [j, i] = D_j x E_i, i > j
        f = _cross2(Ev, self.g2[None, :]) + X @ (v * v)
        return np.linalg.solve(M, f)

    # ------------------------------------------------------------ read-back
    def _rotation3(self, phi):
        """Rotations about ``a`` by ``phi`` (...,) -> (..., 3, 3)."""
        return spatial.so3_exp(np.asarray(phi)[..., None] * self.a)

    def trajectory(self, t, Q, V):
        """Sampled absolute angles and rates as a ``Trajectory``: bodies, joint coordinates (the joint
        angles, relative to the parent link) and the joint reactions (force ON each link, world, N)."""
        n_t, n = Q.shape
        A = np.array([self.acceleration(ti, q, v) if np.all(np.isfinite(q)) and np.all(np.isfinite(v))
                      else np.full(n, np.nan) for ti, q, v in zip(t, Q, V)])
        Rot = self._rotation3(Q)  # (n_t, n, 3, 3)
        c = np.einsum("tnij,nj->tni", Rot, self.c3)
        d = np.einsum("tnij,nj->tni", Rot, self.d3)
        w = V[..., None] * self.a  # (n_t, n, 3)
        alpha = A[..., None] * self.a

        def perp(x):  # the part normal to the axis
            return x - (x @ self.a)[..., None] * self.a

        # joint i's position, velocity, acceleration: sums over the links before it
        zero = np.zeros((n_t, 1, 3))
        base = np.concatenate([zero, np.cumsum(d, axis=1)[:, :-1]], axis=1) + self.root
        v_d = np.cross(w, d)
        a_d = np.cross(alpha, d) - (V * V)[..., None] * perp(d)
        base_v = np.concatenate([zero, np.cumsum(v_d, axis=1)[:, :-1]], axis=1)
        base_a = np.concatenate([zero, np.cumsum(a_d, axis=1)[:, :-1]], axis=1)
        p = base + c
        vel = base_v + np.cross(w, c)
        acc = base_a + np.cross(alpha, c) - (V * V)[..., None] * perp(c)
        R_WB = Rot @ self.R0
        bodies, joints, extras = {}, {}, {}
        force = np.zeros((n_t, 3))
        for i in reversed(range(n)):
            force = self.m[i] * (acc[:, i] - self.g3) + force  # ON link i: m a - m g + (its child's reaction)
            extras[f"reaction_force:{self.names[i]}"] = force
        for i, name in enumerate(self.names):
            bodies[name] = BodyStates(p[:, i], spatial.matrix_to_quat(R_WB[:, i]), vel[:, i], w[:, i])
            rel_q = Q[:, i] - (Q[:, i - 1] if i else 0.0)
            rel_v = V[:, i] - (V[:, i - 1] if i else 0.0)
            joints[name] = JointStates(rel_q[:, None], rel_v[:, None])
        return Trajectory(t, bodies, joints, {k: extras[k] for k in reversed(list(extras))})
