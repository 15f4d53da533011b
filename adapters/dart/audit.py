"""What DART simulated, read back from the world and skeleton: the audit of a run (``Adapter.audit``)."""

from __future__ import annotations

import numpy as np

from dalembert.adapters.dart import contact
from dalembert.adapters.dart.model import dart_version

__all__ = ["audit", "defaults"]


def audit(prepared, outcome):
    """What DART simulated, read back from the world: gravity, step and integrator, the load path, every joint
    as DART holds it (type, axis, limits, damping, spring, friction, actuator), the bodies' mass properties, the
    world's deactivation and contact settings, the constraints and shapes (none), and what the run reported."""
    model = prepared.model
    world, skeleton = model.world, model.skeleton
    return {
        "gravity": tuple(float(g) for g in world.getGravity()),
        "integrator": "semi-implicit Euler (World.step: integrateVelocities, constraints, integratePositions)",
        "timestep": float(world.getTimeStep()),
        "defaults": model.defaults,
        **defaults(model),
        "joints": _joints(model),
        "bodies": _bodies(model),
        "loads": [f"{ld.effect} on {ld.body}" for ld in model.scene.loads],
        "load_path": ("" if not model.scene.loads else
                      "BodyNode external force/torque, kept in body axes by DART: follower loads set once; "
                      "world-frame loads set again before every step from the pose at the step's start"
                      if any(ld.frame == "world" for ld in model.scene.loads) else
                      "BodyNode external force/torque in body axes, set once (follower loads)"),
        **_loop_audit(model),
        **contact.audit(model),
        "steps": int(outcome.n_steps),
        "dart_version": dart_version(),
    }


def defaults(model):
    """The world's and skeleton's settings that a scene never calls for, read back from DART: deactivation
    (sleeping) and its thresholds, contact in the constraint solver, self-collision, shapes, constraints,
    and the largest joint damping, spring stiffness and Coulomb friction, and whether any limit is enforced."""
    world, skeleton = model.world, model.skeleton
    sleep = world.getDeactivationOptions()
    solver = world.getConstraintSolver()
    joints = list(model.joints.values())
    dof_values = lambda get: [float(abs(get(j, k))) for j in joints for k in range(j.getNumDofs())]  # noqa: E731
    return {
        "deactivation": {"enabled": bool(sleep.mEnabled), "linear_speed_threshold": float(sleep.mLinearSpeedThreshold),
                         "angular_speed_threshold": float(sleep.mAngularSpeedThreshold),
                         "time_until_sleep": float(sleep.mTimeUntilSleep)},
        "contact_enabled": bool(solver.getCollisionOption().enableContact),  # DART's; not settable from dartpy
        "collision_detector": type(solver.getCollisionDetector()).__name__,
        "collision_shape_frames": int(solver.getCollisionGroup().getNumShapeFrames()),
        "self_collision": bool(skeleton.getSelfCollisionCheck()),
        "shapes": int(skeleton.getNumShapeNodes()),
        "constraints": int(solver.getNumConstraints()),
        "split_impulse": bool(solver.isSplitImpulseEnabled()),
        "limits_enforced": any(bool(j.areLimitsEnforced()) for j in joints),
        "max_damping": max(dof_values(lambda j, k: j.getDampingCoefficient(k)), default=0.0),
        "max_spring_stiffness": max(dof_values(lambda j, k: j.getSpringStiffness(k)), default=0.0),
        "max_coulomb_friction": max(dof_values(lambda j, k: j.getCoulombFriction(k)), default=0.0),
        "max_command": max(dof_values(lambda j, k: j.getCommand(k)), default=0.0),
    }


def _joints(model):
    """Every scene joint as DART holds it: dict joint (child) name -> ``type`` (DART's), ``axis`` (revolute and
    prismatic: the unit axis in the joint frame; else None), ``actuator`` (DART's actuator type)."""
    out = {}
    for j in model.scene.joints:
        joint = model.joints[j.child]
        out[j.child] = {
            "type": joint.getType(),
            "axis": [float(v) for v in joint.getAxis()] if j.kind in ("revolute", "prismatic") else None,
            "actuator": str(joint.getActuatorType()).rsplit(".", 1)[-1] if joint.getNumDofs() else "",
        }
    return out


def _bodies(model):
    """Each body's mass (kg), local COM (m, body axes) and inertia about it (kg m^2), as DART holds them."""
    out = {}
    for name, node in model.nodes.items():
        inertia = node.getInertia()
        out[name] = {"mass": float(node.getMass()), "com": [float(v) for v in node.getLocalCOM()],
                     "inertia": np.asarray(inertia.getMoment(), dtype=float).tolist()}
    return out


def _loop_audit(model):
    """The loops as DART's constraint solver holds them: each constraint's type and rows, DART's class-wide
    constraint parameters, the boxed-LCP solvers, and why no reaction is read back (none: empty)."""
    if not model.scene.loops:
        return {}
    from dalembert.adapters.dart.loops import REACTIONS_REASON, parameters

    solver = model.world.getConstraintSolver()
    return {
        "loops": {lp.name: f"{type(c).__name__}, {c.getDimension()} rows" for lp, c in zip(model.scene.loops, model.loops)},
        "loop_parameters": parameters(),
        "lcp_solvers": [type(solver.getBoxedLcpSolver()).__name__, type(solver.getSecondaryBoxedLcpSolver()).__name__],
        "reactions": REACTIONS_REASON,
    }
