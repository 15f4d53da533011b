"""A scene as a Pinocchio model: ``PinocchioModel``.

* A FreeFlyer for each free body, whose joint frame is the body frame at the
  COM; a revolute (``JointModelRevoluteUnaligned``), prismatic
  (``JointModelPrismaticUnaligned``) or spherical joint whose frame is the
  scene's child joint frame, placed in the parent's joint frame (the scene's
  axis, unit, in that frame: Pinocchio's unaligned joints take it as it is, so
  the joint frame stays the scene's and no alignment rotation enters the
  placements, the read-back or the reactions' frame);
  a weld adds the body to its parent's joint (option ``welds=tree``) or gets a
  FreeFlyer of its own held by a 6D constraint (``welds=constraint``). Each
  body's inertia is ``pin.Inertia(mass, lever, I_com)`` in its joint frame
  (Pinocchio applies the parallel-axis shift), and an operational frame marks
  the scene body frame.
* Loop closures: 3D ``RigidConstraintModel``s between the joints that carry the two bodies
  (``loops``), solved with the welds' by ``pin.constraintDynamics``.
* Spring-dampers: an operational frame at each end and external forces at every evaluation
  (``springs``: Pinocchio has no spring element).
* ``model.gravity`` is set from the scene — Pinocchio defaults to -9.81 in z,
  so a scene without gravity gets zero explicitly.

Conventions (converted only through ``dalembert.spatial``): FreeFlyer
``q = (x, y, z, qx, qy, qz, qw)`` (scalar LAST) and ``v = (v_local, w_local)``
(linear velocity of the joint origin in the joint frame); spherical ``q`` is
scalar-last too. External forces enter ``aba``/``rnea`` per joint in the
joint's LOCAL frame (E) about its origin: a load ``f`` at point ``p`` becomes
``(f, p x f)``; world-frame loads are rotated into the local frame at every
evaluation from ``data.oMi`` (refreshed by ``forwardKinematics``: ``aba``
does not update it for us).
"""

from __future__ import annotations

import numpy as np

from dalembert import closure, spatial
from dalembert.lstsq import svd_cut
from dalembert.adapters.pinocchio import springs
from dalembert.scene import AXIS_KINDS, WORLD

__all__ = ["PinocchioModel", "WELDS", "depth_first_order"]

# Welds: merged into the parent's joint (``tree``, exact), or 6D constraints between free
# flyers solved by ``pin.constraintDynamics`` (``constraint``).
WELDS = ("tree", "constraint")
# The joints built here whose configuration space is a vector space (``integrate(q, v) = q + v``), so
# ``dexp^-1`` is the identity: a model of these only needs no ``dIntegrate`` solve (``dexpinv_kind``).
VECTOR_SPACE_JOINTS = ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned")


def _se3(R, p):
    import pinocchio as pin

    return pin.SE3(np.asarray(R, dtype=float), np.asarray(p, dtype=float))


def _joint_model(joint):
    """The ``pin.JointModel*`` of a revolute, prismatic or ball ``joint``: the unaligned revolute and prismatic
    joints take the scene's axis (unit, in the joint frame) as it is."""
    import pinocchio as pin

    if joint.kind == "ball":
        return pin.JointModelSpherical()
    axis = np.asarray(joint.axis, dtype=float) / np.linalg.norm(joint.axis)
    return (pin.JointModelRevoluteUnaligned if joint.kind == "revolute" else pin.JointModelPrismaticUnaligned)(axis)


def depth_first_order(scene):
    """The scene's bodies, each subtree after its root and contiguous (siblings in ``scene.joints`` order).

    Pinocchio's ``crba``, its Cholesky and ``constraintDynamics`` take a subtree's velocity indices to be
    contiguous (``model.nvSubtree``); a parents-first order that is not depth-first (the four-bar's
    crank, rocker, coupler) gives a wrong mass matrix there (the crank-coupler coupling lands on the
    rocker: measured, ``crba`` and ``constraintDynamics`` against the reference's), while ``aba`` does
    not notice."""
    children = {}
    for j in scene.joints:
        children.setdefault(j.parent, []).append(j.child)
    order, stack = [], list(reversed(children.get(WORLD, [])))
    while stack:
        name = stack.pop()
        order.append(scene.body(name))
        stack.extend(reversed(children.get(name, [])))
    return order


class PinocchioModel:
    """A scene as a ``pin.Model`` plus the maps the adapter needs: per body, ``carrier`` (the
    joint that carries it), ``X_EB`` (its scene frame B in that joint's frame E, ``pin.SE3``;
    ``dalembert.adapters.base``), ``joint_ids`` (its own joint, if it has one) and
    ``frame_ids`` (the operational frame at B).

    ``welds="constraint"``: a welded body gets its own FreeFlyer, held to its parent by a 6D
    ``RigidConstraintModel``, and the dynamics is ``pin.constraintDynamics`` (no Baumgarte
    correction: the constraints are met at the acceleration level, so what drift the
    integrator leaves shows in the pairwise distances).

    Loop closures (``scene.loops``) add 3D ``RigidConstraintModel``s (``loops``: their placement,
    regularisation and Baumgarte correction), and the dynamics is ``pin.constraintDynamics``
    with the loads as joint torques (``load_torques``). ``cmodels``/``cdatas`` hold every
    constraint, welds first; ``loop_contacts`` says which are each loop's.
    """

    def __init__(self, scene, welds="tree"):
        import pinocchio as pin

        self.scene = scene
        self.constraints = []  # (parent joint, placement in it, child joint, placement in it)
        model = pin.Model()
        model.gravity = pin.Motion(np.array(scene.gravity, dtype=float), np.zeros(3))
        self.carrier, self.X_EB, self.joint_ids = {}, {}, {}
        lines = []
        for body in depth_first_order(scene):
            j = scene.joint(body.name)
            if j.parent == WORLD:
                parent_id, X_EpP = 0, _se3(np.eye(3), np.zeros(3))
            else:
                parent_id, X_EpP = self.carrier[j.parent], self.X_EB[j.parent]
            X_PJ = _se3(spatial.quat_to_matrix(j.parent_quat), j.parent_point)  # Jp in parent body coords
            X_CJ = _se3(spatial.quat_to_matrix(j.child_quat), j.child_point)  # Jc in child body coords
            if j.kind == "free" or (j.kind == "weld" and welds == "constraint"):
                jid = model.addJoint(0, pin.JointModelFreeFlyer(), _se3(np.eye(3), np.zeros(3)), body.name)
                X_EB = _se3(np.eye(3), np.zeros(3))
                if j.kind == "weld":  # the weld frame, in the parent's joint frame and in the child's (= body)
                    self.constraints.append((parent_id, X_EpP * X_PJ, jid, X_CJ))
            elif j.kind in ("revolute", "prismatic", "ball"):
                jm = _joint_model(j)
                jid = model.addJoint(parent_id, jm, X_EpP * X_PJ, body.name)
                X_EB = X_CJ.inverse()
            else:  # weld: rigidly on the parent's joint
                jid = parent_id
                X_EB = X_EpP * X_PJ * X_CJ.inverse()
            if j.kind != "weld" or welds == "constraint":
                self.joint_ids[body.name] = jid
            self.carrier[body.name], self.X_EB[body.name] = jid, X_EB
            R, p = X_EB.rotation, X_EB.translation
            model.appendBodyToJoint(jid, pin.Inertia(body.mass, p, R @ body.inertia_matrix @ R.T),
                                    _se3(np.eye(3), np.zeros(3)))
            model.addFrame(pin.Frame(body.name, jid, X_EB, pin.FrameType.OP_FRAME))
            axis = (f", axis {np.round(model.joints[jid].extract().axis, 12).tolist()} (joint frame)"
                    if j.kind in AXIS_KINDS else "")  # read back from the built joint
            lines.append(f"{body.name}: {j.kind} -> pin joint {jid} "
                         f"({model.joints[jid].shortname() if jid else 'universe'}{axis}), mass {body.mass:g} kg")
        self.springs = springs.build(self, model)  # frames at the ends: before createData
        for el in self.springs:
            lines.append(f"spring {el.name!r}: external forces between frames {model.frames[el.frame_a].name!r} "
                         f"(joint {el.joint_a}) and {model.frames[el.frame_b].name!r} (joint {el.joint_b}), "
                         f"k = {el.stiffness:g} N/m, c = {el.damping:g} N s/m, l0 = {el.rest_length:g} m")
        self.model = model
        self.data = model.createData()
        self.cmodels = self.cdatas = self.prox = None
        self.loop_contacts = []  # per loop: its contacts' indices in cmodels (loops.LoopContacts)
        self.mu = 0.0
        if self.constraints or scene.loops:
            self._build_constraints(lines)
        self.frame_ids = {b.name: model.getFrameId(b.name) for b in scene.bodies}
        self.summary = "\n".join([f"pin.Model: nq = {model.nq}, nv = {model.nv}, gravity = "
                                  f"{model.gravity.linear.tolist()}"] + lines)
        self._prepare_loads()

    def _build_constraints(self, lines):
        """The welds' 6D and the loops' 3D ``RigidConstraintModel``s, their data, and the proximal
        settings (``loops``): Pinocchio's defaults (``mu = 0``, one iteration: the exact Cholesky) for
        welds alone, which are never redundant; the loops' regularisation when there are loops."""
        import pinocchio as pin

        from dalembert.adapters.pinocchio import loops

        model = self.model
        self.cmodels = pin.StdVec_RigidConstraintModel()
        for j1, X1, j2, X2 in self.constraints:
            self.cmodels.append(pin.RigidConstraintModel(pin.ContactType.CONTACT_6D, model, j1, X1, j2, X2,
                                                         pin.ReferenceFrame.LOCAL))
        found, self.loop_contacts = loops.loop_contacts(self, len(self.cmodels))
        for cm in found:
            self.cmodels.append(cm)
        self.cdatas = pin.StdVec_RigidConstraintData()
        for cm in self.cmodels:
            self.cdatas.append(cm.createData())
        pin.initConstraintDynamics(model, self.data, self.cmodels, self.cdatas)
        if self.constraints:
            lines.append(f"{len(self.constraints)} weld(s) as 6D RigidConstraintModels (pin.constraintDynamics)")
        if self.loop_contacts:
            self.mu = loops.PROXIMAL_MU_REL * self.delassus_scale(*self.initial_state())
            self.prox = loops.proximal_settings(self.mu)
            Kp, Kd = loops.baumgarte()
            for lc in self.loop_contacts:
                lp = lc.loop
                lines.append(f"loop {lp.name!r} ({lp.kind} {lp.body_a} -> {lp.body_b}): {len(lc.indices)} CONTACT_3D"
                             + (f" (at the point and {lc.lever:g} m along the axis)" if lp.kind == "revolute" else ""))
            lines.append(f"constraintDynamics: proximal mu = {self.mu:.3g}, {loops.PROXIMAL_ITERATIONS} iterations; "
                         f"Baumgarte Kp = {Kp:g} 1/s^2, Kd = {Kd:g} 1/s on the loops")
        else:
            self.prox = pin.ProximalSettings()

    def delassus_scale(self, q, v):
        """The largest eigenvalue of the Delassus operator ``J M^-1 J^T`` of every constraint at ``q``
        (1/kg for point rows): the scale the loops' regularisation is relative to."""
        import pinocchio as pin

        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T  # crba fills the upper triangle
        for cm, cd in zip(self.cmodels, self.cdatas):
            cm.calc(model, data, cd)
        J = pin.getConstraintsJacobian(model, data, self.cmodels, self.cdatas)
        return float(np.linalg.eigvalsh(J @ np.linalg.solve(M, J.T)).max())

    @property
    def constrained(self):
        """True when the dynamics is ``pin.constraintDynamics`` (welds as constraints, or loops)."""
        return self.cmodels is not None

    def constraint_readout(self, q):
        """What the last ``constraintDynamics`` at ``q`` left for the read-back: ``lam (rows,)``, every constraint's
        multipliers concatenated ((3,) N for a 3D contact, (6,) force and moment for a 6D one, in the frame c1 of
        joint1's placement, acting on joint1: ``loops``); ``R_Wc1 (n_constraints, 3, 3)``, those frames in world
        axes; and, with loops, the constraints' Jacobian ``J (rows, nv)`` at ``q`` (``minimum_norm``'s), else None."""
        import pinocchio as pin

        lam = np.concatenate([cd.contact_force.linear if cm.type == pin.ContactType.CONTACT_3D
                              else cd.contact_force.vector for cm, cd in zip(self.cmodels, self.cdatas)])
        R_Wc1 = np.array([cd.oMc1.rotation for cd in self.cdatas])
        J = None
        if self.loop_contacts:
            pin.computeJointJacobians(self.model, self.data, q)
            J = pin.getConstraintsJacobian(self.model, self.data, self.cmodels, self.cdatas)
        return lam, R_Wc1, J

    def minimum_norm(self, J, lam):
        """The minimum-norm multipliers with the same generalized force ``J^T lambda``, at m states at once:
        ``J (m, rows, nv)``, ``lam (m, rows)`` (``constraint_readout``'s) -> ``(m, rows)``.

        With loops, the part in the null space of ``J^T`` moves nothing, and the proximal iterations grow roundoff
        there by ``1/mu`` per iteration (measured: 4e-6 N out of the four-bar's plane, where the truth has 1e-14);
        the reference reads back the same minimum-norm multipliers (``reference.loops``): ``lam`` projected on the
        range of ``J``, each state's singular values at or below ``closure.RANK_RTOL`` of its largest cut."""
        U = svd_cut(J, closure.RANK_RTOL)[0]
        return np.einsum("mik,mk->mi", U, np.einsum("mik,mi->mk", U, lam))

    def constraint_forces(self, lam, R_Wc1):
        """Each constraint's force on joint1's side (N, world), ``R_Wc1 lambda`` (a 6D one's force part), at m
        states: ``lam (m, rows)``, ``R_Wc1 (m, n_constraints, 3, 3)`` -> ``(m, n_constraints, 3)``; joint2's side
        gets its opposite (``loops``)."""
        import pinocchio as pin

        starts = np.cumsum([0] + [3 if cm.type == pin.ContactType.CONTACT_3D else 6 for cm in self.cmodels])[:-1]
        return np.einsum("mcij,mcj->mci", R_Wc1, np.stack([lam[:, i:i + 3] for i in starts], axis=1))

    def carried_by(self, joint_ids):
        """``S (len(joint_ids), n_constraints)``: +1 where a constraint's joint1 lies in the joint's subtree, -1
        where its joint2 does (0 where both or neither): a tree joint's reaction force (world, on its child) holds
        ``-S @ f`` of the constraints' forces ``f`` (``constraint_forces``) beyond ``rnea``'s without them, as
        ``rnea`` subtracts external forces on a subtree from the force through the joint above it (the force's
        linear part is the same wherever it acts)."""
        supports = [set(self.model.supports[j]) for j in range(self.model.njoints)]

        def below(j, jid):
            return jid > 0 and j in supports[jid]

        return np.array([[below(j, cm.joint1_id) - below(j, cm.joint2_id) for cm in self.cmodels]
                         for j in joint_ids], dtype=float).reshape(len(joint_ids), len(self.cmodels))

    # ---------------------------------------------------------------- loads
    def _prepare_loads(self):
        import pinocchio as pin

        model = self.model
        self.const_f = {}  # joint id -> constant local spatial force (follower loads)
        self.world_loads = []  # (joint id, point in E, force_W or None, torque_W or None)
        for ld in self.scene.loads:
            jid = self.carrier[ld.body]
            X_EB = self.X_EB[ld.body]
            p_E = X_EB.rotation @ np.array(ld.point) + X_EB.translation
            vec = np.array(ld.vector)
            if ld.frame == "body":
                v_E = X_EB.rotation @ vec
                f = pin.Force(v_E, np.cross(p_E, v_E)) if ld.kind == "force" else pin.Force(np.zeros(3), v_E)
                self.const_f[jid] = self.const_f.get(jid, pin.Force.Zero()) + f
            else:
                self.world_loads.append((jid, p_E, vec if ld.kind == "force" else None,
                                         vec if ld.kind == "torque" else None))
        self.has_loads = bool(self.scene.loads)
        self.has_forces = self.has_loads or bool(self.springs)  # external forces at every evaluation
        self.fext = pin.StdVec_Force()
        for _ in range(model.njoints):
            self.fext.append(pin.Force.Zero())
        self.tau = np.zeros(model.nv)

    def external_forces(self, q, v=None, spring_elements=None):
        """Per-joint local forces for ``aba``/``rnea`` at ``(q, v)`` (``pin.StdVec_Force``, reused): the
        loads and the springs (``spring_elements``, default every one; ``v`` (nv,) is needed when there are
        any: the dampers act on the rate)."""
        import pinocchio as pin

        elements = self.springs if spring_elements is None else spring_elements
        if elements:
            if v is None:
                raise ValueError("PinocchioModel.external_forces: v is None — the springs need the velocities")
            pin.forwardKinematics(self.model, self.data, q, v)
        elif self.world_loads:
            pin.forwardKinematics(self.model, self.data, q)
        for i in range(self.model.njoints):
            self.fext[i] = self.const_f.get(i, pin.Force.Zero())
        for jid, p_E, f_W, t_W in self.world_loads:
            R_WE = self.data.oMi[jid].rotation
            if f_W is not None:
                f_E = R_WE.T @ f_W
                self.fext[jid] = self.fext[jid] + pin.Force(f_E, spatial.cross(p_E, f_E))
            else:
                self.fext[jid] = self.fext[jid] + pin.Force(np.zeros(3), R_WE.T @ t_W)
        springs.add_forces(elements, self.data, self.fext)
        return self.fext

    def load_torques(self, q, v, spring_elements=None):
        """The loads' and springs' (``external_forces``) generalized forces ``sum J_i^T f_i`` (nv,) at ``(q, v)``:
        ``constraintDynamics`` takes no external forces, only ``tau``; ``rnea`` with them subtracts exactly this
        from ``nle``."""
        import pinocchio as pin

        fext = self.external_forces(q, v, spring_elements)
        return (pin.nonLinearEffects(self.model, self.data, q, v)
                - pin.rnea(self.model, self.data, q, v, np.zeros(self.model.nv), fext))

    def acceleration(self, q, v):
        import pinocchio as pin

        if self.constrained:
            tau = self.load_torques(q, v) if self.has_forces else self.tau
            return pin.constraintDynamics(self.model, self.data, q, v, tau, self.cmodels, self.cdatas, self.prox)
        if self.has_forces:
            return pin.aba(self.model, self.data, q, v, self.tau, self.external_forces(q, v))
        return pin.aba(self.model, self.data, q, v, self.tau)

    def acceleration_function(self):
        """``acc(q, v)`` with the fewest Python calls: the external forces are built once
        when they do not depend on the state (no world-frame loads, no springs)."""
        import pinocchio as pin

        aba, model, data, tau = pin.aba, self.model, self.data, self.tau
        if self.constrained:
            return self.acceleration
        if not self.has_forces:
            return lambda q, v: aba(model, data, q, v, tau)
        if not self.world_loads and not self.springs:
            fext = self.external_forces(None)  # follower loads only: constant in the joint frames
            return lambda q, v: aba(model, data, q, v, tau, fext)
        return self.acceleration

    def dexpinv_kind(self):
        """0: the configuration space is a vector space (only revolute and prismatic joints); 2: the
        ``dIntegrate`` solve; 3: several FreeFlyers and nothing else (the same solve, block by
        block) — see ``dexpinv_function``. The compiled loop takes 0 and 2."""
        names = [self.model.joints[i].shortname() for i in range(1, self.model.njoints)]
        if all(n in VECTOR_SPACE_JOINTS for n in names):
            return 0
        return 3 if len(names) > 1 and all(n == "JointModelFreeFlyer" for n in names) else 2

    def dexpinv_function(self):
        """``dexpinv(q, theta, vel)``: the tangent ``theta'`` of ``q (+) theta`` moving with
        velocity ``vel`` — ``dIntegrate(q, theta, ARG1)^-1 vel`` — or None where it is ``vel``
        (only revolute and prismatic joints: the configuration space is a vector space).

        Always the solve: Pinocchio's closed-form inverse, ``Jlog6(exp6(theta))``, is off by up
        to 5e-9 for rotations of 1e-4 to 1e-3 rad (measured against the solve, which agrees with
        the series of dexp^-1 ~15x better there) — a step's stage rotations on slow bodies. With
        FreeFlyers only, ``dIntegrate`` is block diagonal: 6 x 6 solves in one batched call.
        """
        import pinocchio as pin

        model, kind = self.model, self.dexpinv_kind()
        if kind == 0:
            return None
        dIntegrate, ARG1, solve = pin.dIntegrate, pin.ArgumentPosition.ARG1, np.linalg.solve
        if kind == 3:
            n = model.nv // 6
            diag = np.arange(n)

            def per_block(q, theta, vel):
                J = dIntegrate(model, q, theta, ARG1).reshape(n, 6, n, 6)[diag, :, diag, :]  # (n, 6, 6)
                return solve(J, vel.reshape(n, 6, 1)).ravel()
            return per_block
        return lambda q, theta, vel: solve(dIntegrate(model, q, theta, ARG1), vel)

    # ---------------------------------------------------------- conversions
    def initial_state(self):
        import pinocchio as pin

        q, v = pin.neutral(self.model), np.zeros(self.model.nv)
        state0 = spatial.initial_body_states(self.scene) if self.constraints else {}
        for j in self.scene.joints:
            if j.kind == "weld" and not self.constraints:
                continue
            jm = self.model.joints[self.joint_ids[j.child]]
            iq, iv = jm.idx_q, jm.idx_v
            if j.kind == "weld":  # a FreeFlyer at the body's initial state, velocities local
                s0 = state0[j.child]
                q[iq:iq + 7] = np.concatenate([s0["p"], spatial.wxyz_to_xyzw(spatial.matrix_to_quat(s0["R"]))])
                v[iv:iv + 6] = np.concatenate([s0["R"].T @ s0["v"], s0["R"].T @ s0["w"]])
            elif j.kind == "free":
                R = spatial.quat_to_matrix(j.q0[3:])
                q[iq:iq + 7] = np.concatenate([j.q0[:3], spatial.wxyz_to_xyzw(j.q0[3:])])
                v[iv:iv + 6] = np.concatenate([R.T @ np.array(j.v0[:3]), j.v0[3:]])
            elif j.kind == "ball":
                q[iq:iq + 4] = spatial.wxyz_to_xyzw(j.q0)
                v[iv:iv + 3] = j.v0
            else:
                q[iq], v[iv] = j.q0[0], j.v0[0]
        return q, v
