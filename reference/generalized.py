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
moment about its COM). Poses, velocities and bias accelerations come from one recursive
pass from the root to the leaves (``tree_pass``, in scalar arithmetic: as numpy calls on 3-vectors it
ran in call overhead), which also gives each speed's motion: the axis ``omega`` it turns its joint's
subtree about, through the point ``o``, and the translation ``nu`` it gives. The Jacobians' columns
follow for every body at once, ``J_v[:, c] = nu_c + omega_c x (p_i - o_c)`` and ``J_w[:, c] =
omega_c`` where speed c moves body i, else 0; and ``M``, ``f`` as products of the bodies' stacked
Jacobians (6 nb, nv), not a sum over bodies. ``kinematics`` is ``velocities(positions(q), u)``, the configuration's
part (poses, Jacobians: the mass matrix's and a loop projection's) apart, so that one serves several evaluations.

A prismatic joint slides the child joint frame by ``d a_W`` along the unit axis ``a_W`` fixed in
the parent joint frame (no relative rotation): the lever from the parent's COM to the child's
joint point, ``r = r_PJ + d a_W``, gains the slide; the COM's partial velocity in ``d'`` is
``a_W``; and since ``a_W`` turns with the parent, ``d/dt (d' a_W) = d'' a_W + d' w_P x a_W`` while
the lever's transport ``w_P x r`` changes by ``w_P x (d' a_W)`` too: the bias acceleration gains
the Coriolis term ``2 w_P x (d' a_W)`` (the centripetal ``w_P x (w_P x r)`` uses the slid lever). Joint reaction forces follow from Newton's
law per body, from the leaves back to the root.

The read-back (``trajectory``) solves the same system at every sample at once (``_solve_stacked``:
the same code, each scalar of the pass an array over the samples, each table with a leading sample
axis), where the integrators call
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
from dalembert.reference.loads import BodyLoads, TreeLoads
from dalembert.reference import tree_pass
from dalembert.reference.tree_pass import ARRAY_MATH, FLOAT_MATH, Step

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


def _T(A):
    """The transpose of the last two axes: ``A.T`` of a matrix, each matrix's of a stack."""
    return A.swapaxes(-1, -2)


def _linear_solve(M, f):
    """``M^-1 f``: ``M`` (n, n), ``f`` (n,); or stacked (m, n, n), (m, n). One speed: the division LAPACK's solve
    does (the same numbers, measured on 20000 random systems), without its ~3 us of call overhead."""
    if f.shape[-1] == 1:
        return f / M[..., 0]
    return np.linalg.solve(M, f) if f.ndim == 1 else np.linalg.solve(M, f[..., None])[..., 0]


def _table(values, lead, width):
    """The scalars ``values`` (k * width of them: floats, or arrays of shape ``lead``) as an array (k, width), or
    (lead..., k, width): ``tree_pass``'s output in one allocation per table."""
    if not lead:
        return np.array(values, dtype=float).reshape(-1, width)
    flat = np.stack(np.broadcast_arrays(*values, np.empty(lead)))[:-1]  # (the last one: the shape, if no values)
    return np.moveaxis(flat.reshape((-1, width) + lead), (0, 1), (-2, -1))


def _skew9(x):
    """``skew(x)`` of a 3-tuple of scalars, row-major: ``skew(x) y = x cross y``."""
    return 0.0, -x[2], x[1], x[2], 0.0, -x[0], -x[1], x[0], 0.0


def _frozen(a):
    a.flags.writeable = False
    return a


# The world's and the joints' constant terms in ``kinematics``: one allocation each, shared by every call
# (read-only, so that sharing them cannot leak a write from one body's entry into another's).
_EYE3, _ZERO3 = _frozen(np.eye(3)), _frozen(np.zeros(3))
# Each body's entry in ``positions``; the ones ``velocities`` adds
_POSE_KEYS = ("R", "p", "Jv", "Jw")
_RATE_KEYS = ("w", "v", "a_bias", "alpha_bias")
_ALL_KEYS = _POSE_KEYS + _RATE_KEYS
# The key of ``kinematics``' stacked tables (a tuple: never a body name)
TREE = ("tree",)


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
        self._zeros = _frozen(np.zeros((3, iv)))  # (3, nv): the world's Jacobians
        # The pass's constants (``tree_pass``), and which speeds move which body: ``_moves[b, 0, c]`` when speed c
        # is one of body b's joint's or of its ancestors' up to the nearest free joint (whose coordinates are
        # the world's: ``tree_pass.positions``)
        slot = {WORLD: 0} | {jd["joint"].child: i + 1 for i, jd in enumerate(self.joints)}
        self._steps = [Step(jd["joint"].kind, slot[jd["joint"].parent], jd["q"].start, jd["v"].start, jd["R_PJ"],
                            jd["p_PJ"], jd["R_CJ"], jd["p_CJ"], jd["axis"]) for jd in self.joints]
        nb = len(self.joints)
        moves = np.zeros((nb + 1, iv), dtype=bool)
        for i, jd in enumerate(self.joints):
            if jd["joint"].kind != "free":
                moves[i + 1] = moves[slot[jd["joint"].parent]]
            moves[i + 1, jd["v"]] = True
        self._moves = _frozen(moves[1:, None, :])  # (nb, 1, nv)
        self._names = [jd["joint"].child for jd in self.joints]
        self._masses = np.array([jd["m"] for jd in self.joints], dtype=float).reshape(nb, 1)
        self._I_B = np.array([jd["I_B"] for jd in self.joints], dtype=float).reshape(nb, 3, 3)
        self._loads = TreeLoads(scene, [jd["body"] for jd in self.joints])
        self._children = {name: [c["joint"].child for c in self.joints if c["joint"].parent == name]
                          for name in self._names}

    # ------------------------------------------------------------ kinematics
    def kinematics(self, q, u):
        """Pose, velocity, Jacobians and bias accelerations of every body, world axes.

        ``q`` (nq,), ``u`` (nv,) for one state, or ``(m, nq)``, ``(m, nv)`` for m states at once: every entry
        then has a leading sample axis. Returns a dict per body name with ``R (3,3)``, ``p (3,)``,
        ``w (3,)``, ``v (3,)``, ``Jv (3, nv)``, ``Jw (3, nv)``, ``a_bias (3,)``, ``alpha_bias (3,)`` (views of
        the tables under ``TREE``: the same names, each body's along the axis -3 or -2).

        ``velocities(positions(q), u)`` in one piece (one table, one entry per body: the split's own assembly cost
        ~10% of a tree's right-hand side, ``benchmarks/reference_rhs.py``), the same numbers to the last bit.
        """
        fns = ARRAY_MATH if q.ndim > 1 else FLOAT_MATH
        poses, motions, links = tree_pass.positions(self._steps, self._scalars(q), fns)
        states = tree_pass.velocities(self._steps, links, self._scalars(u))
        return self._assemble(q.shape[:-1], poses, motions, links, states)

    def positions(self, q):
        """The configuration's part of ``kinematics``: every body's ``R``, ``p``, ``Jv``, ``Jw`` (and ``TREE``'s
        ``R``, ``p``, ``J``, ``Jv``, ``Jw``), shapes as ``kinematics``'; what ``mass_matrix`` and a projection onto
        loop closures need, and ``velocities``' input (``TREE``'s ``links``: the pass's per-joint terms)."""
        fns = ARRAY_MATH if q.ndim > 1 else FLOAT_MATH
        return self._assemble(q.shape[:-1], *tree_pass.positions(self._steps, self._scalars(q), fns))

    def velocities(self, pos, u):
        """``kinematics`` at the configuration of ``pos`` (``positions``, left as it is: it may serve again) and the
        speeds ``u`` (nv,), or (m, nv) where ``pos`` is at m configurations: new dicts, ``pos``' arrays shared."""
        lead, nb = u.shape[:-1], len(self.joints)
        states = tree_pass.velocities(self._steps, pos[TREE]["links"], self._scalars(u))
        body = [x for w, v, a, al in states for x in (*v, *a, *al, *w, *_skew9(w))]
        body = _table(body, lead, 21) if lead else np.array(body, dtype=float).reshape(nb, 21)
        tree = {k: x for k, x in pos[TREE].items() if k != "I_W"}  # (mass_matrix adds I_W where it is asked)
        self._rates(tree, body, 0, lead)
        zero = pos[WORLD]["p"]
        out = {WORLD: dict(pos[WORLD], w=zero, v=zero, a_bias=zero, alpha_bias=zero), TREE: tree}
        each = self._each(tree, _RATE_KEYS, lead)
        for i, name in enumerate(self._names):
            out[name] = {**pos[name], **{k: x[i] for k, x in each}}
        return out

    @staticmethod
    def _scalars(x):
        """The pass's scalars: ``x`` (n,) as n floats, or (m, n) as n arrays (m,)."""
        return list(np.moveaxis(x, -1, 0)) if x.ndim > 1 else x.tolist()

    @staticmethod
    def _each(tree, keys, lead):
        """``tree``'s tables under ``keys``, body first (each body's entries: their views)."""
        return [(k, np.moveaxis(tree[k], len(lead), 0) if lead else tree[k]) for k in keys]

    def _rates(self, tree, body, o, lead):
        """``tree``'s velocity tables from ``body``'s columns from ``o`` on: v, a_bias, alpha_bias, w, skew(w)."""
        tree.update(v=body[..., o:o + 3], a_bias=body[..., o + 3:o + 6], alpha_bias=body[..., o + 6:o + 9],
                    w=body[..., o + 9:o + 12])
        # (mass_and_forces: I_W alpha, I_W w at once)
        tree["alpha_w"] = body[..., o + 6:o + 12].reshape(lead + (len(self.joints), 2, 3))
        tree["skew_w"] = body[..., o + 12:o + 21].reshape(lead + (len(self.joints), 3, 3))

    def _assemble(self, lead, poses, motions, links, states=None):
        """``positions``' dicts from the pass (``tree_pass.positions``'), or with its ``states`` (``velocities``')
        ``kinematics``'.

        Each body's pose (and velocities) and each speed's motion ``(omega, nu, o)`` as tables; the Jacobians'
        columns follow at once: speed c moves body b's COM at ``nu_c + omega_c x (p_b - o_c)`` and turns it at
        ``omega_c`` where c is its joint's or an ancestor's (``_moves``), else 0.
        """
        n, nb = self.nv, len(self.joints)
        if lead:
            zero, zeros, eye = np.zeros(lead + (3,)), np.zeros(lead + (3, n)), np.broadcast_to(_EYE3, lead + (3, 3))
        else:
            zero, zeros, eye = _ZERO3, self._zeros, _EYE3
        # each body's R, p (and v, a_bias, alpha_bias, w and skew(w)); each speed's omega, nu, o and skew(omega)
        if states is None:
            body, width = [x for R, p in poses for x in (*R, *p)], 12
        else:
            body = [x for (R, p), (w, v, a, al) in zip(poses, states) for x in (*R, *p, *v, *a, *al, *w, *_skew9(w))]
            width = 33
        cols = [x for om, nu, o in motions for x in (*om, *nu, *o, *_skew9(om))]
        if lead:
            body, cols = _table(body, lead, width), _table(cols, lead, 18)
        else:  # (one conversion)
            flat = np.array(body + cols, dtype=float)
            body, cols = flat[:width * nb].reshape(nb, width), flat[width * nb:].reshape(n, 18)
        p = body[..., 9:12]
        lever = _T(p)[..., None, :, :] - cols[..., 6:9, None]  # (..., nv, 3, nb): o_c -> p_b
        Jv = cols[..., 3:6, None] + cols[..., 9:18].reshape(lead + (n, 3, 3)) @ lever  # (..., nv, 3, nb)
        # Jv (rows 0-2) and Jw (rows 3-5) of each body in one table (mass_and_forces: M and f in one product each)
        J = np.zeros(lead + (nb, 6, n))
        np.copyto(J[..., 0:3, :], np.swapaxes(Jv, -1, -3), where=self._moves)
        np.copyto(J[..., 3:6, :], _T(cols[..., 0:3])[..., None, :, :], where=self._moves)
        tree = dict(R=body[..., 0:9].reshape(lead + (nb, 3, 3)), p=p, Jv=J[..., 0:3, :], Jw=J[..., 3:6, :], J=J,
                    links=links)
        world, keys = dict(R=eye, p=zero, Jv=zeros, Jw=zeros), _POSE_KEYS
        if states is not None:  # the velocities' columns after the pose's 12, laid out as ``velocities``' own table
            self._rates(tree, body, 12, lead)
            world.update(w=zero, v=zero, a_bias=zero, alpha_bias=zero)
            keys = _ALL_KEYS
        out = {WORLD: world, TREE: tree}
        each = self._each(tree, keys, lead)
        for i, name in enumerate(self._names):
            out[name] = {k: x[i] for k, x in each}
        return out

    # -------------------------------------------------------------- dynamics
    def _solve(self, t, q, u):
        M, f, kin = self.mass_and_forces(t, q, u)
        return (_linear_solve(M, f) if self.nv else np.zeros(f.shape)), kin

    def mass_matrix(self, kin):
        """Kane's mass matrix ``M`` (nv, nv), or (m, nv, nv), at the configuration(s) of ``kin``
        (``kinematics``; its ``TREE`` tables gain ``I_W`` (..., nb, 3, 3), each body's inertia about its COM in
        world axes, kg m^2): ``sum_b m_b Jv_b^T Jv_b + Jw_b^T I_W,b Jw_b`` as one product of the bodies'
        stacked Jacobians (..., 6 nb, nv)."""
        tree = kin[TREE]
        R, J = tree["R"], tree["J"]
        tree["I_W"] = I_W = R @ self._I_B @ _T(R)
        weighted = np.empty(J.shape)  # (..., nb, 6, nv): m Jv, I_W Jw
        np.multiply(self._masses[:, :, None], J[..., 0:3, :], out=weighted[..., 0:3, :])
        np.matmul(I_W, J[..., 3:6, :], out=weighted[..., 3:6, :])
        flat = J.shape[:-3] + (-1, self.nv)
        return _T(J.reshape(flat)) @ weighted.reshape(flat)

    def mass_and_forces(self, t, q, u, kin=None):
        """Kane's ``M u' = f``: ``M`` (nv, nv), ``f`` (nv,) and the ``kinematics`` (each body's
        entry gains ``F``, the resultant of its loads, springs and gravity, N, world); at m states at once
        (``q`` (m, nq), ``u`` (m, nv)), ``M`` (m, nv, nv), ``f`` (m, nv), ``F`` (m, 3). ``kin``: the
        ``kinematics`` at ``(q, u)`` where the caller has them (``loops``: from its projection's positions)."""
        kin = self.kinematics(q, u) if kin is None else kin
        M = self.mass_matrix(kin)
        tree = kin[TREE]
        F, T = self._loads.resultant(tree["R"])  # (..., nb, 3) each, new arrays
        if self.scene.springs:
            wrenches = springs.wrenches if q.ndim == 1 else springs.wrenches_stacked
            for name, (F_s, T_s) in wrenches(self.scene.springs, kin).items():
                i = self._names.index(name)
                F[..., i, :] += F_s
                T[..., i, :] += T_s
        I_alpha_w = tree["I_W"] @ _T(tree["alpha_w"])  # (..., nb, 3, 2): I_W alpha, I_W w
        # generalized active + inertia forces: sum_b Jv_b^T (F_b - m_b a_b) + Jw_b^T (T_b - I_b alpha_b - w_b x I_b w_b)
        gh = np.empty(F.shape[:-1] + (6,))
        np.subtract(F, self._masses * tree["a_bias"], out=gh[..., 0:3])
        np.subtract(T - I_alpha_w[..., 0], (tree["skew_w"] @ I_alpha_w[..., 1:])[..., 0], out=gh[..., 3:6])
        lead = q.shape[:-1]
        f = _tdot(tree["J"].reshape(lead + (-1, self.nv)), gh.reshape(lead + (-1,)))
        for i, name in enumerate(self._names):
            kin[name]["F"] = F[..., i, :]
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
            children = sum((out[c] for c in self._children[name]), np.zeros(3))
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
