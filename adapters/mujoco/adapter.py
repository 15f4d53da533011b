"""``MujocoAdapter``: the contract (``dalembert.adapters``) for MuJoCo.

``prepare`` compiles the generated MJCF (``mjcf``) and checks the compiled mass
properties and springs against the scene's; ``run`` steps (``stepping``) with MuJoCo's
warnings sent to the adapter, not to ``MUJOCO_LOG.TXT`` or the console, then
reads the states back in body terms (``readback``); ``audit`` (the module) reads the
compiled options, joints, loop constraints and springs back from the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dalembert import spatial
from dalembert.adapters import file_model
from dalembert.adapters.base import Adapter, IntegratorSpec, Outcome, Prepared, option_value
from dalembert.adapters.mujoco.audit import audit
from dalembert.adapters.mujoco.mjcf import MJCF_OPTIONS, engine_frames, mjcf
from dalembert.adapters.mujoco import contact, from_file
from dalembert.adapters.mujoco.readback import read_back
from dalembert.adapters.mujoco.springs import check_springs
from dalembert.adapters.mujoco.stepping import step_loop, step_rollout
from dalembert.scene import CONTACT_EFFECTS, EFFECTS, LOOP_EFFECTS, SPRING_EFFECTS
from dalembert.settings import steps_per_interval

__all__ = ["MujocoAdapter", "MujocoPrepared"]

OPTIONS = ("loads", "welds", *contact.OPTIONS, *file_model.FILE_OPTION_NAMES)
# Why loop:distance is not declared (measured: a crank-coupler tree closed by a distance loop to the world,
# the four-bar with a massless rocker, against the reference; tests/test_mujoco_loops.py).
DISTANCE_REASON = ("the tendon equality holds the closure and the motion (7e-7 m from the reference at dt = 1e-4) but "
                   "its constraint force read back from efc_force is 4-100 % off the reference's multiplier from "
                   "sample to sample, not understood yet")
# Compiled mass properties must reproduce the scene's to this relative accuracy:
# MuJoCo diagonalizes the full inertia (an eigen-solve), which costs a few ulps.
MASS_PROPERTY_REL_TOL = 1e-10
@dataclass(frozen=True, eq=False)
class MujocoPrepared(Prepared):
    """MuJoCo's prepared run (``Prepared``): the compiled model and its initial state.

    Attributes
    ----------
    model : mujoco.MjModel — compiled from ``mjcf``, its mass properties and springs checked against the scene
    data : mujoco.MjData — the state a run steps (set to the initial state at each run's start)
    scratch : mujoco.MjData — the read-back's, for the derived quantities of each sampled state
    qpos0 : ndarray (nq,) — the initial configuration, MuJoCo's coordinates (a free joint's quaternion w first)
    qvel0 : ndarray (nv,) — the initial velocity (a free joint's: linear in world axes, angular in body axes)
    steps : ndarray (n - 1,) of int — steps per sample interval (``settings.steps_per_interval``)
    frames : dict body name -> (p_EB (3,), R_EB (3, 3)) — the scene's body frame B in MuJoCo's body frame E
        (``mjcf.engine_frames``), m
    ids : dict body name -> int — MuJoCo's body ids
    mjcf : str — the generated MJCF the model was compiled from
    load_path : str — option ``loads``: ``actuator`` or ``xfrc_applied``
    welds : str — option ``welds``: ``tree`` or ``equality``
    """

    model: object
    data: object
    scratch: object
    qpos0: np.ndarray
    qvel0: np.ndarray
    steps: np.ndarray
    frames: dict
    ids: dict
    mjcf: str
    load_path: str
    welds: str


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
    # loads, welds; cone, impratio, ...; model_file, file_effects (the file read by MuJoCo itself: from_file)
    options = {**MJCF_OPTIONS, **contact.CONTACT_OPTIONS, **file_model.FILE_OPTIONS}
    integrators = {
        "euler": IntegratorSpec(True, OPTIONS, "semi-implicit Euler", order=1),
        "rk4": IntegratorSpec(True, OPTIONS, "classical RK4", order=4),
        "implicit": IntegratorSpec(True, OPTIONS, "implicit in velocity (Coriolis and damping)", order=1),
        "implicitfast": IntegratorSpec(True, OPTIONS, "implicit in velocity, no Coriolis derivatives", order=1),
        "discrete": IntegratorSpec(True, OPTIONS, "MuJoCo 4's discrete integrator", order=1),
    }
    # Run here on the canonical cases from 3.2.7 to 4.0.0 (every minor release, in engine environments); 3.2 and
    # older name the passive-force flags otherwise (``mjcf._disabled_names``: a shim).
    supported_versions = ">=3.2"
    unsupported_versions_why = "releases before 3.2 were never run with this adapter's MJCF and API"
    # (measured: 3.12.0's MJCF parser rejects integrator="discrete" as an invalid keyword; 3.13.0 has mjINT_DISCRETE)
    integrator_versions = {"discrete": (">=3.13", "MuJoCo's discrete integrator arrived in 3.13.0")}

    def version(self):
        import mujoco

        return mujoco.__version__

    def beyond_scene(self, scene, settings):
        return file_model.beyond(settings)  # the robot file's effects, when the engine reads the file with them

    def unsupported(self, scene, settings):
        reason = file_model.why_not(scene, settings) or super().unsupported(scene, settings)
        if reason and "loop:distance" in reason:
            reason += f" (a distance loop: {DISTANCE_REASON})"
        return reason or contact.why_not(scene)

    def repro(self, scene, times, settings, quantity):
        if file_model.model_file(settings):
            raise ValueError(file_model.NO_REPRO)
        return super().repro(scene, times, settings, quantity)

    def variants(self, scene):
        """Default matrix: where the scene has welds, also as equality constraints."""
        return [{}, {"welds": "equality"}] if any(j.kind == "weld" for j in scene.joints) else [{}]

    def describe(self, scene, settings):
        """The generated model (or the one MuJoCo read from ``model_file``), for reports and ``show-model``."""
        return from_file.describe(scene, settings) if file_model.model_file(settings) else mjcf(scene, settings)

    # ------------------------------------------------------------- build
    def prepare(self, scene, times, settings):
        import mujoco

        if file_model.model_file(settings):
            return from_file.prepare(scene, times, settings)
        text = mjcf(scene, settings)
        model = mujoco.MjModel.from_xml_string(text)
        welds = self.option(settings, "welds")
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
        # the load path the MJCF was written with, from its declaration (MJX, prepared here too, declares no loads)
        return MujocoPrepared(scene, np.asarray(times, float), settings, model=model, data=data,
                              scratch=mujoco.MjData(model), qpos0=qpos0, qvel0=qvel0, steps=steps, frames=X_EB, ids=ids,
                              mjcf=text, load_path=option_value(MJCF_OPTIONS, settings, "loads"), welds=welds)

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

        if isinstance(prepared, file_model.FilePrepared):
            return from_file.run(prepared)
        p = prepared
        messages = []
        previous = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(messages.append)  # no MUJOCO_LOG.TXT, no printing
        try:
            if p.load_path == "actuator":
                Q, V, wall, diverged_at = step_rollout(p)
                if diverged_at is not None:  # locate the first bad sample
                    messages.clear()
                    Q, V, wall, diverged_at = step_loop(p)
            else:
                Q, V, wall, diverged_at = step_loop(p)
        finally:
            mujoco.set_mju_user_warning(previous)
        n_steps = int(p.steps[:diverged_at].sum()) if diverged_at else int(p.steps.sum())
        stages = 4 if p.settings.integrator == "rk4" else 1
        info = {"message": f"MuJoCo: {messages[0]}" if messages else "", "warnings": messages[:5]}

        def read():
            traj, info["audit"] = read_back(p, Q, V)
            return traj

        return Outcome(read, wall, n_steps, n_steps * stages, info)

    # ------------------------------------------------------------- audit
    def audit(self, prepared, outcome):
        if isinstance(prepared, file_model.FilePrepared):
            return from_file.audit(prepared, outcome)
        return audit(prepared, outcome)

