"""What PyBullet simulated, read back from the engine: the audit of a run (``Adapter.audit``).

Read from PyBullet's own reports: gravity, step, sub-steps and solver iterations
(``getPhysicsEngineParameters``), each body's mass, principal moments and inertial frame
(``getDynamicsInfo``), each joint's type, axis, damping, friction, limits and motor settings
(``getJointInfo``), collision shapes, contacts and constraints, and the motor forces the read-back's
steps applied.

PyBullet 3.2.7 reports neither a multibody's linear and angular damping, nor its joint-rate clamp, nor
whether it may sleep. The first two are measured instead (``velocity_odd_acceleration``): one step
from the initial configuration at velocities v and at -v (every velocity 1 where the scene starts at
rest), in the scratch client. Every velocity-dependent force of a tree without damping (gyroscopic,
Coriolis and centrifugal) is even in v, and gravity and the loads do not depend on it, so the odd part
of the step's acceleration, ``(a(v) - a(-v)) / 2``, is zero but for roundoff unless something
damps the motion: PyBullet's damping (linear plus quadratic in the speed), a joint's damping or
friction, or the velocity motor that holds a joint still. Sleeping is not reported: the adapter
switches it off (``activationState``), and no scene here comes to rest.
"""

from __future__ import annotations

import numpy as np

from dalembert.adapters.pybullet import contact
from dalembert.adapters.pybullet.model import NO_VELOCITY_CLAMP, SOLVERS, engine
from dalembert.adapters.pybullet.stepping import apply_loads, read_state, state_size, write_state

__all__ = ["audit", "velocity_odd_acceleration", "JOINT_TYPES"]

JOINT_TYPES = {0: "revolute", 1: "prismatic", 2: "spherical", 3: "planar", 4: "fixed"}


def audit(prepared, outcome):
    """What PyBullet simulated (``Adapter.audit``): a dict, read back from the engine (module docstring)."""
    pb = engine()
    model = prepared.model
    c = model.client
    params = pb.getPhysicsEngineParameters(physicsClientId=c)
    outcome.trajectory  # reads back, once, if nothing has yet
    shapes = sum(len(pb.getCollisionShapeData(mb, link, physicsClientId=c))
                 for mb, links in model.links.items() for link in (-1, *links))
    shapes += sum(len(pb.getCollisionShapeData(mb, -1, physicsClientId=c)) for mb in model.planes.values())
    return {
        "gravity": tuple(float(params[f"gravityAcceleration{a}"]) for a in "XYZ"),
        "integrator": "semi-implicit Euler (btMultiBody: velocities, then positions from the new velocities)",
        "time_step": float(params["fixedTimeStep"]),
        "sub_steps": int(params["numSubSteps"]),
        "solver_iterations": int(params["numSolverIterations"]),
        "solver": SOLVERS[model.solver],
        "pybullet_api_version": int(pb.getAPIVersion(physicsClientId=c)),
        "defaults": model.defaults,
        "multibodies": len(model.links),
        "bodies": _bodies(pb, model),
        "joints": _joints(pb, model),
        "collision_shapes": int(shapes),
        "contacts": len(pb.getContactPoints(physicsClientId=c)),
        "constraints": int(pb.getNumConstraints(physicsClientId=c)),
        "load_path": ("applyExternalForce/applyExternalTorque before every step (follower loads in the link's "
                      "inertial frame, LINK_FRAME; world torques in world axes; world forces at the point's "
                      "world position)") if prepared.scene.loads else "none",
        "set_not_readable": ({"linear_damping": 0.0, "angular_damping": 0.0, "max_joint_velocity": NO_VELOCITY_CLAMP,
                              "sleeping": "disabled"} if model.defaults == "scene" else
                             "PyBullet's defaults kept: damping 0.04 linear and angular, joint rates clamped at "
                             "100 rad/s, sleeping allowed"),
        "velocity_odd_acceleration": velocity_odd_acceleration(prepared),
        "max_motor_force": outcome.info["read"]["max_motor_force"],
        # contact: the samples whose contact force the read-back's replay gave (all of them: bit for bit the run's)
        **{k: v for k, v in outcome.info["read"].items() if k == "contact_force_samples"},
        **contact.audit(pb, model, prepared.scene),
    }


def _bodies(pb, model):
    """Per scene body: PyBullet's mass (kg), principal moments (kg m^2) and where it is (multibody, link)."""
    out = {}
    for name, part in model.parts.items():
        info = pb.getDynamicsInfo(part.mb, part.link, physicsClientId=model.client)
        out[name] = {"multibody": int(part.mb), "link": int(part.link), "mass": float(info[0]),
                     "principal_moments": [float(v) for v in info[2]]}
    return out


def _joints(pb, model):
    """Per scene joint that PyBullet builds as a link's joint: its type, axis (link frame), damping, friction,
    whether it is limited, and its motor's force and rate bounds, as ``getJointInfo`` reports them."""
    out = {}
    for name, part in model.parts.items():
        if part.link < 0:
            continue
        info = pb.getJointInfo(part.mb, part.link, physicsClientId=model.client)
        out[name] = {"type": JOINT_TYPES.get(info[2], str(info[2])), "axis_L": [float(v) for v in info[13]],
                     "damping": float(info[6]), "friction": float(info[7]), "limited": bool(info[8] <= info[9]),
                     "max_force": float(info[10]), "max_velocity": float(info[11])}
    return out


def velocity_odd_acceleration(prepared):
    """The largest odd part of one step's acceleration in velocity, ``|a(v) - a(-v)| / 2`` over every
    coordinate (m/s^2 or rad/s^2), at the initial configuration with its velocities (every one 1 where
    they are all zero), measured in the scratch client (module docstring): zero but for roundoff when
    nothing damps the motion."""
    pb = engine()
    model, scene = prepared.scratch, prepared.scene
    model.state0(scene)
    row = read_state(pb, model, np.zeros(state_size(model)))
    mask = np.zeros(len(row), dtype=bool)
    k = 0
    for _ in model.floating:
        mask[k + 7:k + 13] = True
        k += 13
    kinds = {(part.mb, part.link): part.kind for part in model.parts.values()}
    for mb, links in model.links.items():
        for link in links:
            mask[k + 4:k + 4 + {"revolute": 1, "prismatic": 1, "ball": 3}.get(kinds[(mb, link)], 0)] = True
            k += 7
    if not np.any(row[mask]):
        row[mask] = 1.0
    after = []
    for sign in (1.0, -1.0):
        x = row.copy()
        x[mask] *= sign
        write_state(pb, model, x)
        for mb, links in model.links.items():  # the links' poses at x, where a world force is applied
            if links:
                pb.getLinkStates(mb, list(links), computeForwardKinematics=1, physicsClientId=model.client)
        apply_loads(pb, model.client, prepared.loads)
        pb.stepSimulation(physicsClientId=model.client)
        after.append(read_state(pb, model, np.zeros(len(row)))[mask] - x[mask])
    h = prepared.settings.dt
    return float(np.max(np.abs(after[0] - after[1]), initial=0.0) / (2.0 * h))
