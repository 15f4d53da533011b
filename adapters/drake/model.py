"""A scene as a Drake ``MultibodyPlant`` in a diagram, exactly the scene's physics: ``DrakeModel``.

* Every body is a rigid body whose Drake body frame is the scene's body frame B
  (origin at the COM), with an explicit spatial inertia about it
  (``SpatialInertia.MakeFromCentralInertia``, the full tensor): ``X_EB`` is the
  identity for every body (``dalembert.adapters.base``).
* Joints between frames fixed in parent and child (``FixedOffsetFrame`` at the
  scene's joint frames): a free body gets a ``QuaternionFloatingJoint`` to the
  world, a revolute joint a ``RevoluteJoint`` about the normalized axis, a
  prismatic joint a ``PrismaticJoint`` along it (Drake's axis is in the joint's
  frame F, as the scene's is in the parent joint frame; ``p_FM = d a``, ``R_FM = I``:
  the scene's convention exactly, so q and v go in and out unchanged), a ball
  joint a ``BallRpyJoint`` (Drake has no quaternion ball joint: roll-pitch-yaw
  coordinates, singular at pitch = +-pi/2, kept clear of it by ``charts``), a weld a ``WeldJoint``; every damping
  zero, no limits.
* Gravity set from the scene (Drake's default is -9.81 in z), zero when the
  scene has none. No actuators. A scene without contact pairs has no SceneGraph and no collision geometry;
  one with them gets both (``contact``: the geoms, planes and named pairs, point contact).
* Loads through ``loads.SceneLoads``, connected to the plant's
  ``applied_spatial_force`` input: a follower force is turned into world axes
  from the pose the plant reports on its ``body_poses`` port, at every
  evaluation of the dynamics.
* Continuous mode (``time_step = 0``: Drake's integrators) or discrete mode
  (``time_step = dt``: the plant's own discrete update, SAP).
* Spring-dampers (``Scene.springs``) as ``LinearSpringDamper`` force elements
  (``springs``), in both modes; the only force elements besides the gravity field.
* Loop closures (``Scene.loops``) as SAP ball and distance constraints, in discrete
  mode only (``loops``: Drake's continuous plant takes no constraints); a loop to the
  world is attached to a body welded to the world (``loops.ANCHOR``).

Drake's coordinates (converted only through ``dalembert.spatial``): quaternion
floating joint ``q = (qw, qx, qy, qz, x, y, z)``, ``v = (w_WB_W, v_WB_W)`` — the
angular velocity in WORLD axes, unlike MuJoCo's and Pinocchio's body axes;
ball joint ``q = (roll, pitch, yaw)`` of ``R_FM`` (``R = Rz(yaw) Ry(pitch) Rx(roll)``),
``v = w_FM_F``.
"""

from __future__ import annotations

import functools

import numpy as np

from dalembert import spatial
from dalembert.adapters.drake import contact
from dalembert.scene import WORLD

__all__ = ["DrakeModel", "AXIS_ROUNDOFF", "drake_version"]

# A unit axis Drake normalized once more against the scene's normalized one: a few roundoffs of a unit vector.
AXIS_ROUNDOFF = 1e-15


def _transform(quat, point):
    from pydrake.math import RigidTransform, RotationMatrix

    return RigidTransform(RotationMatrix(spatial.quat_to_matrix(quat)), np.asarray(point, dtype=float))


class DrakeModel:
    """A scene as a finalized ``MultibodyPlant`` inside a ``Diagram`` (with the loads system).

    Attributes
    ----------
    plant, diagram, loads : the plant, its diagram, the ``SceneLoads`` system (or None)
    bodies : dict body name -> Drake ``RigidBody``
    joints : dict child name -> Drake joint (welds included)
    loops : list of ``loops.LoopConstraints`` (empty in continuous mode)
    springs : list of ``springs.SpringElement`` (one per scene spring)
    time_step : float — 0 for continuous mode, else the discrete step (s)
    summary : str — the plant as text (``dalembert show-model``)
    """

    def __init__(self, scene, time_step=0.0, settings=None):
        from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
        from pydrake.multibody.tree import (BallRpyJoint, FixedOffsetFrame, PrismaticJoint, QuaternionFloatingJoint,
                                            RevoluteJoint, RotationalInertia, SpatialInertia, WeldJoint)
        from pydrake.systems.framework import DiagramBuilder

        from dalembert.adapters.drake.loads import SceneLoads
        from dalembert.adapters.drake.loops import add_loops
        from dalembert.adapters.drake.springs import add_springs

        self.scene, self.time_step, self.settings = scene, float(time_step), settings
        builder = DiagramBuilder()
        self.scene_graph, self.geometry_ids = None, {}
        if scene.contacts:  # with a SceneGraph for the collision geometry (``contact``); else the plant alone
            plant, self.scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=self.time_step)
        else:
            plant = builder.AddSystem(MultibodyPlant(time_step=self.time_step))
        plant.set_name("plant")
        self.bodies, self.joints = {}, {}
        for body in scene.bodies:
            I = body.inertia_matrix
            G = RotationalInertia(I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
            self.bodies[body.name] = plant.AddRigidBody(
                body.name, SpatialInertia.MakeFromCentralInertia(body.mass, np.zeros(3), G))
        for j in scene.joints:
            parent = plant.world_body() if j.parent == WORLD else self.bodies[j.parent]
            child = self.bodies[j.child]
            if j.kind == "free":  # the body frame itself, from the world frame
                joint = QuaternionFloatingJoint(j.child, plant.world_frame(), child.body_frame(), 0.0, 0.0)
            else:
                F = plant.AddFrame(FixedOffsetFrame(f"{j.child}_Jp", parent.body_frame(),
                                                    _transform(j.parent_quat, j.parent_point)))
                M = plant.AddFrame(FixedOffsetFrame(f"{j.child}_Jc", child.body_frame(),
                                                    _transform(j.child_quat, j.child_point)))
                if j.kind == "revolute":
                    axis = np.asarray(j.axis, dtype=float)
                    joint = RevoluteJoint(j.child, F, M, axis / np.linalg.norm(axis), 0.0)
                elif j.kind == "prismatic":  # no limits (Drake's default: +-inf), no damping
                    axis = np.asarray(j.axis, dtype=float)
                    joint = PrismaticJoint(j.child, F, M, axis / np.linalg.norm(axis), -np.inf, np.inf, 0.0)
                elif j.kind == "ball":
                    joint = BallRpyJoint(j.child, F, M, 0.0)
                else:
                    from pydrake.math import RigidTransform

                    joint = WeldJoint(j.child, F, M, RigidTransform())
            self.joints[j.child] = plant.AddJoint(joint)
        # loop closures: SAP constraints, discrete mode only (``loops``; Drake's integrators take none)
        self.loops = add_loops(plant, scene, self.bodies) if scene.loops and self.time_step > 0.0 else []
        self.springs = add_springs(plant, scene, self.bodies)
        plant.mutable_gravity_field().set_gravity_vector(np.asarray(scene.gravity, dtype=float))
        if scene.contacts:
            self.geometry_ids = contact.add_geometry(plant, scene, self.bodies, settings)
        if self.time_step > 0.0:  # output ports from the state they are evaluated at, not from the last step
            plant.SetUseSampledOutputPorts(False)
            contact.set_solver(plant, settings)  # SAP (Drake's default) or TAMSI: option contact_solver
        plant.Finalize()
        if scene.contacts:  # nothing touches that the scene does not name
            contact.exclude_unnamed(self.scene_graph, scene, self.geometry_ids)
        self.loads = None
        if scene.loads:
            self.loads = builder.AddSystem(SceneLoads(scene.loads, {n: b.index() for n, b in self.bodies.items()}))
            builder.Connect(plant.get_body_poses_output_port(), self.loads.get_input_port(0))
            builder.Connect(self.loads.get_output_port(0), plant.get_applied_spatial_force_input_port())
        self.plant, self.diagram = plant, builder.Build()
        self.summary = self._summary()

    # ------------------------------------------------------------ conversions
    def initial_state(self):
        """The plant's ``(q (nq,), v (nv,))`` at the scene's ``q0``, ``v0`` (Drake's coordinates above)."""
        from pydrake.math import RollPitchYaw, RotationMatrix

        plant = self.plant
        q, v = np.zeros(plant.num_positions()), np.zeros(plant.num_velocities())
        for j in self.scene.joints:
            joint = self.joints[j.child]
            a, b = joint.position_start(), joint.velocity_start()
            if j.kind == "free":
                quat = np.asarray(j.q0[3:], dtype=float)
                q[a:a + 7] = np.concatenate([quat, j.q0[:3]])  # Drake: w in world axes, the scene's in body axes
                v[b:b + 6] = np.concatenate([spatial.body_to_world(quat, j.v0[3:]), j.v0[:3]])
            elif j.kind in ("revolute", "prismatic"):  # the angle (rad) or the slide (m), and its rate
                q[a], v[b] = j.q0[0], j.v0[0]
            elif j.kind == "ball":  # rpy of R_FM; w in F = R_FM w in M (the child joint frame)
                R_FM = spatial.quat_to_matrix(np.asarray(j.q0, dtype=float))
                q[a:a + 3] = RollPitchYaw(RotationMatrix(R_FM)).vector()
                v[b:b + 3] = R_FM @ np.asarray(j.v0, dtype=float)
        return q, v

    # ------------------------------------------------------------ audit
    def audit(self):
        """What the plant holds, read back from it: gravity, joints, damping, limits, geometry, forces."""
        plant = self.plant
        joints = [plant.get_joint(i) for i in plant.GetJointIndices()]
        damping = [float(np.max(np.abs(jt.default_damping_vector()), initial=0.0)) for jt in joints]
        lower = np.concatenate([plant.GetPositionLowerLimits(), plant.GetVelocityLowerLimits()])
        upper = np.concatenate([plant.GetPositionUpperLimits(), plant.GetVelocityUpperLimits()])
        return {
            "gravity": tuple(float(g) for g in plant.gravity_field().gravity_vector()),
            "joints": {jt.name(): jt.type_name() for jt in joints if jt.name() in self.joints},
            "max_joint_damping": max(damping, default=0.0),
            "finite_limits": int(np.sum(np.isfinite(lower)) + np.sum(np.isfinite(upper))),
            "collision_geometries": int(plant.num_collision_geometries()),
            "actuators": int(plant.num_actuators()),
            "constraints": int(plant.num_constraints()),
            # the uniform gravity field, always present, and one LinearSpringDamper per spring
            "force_elements": int(plant.num_force_elements()),
            "time_step": float(plant.time_step()),
            "nq": int(plant.num_positions()), "nv": int(plant.num_velocities()),
            **self._prismatic_audit(),
        }

    def prismatic_joints(self):
        """Every ``PrismaticJoint`` of the finalized plant, read back from the plant (not from the scene): a dict
        joint name -> dict ``type`` (Drake's type name), ``parent``, ``child`` (body names), ``axis_F`` (3-tuple,
        the unit sliding direction in the joint's frame F on the parent), ``position_limits`` (m),
        ``velocity_limits`` (m/s), ``acceleration_limits`` (m/s^2) as (lower, upper) pairs, and ``damping``
        (N s/m, the default the simulator's context starts from)."""
        from pydrake.multibody.tree import PrismaticJoint

        plant, out = self.plant, {}
        pair = lambda lo, hi: (float(lo[0]), float(hi[0]))  # noqa: E731
        for i in plant.GetJointIndices():
            jt = plant.get_joint(i)
            if isinstance(jt, PrismaticJoint):
                out[jt.name()] = dict(
                    type=jt.type_name(), parent=jt.parent_body().name(), child=jt.child_body().name(),
                    axis_F=tuple(float(x) for x in jt.translation_axis()),
                    position_limits=pair(jt.position_lower_limits(), jt.position_upper_limits()),
                    velocity_limits=pair(jt.velocity_lower_limits(), jt.velocity_upper_limits()),
                    acceleration_limits=pair(jt.acceleration_lower_limits(), jt.acceleration_upper_limits()),
                    damping=float(jt.default_damping()))
        return out

    def _prismatic_audit(self):
        """The prismatic joints as the plant holds them (``prismatic_joints``), and whether each is the scene's:
        type ``prismatic``, the scene's unit axis (to a rounding: Drake normalizes it again), every limit infinite,
        no damping."""
        built = self.prismatic_joints()
        if not built:
            return {}
        inf = (-np.inf, np.inf)
        free = lambda b: b["position_limits"] == b["velocity_limits"] == b["acceleration_limits"] == inf  # noqa: E731
        same = []
        for j in self.scene.joints:
            if j.kind == "prismatic":
                b = built.get(j.child)
                a = np.asarray(j.axis, dtype=float) / np.linalg.norm(j.axis)
                same.append(b is not None and b["type"] == "prismatic" and b["child"] == j.child and free(b)
                            and b["damping"] == 0.0 and np.allclose(b["axis_F"], a, rtol=0.0, atol=AXIS_ROUNDOFF))
        return {
            "prismatic_joints": {name: (f"{b['type']} {b['parent']} -> {b['child']}, axis_F {list(b['axis_F'])}, "
                                        f"position limits {b['position_limits']} m, velocity limits "
                                        f"{b['velocity_limits']} m/s, acceleration limits {b['acceleration_limits']} "
                                        f"m/s^2, damping {b['damping']!r} N s/m")
                                 for name, b in built.items()},
            "prismatic_as_scene": len(built) == len(same) and all(same),
        }

    def _summary(self):
        plant = self.plant
        mode = ("continuous (Drake's integrators)" if self.time_step == 0.0
                else f"discrete, time_step = {self.time_step!r} s ({plant.get_discrete_contact_solver().name} "
                     f"solver, {plant.get_discrete_contact_approximation().name} approximation)")
        lines = [f"MultibodyPlant: {mode}; nq = {plant.num_positions()}, nv = {plant.num_velocities()}, "
                 f"gravity = {plant.gravity_field().gravity_vector().tolist()} m/s^2; "
                 f"{plant.num_collision_geometries()} collision geometries, {plant.num_actuators()} actuators"]
        for name, body in self.bodies.items():
            M = body.default_spatial_inertia()
            lines.append(f"body {name}: mass {body.default_mass():g} kg, COM at the body origin "
                         f"{M.get_com().tolist()}, I_Bcm = {M.CalcRotationalInertia().CopyToFullMatrix3().tolist()}")
        for child, joint in self.joints.items():
            X_PF = joint.frame_on_parent().GetFixedPoseInBodyFrame()
            X_CM = joint.frame_on_child().GetFixedPoseInBodyFrame()
            lines.append(f"joint {child}: {joint.type_name()} {joint.parent_body().name()} -> {joint.child_body().name()}"
                         f", X_PF p = {X_PF.translation().tolist()}, X_CM p = {X_CM.translation().tolist()}, "
                         f"damping {joint.default_damping_vector().tolist()}"
                         + (f", translation axis (in F) {joint.translation_axis().tolist()}, position limits "
                            f"[{joint.position_lower_limit()}, {joint.position_upper_limit()}] m"
                            if joint.type_name() == "prismatic" else ""))
        for lc in self.loops:
            lp = lc.loop
            what = (f"1 distance constraint ({lp.length:g} m, stiffness inf)" if lp.kind == "distance" else
                    f"2 ball constraints, the second {lc.lever:g} m along the axis" if lp.kind == "revolute" else
                    "1 ball constraint")
            lines.append(f"loop {lp.name}: {lp.kind} {lp.body_a} -> {lp.body_b}: {what} (SAP, near-rigid)")
        if self.scene.loops and not self.loops:
            lines.append(f"loops: {len(self.scene.loops)} not built (continuous mode takes no constraints)")
        for se in self.springs:
            fe = se.element
            lines.append(f"spring {se.spring.name}: LinearSpringDamper {fe.bodyA().name()} {fe.p_AP().tolist()} -> "
                         f"{fe.bodyB().name()} {fe.p_BQ().tolist()}, free length {fe.free_length():g} m, stiffness "
                         f"{fe.stiffness():g} N/m, damping {fe.damping():g} N s/m")
        for ld in self.scene.loads:
            lines.append(f"load {ld.effect} on {ld.body}: {list(ld.vector)} at {list(ld.point)} (SceneLoads system)")
        lines.extend(contact.summary_lines(self))
        return "\n".join(lines) + "\n"


def drake_version():
    """The installed Drake's version (ImportError when it is missing): ``pydrake.__version__``, or the
    distribution's where the package has none."""
    import pydrake

    return pydrake.__version__ if hasattr(pydrake, "__version__") else _distribution_version()


@functools.cache  # (installed packages do not change under a process; every run asks twice: ~1 ms a time)
def _distribution_version():
    from importlib.metadata import version

    return version("drake")
