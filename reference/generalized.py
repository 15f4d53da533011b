"""d'Alembert's principle in generalized coordinates (Kane's form) for trees of
rigid bodies with free, revolute, prismatic, ball and weld joints.

Kane & Levinson, *Dynamics: Theory and Applications* (1985), chapters 4 and 6: with partial
velocities ``dV_i/du_j`` (of each body's centre of mass) and partial angular velocities
``dw_i/du_j``, the generalized active forces

    Q_j  = sum_i F_i . dV_i/du_j + T_i . dw_i/du_j

and the generalized inertia forces

    Q*_j = -sum_i (m_i a_i) . dV_i/du_j + (I_i alpha_i + w_i x I_i w_i) . dw_i/du_j

satisfy ``Q_j + Q*_j = 0`` for every generalized speed ``u_j``. Writing
``a_i = J_v,i u' + a_bias,i`` and ``alpha_i = J_w,i u' + alpha_bias,i`` (the
partial velocities are the columns of the Jacobians ``J``), this is the linear
system ``M u' = f`` with

    M = sum_i m_i J_v^T J_v + J_w^T I_i J_w
    f = sum_i J_v^T (F_i - m_i a_bias) + J_w^T (T_i - I_i alpha_bias - w_i x I_i w_i)

all in world axes (``F_i``, ``T_i``: the loads, gravity and spring-dampers on body i, force and
moment about its COM). Jacobians and bias accelerations come from one recursive
pass from the root to the leaves.

A prismatic joint slides the child joint frame by ``d a_W`` along the unit axis ``a_W`` fixed in
the parent joint frame (no relative rotation): the lever from the parent's COM to the child's
joint point, ``r = r_PJ + d a_W``, gains the slide; the COM's partial velocity in ``d'`` is
``a_W``; and since ``a_W`` turns with the parent, ``d/dt (d' a_W) = d'' a_W + d' w_P x a_W`` while
the lever's transport ``w_P x r`` changes by ``w_P x (d' a_W)`` too: the bias acceleration gains
the Coriolis term ``2 w_P x (d' a_W)`` (the centripetal ``w_P x (w_P x r)`` uses the slid lever). Joint reaction forces follow from Newton's
law per body, from the leaves back to the root.

The read-back (``trajectory``) solves the same system at every sample at once (``_solve_stacked``:
the same terms in the same order, each with a leading sample axis), where the integrators call
``_solve`` one state at a time: a Python pass per sample cost about one evaluation of the
right-hand side per sample, as much as a whole run where a run takes one or two evaluations per
sample. The two agree to roundoff (``tests/test_reference.py``); a formulation whose solve is its
own (``loops.ClosedLoops``) brings its stacked twin, or reads back sample by sample.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial, springs
from dalembert.scene import JOINT_KINDS, WORLD
from dalembert.trajectory import BodyStates, JointStates, Trajectory
from dalembert.reference.configuration import Block
from dalembert.reference.loads import BodyLoads

__all__ = ["Kane"]


def _mv(A, x):
    """Stacked matrix-vector products: ``A`` (m, i, j), ``x`` (m, j) -> (m, i)."""
    return (A @ x[..., None])[..., 0]


def _mtv(A, x):
    """Stacked transposed products: ``A`` (m, i, j), ``x`` (m, i) -> ``A^T x`` (m, j)."""
    return (x[..., None, :] @ A)[..., 0, :]


# Kane's terms below are written once for one state and for a stack of states (a leading sample axis
# on every array). The few operations whose numpy call differs with the shape go through these, each
# keeping the call either path made before, so both give the bits they always gave.
def _dot(A, x):
    """``A x``: ``A`` (i, j), ``x`` (j,) -> (i,); or stacked (m, i, j), (m, j) -> (m, i)."""
    return A @ x if A.ndim == 2 else _mv(A, x)


def _tdot(A, x):
    """``A^T x``: ``A`` (i, j), ``x`` (i,) -> (j,); or stacked (m, i, j), (m, i) -> (m, j)."""
    return A.T @ x if A.ndim == 2 else _mtv(A, x)


def _unit(x):
    """``x`` over its norm along the last axis: (k,) or (m, k)."""
    return x / np.linalg.norm(x) if x.ndim == 1 else x / np.linalg.norm(x, axis=-1, keepdims=True)


def _T(A):
    """The transpose of the last two axes: ``A.T`` of a matrix, each matrix's of a stack."""
    return A.swapaxes(-1, -2)


def _linear_solve(M, f):
    """``M^-1 f``: ``M`` (n, n), ``f`` (n,); or stacked (m, n, n), (m, n)."""
    return np.linalg.solve(M, f) if f.ndim == 1 else np.linalg.solve(M, f[..., None])[..., 0]


def _child(P, R, r_PJ, r_JC, w, alpha_bias, Jw, Jv_slide, v_slide, a_slide):
    """A child's ``kinematics`` entry from its parent's ``P``: its COM reached through the joint (``r_PJ``: parent
    COM -> joint point, slid; ``r_JC``: joint point -> child COM), with its rotation ``R``, angular velocity
    ``w``, angular bias ``alpha_bias`` and angular Jacobian ``Jw`` and the slide's terms. One state or many (a
    leading sample axis on every array: ``Kane.kinematics`` of a stack): the same operations either way."""
    Jv = P["Jv"] - spatial.skew(r_PJ) @ P["Jw"] + Jv_slide - spatial.skew(r_JC) @ Jw
    v = P["v"] + spatial.cross(P["w"], r_PJ) + v_slide + spatial.cross(w, r_JC)
    a_bias = (P["a_bias"] + spatial.cross(P["alpha_bias"], r_PJ) + spatial.cross(P["w"], spatial.cross(P["w"], r_PJ))
              + a_slide + spatial.cross(alpha_bias, r_JC) + spatial.cross(w, spatial.cross(w, r_JC)))
    return dict(R=R, p=P["p"] + r_PJ + r_JC, w=w, v=v, Jv=Jv, Jw=Jw, a_bias=a_bias, alpha_bias=alpha_bias)


def _frozen(a):
    a.flags.writeable = False
    return a


# The world's and the joints' constant terms in ``kinematics``: one allocation each, shared by every call
# (read-only, so that sharing them cannot leak a write from one body's entry into another's).
_EYE3, _ZERO3 = _frozen(np.eye(3)), _frozen(np.zeros(3))


class Kane:
    """A ``System`` (see ``integrators``) for any valid tree scene.

    The generalized coordinates and speeds are the joints' own (``JOINT_KINDS``),
    concatenated in topological order (parents first).
    """

    def __init__(self, scene):
        self.scene = scene
        self.order = scene.topological_order()
        self.joints, blocks, q0, v0 = [], [], [], []
        iq = iv = 0
        for body in self.order:
            j = scene.joint(body.name)
            nq, nv = JOINT_KINDS[j.kind]
            jb = []
            if j.kind == "free":
                jb = [Block("vector", slice(iq, iq + 3), slice(iv, iv + 3)),
                      Block("quat", slice(iq + 3, iq + 7), slice(iv + 3, iv + 6))]
            elif j.kind in ("revolute", "prismatic"):
                jb = [Block("vector", slice(iq, iq + 1), slice(iv, iv + 1))]
            elif j.kind == "ball":
                jb = [Block("quat", slice(iq, iq + 4), slice(iv, iv + 3))]
            blocks += jb
            self.joints.append(dict(
                joint=j, body=body, q=slice(iq, iq + nq), v=slice(iv, iv + nv),
                m=body.mass, I_B=body.inertia_matrix, loads=BodyLoads(scene, body),
                R_PJ=spatial.quat_to_matrix(j.parent_quat), p_PJ=np.array(j.parent_point),
                R_CJ=spatial.quat_to_matrix(j.child_quat), p_CJ=np.array(j.child_point),
                axis=None if j.axis is None else np.array(j.axis) / np.linalg.norm(j.axis),
            ))
            q0.append(np.array(j.q0))
            v0.append(np.array(j.v0))
            iq, iv = iq + nq, iv + nv
        self.blocks = tuple(blocks)
        self.q0 = np.concatenate(q0) if q0 else np.zeros(0)
        self.v0 = np.concatenate(v0) if v0 else np.zeros(0)
        self.nv = iv
        self._zeros = _frozen(np.zeros((3, iv)))  # (3, nv): the world's Jacobians, a joint's no-slide term

    # ------------------------------------------------------------ kinematics
    def kinematics(self, q, u):
        """Pose, velocity, Jacobians and bias accelerations of every body, world axes.

        ``q`` (nq,), ``u`` (nv,) for one state, or ``(m, nq)``, ``(m, nv)`` for m states at once: every entry
        then has a leading sample axis. Returns a dict per body name with ``R (3,3)``, ``p (3,)``,
        ``w (3,)``, ``v (3,)``, ``Jv (3, nv)``, ``Jw (3, nv)``, ``a_bias (3,)``, ``alpha_bias (3,)``.
        """
        lead, n = q.shape[:-1], self.nv
        if lead:
            zero, zeros, eye = np.zeros(lead + (3,)), np.zeros(lead + (3, n)), np.broadcast_to(_EYE3, lead + (3, 3))
        else:  # read-only and shared: every entry below is a new array or a copy
            zero, zeros, eye = _ZERO3, self._zeros, _EYE3
        out = {WORLD: dict(R=eye, p=zero, w=zero, v=zero, Jv=zeros, Jw=zeros, a_bias=zero, alpha_bias=zero)}
        for jd in self.joints:
            j = jd["joint"]
            P = out[j.parent]
            qj, uj, cols = q[..., jd["q"]], u[..., jd["v"]], jd["v"]
            if j.kind == "free":
                R = spatial.quat_to_matrix(_unit(qj[..., 3:]))
                Jv = np.zeros(lead + (3, n))
                Jv[..., cols.start:cols.start + 3] = _EYE3
                Jw = np.zeros(lead + (3, n))
                Jw[..., cols.start + 3:cols.stop] = R
                out[j.child] = dict(R=R, p=qj[..., :3].copy(), w=_dot(R, uj[..., 3:]), v=uj[..., :3].copy(), Jv=Jv,
                                    Jw=Jw, a_bias=zero, alpha_bias=zero)
                continue
            R_WJp = P["R"] @ jd["R_PJ"]
            if j.kind == "revolute":
                R_J = spatial.so3_exp(jd["axis"] * qj[..., :1])
            elif j.kind == "ball":
                R_J = spatial.quat_to_matrix(_unit(qj))
            else:
                R_J = eye
            R_WJc = R_WJp @ R_J
            R = R_WJc @ jd["R_CJ"].T
            r_PJ = P["R"] @ jd["p_PJ"]  # parent COM -> (parent's) joint point
            r_JC = -R @ jd["p_CJ"]  # joint point -> child COM
            Jw = P["Jw"].copy()
            w, alpha_bias = P["w"].copy(), P["alpha_bias"].copy()
            v_slide, a_slide, Jv_slide = zero, zero, zeros
            if j.kind == "prismatic":
                Jv_slide = np.zeros(lead + (3, n))
                a_W = R_WJp @ jd["axis"]
                r_PJ = r_PJ + a_W * qj[..., :1]  # parent COM -> the child's joint point, slid
                v_slide = a_W * uj[..., :1]
                a_slide = 2.0 * spatial.cross(P["w"], v_slide)  # Coriolis: the axis turns with the parent
                Jv_slide[..., cols] = a_W[..., None]
            if j.kind == "revolute":
                s = R_WJp @ jd["axis"]
                Jw[..., cols] += s[..., None]
                w_rel = s * uj[..., :1]
                w += w_rel
                alpha_bias += spatial.cross(P["w"], w_rel)
            elif j.kind == "ball":
                Jw[..., cols] += R_WJc
                w_rel = _dot(R_WJc, uj)
                w += w_rel
                alpha_bias += spatial.cross(w, w_rel)
            out[j.child] = _child(P, R, r_PJ, r_JC, w, alpha_bias, Jw, Jv_slide, v_slide, a_slide)
        return out

    # -------------------------------------------------------------- dynamics
    def _solve(self, t, q, u):
        M, f, kin = self.mass_and_forces(t, q, u)
        return (_linear_solve(M, f) if self.nv else np.zeros(f.shape)), kin

    def mass_matrix(self, kin):
        """Kane's mass matrix ``M`` (nv, nv), or (m, nv, nv), at the configuration(s) of ``kin``
        (``kinematics``; each body's entry gains ``I_W``, its inertia about the COM in world axes, kg m^2)."""
        M = np.zeros(kin[WORLD]["p"].shape[:-1] + (self.nv, self.nv))
        for jd in self.joints:
            k = kin[jd["joint"].child]
            R, Jv, Jw = k["R"], k["Jv"], k["Jw"]
            k["I_W"] = I_W = R @ jd["I_B"] @ _T(R)
            M += jd["m"] * _T(Jv) @ Jv + _T(Jw) @ I_W @ Jw
        return M

    def mass_and_forces(self, t, q, u):
        """Kane's ``M u' = f``: ``M`` (nv, nv), ``f`` (nv,) and the ``kinematics`` (each body's
        entry gains ``F``, the resultant of its loads, springs and gravity, N, world); at m states at once
        (``q`` (m, nq), ``u`` (m, nv)), ``M`` (m, nv, nv), ``f`` (m, nv), ``F`` (m, 3)."""
        kin = self.kinematics(q, u)
        M, f = self.mass_matrix(kin), np.zeros(q.shape[:-1] + (self.nv,))
        wrenches = springs.wrenches if q.ndim == 1 else springs.wrenches_stacked
        spring_wrenches = wrenches(self.scene.springs, kin) if self.scene.springs else {}
        for jd in self.joints:
            k = kin[jd["joint"].child]
            m, I_W = jd["m"], k["I_W"]
            F, T = jd["loads"].resultant(k["R"])
            if jd["joint"].child in spring_wrenches:
                F_s, T_s = spring_wrenches[jd["joint"].child]
                F, T = F + F_s, T + T_s
            k["F"] = F
            f += _tdot(k["Jv"], F - m * k["a_bias"])  # generalized active + inertia forces
            f += _tdot(k["Jw"], T - _dot(I_W, k["alpha_bias"]) - spatial.cross(k["w"], _dot(I_W, k["w"])))
        return M, f, kin

    def _solve_stacked(self, Q, U):
        """``_solve`` at m states at once (``Q`` (m, nq), ``U`` (m, nv)): ``udot`` (m, nv) and the stacked
        kinematics; a formulation whose ``_solve`` is its own brings its own twin (``sampled``)."""
        return self._solve(None, Q, U)

    def acceleration(self, t, q, v):
        """Generalized accelerations ``u'`` (nv,) from ``Q + Q* = 0``."""
        return self._solve(t, q, v)[0]

    def reaction_forces(self, t, q, v):
        """Force each joint exerts ON its child (N, world axes), dict joint name -> (3,).

        Newton's law per body: ``m a = F_loads + F_joint - sum_children F_child_joint``.
        """
        return self._reactions(*self._solve(t, q, v))

    def _reactions(self, udot, kin):
        unbalanced = {}
        for jd in self.joints:
            k = kin[jd["joint"].child]
            unbalanced[jd["joint"].child] = jd["m"] * (_dot(k["Jv"], udot) + k["a_bias"]) - k["F"]
        return self.joint_forces(unbalanced)

    def joint_forces(self, unbalanced):
        """Newton's law per body, from the leaves back to the root: the force each joint exerts ON its child
        (N, world, dict joint name -> (3,)) when each body's ``m a - F`` (its force not balanced by the other
        loads, ``unbalanced``: dict body name -> (3,)) is carried by its joint and its children's joints."""
        out = {}
        for jd in reversed(self.joints):
            name = jd["joint"].child
            children = sum((out[c["joint"].child] for c in self.joints if c["joint"].parent == name), np.zeros(3))
            out[name] = unbalanced[name] + children
        return out

    # ------------------------------------------------------------ read-back
    def forces(self, udot, kin):
        """The forces read back at one state, from its ``_solve``: each joint's ON its child
        (``_reactions``; N, world, dict name -> (3,)); at m states, from ``_solve_stacked``, name -> (m, 3)."""
        return self._reactions(udot, kin)

    def _forces_stacked(self, udot, kin):
        """``forces`` at m states at once (a formulation with forces of its own adds them to its twin)."""
        return self.forces(udot, kin)

    def sampled(self, t, Q, V):
        """Each body's ``p``, ``R``, ``v``, ``w`` and the ``forces`` at the states ``(Q[i], V[i])`` at times
        ``t[i]`` (m,): two dicts, body name -> dict of (m, ...) arrays, force name -> (m, 3). At once
        (``_solve_stacked``) where the formulation's stacked solve is the twin of its ``_solve``."""
        owner = lambda name: next(c for c in type(self).__mro__ if name in vars(c))  # noqa: E731
        if owner("_solve") is not owner("_solve_stacked"):  # a solve of its own without its stacked twin
            return self.sampled_one_by_one(t, Q, V)
        with np.errstate(over="ignore", invalid="ignore"):  # the last finite samples of a blow-up: inf, NaN are data
            udot, kin = self._solve_stacked(Q, V)
            forces = self._forces_stacked(udot, kin)
        return {jd["joint"].child: kin[jd["joint"].child] for jd in self.joints}, forces

    def sampled_one_by_one(self, t, Q, V):
        """``sampled`` from one ``_solve`` per state (the integrators' path)."""
        m = len(t)
        bodies = {jd["joint"].child: {k: np.empty((m, 3)) for k in "pvw"} | {"R": np.empty((m, 3, 3))}
                  for jd in self.joints}
        forces = {name: np.empty((m, 3)) for name in self.force_names}
        for i in range(m):
            udot, kin = self._solve(t[i], Q[i], V[i])  # one solve gives poses and reactions
            for name, out in bodies.items():
                for key, arr in out.items():
                    arr[i] = kin[name][key]
            for name, f in self.forces(udot, kin).items():
                forces[name][i] = f
        return bodies, forces

    def trajectory(self, t, Q, V):
        """Sampled states as a ``Trajectory``: bodies, joints, and each non-free joint's ``forces`` as
        ``reaction_force:<name>`` (``sampled``; NaN at samples whose state is not finite)."""
        n = len(t)
        bodies = {jd["joint"].child: [np.full((n, 3), np.nan), np.full((n, 3, 3), np.nan), np.full((n, 3), np.nan),
                                      np.full((n, 3), np.nan)] for jd in self.joints}
        forces = {}
        finite = np.flatnonzero(np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1))
        if len(finite):
            kin, found = self.sampled(t[finite], Q[finite], V[finite])
            for name, arrs in bodies.items():
                for arr, key in zip(arrs, "pRvw"):
                    arr[finite] = kin[name][key]
            for name, f in found.items():
                forces[name] = np.full((n, 3), np.nan)
                forces[name][finite] = f
        for arrs in bodies.values():  # to quaternions at once (NaN where a sample was not finite)
            arrs[1] = spatial.matrix_to_quat(arrs[1])
        # A free joint's attitude is the stored quaternion itself (its norm drift is data).
        free = {jd["joint"].child for jd in self.joints if jd["joint"].kind == "free"}
        for jd in self.joints:
            if jd["joint"].child in free:
                bodies[jd["joint"].child][1] = Q[:, jd["q"]][:, 3:].copy()
        traj_bodies = {name: BodyStates(*arrs) for name, arrs in bodies.items()}
        joints = {jd["joint"].child: JointStates(Q[:, jd["q"]], V[:, jd["v"]]) for jd in self.joints}
        extras = {f"reaction_force:{name}": forces.get(name, np.full((n, 3), np.nan))
                  for name in self.force_names if name not in free}
        return Trajectory(t, traj_bodies, joints, extras)

    @property
    def force_names(self):
        """The names ``forces`` returns, in order: the joints' (by child)."""
        return [jd["joint"].child for jd in self.joints]
