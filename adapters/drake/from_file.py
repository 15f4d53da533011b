"""Drake reading the robot's URDF itself (option ``model_file``; ``dalembert.adapters.file_model``).

Drake's ``Parser`` reads the file without its geometry, the scene's locked joints fixed
(``file_model.bare_urdf``), into a ``MultibodyPlant`` (continuous, or discrete with ``time_step = dt`` for the
integrator ``discrete``), its root link welded to the world (Drake leaves a URDF's root floating unless it is
the link ``world``) or, where the scene's base floats, left floating (Drake's quaternion floating body). Drake
reads a joint's ``<dynamics damping>`` as the joint's damping, applied in both modes;
its ``<limit lower upper>`` as position limits, enforced by the discrete plant only (a continuous plant ignores
them); ``friction`` is not read. ``file_effects=off`` zeroes the damping and removes the limits before the plant
is finalized. The case's gravity is set on the plant; the stepping is the adapter's (``stepping.simulate``).
"""

from __future__ import annotations

import logging
import os
from types import SimpleNamespace

import numpy as np

from dalembert import spatial
from dalembert.adapters import file_model
from dalembert.adapters.base import Outcome

__all__ = ["prepare", "run", "audit", "describe"]


def _plant(scene, settings, path):
    """``(plant, diagram, {child link: joint}, locked names, effects read)``: Drake's reading of the file."""
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant
    from pydrake.systems.framework import DiagramBuilder

    if not path.lower().endswith(".urdf"):
        raise ValueError(f"options.model_file: {os.path.basename(path)} — Drake reads URDF files here (its MJCF "
                         "reader is not wired) — give the robot's .urdf, or run model_file with mujoco")
    joints = file_model.urdf_joints(path)
    locked = file_model.locked_joints(scene, joints)
    builder = DiagramBuilder()
    plant = builder.AddSystem(MultibodyPlant(time_step=settings.dt if settings.integrator == "discrete" else 0.0))
    logger, said = logging.getLogger("drake"), []

    def keep(record):  # the parser's warnings go to the audit, not the console (the contract: no printing)
        said.append(record.getMessage())
        return False

    logger.addFilter(keep)
    try:
        (instance,) = Parser(plant).AddModelsFromString(file_model.bare_urdf(path, locked), "urdf")
    except (RuntimeError, ValueError) as err:
        raise ValueError(f"options.model_file: Drake cannot read {os.path.basename(path)} ({err}) — give a URDF "
                         "Drake parses") from None
    finally:
        logger.removeFilter(keep)
    children = {j.child for j in joints}
    roots = [lk for lk in (b.name() for b in _links(plant, instance)) if lk not in children]
    if roots and roots[0] != "world" and file_model.free_root(scene) is None:  # (a floating base stays free)
        plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(roots[0], instance))
    by_child = {}
    for j in joints:
        if j.name in locked or j.kind not in ("revolute", "continuous", "prismatic"):
            continue
        by_child[j.child] = plant.GetJointByName(j.name, instance)
    effects = _effects(by_child, settings)
    effects["parser_warnings"] = sorted({w.split("warning: ", 1)[-1] for w in said})
    if not file_model.effects_on(settings):
        for joint in by_child.values():
            joint.set_default_damping(0.0)
            joint.set_position_limits([-np.inf], [np.inf])
    plant.mutable_gravity_field().set_gravity_vector(np.asarray(scene.gravity, float))
    plant.Finalize()
    return plant, builder.Build(), by_child, tuple(locked), effects


def _base(plant, context, scene):
    """``(position start, velocity start, c_E (3,))`` of the floating root body: ``c_E`` the COM of it and the bodies
    welded to it, in its frame (m); None for a fixed base."""
    base = file_model.free_root(scene)
    if base is None:
        return None
    root = plant.GetBodyByName(base.child)
    welded = plant.GetBodiesWeldedTo(root)  # (the root included)
    mass, moment = 0.0, np.zeros(3)
    for b in welded:
        X = plant.CalcRelativeTransform(context, root.body_frame(), b.body_frame())
        m = b.get_mass(context)
        mass, moment = mass + m, moment + m * (X @ b.CalcCenterOfMassInBodyFrame(context))
    return root.floating_positions_start(), root.floating_velocities_start_in_v(), moment / mass


def _links(plant, instance):
    return [plant.get_body(i) for i in plant.GetBodyIndices(instance)]


def _effects(by_child, settings):
    on = file_model.effects_on(settings)
    discrete = settings.integrator == "discrete"
    damping = {j.name(): float(j.default_damping()) for j in by_child.values()}
    limited = [j.name() for j in by_child.values() if np.all(np.isfinite(j.position_lower_limits()))]
    return {
        "damping": file_model.effects_summary(damping, "N m s/rad", "applied" if on else "zeroed (file_effects=off)"),
        "friction": "not read (Drake's URDF parser ignores <dynamics friction>)",
        "armature": "none (a URDF gives Drake none; drake:rotor_inertia would)",
        "limits": (f"{len(limited)} of {len(damping)} joints, "
                   + ("removed (file_effects=off)" if not on else
                      "enforced (discrete plant)" if discrete else "read, not enforced (a continuous plant ignores "
                      "them)") if limited else "none"),
    }


def prepare(scene, times, settings):
    """``FilePrepared`` of Drake's reading of the file (``model_file``), its masses checked against the scene."""
    from dalembert.adapters.drake.adapter import ADAPTIVE_SUFFIX
    from dalembert.adapters.drake.stepping import SCHEMES

    path = file_model.model_file(settings)
    plant, diagram, by_child, locked, effects = _plant(scene, settings, path)
    context = plant.CreateDefaultContext()
    masses = {c: float(sum(plant.get_body(b).get_mass(context)
                           for b in plant.GetBodiesKinematicallyAffectedBy([j.index()])))
              for c, j in by_child.items()}
    file_model.check_same_model(scene, path, masses, "Drake")
    q0, v0 = np.zeros(plant.num_positions()), np.zeros(plant.num_velocities())
    base = _base(plant, context, scene)
    if base is not None:  # Drake's floating body: (quaternion w x y z, p), then (w_W, v_W of its origin)
        a, d, c_E = base
        p_E, q_E, v_E, w_B = file_model.base_initial(file_model.free_root(scene), c_E)
        R = spatial.quat_to_matrix(q_E / np.linalg.norm(q_E))
        q0[a:a + 7], v0[d:d + 6] = np.concatenate([q_E, p_E]), np.concatenate([R @ w_B, v_E])
    for c, joint in file_model.moving_children(scene).items():
        j = by_child[c]
        q0[j.position_start()], v0[j.velocity_start()] = joint.q0[0], joint.v0[0]
    discrete = settings.integrator == "discrete"
    scheme = None if discrete else SCHEMES[settings.integrator.removesuffix(ADAPTIVE_SUFFIX)]
    model = SimpleNamespace(plant=plant, diagram=diagram, time_step=plant.time_step(), loads=None, scene=scene,
                            joints={})
    return file_model.FilePrepared(scene, np.asarray(times, float), settings, path, plant, q0, v0, None, locked,
                                   effects, (model, by_child, scheme))


def run(p):
    """The adapter's stepping (``stepping.simulate``) on Drake's plant of the file."""
    from dalembert.adapters.drake.stepping import simulate

    model, by_child, scheme = p.extra
    view = SimpleNamespace(model=model, times=p.times, settings=p.settings, q0=p.q0, v0=p.v0, scheme=scheme)
    X, wall, n_steps, n_rhs, message, _ = simulate(view)
    nq = model.plant.num_positions()

    def read():
        children = file_model.moving_children(p.scene)
        q = {c: X[:, by_child[c].position_start()] for c in children}
        v = {c: X[:, nq + by_child[c].velocity_start()] for c in children}
        base = _base(model.plant, model.plant.CreateDefaultContext(), p.scene)
        if base is not None:
            a, d, c_E = base
            q_E = X[:, a:a + 4]
            R = spatial.quat_to_matrix(q_E / np.linalg.norm(q_E, axis=1, keepdims=True))
            w_B = np.einsum("nji,nj->ni", R, X[:, nq + d:nq + d + 3])
            root = file_model.free_root(p.scene).child
            q[root], v[root] = file_model.base_series(X[:, a + 4:a + 7], q_E, X[:, nq + d + 3:nq + d + 6], w_B, c_E)
        return file_model.trajectory(p.scene, p.times, q, v)

    return Outcome(read, wall, n_steps, n_rhs, {"message": message})


def audit(p, outcome):
    """What Drake read from the file and simulated."""
    from dalembert.adapters.drake.model import drake_version

    plant = p.engine_model
    return {
        "gravity": tuple(float(g) for g in plant.gravity_field().gravity_vector()),
        "model_source": f"{os.path.basename(p.path)} read by Drake's Parser (URDF)",
        "file_effects": "on" if file_model.effects_on(p.settings) else "off",
        "file_effects_read": dict(p.effects),
        "locked": list(p.locked),
        "time_step": float(plant.time_step()),
        "integrator": p.settings.integrator,
        "drake_version": drake_version(),
    }


def describe(scene, settings):
    """Drake's plant of the file: its joints and their damping and limits."""
    plant, _, by_child, locked, effects = _plant(scene, settings, file_model.model_file(settings))
    lines = [f"MultibodyPlant read from {file_model.model_file(settings)} (locked: {list(locked)}); "
             f"{plant.num_positions()} positions, {plant.num_velocities()} velocities"]
    lines += [f"  {j.name()} ({j.type_name()}): damping {j.default_damping():g}, limits "
              f"{j.position_lower_limits().tolist()} .. {j.position_upper_limits().tolist()}"
              for j in by_child.values()]
    lines += [f"  {k}: {v}" for k, v in effects.items()]
    return "\n".join(lines)
