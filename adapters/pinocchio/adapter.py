"""``PinocchioAdapter``: the contract (``dalembert.adapters``) for Pinocchio.

The scene through Pinocchio's dynamics (ABA, RNEA; ``model``: free, revolute,
prismatic, ball and weld joints), with the
integrators owned here (``integrators``), so their quality is part of what is
measured. The fixed-step loops run compiled (``native``: the same integrators
and loads in ``stepper.cpp`` against the installed Pinocchio, no Python call per
step), or in Python with ``--option loop=python`` and wherever the compiled loop
cannot be built (the audit says which ran). Welds as constraints and loop
closures (``loops``: ball and revolute; distance is unsupported) run
``pin.constraintDynamics``, which the compiled loop does not have: their
fixed-step runs take the Python loop. Spring-dampers (``springs``) are external
forces at every evaluation, in every loop; the audit identifies each one's
stiffness, damping and rest length from the dynamics the run used.
"""

from __future__ import annotations

import time

import numpy as np

from dalembert import contact
from dalembert import spatial
from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, option_choice
from dalembert.adapters.pinocchio import loops, springs
from dalembert.adapters.pinocchio.integrators import STAGES, adaptive, fixed_step
from dalembert.adapters.pinocchio.model import WELDS, PinocchioModel
from dalembert.scene import AXIS_KINDS, EFFECTS, SPRING_EFFECTS
from dalembert.settings import steps_per_interval

__all__ = ["PinocchioAdapter"]

# Fixed-step loops: compiled (stepper.cpp, the default) or the Python one
# (the same integrators, kept as the readable specification and the fallback).
LOOPS = ("native", "python")
# The joint kinds whose reactions are read back (``reaction_force:<child>``): the force through the joint from
# ``rnea`` (``data.f``, the joint's LOCAL frame), rotated to world axes.
REACTING = ("revolute", "prismatic", "ball")


class PinocchioAdapter(Adapter):
    """Pinocchio (``pin``), integrators owned by the adapter."""

    name = "pinocchio"
    # loop:distance: loops.DISTANCE_REASON
    effects = EFFECTS | SPRING_EFFECTS | frozenset(f"loop:{k}" for k in loops.LOOP_KINDS)
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
        if (why := contact.not_mapped(scene, self.name)):  # contact: not mapped here yet
            return why
        if any(lp.kind == "distance" for lp in scene.loops):
            return loops.DISTANCE_REASON
        reason = super().unsupported(scene, settings)
        if reason or settings.options.get("welds", "tree") != "constraint":
            return reason
        if scene.loads:
            return ("welds=constraint with loads: pin.constraintDynamics takes no external forces — "
                    "use welds=tree")
        if scene.springs:
            return ("welds=constraint with spring-dampers: pin.constraintDynamics takes no external forces (and the "
                    "springs' joint torques are not checked against welds held by constraints) — use welds=tree")
        if any(j.kind in REACTING for j in scene.joints):
            return ("welds=constraint with revolute, prismatic or ball joints: their reactions would miss the "
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
        from dalembert.adapters.pinocchio import native

        pm = PinocchioModel(scene, settings.options.get("welds", "tree"))
        q0, v0 = pm.initial_state()
        times = np.asarray(times, dtype=float)
        steps = steps_per_interval(times, settings.dt) if settings.dt else None
        p = dict(scene=scene, pm=pm, q0=q0, v0=v0, times=times, settings=settings, steps=steps, native=None)
        # the compiled loop is loaded (or built) here, with the model, never inside a timed run
        if steps is not None and settings.options.get("loop", "native") == "native" and not pm.constrained:
            try:
                p["native"] = native.NativeModel(pm)
            except RuntimeError as e:  # not built here: the Python loop runs, saying why
                p["native_error"] = str(e)
        return p

    # ------------------------------------------------------------ stepping
    def run(self, prepared):
        p = prepared
        method = p["settings"].integrator
        info = {}
        start = time.perf_counter()
        if method in ("rk45", "dop853"):
            s = p["settings"]
            Q, V, n_steps, n_rhs = adaptive(p["pm"], method.upper(), p["q0"], p["v0"], p["times"], s.rtol, s.atol)
            info["loop"] = "Python around scipy solve_ivp"
        else:
            Q, V, n_steps, n_rhs, info["loop"] = self._fixed_loop(p, method)
        wall = time.perf_counter() - start
        return Outcome(lambda: self._read_back(p, Q, V), wall, n_steps, n_rhs, info)

    def _fixed_loop(self, p, method):
        """The compiled loop (``native``) unless ``options.loop`` is ``python`` or it cannot be
        built; the fifth item says which ran, and why not the compiled one."""
        pm = p["pm"]
        args = (pm, method, p["q0"], p["v0"], p["times"], p["steps"])
        if p["settings"].options.get("loop", "native") == "python":
            return (*fixed_step(*args), "Python (options.loop = python)")
        if pm.constrained:
            return (*fixed_step(*args), "Python (constraint dynamics: the compiled loop has aba only)")
        if p["native"] is None:
            return (*fixed_step(*args), f"Python (the compiled loop is unavailable: {p['native_error']})")
        Q, V, n, error = p["native"].run(method, p["q0"], p["v0"], p["times"], p["steps"])
        loop = "C++ (adapters/pinocchio/stepper.cpp)" + (f"; stopped: {error}" if error else "")
        return Q, V, n, n * STAGES[method], loop

    # ------------------------------------------------------------ read-back
    def _read_back(self, p, Q, V):
        import pinocchio as pin

        from dalembert.trajectory import BodyStates, JointStates, Trajectory

        pm, scene = p["pm"], p["scene"]
        model, data = pm.model, pm.data
        n = len(p["times"])
        bodies = {b.name: [np.full((n, 3), np.nan), None, np.full((n, 3), np.nan),
                           np.full((n, 3), np.nan)] for b in scene.bodies}
        R_WB = {b.name: np.full((n, 3, 3), np.nan) for b in scene.bodies}  # to quaternions once, below
        reacting = [j for j in scene.joints if j.kind in REACTING]
        reactions = {j.child: np.full((n, 3), np.nan) for j in reacting}
        loop_forces = {lc.loop.name: np.full((n, 3), np.nan) for lc in pm.loop_contacts}
        finite = np.all(np.isfinite(Q), axis=1) & np.all(np.isfinite(V), axis=1)  # once, not per sample
        # the constraints' multipliers and frames per sample (and their Jacobians, with loops), resolved after the
        # sample loop for all samples at once (``minimum_norm``, ``constraint_forces``)
        lams, R_Wc1, Js = [], [], []
        for k in np.flatnonzero(finite):
            q, v = Q[k], V[k]
            local = {}
            if reacting or loop_forces:  # rnea: data.f[joint] is the force through the joint
                a = pm.acceleration(q, v)
                if pm.constrained:  # from this constraintDynamics, before rnea overwrites data
                    lam, R, J = pm.constraint_readout(q)
                    lams.append(lam)
                    R_Wc1.append(R)
                    Js.append(J)
                if pm.has_forces:
                    pin.rnea(model, data, q, v, a, pm.external_forces(q, v))
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
                R_WB[name][k] = X.rotation
        if lams:
            lam = np.stack(lams)
            if pm.loop_contacts:
                lam = pm.minimum_norm(np.stack(Js), lam)
            forces = pm.constraint_forces(lam, np.stack(R_Wc1))  # (m, constraints, 3) on joint1's side, world
            for lc in pm.loop_contacts:
                loop_forces[lc.loop.name][finite] = loops.force_on_b(forces, lc)
            if reacting:  # the constraints' forces on the tree's joints (``carried_by``)
                S = pm.carried_by([pm.joint_ids[j.child] for j in reacting])
                for r, j in enumerate(reacting):
                    reactions[j.child][finite] -= np.einsum("c,mci->mi", S[r], forces)
        for name, arrs in bodies.items():
            arrs[1] = spatial.matrix_to_quat(R_WB[name])
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
        extras.update({f"reaction_force:{name}": f for name, f in loop_forces.items()})
        return Trajectory(p["times"], traj_bodies, joints, extras)

    # ------------------------------------------------------------ audit
    def audit(self, prepared, outcome):
        pm = prepared["pm"]
        model = pm.model
        return {
            "gravity": tuple(float(g) for g in model.gravity.linear),
            "joints": {name: model.joints[jid].shortname() for name, jid in pm.joint_ids.items()},
            # the unaligned revolute and prismatic joints' axes as the built model holds them (unit, joint frame)
            "joint_axes": {j.child: model.joints[pm.joint_ids[j.child]].extract().axis.tolist()
                           for j in prepared["scene"].joints if j.kind in AXIS_KINDS},
            "external_forces_per_evaluation": [f"{ld.effect} on {ld.body}" for ld in prepared["scene"].loads]
            + [f"spring_damper {el.name}: frames {model.frames[el.frame_a].name} -> {model.frames[el.frame_b].name}"
               for el in pm.springs],
            "nq": int(model.nq), "nv": int(model.nv),
            "integrator": prepared["settings"].integrator,
            "loop": outcome.info.get("loop", ""),
            "pinocchio_version": self.version(),
            "contacts": 0,
            "constraint_rows": int(sum(cm.residualSize() for cm in pm.cmodels)) if pm.constrained else 0,
            # what Pinocchio's joints could add on their own: none is set (springs are external forces only)
            "joint_passive_effects": {name: float(np.abs(getattr(model, name)).max(initial=0.0))
                                      for name in ("damping", "friction", "armature", "rotorInertia")},
            **(self._loop_audit(pm) if pm.loop_contacts else {}),
            **(self._spring_audit(prepared, outcome) if pm.springs else {}),
        }

    @staticmethod
    def _spring_audit(prepared, outcome):
        """Each spring identified from the generalized force the run's right-hand side gives it at the initial
        configuration (``springs.identify``): the compiled one's where the compiled loop ran, else the Python
        one's (the joint torques ``constraintDynamics`` is given, with loops or welds as constraints)."""
        import pinocchio as pin

        pm = prepared["pm"]
        model, data = pm.model, pm.data
        native = prepared["native"] if outcome.info.get("loop", "").startswith("C++") else None
        if native is not None:
            by = "the compiled right-hand side (stepper.cpp): M a"

            def forces(q, v, elements):
                return springs.mass_matrix(model, data, q) @ native.acceleration(q, v, elements)
        elif pm.constrained:
            by = "the joint torques given to pin.constraintDynamics (PinocchioModel.load_torques)"
            forces = pm.load_torques
        else:
            by = "the Python right-hand side (pin.aba with the external forces): M a"

            def forces(q, v, elements):
                a = pin.aba(model, data, q, v, pm.tau, pm.external_forces(q, v, elements))
                return springs.mass_matrix(model, data, q) @ a
        q0 = prepared["q0"]
        return {"springs": {el.name: springs.identify(pm, el, forces, q0) for el in pm.springs},
                "springs_identified_from": by}

    @staticmethod
    def _loop_audit(pm):
        """How the loops were closed and solved (``loops``): constraints, regularisation, drift correction."""
        Kp, Kd = loops.baumgarte()
        return {
            "loops": {lc.loop.name: f"{lc.loop.kind}: {len(lc.indices)} CONTACT_3D (LOCAL)"
                      + (f", the second {lc.lever:g} m along the axis" if lc.loop.kind == "revolute" else "")
                      for lc in pm.loop_contacts},
            "loop_summary": str(pm.scene.loop_summary()),
            "proximal": {"mu": pm.mu, "mu_relative_to_delassus": loops.PROXIMAL_MU_REL,
                         "max_iter": loops.PROXIMAL_ITERATIONS, "accuracy": loops.PROXIMAL_ACCURACY},
            "drift_correction": {"method": "Baumgarte (RigidConstraintModel corrector)", "Kp": Kp, "Kd": Kd},
        }

