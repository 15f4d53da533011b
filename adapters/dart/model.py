"""A scene as a DART ``World`` with one ``Skeleton``, exactly the scene's physics: ``DartModel``.

* Every body is a ``BodyNode`` whose DART frame is the scene's body frame B (origin at the COM): its
  ``Inertia`` has the scene's mass, a zero local COM and the full tensor about the COM, so ``X_EB`` is
  the identity for every body (``dalembert.adapters.base``), and each node's world transform, linear
  velocity (of its origin, the COM) and angular velocity are the scene's body states.
* One skeleton holds every tree (a free body is a tree of its own). Joints between the scene's joint
  frames: ``setTransformFromParentBodyNode`` is ``X_PJp`` (``parent_point``, ``parent_quat``; the world's
  frame for a root), ``setTransformFromChildBodyNode`` is ``X_CJc``; a free body gets a ``FreeJoint``, a
  revolute joint a ``RevoluteJoint`` about the normalized axis, a prismatic joint a ``PrismaticJoint`` along
  it (DART's axis is in the joint frame, Jp and Jc coinciding at q = 0: the scene's convention), a ball joint a
  ``BallJoint``, a weld a ``WeldJoint``.
* DART's coordinates (converted only through ``dalembert.spatial``): a ``FreeJoint``'s positions are the
  rotation vector of ``R_WB`` and ``p_WB``; its velocities are solved from the body's spatial velocity in body
  axes, ``(w_WB_B, R_WB^T v_WB_W)``, through the joint's own relative Jacobian (they are not that velocity:
  measured, its linear part comes out turned by ``R_WB``); a ``BallJoint``'s positions are the rotation vector
  of ``R_JpJc``, its velocities the relative angular velocity in Jc axes (the scene's ``v``); revolute and
  prismatic coordinates are the scene's.
* Loop closures (``Scene.loops``) as DART's ball and revolute joint constraints (``loops``).
* Gravity set from the scene (DART's default is -9.81 in z). Loads as the body's external force and
  torque (``loads``). No shapes but a contact pair's (``contact``): nothing collides that the scene does not name.
* Nothing the scene does not call for (``ENGINE_DEFAULTS``): with option ``defaults=scene`` (the default)
  every joint's limits, damping, spring, Coulomb friction are zero or off (written explicitly, whatever DART's
  defaults), every actuator a force actuator with no command, and the world's deactivation (DART 6.20's
  sleeping: a body resting in a contact island for a while is frozen) is switched off. Contact needs shapes, and
  only a contact pair's exist (the constraint solver's collision group is read back); its ``enableContact`` flag
  cannot be set from dartpy 6.20 (``getCollisionOption`` returns a copy) and is read back as DART leaves it.
  ``defaults=engine`` keeps what DART sets on a fresh world and skeleton, so that their effect can be measured;
  the audit reads each back either way.
"""

from __future__ import annotations

import functools

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Option, typed_options
from dalembert.scene import WORLD

__all__ = ["DartModel", "dart_version", "MODEL_OPTIONS", "DEFAULTS", "ENGINE_DEFAULTS"]

DEFAULTS = ("scene", "engine")
# The options the model is built by, declared where ``DartModel`` reads them (``DartAdapter.options``).
MODEL_OPTIONS = {
    "defaults": Option(DEFAULTS, DEFAULTS[0], "scene: everything the scene does not call for off (sleeping, "
                       "joint limits, damping, springs, friction, commands), read back in the audit; engine: DART's "
                       "own defaults, to measure their effect"),
}
# What a fresh DART 6.20 world and skeleton do that a scene never calls for, switched off with
# ``defaults=scene`` (each read back in the audit: ``audit.defaults``). Read from dartpy 6.20.0 on a fresh
# ``World()``: deactivation enabled, linear 0.01 m/s, angular 0.05 rad/s, 0.5 s until sleep (it acts on bodies in a
# contact island: measured, a box sliding frictionless at 0.5 mm/s stops 0.5 s in; every built-in case runs bit for
# bit the same either way, tests/test_dart*.py); joints' limits not
# enforced, damping, springs, friction zero, force actuators; contact enabled in the constraint solver's collision
# option (not settable from dartpy; no shapes, so nothing collides).
ENGINE_DEFAULTS = ("deactivation (sleeping)",)


@functools.cache
def dart_version():
    """DART's version (``dartpy.__version__``); ImportError when dartpy is missing."""
    import dartpy

    return dartpy.__version__


def isometry(p, R):
    """A ``dartpy.math.Isometry3`` of translation ``p`` (3,) and rotation ``R`` (3, 3)."""
    import dartpy

    T = dartpy.math.Isometry3()
    T.set_rotation(np.asarray(R, dtype=float))
    T.set_translation(np.asarray(p, dtype=float))
    return T


class DartModel:
    """The world, its skeleton and the scene's bodies and joints in it.

    Attributes
    ----------
    scene : Scene
    world : dartpy.simulation.World — time step ``dt``, the scene's gravity
    skeleton : dartpy.dynamics.Skeleton — every body of the scene
    nodes : dict body name -> dartpy.dynamics.BodyNode
    joints : dict joint (child) name -> dartpy.dynamics.Joint
    dofs : dict joint name -> slice of the skeleton's generalized coordinates (positions and velocities alike)
    contact : dict geom or plane name -> dartpy.dynamics.ShapeNode — the scene's contact shapes (``contact``)
    loops : list of dartpy.constraint.DynamicJointConstraint — the scene's loops (``loops.add_loops``), in order
    defaults : str — option ``defaults``: ``scene`` or ``engine``
    """

    def __init__(self, scene, dt, settings=None):
        import dartpy

        self.scene = scene
        self.defaults = typed_options(MODEL_OPTIONS, settings)["defaults"]
        self.world = dartpy.simulation.World()
        self.world.setTimeStep(float(dt))
        self.world.setGravity(np.asarray(scene.gravity, dtype=float))
        self.skeleton = dartpy.dynamics.Skeleton(scene.name)
        self.nodes, self.joints = {}, {}
        for body in scene.topological_order():
            self._add(scene.joint(body.name), body)
        if self.defaults == "scene":
            self._scene_defaults()
        self.world.addSkeleton(self.skeleton)
        if self.defaults == "scene":
            options = self.world.getDeactivationOptions()
            options.mEnabled = False
            self.world.setDeactivationOptions(options)
        self.dofs = {}
        for name, joint in self.joints.items():
            n = joint.getNumDofs()
            start = joint.getIndexInSkeleton(0) if n else 0
            self.dofs[name] = slice(start, start + n)
        self.q0, self.v0 = self.initial_state()
        from dalembert.adapters.dart.contact import add_contact

        self.contact = add_contact(self)  # shape nodes by geom or plane name (none without contact pairs)
        self.loops = []
        self.reset()  # the loops' constraints built at the initial state

    def _add(self, j, body):
        import dartpy

        dyn = dartpy.dynamics
        parent = None if j.parent == WORLD else self.nodes[j.parent]
        make = {"free": self.skeleton.createFreeJointAndBodyNodePair,
                "revolute": self.skeleton.createRevoluteJointAndBodyNodePair,
                "prismatic": self.skeleton.createPrismaticJointAndBodyNodePair,
                "ball": self.skeleton.createBallJointAndBodyNodePair,
                "weld": self.skeleton.createWeldJointAndBodyNodePair}[j.kind]
        joint, node = make(parent) if parent is not None else make()
        joint.setName(body.name)
        node.setName(body.name)
        node.setInertia(dyn.Inertia(float(body.mass), np.zeros(3), np.asarray(body.inertia_matrix, dtype=float)))
        if j.kind != "free":  # a free body's joint frames are the world's and B itself
            joint.setTransformFromParentBodyNode(isometry(j.parent_point, spatial.quat_to_matrix(j.parent_quat)))
            joint.setTransformFromChildBodyNode(isometry(j.child_point, spatial.quat_to_matrix(j.child_quat)))
        if j.kind in ("revolute", "prismatic"):
            joint.setAxis(np.asarray(j.axis, dtype=float) / np.linalg.norm(j.axis))
        self.nodes[body.name], self.joints[j.child] = node, joint

    def _scene_defaults(self):
        """Every joint exactly the scene's: no limits, damping, spring, friction; force actuators, no command."""
        import dartpy

        self.skeleton.setSelfCollisionCheck(False)
        for joint in self.joints.values():
            joint.setLimitEnforcement(False)
            joint.setActuatorType(dartpy.dynamics.ActuatorType.FORCE)
            for k in range(joint.getNumDofs()):
                joint.setDampingCoefficient(k, 0.0)
                joint.setSpringStiffness(k, 0.0)
                joint.setCoulombFriction(k, 0.0)
                joint.setPositionLowerLimit(k, -np.inf)
                joint.setPositionUpperLimit(k, np.inf)
                joint.setVelocityLowerLimit(k, -np.inf)
                joint.setVelocityUpperLimit(k, np.inf)
                joint.setForceLowerLimit(k, -np.inf)
                joint.setForceUpperLimit(k, np.inf)
                joint.setCommand(k, 0.0)

    def initial_state(self):
        """The skeleton's ``(positions, velocities)`` at the joints' ``q0``, ``v0``, DART's coordinates."""
        nq = self.skeleton.getNumDofs()
        q, v = np.zeros(nq), np.zeros(nq)
        for j in self.scene.joints:
            joint, s = self.joints[j.child], self.dofs[j.child]
            q0, v0 = np.asarray(j.q0, dtype=float), np.asarray(j.v0, dtype=float)
            if j.kind == "free":
                R = spatial.quat_to_matrix(q0[3:] / np.linalg.norm(q0[3:]))
                q[s] = joint.convertToPositions(isometry(q0[:3], R))
                # DART's FreeJoint velocities are not the body's spatial velocity (w_WB_B, R_WB^T v_WB_W): its
                # relative Jacobian at q maps them onto it, so they are solved from it
                J = np.asarray(joint.getRelativeJacobianStatic(q[s]), dtype=float)
                v[s] = np.linalg.solve(J, np.concatenate([v0[3:], R.T @ v0[:3]]))
            elif j.kind == "ball":
                R = spatial.quat_to_matrix(q0 / np.linalg.norm(q0))
                q[s] = self._rotation_vector(R)
                v[s] = v0
            elif j.kind in ("revolute", "prismatic"):
                q[s], v[s] = q0, v0
        return q, v

    @staticmethod
    def _rotation_vector(R):
        """The rotation vector (3,) of ``R`` (DART's ``BallJoint.convertToPositions``, its log map)."""
        import dartpy

        return np.asarray(dartpy.dynamics.BallJoint.convertToPositions(np.asarray(R, dtype=float)), dtype=float)

    def reset(self):
        """The skeleton at the initial state, the world's clock at 0, no constraint impulses, and the loops'
        constraints built afresh there (a constraint kept from a previous run carries that run's state: measured,
        a repeated run of the n-four-bar differed from the first)."""
        self.world.reset()
        self.skeleton.setPositions(self.q0)
        self.skeleton.setVelocities(self.v0)
        self.skeleton.resetAccelerations()
        if self.scene.loops:
            from dalembert.adapters.dart.loops import add_loops

            self.world.getConstraintSolver().removeAllConstraints()
            self.loops = add_loops(self)

    @property
    def summary(self):
        """The model in words, one line per body: its joint, DART's type and coordinates."""
        lines = [f"DART {dart_version()} World: gravity {self.world.getGravity().tolist()}, time step "
                 f"{self.world.getTimeStep()!r} s, defaults={self.defaults}"]
        for j in self.scene.joints:
            joint, node = self.joints[j.child], self.nodes[j.child]
            axis = f" axis {joint.getAxis().tolist()}" if j.kind in ("revolute", "prismatic") else ""
            lines.append(f"  {node.getName()}: {joint.getType()} from {j.parent}{axis}, mass {node.getMass()!r} kg, "
                         f"{joint.getNumDofs()} dofs")
        return "\n".join(lines)
