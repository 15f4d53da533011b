"""Pinocchio reading the robot's URDF itself (option ``model_file``; ``dalembert.adapters.file_model``).

``pin.buildModelFromXML`` of the file without its geometry, the scene's locked joints fixed
(``file_model.bare_urdf``), with a ``JointModelFreeFlyer`` root where the scene's base floats: Pinocchio
merges every fixed link into its parent's body and reads a joint's
``<dynamics damping friction>`` into ``model.damping`` and ``model.friction``, its ``<limit>`` into the position,
velocity and effort limits, and an armature (``model.armature``: zero from a URDF). Its forward dynamics
(``pin.aba``) applies the armature only: damping, friction and limits are read for the caller to apply, and a
Pinocchio user's simulation gets none of them unless it adds them — which is what runs here with
``file_effects=on`` (the audit says so). ``file_effects=off`` zeroes the armature too. The integrators are the
adapter's own (``integrators``: the Python loops and scipy's; the compiled loop is built for the scene's model
only). A continuous joint is Pinocchio's unit-circle joint (cos, sin): its angle is read back unwrapped.
"""

from __future__ import annotations

import os

import numpy as np

from dalembert import spatial
from dalembert.adapters import file_model
from dalembert.adapters.base import Outcome
from dalembert.adapters.pinocchio.integrators import adaptive, fixed_step
from dalembert.settings import steps_per_interval

__all__ = ["FileModel", "prepare", "run", "audit", "describe"]


class FileModel:
    """Pinocchio's model of the file, as the adapter's integrators take a model (``model``, ``acceleration_function``,
    ``dexpinv_function``): no loads, no constraints; ``aba`` with zero joint torques."""

    def __init__(self, model):
        self.model = model
        self.data = model.createData()

    def acceleration_function(self):
        import pinocchio as pin

        model, data, tau = self.model, self.data, np.zeros(self.model.nv)
        return lambda q, v: pin.aba(model, data, q, v, tau)

    def dexpinv_function(self):
        """None where the configuration space is a vector space (nq = nv), else the ``dIntegrate`` solve."""
        import pinocchio as pin

        if self.model.nq == self.model.nv:
            return None
        model, ARG1 = self.model, pin.ArgumentPosition.ARG1
        return lambda q, theta, vel: np.linalg.solve(pin.dIntegrate(model, q, theta, ARG1), vel)


def _build(scene, path):
    """``(pin.Model, {child link: joint id}, locked joint names)`` of the file as Pinocchio reads it."""
    import pinocchio as pin

    if not path.lower().endswith(".urdf"):
        raise ValueError(f"options.model_file: {os.path.basename(path)} — Pinocchio reads URDF files here (its MJCF "
                         "reader is not wired) — give the robot's .urdf, or run model_file with mujoco")
    joints = file_model.urdf_joints(path)
    locked = file_model.locked_joints(scene, joints)
    try:
        text = file_model.bare_urdf(path, locked)
        # a floating base: Pinocchio's FreeFlyer on the root link (its frame E, the link's)
        model = (pin.buildModelFromXML(text) if file_model.free_root(scene) is None
                 else pin.buildModelFromXML(text, pin.JointModelFreeFlyer()))
    except (ValueError, RuntimeError) as err:
        raise ValueError(f"options.model_file: Pinocchio cannot read {os.path.basename(path)} ({err}) — give a URDF "
                         "Pinocchio reads") from None
    child = {j.name: j.child for j in joints}
    ids = {child[model.names[i]]: i for i in range(1, model.njoints) if model.names[i] in child}
    return model, ids, tuple(locked)


def _effects(model, on):
    # the file's joints (a FreeFlyer added for a floating base is the case's)
    kept = [i for i in range(1, model.njoints) if model.joints[i].shortname() != "JointModelFreeFlyer"]
    names = [model.names[i] for i in kept]
    v = [model.joints[i].idx_v for i in kept]
    lower = model.lowerPositionLimit
    joints = [model.joints[i] for i in kept]
    # a continuous joint (nq = 2: cos, sin) has no limits; Pinocchio's bounds on its (cos, sin) are not the file's
    finite = [n for n, j in zip(names, joints) if j.nq == 1 and np.isfinite(lower[j.idx_q]) and lower[j.idx_q] > -1e10]
    return {
        "damping": file_model.effects_summary({n: float(model.damping[i]) for n, i in zip(names, v)}, "N m s/rad",
                                              "read, not applied (pin.aba takes none)"),
        "friction": file_model.effects_summary({n: float(model.friction[i]) for n, i in zip(names, v)}, "N m",
                                               "read, not applied (pin.aba takes none)"),
        "armature": file_model.effects_summary({n: float(model.armature[i]) for n, i in zip(names, v)}, "kg m^2",
                                               "applied by pin.aba" if on else "zeroed (file_effects=off)"),
        "limits": (f"{len(finite)} of {len(names)} joints, read, not enforced (pin.aba has no limits)"
                   if finite else "none"),
        "effort": file_model.effects_summary({n: float(model.effortLimit[i]) for n, i in zip(names, v)}, "N m",
                                             "read as limits (no actuator: no force)"),
    }


def prepare(scene, times, settings):
    """``FilePrepared`` of Pinocchio's reading of the file (``model_file``), its masses checked against the scene."""
    import pinocchio as pin

    path = file_model.model_file(settings)
    model, ids, locked = _build(scene, path)
    data = model.createData()
    pin.computeSubtreeMasses(model, data)
    file_model.check_same_model(scene, path, {c: float(data.mass[i]) for c, i in ids.items()}, "Pinocchio")
    on = file_model.effects_on(settings)
    effects = _effects(model, on)
    if not on:
        model.armature[:] = 0.0
    model.gravity.linear = np.asarray(scene.gravity, float)
    q0, v0 = pin.neutral(model), np.zeros(model.nv)
    base = file_model.free_root(scene)
    if base is not None:  # FreeFlyer: (p, quaternion x y z w), velocities in the root frame E
        p_E, q_E, v_E, w_B = file_model.base_initial(base, model.inertias[1].lever)
        R = pin.Quaternion(*q_E).toRotationMatrix()  # (w, x, y, z)
        q0[:7] = np.concatenate([p_E, q_E[1:], q_E[:1]])
        v0[:6] = np.concatenate([R.T @ v_E, w_B])
    for c, joint in file_model.moving_children(scene).items():
        jm = model.joints[ids[c]]
        if jm.nq == 2:  # unit circle: (cos, sin)
            q0[jm.idx_q:jm.idx_q + 2] = np.cos(joint.q0[0]), np.sin(joint.q0[0])
        else:
            q0[jm.idx_q] = joint.q0[0]
        v0[jm.idx_v] = joint.v0[0]
    times = np.asarray(times, float)
    steps = steps_per_interval(times, settings.dt) if settings.dt else None
    return file_model.FilePrepared(scene, times, settings, path, model, q0, v0, steps, locked, effects,
                                   (FileModel(model), ids))


def run(p):
    """The adapter's Python integrators on Pinocchio's model of the file."""
    import time

    fm, ids = p.extra
    s = p.settings
    start = time.perf_counter()
    if p.steps is None:
        Q, V, n_steps, n_rhs = adaptive(fm, s.integrator.upper(), p.q0, p.v0, p.times, s.rtol, s.atol)
    else:
        Q, V, n_steps, n_rhs = fixed_step(fm, s.integrator, p.q0, p.v0, p.times, p.steps)
    wall = time.perf_counter() - start
    model = p.engine_model

    def read():
        q, v = {}, {}
        for c, joint in file_model.moving_children(p.scene).items():
            jm = model.joints[ids[c]]
            if jm.nq == 2:  # the angle on the unit circle, unwrapped from the scene's initial angle
                angle = np.unwrap(np.arctan2(Q[:, jm.idx_q + 1], Q[:, jm.idx_q]))
                q[c] = angle + (joint.q0[0] - angle[0])
            else:
                q[c] = Q[:, jm.idx_q]
            v[c] = V[:, jm.idx_v]
        base = file_model.free_root(p.scene)
        if base is not None:
            q_E = np.concatenate([Q[:, 6:7], Q[:, 3:6]], axis=1)  # scalar first
            R = spatial.quat_to_matrix(q_E / np.linalg.norm(q_E, axis=1, keepdims=True))
            q[base.child], v[base.child] = file_model.base_series(Q[:, :3], q_E, np.einsum("nij,nj->ni", R, V[:, :3]),
                                                                  V[:, 3:6], model.inertias[1].lever)
        return file_model.trajectory(p.scene, p.times, q, v)

    return Outcome(read, wall, n_steps, n_rhs, {"loop": "Python (adapters/pinocchio/integrators.py) on the file's "
                                                        "model"})


def audit(p, outcome):
    """What Pinocchio read from the file and simulated."""
    import pinocchio as pin

    return {
        "gravity": tuple(float(g) for g in p.engine_model.gravity.linear),
        "model_source": f"{os.path.basename(p.path)} read by pin.buildModelFromXML (Pinocchio's URDF reader)",
        "file_effects": "on" if file_model.effects_on(p.settings) else "off",
        "file_effects_read": dict(p.effects),
        "locked": list(p.locked),
        "joints": {p.engine_model.names[i]: p.engine_model.joints[i].shortname()
                   for i in range(1, p.engine_model.njoints)},
        "integrator": p.settings.integrator,
        "loop": outcome.info.get("loop", ""),
        "pinocchio_version": pin.__version__,
    }


def describe(scene, settings):
    """Pinocchio's model of the file, as its own summary."""
    model, _, locked = _build(scene, file_model.model_file(settings))
    return f"pin.Model read from {file_model.model_file(settings)} (locked: {list(locked)}):\n{model}"
