"""``MujocoAdapter``: the contract (``dalembert.adapters``) for MuJoCo.

``prepare`` compiles the generated MJCF (``mjcf``) and checks the compiled mass
properties and springs against the scene's; ``run`` steps (``stepping``) with MuJoCo's
warnings sent to the adapter, not to ``MUJOCO_LOG.TXT`` or the console, then
reads the states back in body terms (``readback``); ``audit`` reads the
compiled options, joints, loop constraints and springs back from the model.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, option_choice
from dalembert.adapters.mujoco import contact
from dalembert.adapters.mujoco.mjcf import LOAD_PATHS, WELDS, engine_frames, loop_softness, mjcf
from dalembert.adapters.mujoco.readback import read_back
from dalembert.adapters.mujoco.springs import check_springs, other_passive, read_springs
from dalembert.adapters.mujoco.stepping import step_loop, step_rollout
from dalembert.scene import CONTACT_EFFECTS, EFFECTS, LOOP_EFFECTS, SPRING_EFFECTS
from dalembert.settings import steps_per_interval

__all__ = ["MujocoAdapter"]

OPTIONS = ("loads", "welds", *contact.OPTIONS)
# Why loop:distance is not declared (measured: a crank-coupler tree closed by a distance loop to the world,
# the four-bar with a massless rocker, against the reference; tests/test_mujoco_loops.py).
DISTANCE_REASON = ("the tendon equality holds the closure and the motion (7e-7 m from the reference at dt = 1e-4) but "
                   "its constraint force read back from efc_force is 4-100 % off the reference's multiplier from "
                   "sample to sample, not understood yet")
# Compiled mass properties must reproduce the scene's to this relative accuracy:
# MuJoCo diagonalizes the full inertia (an eigen-solve), which costs a few ulps.
MASS_PROPERTY_REL_TOL = 1e-10
# How each integrator treats a spring's tendon force (measured, one step of a damper alone: Euler's velocity
# falls by h c / m, implicit's and implicitfast's by the factor 1 / (1 + h c / m); the eulerdamp flag changes
# neither, it covers joint damping only).
SPRING_INTEGRATION = {
    "euler": "stiffness and damping explicit (semi-implicit Euler); MuJoCo's eulerdamp covers joint damping only",
    "rk4": "stiffness and damping explicit, in every RK4 stage",
    "implicit": "stiffness explicit; tendon damping implicit in velocity (backward Euler: -h c J^T J in the matrix)",
    "implicitfast": "stiffness explicit; tendon damping implicit in velocity (backward Euler: -h c J^T J in the matrix)",
    "discrete": "stiffness explicit; tendon damping implicit in velocity (MuJoCo's discrete integrator)",
}


class MujocoAdapter(Adapter):
    """MuJoCo (``mujoco`` Python bindings). Options: ``loads`` = ``actuator`` | ``xfrc_applied``;
    ``welds`` = ``tree`` | ``equality``; contact (``contact.OPTIONS``): ``cone`` = ``pyramidal`` | ``elliptic``,
    ``impratio``, ``noslip_iterations``, ``contact_timeconst``."""

    name = "mujoco"
    # loops: equality constraints (mjcf), soft as MuJoCo's are: the audit states their softness. A distance
    # loop (a tendon equality) is generated but not declared: DISTANCE_REASON. Springs: spatial tendons (mjcf),
    # checked against the scene when built and read back in the audit. Prismatic joints: slide joints (mjcf),
    # read back in the audit (``_joint_audit``).
    # Contact: geoms, planes and explicit pairs (``contact``), read back in the audit.
    effects = EFFECTS | (LOOP_EFFECTS - {"loop:distance"}) | SPRING_EFFECTS | CONTACT_EFFECTS
    integrators = {
        "euler": IntegratorSpec(True, OPTIONS, "semi-implicit Euler"),
        "rk4": IntegratorSpec(True, OPTIONS, "classical RK4"),
        "implicit": IntegratorSpec(True, OPTIONS, "implicit in velocity (Coriolis and damping)"),
        "implicitfast": IntegratorSpec(True, OPTIONS, "implicit in velocity, no Coriolis derivatives"),
        "discrete": IntegratorSpec(True, OPTIONS, "MuJoCo 4's discrete integrator"),
    }

    def version(self):
        import mujoco

        return mujoco.__version__

    def check(self, scene, times, settings):
        super().check(scene, times, settings)
        option_choice(settings, "loads", LOAD_PATHS)
        option_choice(settings, "welds", WELDS)
        contact.contact_options(settings)

    def unsupported(self, scene, settings):
        reason = super().unsupported(scene, settings)
        if reason and "loop:distance" in reason:
            reason += f" (a distance loop: {DISTANCE_REASON})"
        return reason or contact.why_not(scene)

    def variants(self, scene):
        """Default matrix: where the scene has welds, also as equality constraints."""
        return [{}, {"welds": "equality"}] if any(j.kind == "weld" for j in scene.joints) else [{}]

    def describe(self, scene, settings):
        """The generated model, for reports and ``dalembert show-model``."""
        return mjcf(scene, settings)

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        import mujoco

        text = mjcf(scene, settings)
        model = mujoco.MjModel.from_xml_string(text)
        welds = settings.options.get("welds", "tree")
        X_EB = engine_frames(scene, welds)
        ids = {b.name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b.name) for b in scene.bodies}
        self._check_mass_properties(model, scene, X_EB, ids)
        check_springs(model, scene, X_EB)
        data = mujoco.MjData(model)
        qpos0, qvel0 = np.zeros(model.nq), np.zeros(model.nv)
        state0 = spatial.initial_body_states(scene) if welds == "equality" else {}
        for j in scene.joints:
            if j.kind == "weld" and welds == "tree":
                continue
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j.child)
            a, v = model.jnt_qposadr[jid], model.jnt_dofadr[jid]
            if j.kind == "weld":  # a free body at its initial state: qvel = (v world, w body)
                s0 = state0[j.child]
                qpos0[a:a + 7] = np.concatenate([s0["p"], spatial.matrix_to_quat(s0["R"])])
                qvel0[v:v + 6] = np.concatenate([s0["v"], s0["R"].T @ s0["w"]])
                continue
            qpos0[a:a + len(j.q0)] = j.q0
            qvel0[v:v + len(j.v0)] = j.v0
        steps = steps_per_interval(np.asarray(times, float), settings.dt)
        return dict(scene=scene, times=np.asarray(times, float), settings=settings, model=model, data=data,
                    scratch=mujoco.MjData(model), qpos0=qpos0, qvel0=qvel0, steps=steps, frames=X_EB, ids=ids,
                    mjcf=text, load_path=settings.options.get("loads", "actuator"), welds=welds)

    @staticmethod
    def _check_mass_properties(model, scene, X_EB, ids):
        for b in scene.bodies:
            i = ids[b.name]
            p_EB, R_EB = X_EB[b.name]
            R = spatial.quat_to_matrix(model.body_iquat[i])
            I_E = R @ np.diag(model.body_inertia[i]) @ R.T
            expected = R_EB @ b.inertia_matrix @ R_EB.T
            scale = np.abs(expected).max()
            if (abs(model.body_mass[i] - b.mass) > MASS_PROPERTY_REL_TOL * b.mass
                    or np.abs(I_E - expected).max() > MASS_PROPERTY_REL_TOL * scale
                    or np.abs(model.body_ipos[i] - p_EB).max() > MASS_PROPERTY_REL_TOL * max(1.0, np.abs(p_EB).max())):
                raise RuntimeError(f"MuJoCo compiled body {b.name!r} with mass {model.body_mass[i]}, "
                                   f"COM {model.body_ipos[i]} and inertia {I_E.tolist()}; the scene has "
                                   f"{b.mass}, {p_EB.tolist()}, {expected.tolist()}")

    # ------------------------------------------------------------- run
    def run(self, prepared):
        import mujoco

        p = prepared
        messages = []
        previous = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(messages.append)  # no MUJOCO_LOG.TXT, no printing
        try:
            if p["load_path"] == "actuator":
                Q, V, wall, diverged_at = step_rollout(p)
                if diverged_at is not None:  # locate the first bad sample
                    messages.clear()
                    Q, V, wall, diverged_at = step_loop(p)
            else:
                Q, V, wall, diverged_at = step_loop(p)
        finally:
            mujoco.set_mju_user_warning(previous)
        n_steps = int(p["steps"][:diverged_at].sum()) if diverged_at else int(p["steps"].sum())
        stages = 4 if p["settings"].integrator == "rk4" else 1
        info = {"message": f"MuJoCo: {messages[0]}" if messages else "", "warnings": messages[:5]}

        def read():
            traj, info["audit"] = read_back(p, Q, V)
            return traj

        return Outcome(read, wall, n_steps, n_steps * stages, info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        import mujoco

        model = prepared["model"]
        disabled = [name[len("mjDSBL_"):].lower() for name in dir(mujoco.mjtDisableBit) if name.startswith("mjDSBL_")
                    and model.opt.disableflags & int(getattr(mujoco.mjtDisableBit, name))]
        enabled = [name[len("mjENBL_"):].lower() for name in dir(mujoco.mjtEnableBit) if name.startswith("mjENBL_")
                   and model.opt.enableflags & int(getattr(mujoco.mjtEnableBit, name))]
        return {
            "gravity": tuple(float(g) for g in model.opt.gravity),
            "disabled": sorted(disabled),
            "enabled": sorted(enabled),
            "integrator": mujoco.mjtIntegrator(model.opt.integrator).name,
            "timestep": float(model.opt.timestep),
            "mujoco_version": mujoco.__version__,
            "load_path": prepared["load_path"],
            "actuators": [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(model.nu)],
            "max_armature": float(np.abs(model.dof_armature).max(initial=0.0)),
            "max_damping": float(np.abs(model.dof_damping).max(initial=0.0)),
            "ngeom": int(model.ngeom),
            "joints": self._joint_audit(prepared),
            **self._loop_audit(prepared),
            **self._spring_audit(prepared),
            **contact.audit(model, prepared["scene"]),
            **self._read_audit(outcome),
        }

    @staticmethod
    def _joint_audit(prepared):
        """Every scene joint MuJoCo builds as a joint, as the compiled model holds it: dict joint (child) name ->
        ``type`` (MuJoCo's: free, ball, slide, hinge), ``axis_W`` (hinge and slide: the unit axis in world axes at
        the initial state, MuJoCo's ``xaxis``; else None) and the joint's own limit, stiffness, damping,
        armature and friction loss (``limited`` a bool, the others the largest magnitude over its dofs)."""
        import mujoco

        model, scene = prepared["model"], prepared["scene"]
        d = mujoco.MjData(model)
        d.qpos[:] = prepared["qpos0"]
        mujoco.mj_kinematics(model, d)
        out = {}
        for j in scene.joints:
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, j.child)
            if jid < 0:  # a weld built as nesting: no joint
                continue
            kind = mujoco.mjtJoint(model.jnt_type[jid])
            dofs = np.flatnonzero(model.dof_jntid == jid)
            axial = kind in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE)
            out[j.child] = {
                "type": kind.name[len("mjJNT_"):].lower(),
                "axis_W": [float(v) for v in d.xaxis[jid]] if axial else None,
                "limited": bool(model.jnt_limited[jid]),
                "stiffness": float(abs(model.jnt_stiffness[jid])),
                "damping": float(np.abs(model.dof_damping[dofs]).max()),
                "armature": float(np.abs(model.dof_armature[dofs]).max()),
                "frictionloss": float(np.abs(model.dof_frictionloss[dofs]).max()),
            }
        return out

    @staticmethod
    def _loop_audit(prepared):
        """The loops' constraints and their softness, read back from the compiled model (none: empty)."""
        import mujoco

        model, scene = prepared["model"], prepared["scene"]
        if not scene.loops:
            return {}
        (tc, zeta), _ = loop_softness(prepared["settings"])
        refsafe = not model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)
        kinds = [mujoco.mjtEq(t).name[len("mjEQ_"):].lower() for t in model.eq_type]
        return {
            "loop_constraints": {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_EQUALITY, i): kinds[i]
                                 for i in range(model.neq)},
            "loop_solref": [float(v) for v in model.eq_solref[0]],
            "loop_solimp": [float(v) for v in model.eq_solimp[0]],
            "loop_softness": (f"MuJoCo's soft equality constraints: reference acceleration -b v - k r with time "
                              f"constant {tc:g} s ({tc / prepared['settings'].dt:g} steps; refsafe {'on' if refsafe else 'off'}) "
                              f"and damping ratio {zeta:g}; impedance {model.eq_solimp[0][0]:g} (MuJoCo's largest), so the "
                              "solver's regularization leaves each constraint force ~1e-4 relative short, made up by the "
                              "residual's spring: the closure is not exact, its residual is the run's loop_residual"),
        }

    @staticmethod
    def _spring_audit(prepared):
        """The springs as the compiled model holds them (``springs.read_springs``: stiffness, damping, rest
        length, the bodies and points of the tendon's sites), every other passive parameter (all zero), and
        how the integrator treats them (none: empty)."""
        model, scene = prepared["model"], prepared["scene"]
        if not scene.springs:
            return {}
        springs = [{k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in s.items()}
                   for s in read_springs(model, scene, prepared["frames"])]
        return {"springs": springs, "passive_not_springs": other_passive(model, scene),
                "spring_integration": SPRING_INTEGRATION.get(prepared["settings"].integrator, "")}

    @staticmethod
    def _read_audit(outcome):
        """The figures the read-back collects on its way (contacts, constraint rows, passive forces)."""
        outcome.trajectory  # reads back, once, if nothing has yet
        return outcome.info["audit"]
