"""MuJoCo reading the robot's file itself (option ``model_file``; ``dalembert.adapters.file_model``).

A URDF goes through MuJoCo's own URDF compiler (``mujoco.MjSpec.from_string`` of the file without its
geometry, the scene's locked joints fixed: ``file_model.bare_urdf``; its root link given a free joint where the
scene's base floats), an MJCF through ``MjSpec.from_file`` (its
locked joints deleted, contact disabled: these cases have none). MuJoCo reads a URDF joint's
``<dynamics damping friction>`` as ``dof_damping`` and ``dof_frictionloss``, its ``<limit lower upper>`` as a
range (``jnt_limited``) and its ``effort`` as an actuator-force range; with ``file_effects=on`` all stay as read
(damping and friction loss act in every integrator, limits through MuJoCo's constraint solver), with ``off`` the
passive parameters are zeroed and the limit constraint disabled after compiling. The run's integrator and step
and the case's gravity are set on the compiled model; the stepping is the adapter's (``stepping``).
"""

from __future__ import annotations

import os
from types import SimpleNamespace

import numpy as np

from dalembert.adapters import file_model
from dalembert.adapters.base import Outcome
from dalembert.adapters.mujoco.mjcf import INTEGRATORS
from dalembert.adapters.mujoco.stepping import step_loop, step_rollout
from dalembert.settings import steps_per_interval

__all__ = ["prepare", "run", "audit", "describe"]


def _spec(scene, path):
    """``(MjSpec, locked joint names)`` of the file as MuJoCo reads it (module docstring)."""
    import mujoco

    if path.lower().endswith(".urdf"):
        locked = file_model.locked_joints(scene, file_model.urdf_joints(path))
        spec = mujoco.MjSpec.from_string(file_model.bare_urdf(path, locked))
        base = file_model.free_root(scene)
        if base is not None:  # MuJoCo fixes a URDF's root link: freed as the scene's base is
            root = spec.worldbody.first_body()
            if root is None or root.name != base.child:
                raise ValueError(f"options.model_file: MuJoCo's root body of {os.path.basename(path)} is "
                                 f"{getattr(root, 'name', None)!r}, the scene's floating base {base.child!r} — give "
                                 "the file the case's scene was read from (its --param model)")
            root.add_freejoint()
        return spec, tuple(locked)
    spec = mujoco.MjSpec.from_file(path)
    moving = file_model.moving_children(scene)
    locked = []
    for joint in list(spec.joints):
        body = joint.parent.name if hasattr(joint, "parent") else ""
        if joint.type in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE) and body not in moving:
            locked.append(joint.name)
            spec.delete(joint)
    return spec, tuple(locked)


def _compile(scene, settings, path):
    import mujoco

    try:
        spec, locked = _spec(scene, path)
        model = spec.compile()
    except ValueError as err:  # MuJoCo's XML and compiler errors
        raise ValueError(f"options.model_file: MuJoCo cannot read {os.path.basename(path)} ({err}) — give a URDF "
                         "or MJCF file MuJoCo compiles") from None
    model.opt.timestep = settings.dt
    model.opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{INTEGRATORS[settings.integrator].upper()}")
    model.opt.gravity[:] = scene.gravity
    model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    effects = _effects(model, file_model.effects_on(settings))  # as read, before any is zeroed
    if not file_model.effects_on(settings):
        model.dof_damping[:] = model.dof_frictionloss[:] = model.dof_armature[:] = 0.0
        model.jnt_stiffness[:] = 0.0
        model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_LIMIT)
    return model, locked, effects


def _joints(model):
    """``{child body name: joint id}`` of the model's hinge and slide joints."""
    import mujoco

    return {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(model.jnt_bodyid[j])): j for j in range(model.njnt)
            if int(model.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))}


def _base(model, scene):
    """``(qpos address, dof address, c_E (3,))`` of the freed root (its COM in its frame, fixed links merged in), or
    None for a fixed base."""
    import mujoco

    if file_model.free_root(scene) is None:
        return None
    (j,) = [j for j in range(model.njnt) if int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE)]
    return int(model.jnt_qposadr[j]), int(model.jnt_dofadr[j]), model.body_ipos[model.jnt_bodyid[j]].copy()


def _effects(model, on):
    """What MuJoCo read of the file's effects, by joint name, and what it applies (the audit's)."""
    import mujoco

    # the file's joints (a free joint added for a floating base is the case's, unnamed)
    names = {j: mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(model.njnt)
             if int(model.jnt_type[j]) != int(mujoco.mjtJoint.mjJNT_FREE)}
    dof = model.jnt_dofadr
    limits = {n: (tuple(float(x) for x in model.jnt_range[j]) if model.jnt_limited[j] else None)
              for j, n in names.items()}
    applied = "applied" if on else "zeroed (file_effects=off)"
    effort = int(np.count_nonzero(model.jnt_actfrclimited[list(names)]))
    return {
        "damping": file_model.effects_summary({n: float(model.dof_damping[dof[j]]) for j, n in names.items()},
                                              "N m s/rad", applied),
        "friction": file_model.effects_summary({n: float(model.dof_frictionloss[dof[j]]) for j, n in names.items()},
                                               "N m", applied),
        "armature": file_model.effects_summary({n: float(model.dof_armature[dof[j]]) for j, n in names.items()},
                                               "kg m^2", applied),
        "limits": (f"{sum(v is not None for v in limits.values())} of {len(names)} joints, "
                   + ("enforced by the constraint solver" if on else "disabled (file_effects=off)")
                   if any(v is not None for v in limits.values()) else "none"),
        "effort": (f"{effort} of {len(names)} joints, read as actuator-force ranges (no actuator: no force)"
                   if effort else "none"),
        "joint_values": {n: {"damping": float(model.dof_damping[dof[j]]),
                             "frictionloss": float(model.dof_frictionloss[dof[j]]),
                             "armature": float(model.dof_armature[dof[j]]), "range": limits[n]}
                         for j, n in names.items()},
    }


def prepare(scene, times, settings):
    """``FilePrepared`` of MuJoCo's reading of the file (``model_file``), its masses checked against the scene."""
    import mujoco

    path = file_model.model_file(settings)
    model, locked, effects = _compile(scene, settings, path)
    joints = _joints(model)
    file_model.check_same_model(scene, path, {c: float(model.body_subtreemass[model.jnt_bodyid[j]])
                                              for c, j in joints.items()}, "MuJoCo")
    qpos0, qvel0 = model.qpos0.copy(), np.zeros(model.nv)
    base = _base(model, scene)
    if base is not None:
        a, d, c_E = base
        p_E, q_E, v_E, w_B = file_model.base_initial(file_model.free_root(scene), c_E)
        qpos0[a:a + 7], qvel0[d:d + 6] = np.concatenate([p_E, q_E]), np.concatenate([v_E, w_B])
    for child, joint in file_model.moving_children(scene).items():
        j = joints[child]
        qpos0[model.jnt_qposadr[j]], qvel0[model.jnt_dofadr[j]] = joint.q0[0], joint.v0[0]
    times = np.asarray(times, float)
    data = mujoco.MjData(model)
    return file_model.FilePrepared(scene, times, settings, path, model, qpos0, qvel0,
                                   steps_per_interval(times, settings.dt), locked, effects, data)


def run(p):
    """Step MuJoCo's model of the file (the adapter's rollout, its loop where a chunk diverges)."""
    import mujoco

    view = SimpleNamespace(model=p.engine_model, data=p.extra, qpos0=p.q0, qvel0=p.v0, load_path="actuator",
                           times=p.times, steps=p.steps, scene=p.scene)
    messages = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(messages.append)
    try:
        Q, V, wall, diverged_at = step_rollout(view)
        if diverged_at is not None:
            messages.clear()
            Q, V, wall, diverged_at = step_loop(view)
    finally:
        mujoco.set_mju_user_warning(previous)
    n_steps = int(p.steps[:diverged_at].sum()) if diverged_at else int(p.steps.sum())
    stages = 4 if p.settings.integrator == "rk4" else 1
    joints = _joints(p.engine_model)
    model = p.engine_model

    def read():
        children = file_model.moving_children(p.scene)
        q = {c: Q[:, model.jnt_qposadr[joints[c]]] for c in children}
        v = {c: V[:, model.jnt_dofadr[joints[c]]] for c in children}
        base = _base(model, p.scene)
        if base is not None:  # MuJoCo's free qvel: the frame origin's velocity in world axes, w in body axes
            a, d, c_E = base
            root = file_model.free_root(p.scene).child
            q[root], v[root] = file_model.base_series(Q[:, a:a + 3], Q[:, a + 3:a + 7], V[:, d:d + 3],
                                                      V[:, d + 3:d + 6], c_E)
        return file_model.trajectory(p.scene, p.times, q, v)

    return Outcome(read, wall, n_steps, n_steps * stages,
                   {"message": f"MuJoCo: {messages[0]}" if messages else "", "warnings": messages[:5]})


def audit(p, outcome):
    """What MuJoCo read from the file and simulated: gravity, integrator, step, the file's effects as read."""
    import mujoco

    model = p.engine_model
    return {
        "gravity": tuple(float(g) for g in model.opt.gravity),
        "model_source": f"{os.path.basename(p.path)} read by MuJoCo's {'URDF' if p.path.endswith('.urdf') else 'MJCF'} "
                        "compiler",
        "file_effects": "on" if file_model.effects_on(p.settings) else "off",
        "file_effects_read": {k: v for k, v in p.effects.items() if k != "joint_values"},
        "joint_values": p.effects["joint_values"],
        "locked": list(p.locked),
        "integrator": mujoco.mjtIntegrator(model.opt.integrator).name,
        "timestep": float(model.opt.timestep),
        "mujoco_version": mujoco.__version__,
    }


def describe(scene, settings):
    """The model MuJoCo compiled from the file, as MJCF (``mj_saveLastXML`` needs a file: ``MjSpec.to_xml``)."""
    spec, _ = _spec(scene, file_model.model_file(settings))
    return spec.to_xml()
