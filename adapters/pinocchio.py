"""Pinocchio adapter: the scene through Pinocchio's dynamics (ABA, RNEA), with
the integrators owned here — so their quality is part of what is measured.

Model (built programmatically, summarized by ``describe``):

* A FreeFlyer for each free body, whose joint frame is the body frame at the
  COM; a revolute (``JointModelRevoluteUnaligned``) or spherical joint whose
  frame is the scene's child joint frame, placed in the parent's joint frame;
  a weld adds the body to its parent's joint. Each body's inertia is
  ``pin.Inertia(mass, lever, I_com)`` in its joint frame (Pinocchio applies the
  parallel-axis shift), and an operational frame marks the scene body frame.
* ``model.gravity`` is set from the scene — Pinocchio defaults to -9.81 in z,
  so a scene without gravity gets zero explicitly.

Conventions (converted only through ``dalembert.spatial``): FreeFlyer
``q = (x, y, z, qx, qy, qz, qw)`` (scalar LAST) and ``v = (v_local, w_local)``
(linear velocity of the joint origin in the joint frame); spherical ``q`` is
scalar-last too. External forces enter ``aba``/``rnea`` per joint in the
joint's LOCAL frame about its origin: a load ``f`` at point ``p`` becomes
``(f, p x f)``; world-frame loads are rotated into the local frame at every
evaluation from ``data.oMi`` (refreshed by ``forwardKinematics``: ``aba``
does not update it for us).

Integrators, each evaluating the loads at every stage:

* ``euler``: semi-implicit (symplectic) Euler on the group;
* ``rk4``: Runge-Kutta-Munthe-Kaas with the classical tableau, the stage
  tangents corrected by the exact ``dexp^-1`` — Pinocchio's own
  ``dIntegrate(q, theta, ARG1)`` is the right Jacobian of ``integrate``, so
  ``theta' = dIntegrate^-1 v`` — and the configuration advanced by
  ``pin.integrate``. Fourth order on the group;
* ``rk4-naive``: RK4 on ``v`` with ``q`` advanced stagewise by
  ``integrate(q, c h v_i)`` and no ``dexp^-1`` correction (lower order on a
  non-commutative group: kept because the difference is a result);
* ``rk45``, ``dop853``: scipy ``solve_ivp`` in local coordinates
  ``q = integrate(q_k, delta)`` restarted at every sample ``q_k``: the state
  ``(delta, v)`` has no redundant component, so error control is not fooled by
  the quaternion's unit-norm constraint, and the quaternion never drifts.

The fixed-step loops run compiled (``pinocchio_stepper.cpp`` through
``pinocchio_native``: the same integrators and loads against the installed
Pinocchio, no Python call per step), or in Python with ``--option loop=python``
and wherever the compiled loop cannot be built (the audit says which ran).
"""

from __future__ import annotations

import time

import numpy as np

from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, option_choice
from dalembert import spatial
from dalembert.scene import EFFECTS, WORLD
from dalembert.settings import is_numerical_failure, steps_per_interval
from dalembert.stepping import march

__all__ = ["PinocchioAdapter"]

# Fixed-step loops: compiled (adapters/pinocchio_stepper.cpp, the default) or the Python one
# (the same integrators, kept as the readable specification and the fallback).
LOOPS = ("native", "python")
STAGES = {"euler": 1, "rk4": 4, "rk4-naive": 4}  # right-hand-side evaluations per fixed step
# Welds: merged into the parent's joint (``tree``, exact), or 6D constraints between free
# flyers solved by ``pin.constraintDynamics`` (``constraint``).
WELDS = ("tree", "constraint")


def _se3(R, p):
    import pinocchio as pin

    return pin.SE3(np.asarray(R, dtype=float), np.asarray(p, dtype=float))


class PinocchioModel:
    """A scene as a ``pin.Model`` plus the maps the adapter needs.

    ``welds="constraint"``: a welded body gets its own FreeFlyer, held to its parent by a 6D
    ``RigidConstraintModel``, and the dynamics is ``pin.constraintDynamics`` (no Baumgarte
    correction: the constraints are met at the acceleration level, so what drift the
    integrator leaves shows in the pairwise distances).
    """

    def __init__(self, scene, welds="tree"):
        import pinocchio as pin

        self.scene = scene
        self.constraints = []  # (parent joint, placement in it, child joint, placement in it)
        model = pin.Model()
        model.gravity = pin.Motion(np.array(scene.gravity, dtype=float), np.zeros(3))
        self.carrier, self.X_JB, self.joint_ids = {}, {}, {}
        lines = []
        for body in scene.topological_order():
            j = scene.joint(body.name)
            if j.parent == WORLD:
                parent_id, X_parent = 0, _se3(np.eye(3), np.zeros(3))
            else:
                parent_id, X_parent = self.carrier[j.parent], self.X_JB[j.parent]
            X_PJ = _se3(spatial.quat_to_matrix(j.parent_quat), j.parent_point)  # Jp in parent body coords
            X_CJ = _se3(spatial.quat_to_matrix(j.child_quat), j.child_point)  # Jc in child body coords
            if j.kind == "free" or (j.kind == "weld" and welds == "constraint"):
                jid = model.addJoint(0, pin.JointModelFreeFlyer(), _se3(np.eye(3), np.zeros(3)), body.name)
                X_JB = _se3(np.eye(3), np.zeros(3))
                if j.kind == "weld":  # the weld frame, in the parent's joint frame and in the child's (= body)
                    self.constraints.append((parent_id, X_parent * X_PJ, jid, X_CJ))
            elif j.kind in ("revolute", "ball"):
                jm = (pin.JointModelRevoluteUnaligned(np.array(j.axis) / np.linalg.norm(j.axis))
                      if j.kind == "revolute" else pin.JointModelSpherical())
                jid = model.addJoint(parent_id, jm, X_parent * X_PJ, body.name)
                X_JB = X_CJ.inverse()
            else:  # weld: rigidly on the parent's joint
                jid = parent_id
                X_JB = X_parent * X_PJ * X_CJ.inverse()
            if j.kind != "weld" or welds == "constraint":
                self.joint_ids[body.name] = jid
            self.carrier[body.name], self.X_JB[body.name] = jid, X_JB
            R, p = X_JB.rotation, X_JB.translation
            model.appendBodyToJoint(jid, pin.Inertia(body.mass, p, R @ body.inertia_matrix @ R.T),
                                    _se3(np.eye(3), np.zeros(3)))
            model.addFrame(pin.Frame(body.name, jid, X_JB, pin.FrameType.OP_FRAME))
            lines.append(f"{body.name}: {j.kind} -> pin joint {jid} "
                         f"({model.joints[jid].shortname() if jid else 'universe'}), mass {body.mass:g} kg")
        self.model = model
        self.data = model.createData()
        if self.constraints:
            self.cmodels = pin.StdVec_RigidConstraintModel()
            for j1, X1, j2, X2 in self.constraints:
                self.cmodels.append(pin.RigidConstraintModel(pin.ContactType.CONTACT_6D, model, j1, X1, j2, X2,
                                                             pin.ReferenceFrame.LOCAL))
            self.cdatas = pin.StdVec_RigidConstraintData()
            for cm in self.cmodels:
                self.cdatas.append(cm.createData())
            pin.initConstraintDynamics(model, self.data, self.cmodels, self.cdatas)
            lines.append(f"{len(self.constraints)} weld(s) as 6D RigidConstraintModels (pin.constraintDynamics)")
        self.frame_ids = {b.name: model.getFrameId(b.name) for b in scene.bodies}
        self.summary = "\n".join([f"pin.Model: nq = {model.nq}, nv = {model.nv}, gravity = "
                                  f"{model.gravity.linear.tolist()}"] + lines)
        self._prepare_loads()

    # ---------------------------------------------------------------- loads
    def _prepare_loads(self):
        import pinocchio as pin

        model = self.model
        self.const_f = {}  # joint id -> constant local spatial force (follower loads)
        self.world_loads = []  # (joint id, point in J, force_W or None, torque_W or None)
        for ld in self.scene.loads:
            jid = self.carrier[ld.body]
            X = self.X_JB[ld.body]
            p_J = X.rotation @ np.array(ld.point) + X.translation
            vec = np.array(ld.vector)
            if ld.frame == "body":
                v_J = X.rotation @ vec
                f = pin.Force(v_J, np.cross(p_J, v_J)) if ld.kind == "force" else pin.Force(np.zeros(3), v_J)
                self.const_f[jid] = self.const_f.get(jid, pin.Force.Zero()) + f
            else:
                self.world_loads.append((jid, p_J, vec if ld.kind == "force" else None,
                                         vec if ld.kind == "torque" else None))
        self.has_loads = bool(self.scene.loads)
        self.fext = pin.StdVec_Force()
        for _ in range(model.njoints):
            self.fext.append(pin.Force.Zero())
        self.tau = np.zeros(model.nv)

    def external_forces(self, q):
        """Per-joint local forces for ``aba``/``rnea`` at configuration ``q``."""
        import pinocchio as pin

        if self.world_loads:
            pin.forwardKinematics(self.model, self.data, q)
        for i in range(self.model.njoints):
            self.fext[i] = self.const_f.get(i, pin.Force.Zero())
        for jid, p_J, f_W, t_W in self.world_loads:
            R_WJ = self.data.oMi[jid].rotation
            if f_W is not None:
                f_J = R_WJ.T @ f_W
                self.fext[jid] = self.fext[jid] + pin.Force(f_J, np.cross(p_J, f_J))
            else:
                self.fext[jid] = self.fext[jid] + pin.Force(np.zeros(3), R_WJ.T @ t_W)
        return self.fext

    def acceleration(self, q, v):
        import pinocchio as pin

        if self.constraints:  # no external forces here: such scenes are unsupported (see the adapter)
            return pin.constraintDynamics(self.model, self.data, q, v, self.tau, self.cmodels, self.cdatas)
        if self.has_loads:
            return pin.aba(self.model, self.data, q, v, self.tau, self.external_forces(q))
        return pin.aba(self.model, self.data, q, v, self.tau)

    def acceleration_function(self):
        """``acc(q, v)`` with the fewest Python calls: the external forces are built once
        when they do not depend on the configuration (no world-frame loads)."""
        import pinocchio as pin

        aba, model, data, tau = pin.aba, self.model, self.data, self.tau
        if self.constraints:
            return self.acceleration
        if not self.has_loads:
            return lambda q, v: aba(model, data, q, v, tau)
        if not self.world_loads:
            fext = self.external_forces(None)  # follower loads only: constant in the joint frames
            return lambda q, v: aba(model, data, q, v, tau, fext)
        return self.acceleration

    def dexpinv_kind(self):
        """0: the configuration space is a vector space (only revolute joints); 2: the
        ``dIntegrate`` solve; 3: several FreeFlyers and nothing else (the same solve, block by
        block) — see ``dexpinv_function``. The compiled loop takes 0 and 2."""
        names = [self.model.joints[i].shortname() for i in range(1, self.model.njoints)]
        if all(n.startswith("JointModelR") for n in names):  # RevoluteUnaligned / RX / RY / RZ
            return 0
        return 3 if len(names) > 1 and all(n == "JointModelFreeFlyer" for n in names) else 2

    def dexpinv_function(self):
        """``dexpinv(q, theta, vel)``: the tangent ``theta'`` of ``q (+) theta`` moving with
        velocity ``vel`` — ``dIntegrate(q, theta, ARG1)^-1 vel`` — or None where it is ``vel``
        (only revolute joints: the configuration space is a vector space).

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


class PinocchioAdapter(Adapter):
    """Pinocchio (``pin``), integrators owned by the adapter."""

    name = "pinocchio"
    effects = EFFECTS
    integrators = {
        "euler": IntegratorSpec(True, ("loop", "welds"), "semi-implicit Euler on the group"),
        "rk4": IntegratorSpec(True, ("loop", "welds"), "Runge-Kutta-Munthe-Kaas 4 (exact dexp^-1 from dIntegrate)"),
        "rk4-naive": IntegratorSpec(True, ("loop", "welds"), "RK4 with stagewise integrate, no dexp^-1 correction"),
        "rk45": IntegratorSpec(False, ("welds",), "scipy RK45 in local coordinates"),
        "dop853": IntegratorSpec(False, ("welds",), "scipy DOP853 in local coordinates"),
    }

    def version(self):
        import pinocchio

        return pinocchio.__version__

    def check(self, scene, times, settings):
        super().check(scene, times, settings)
        option_choice(settings, "loop", LOOPS)
        option_choice(settings, "welds", WELDS)

    def unsupported(self, scene, settings):
        reason = super().unsupported(scene, settings)
        if reason or settings.options.get("welds", "tree") != "constraint":
            return reason
        if scene.loads:
            return ("welds=constraint with loads: pin.constraintDynamics takes no external forces — "
                    "use welds=tree")
        if any(j.kind in ("revolute", "ball") for j in scene.joints):
            return ("welds=constraint with revolute or ball joints: their reactions would miss the "
                    "constraint forces — use welds=tree")
        return None

    def variants(self, scene):
        """Default matrix: where the scene has welds, also as constraints (where supported)."""
        out = [{}]
        if any(j.kind == "weld" for j in scene.joints):
            out.append({"welds": "constraint"})
        return out

    def describe(self, scene, settings):
        return PinocchioModel(scene, settings.options.get("welds", "tree")).summary + "\n"

    def prepare(self, scene, times, settings):
        pm = PinocchioModel(scene, settings.options.get("welds", "tree"))
        q0, v0 = pm.initial_state()
        times = np.asarray(times, dtype=float)
        steps = steps_per_interval(times, settings.dt) if settings.dt else None
        return dict(scene=scene, pm=pm, q0=q0, v0=v0, times=times, settings=settings, steps=steps)

    # ------------------------------------------------------------ stepping
    def run(self, prepared):
        p = prepared
        method = p["settings"].integrator
        info = {}
        start = time.perf_counter()
        if method in ("rk45", "dop853"):
            Q, V, n_steps, n_rhs = self._adaptive(p, method.upper())
            info["loop"] = "Python around scipy solve_ivp"
        else:
            Q, V, n_steps, n_rhs, info["loop"] = self._fixed_loop(p, method)
        wall = time.perf_counter() - start
        return Outcome(self._read_back(p, Q, V), wall, n_steps, n_rhs, info)

    def _fixed_loop(self, p, method):
        """The compiled loop (``pinocchio_native``) unless ``options.loop`` is ``python`` or it
        cannot be built; the fifth item says which ran, and why not the compiled one."""
        from dalembert.adapters import pinocchio_native

        if p["settings"].options.get("loop", "native") == "python":
            return (*self._fixed(p, method), "Python (options.loop = python)")
        pm = p["pm"]
        if pm.constraints:
            return (*self._fixed(p, method), "Python (constraint dynamics: the compiled loop has aba only)")
        try:
            Q, V, n, error = pinocchio_native.run_fixed(pm, method, min(pm.dexpinv_kind(), 2), p["q0"], p["v0"], p["times"],
                                                        p["steps"])
        except RuntimeError as e:  # not built here: the Python loop, saying why
            return (*self._fixed(p, method), f"Python (the compiled loop is unavailable: {e})")
        loop = "C++ (adapters/pinocchio_stepper.cpp)" + (f"; stopped: {error}" if error else "")
        return Q, V, n, n * STAGES[method], loop

    def _fixed(self, p, method):
        import pinocchio as pin

        pm = p["pm"]
        model, acc = pm.model, pm.acceleration_function()
        integrate = pin.integrate
        dexpinv = pm.dexpinv_function()
        J_inv = dexpinv if dexpinv is not None else (lambda q, theta, vel: vel)

        def euler(q, v, h):
            v = v + h * acc(q, v)
            return integrate(model, q, h * v), v

        def rk4(q, v, h):  # Munthe-Kaas: stage tangents k_i, all from q
            hh = 0.5 * h
            a1 = acc(q, v)
            v2 = v + hh * a1
            th2 = hh * v
            k2 = J_inv(q, th2, v2)
            a2 = acc(integrate(model, q, th2), v2)
            v3 = v + hh * a2
            th3 = hh * k2
            k3 = J_inv(q, th3, v3)
            a3 = acc(integrate(model, q, th3), v3)
            v4 = v + h * a3
            th4 = h * k3
            k4 = J_inv(q, th4, v4)
            a4 = acc(integrate(model, q, th4), v4)
            h6 = h / 6.0
            return (integrate(model, q, h6 * (v + 2.0 * (k2 + k3) + k4)),
                    v + h6 * (a1 + 2.0 * (a2 + a3) + a4))

        def rk4_naive(q, v, h):  # stagewise integrate, no dexp^-1
            hh = 0.5 * h
            a1 = acc(q, v)
            v2 = v + hh * a1
            a2 = acc(integrate(model, q, hh * v), v2)
            v3 = v + hh * a2
            a3 = acc(integrate(model, q, hh * v2), v3)
            v4 = v + h * a3
            a4 = acc(integrate(model, q, h * v3), v4)
            h6 = h / 6.0
            return (integrate(model, q, h6 * (v + 2.0 * (v2 + v3) + v4)),
                    v + h6 * (a1 + 2.0 * (a2 + a3) + a4))

        step = {"euler": euler, "rk4": rk4, "rk4-naive": rk4_naive}[method]

        Q, V, n = march(lambda t, q, v, h: step(q, v, h), p["q0"], p["v0"], p["times"], p["steps"])
        return Q, V, n, n * STAGES[method]

    def _adaptive(self, p, method):
        import pinocchio as pin
        from scipy.integrate import solve_ivp

        pm = p["pm"]
        model, nv = pm.model, pm.model.nv
        s = p["settings"]
        acc = pm.acceleration_function()
        dexpinv = pm.dexpinv_function() or (lambda q, theta, vel: vel)
        times = p["times"]
        Q = np.full((len(times), model.nq), np.nan)
        V = np.full((len(times), nv), np.nan)
        q, v = p["q0"].copy(), p["v0"].copy()
        Q[0], V[0] = q, v
        n_steps = n_rhs = 0
        for k in range(1, len(times)):
            q_ref = q

            def rhs(t, y):
                delta, vel = y[:nv], y[nv:]
                qq = pin.integrate(model, q_ref, delta)
                return np.concatenate([dexpinv(q_ref, delta, vel), acc(qq, vel)])

            try:
                sol = solve_ivp(rhs, (times[k - 1], times[k]), np.concatenate([np.zeros(nv), v]), method=method,
                                rtol=s.rtol or 1e-8, atol=s.atol or 1e-8)
            except Exception as e:
                if not is_numerical_failure(e):
                    raise
                break
            n_steps += len(sol.t) - 1
            n_rhs += sol.nfev
            y = sol.y[:, -1]
            if not sol.success or not np.all(np.isfinite(y)):
                break
            q, v = pin.integrate(model, q_ref, y[:nv]), y[nv:]
            Q[k], V[k] = q, v
        return Q, V, n_steps, n_rhs

    # ------------------------------------------------------------ read-back
    def _read_back(self, p, Q, V):
        import pinocchio as pin

        from dalembert.trajectory import BodyStates, JointStates, Trajectory

        pm, scene = p["pm"], p["scene"]
        model, data = pm.model, pm.data
        n = len(p["times"])
        bodies = {b.name: [np.full((n, 3), np.nan), np.full((n, 4), np.nan), np.full((n, 3), np.nan),
                           np.full((n, 3), np.nan)] for b in scene.bodies}
        reacting = [j for j in scene.joints if j.kind in ("revolute", "ball")]
        reactions = {j.child: np.full((n, 3), np.nan) for j in reacting}
        for k in range(n):
            q, v = Q[k], V[k]
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                continue
            local = {}
            if reacting:  # rnea with the external forces: data.f[joint] is the force through the joint
                a = pm.acceleration(q, v)
                if pm.has_loads:
                    pin.rnea(model, data, q, v, a, pm.external_forces(q))
                else:
                    pin.rnea(model, data, q, v, a)
                local = {j.child: data.f[pm.joint_ids[j.child]].linear.copy() for j in reacting}
            # rnea does not refresh data.oMi: rotate with this sample's forward kinematics
            pin.forwardKinematics(model, data, q, v)
            pin.updateFramePlacements(model, data)
            for child, f in local.items():
                reactions[child][k] = data.oMi[pm.joint_ids[child]].rotation @ f
            for name, arrs in bodies.items():
                fid = pm.frame_ids[name]
                X = data.oMf[fid]
                vel = pin.getFrameVelocity(model, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
                arrs[0][k], arrs[2][k], arrs[3][k] = X.translation, vel.linear, vel.angular
                arrs[1][k] = spatial.matrix_to_quat(X.rotation)
        joints = {}
        for j in scene.joints:
            if j.kind == "weld":
                continue
            jm = model.joints[pm.joint_ids[j.child]]
            qj, vj = Q[:, jm.idx_q:jm.idx_q + jm.nq], V[:, jm.idx_v:jm.idx_v + jm.nv]
            if j.kind == "free":  # the engine's own quaternion (its norm is data), scalar first
                quat = spatial.xyzw_to_wxyz(qj[:, 3:])
                bodies[j.child][1] = quat
                R = spatial.quat_to_matrix(spatial.quat_normalize(np.nan_to_num(quat, nan=1.0)))
                v_W = np.einsum("nij,nj->ni", R, vj[:, :3])
                joints[j.child] = JointStates(np.concatenate([qj[:, :3], quat], axis=1),
                                              np.concatenate([v_W, vj[:, 3:]], axis=1))
            elif j.kind == "ball":
                joints[j.child] = JointStates(spatial.xyzw_to_wxyz(qj), vj)
            else:
                joints[j.child] = JointStates(qj, vj)
        traj_bodies = {name: BodyStates(*arrs) for name, arrs in bodies.items()}
        extras = {f"reaction_force:{c}": f for c, f in reactions.items()}
        return Trajectory(p["times"], traj_bodies, joints, extras)

    # ------------------------------------------------------------ audit
    def audit(self, prepared, outcome):
        pm = prepared["pm"]
        return {
            "gravity": tuple(float(g) for g in pm.model.gravity.linear),
            "joints": {name: pm.model.joints[jid].shortname() for name, jid in pm.joint_ids.items()},
            "external_forces_per_evaluation": [f"{ld.effect} on {ld.body}" for ld in prepared["scene"].loads],
            "nq": int(pm.model.nq), "nv": int(pm.model.nv),
            "integrator": prepared["settings"].integrator,
            "loop": outcome.info.get("loop", ""),
            "pinocchio_version": self.version(),
            "contacts": 0, "constraint_rows": 0,
        }
