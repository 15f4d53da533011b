"""A scene as an OpenSim 4.6 ``Model`` on Simbody, exactly the scene's physics: ``SimbodyModel``.

* Every body is an OpenSim ``Body`` whose frame is the scene's body frame B: mass center at its origin and the
  full inertia tensor about it (``Inertia(xx, yy, zz, xy, xz, yz)``), so ``X_EB`` is the identity for every body
  (``dalembert.adapters.base``) and each body's ground transform and spatial velocity are the scene's body states.
* Joints between offset frames of parent and child (OpenSim's seven-argument joint constructors: a point and an
  X-Y-Z body-fixed orientation in each body): a free body gets a ``FreeJoint``, a revolute joint a ``PinJoint``
  (about the frames' common z, so both frames are turned by ``R_JA`` taking z onto the scene's axis), a prismatic
  joint a ``SliderJoint`` (along the frames' common x, turned the same way), a ball joint a ``BallJoint``, a weld a
  ``WeldJoint``.
* Charts. OpenSim 4.6 builds Simbody's Free and Ball mobilizers with X-Y-Z body-fixed Euler angles as
  coordinates (measured: a fresh state's free-joint q is all zero, not a unit quaternion; OpenSim's Python API
  offers no way back to quaternions), singular where the middle angle is +-90 degrees. The adapter therefore
  centres each chart on the initial attitude, turned by ``S`` (``spin_frame``) so that the initial rotation is
  about the last axis (z), where the angles are regular at any rate: a free joint's frames are the ground at
  ``(p_WB, R_WB S)`` at t = 0 and ``(0, S)`` in B, S's z along the body's angular momentum (fixed in space, so a
  steady spin keeps the middle angle zero); a ball joint's are ``Jp`` turned by ``R_JpJc S`` at t = 0 and ``Jc``
  turned by ``S``, S's z along the initial relative rate. Every Euler angle starts at zero; a motion that turns
  its rotation axis a quarter turn away passes the singularity (measured: a spin of 150 rad/s about the middle
  axis made every fixed-step method fail at dt = 1e-3; the harness shows what remains). What remains: on the
  intermediate-axis spins, whose flips turn the rotation axis half a turn in the body, Simbody at accuracy 1e-9
  loses 4.7e-3 rad by t = 1 s of free_top_fast_spin where the reference's dop853 at rtol 1e-9 loses 1.8e-8
  (measured; centring the chart on other axes changed free_top_intermediate's error by less than 2x).
* Gravity set from the scene (OpenSim's default is -9.80665 in y). Loads as ``PrescribedForce``s with constant
  functions; spring-dampers as ``ExpressionBasedPointToPointForce``s (tension ``k (d - L) + c ddot``; OpenSim's
  ``PointToPointSpring`` has no damping); no contact geometry, no other force, no constraint.
* Nothing the scene does not call for (option ``defaults``). OpenSim adds no damping, actuators, muscles or
  contact to a model it is not given; what it does set by default is on each ``Coordinate``: a range of
  [-10, 10] (rad or m), ``clamped`` and ``locked`` false, ``prescribed`` false. With ``defaults=scene`` (the
  default) each coordinate is written explicitly unlocked, unclamped and unprescribed, with an unbounded range;
  ``defaults=engine`` leaves OpenSim's values. The audit reads them back either way (``audit.defaults``).
"""

from __future__ import annotations

import functools

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Option, typed_options
from dalembert.scene import WORLD

__all__ = ["SimbodyModel", "engine", "opensim_version", "MODEL_OPTIONS", "DEFAULTS", "COORDINATE_RANGE"]

DEFAULTS = ("scene", "engine")
# The options the model is built by, declared where ``SimbodyModel`` reads them (``SimbodyAdapter.options``).
MODEL_OPTIONS = {
    "defaults": Option(DEFAULTS, DEFAULTS[0], "scene: every coordinate unlocked, unclamped, unprescribed, unbounded "
                       "(read back in the audit); engine: OpenSim's own coordinate defaults, to measure their effect"),
}
# The range written on every coordinate with ``defaults=scene``: OpenSim takes a finite range only (its property
# is a pair of doubles checked min < max); 1e300 rad or m is unbounded for any motion here.
COORDINATE_RANGE = 1e300
# OpenSim's joint classes by scene joint kind.
JOINT_CLASS = {"free": "FreeJoint", "revolute": "PinJoint", "prismatic": "SliderJoint", "ball": "BallJoint",
               "weld": "WeldJoint"}
# The joint-frame axis each one-dof OpenSim joint moves along: PinJoint about z, SliderJoint along x.
JOINT_AXIS = {"revolute": np.array([0.0, 0.0, 1.0]), "prismatic": np.array([1.0, 0.0, 0.0])}


@functools.cache
def engine():
    """The ``opensim`` module, imported silently. OpenSim's logger writes every message to the console and, from
    its first message on, to a file ``opensim.log`` in the working directory (its ``Manager`` logs a summary at
    every ``integrate``): its file sink is removed and its level set to off here, for the process (the adapter
    writes no files and prints nothing; restoring the level would itself log a line). ``stepping`` turns it on
    only inside a captured console, to read Simbody's statistics."""
    import opensim

    opensim.Logger.removeFileSink()
    opensim.Logger.setLevel(opensim.Logger.Level_Off)
    return opensim


@functools.cache
def opensim_version():
    """OpenSim's version (``opensim.__version__``); ImportError when the ``opensim`` package is missing."""
    return engine().__version__


def vec3(osim, v):
    """``SimTK::Vec3`` of ``v`` (3,)."""
    v = np.asarray(v, dtype=float)
    return osim.Vec3(float(v[0]), float(v[1]), float(v[2]))


def euler_xyz(osim, R):
    """The X-Y-Z body-fixed angles (rad) of rotation matrix ``R`` (3, 3), as OpenSim's offset frames take them
    (Simbody's own conversion, which handles the gimbal-lock case)."""
    q = spatial.matrix_to_quat(np.asarray(R, dtype=float))
    rot = osim.Rotation(osim.Quaternion(*(float(x) for x in q)))
    return rot.convertRotationToBodyFixedXYZ()


def axis_frame(kind, axis):
    """A rotation ``R_JA`` (3, 3) taking the OpenSim joint's own axis (``JOINT_AXIS``: a PinJoint's z, a
    SliderJoint's x) onto the scene's ``axis`` (any length, joint-frame axes)."""
    F = spatial.frame_with_z(axis)  # its z along the axis
    return F if kind == "revolute" else F[:, [2, 0, 1]]  # x along the axis, still a proper rotation


def spin_frame(w):
    """A rotation ``S`` (3, 3) whose z axis is along ``w`` (3,) (the identity where ``w`` is zero): the charts'
    turn that puts the initial rotation about the last Euler axis, where X-Y-Z angles are regular at any rate."""
    w = np.asarray(w, dtype=float)
    return spatial.frame_with_z(w) if np.linalg.norm(w) > 0.0 else np.eye(3)


class SimbodyModel:
    """The OpenSim model of a scene, its system and its initial state.

    Attributes
    ----------
    scene : Scene
    osim : module — ``opensim``
    model : opensim.Model — built and ``initSystem``-ed
    bodies : dict body name -> opensim.Body
    joints : dict joint (child) name -> opensim.Joint
    frames : dict joint (child) name -> (X_PF, X_CM) — the joint's parent and child frames in their bodies'
        frames (the ground's for the world), each ``(p (3,), R (3, 3))``, as built (charts and axes applied)
    forces : list of opensim.PrescribedForce — the scene's loads, in order
    springs : list of opensim.ExpressionBasedPointToPointForce — the scene's springs, in order
    state0 : opensim.State — the initial state (time 0); runs start from copies
    defaults : str — option ``defaults``
    """

    def __init__(self, scene, settings=None):
        osim = self.osim = engine()
        self.scene = scene
        self.defaults = typed_options(MODEL_OPTIONS, settings)["defaults"]
        model = self.model = osim.Model()
        model.setName(scene.name)
        model.setGravity(vec3(osim, scene.gravity))
        self.bodies, self.joints, self.frames, self.forces = {}, {}, {}, []
        for body in scene.topological_order():
            self._add(scene.joint(body.name), body)
        for i, ld in enumerate(scene.loads):
            self.forces.append(self._load(i, ld))
        self.springs = [self._spring(sp) for sp in scene.springs]
        if self.defaults == "scene":
            for joint in self.joints.values():
                for k in range(joint.numCoordinates()):
                    c = joint.upd_coordinates(k)
                    c.set_locked(False)
                    c.set_clamped(False)
                    c.set_prescribed(False)
                    c.setRangeMin(-COORDINATE_RANGE)
                    c.setRangeMax(COORDINATE_RANGE)
        state = model.initSystem()
        self._initial(state)
        self.state0 = osim.State(state)

    def _add(self, j, body):
        osim = self.osim
        b = osim.Body(body.name, body.mass, osim.Vec3(0.0, 0.0, 0.0), _inertia(osim, body.inertia_matrix))
        self.model.addBody(b)
        parent = self.model.getGround() if j.parent == WORLD else self.bodies[j.parent]
        q0 = np.asarray(j.q0, dtype=float)
        if j.kind == "free":  # the chart centred on the initial pose, z along the body's angular momentum
            S = spin_frame(body.inertia_matrix @ np.asarray(j.v0[3:], dtype=float))
            X_PF = (q0[:3], spatial.quat_to_matrix(q0[3:] / np.linalg.norm(q0[3:])) @ S)
            X_CM = (np.zeros(3), S)
        else:
            X_PF = (np.asarray(j.parent_point, dtype=float), spatial.quat_to_matrix(j.parent_quat))
            X_CM = (np.asarray(j.child_point, dtype=float), spatial.quat_to_matrix(j.child_quat))
            if j.kind == "ball":  # the chart centred on the initial relative attitude, z along its rate
                S = spin_frame(j.v0)
                X_PF = (X_PF[0], X_PF[1] @ spatial.quat_to_matrix(q0 / np.linalg.norm(q0)) @ S)
                X_CM = (X_CM[0], X_CM[1] @ S)
            elif j.kind in JOINT_AXIS:
                R_JA = axis_frame(j.kind, j.axis)
                X_PF, X_CM = (X_PF[0], X_PF[1] @ R_JA), (X_CM[0], X_CM[1] @ R_JA)
        joint = getattr(osim, JOINT_CLASS[j.kind])(
            j.child, parent, vec3(osim, X_PF[0]), euler_xyz(osim, X_PF[1]), b, vec3(osim, X_CM[0]),
            euler_xyz(osim, X_CM[1]))
        self.model.addJoint(joint)
        self.bodies[body.name], self.joints[j.child], self.frames[j.child] = b, joint, (X_PF, X_CM)

    def _load(self, i, ld):
        """Load ``ld`` as a ``PrescribedForce`` on its body: constant force (at its point, body axes) or torque,
        in the ground's axes for a world load, the body's for a follower load."""
        osim = self.osim
        f = osim.PrescribedForce(f"load_{i}_{ld.body}", self.bodies[ld.body])
        v = [osim.Constant(float(x)) for x in ld.vector]
        if ld.kind == "force":
            f.setForceFunctions(*v)
            f.setPointFunctions(*(osim.Constant(float(x)) for x in ld.point))
        else:
            f.setTorqueFunctions(*v)
        f.setForceIsInGlobalFrame(ld.frame == "world")
        f.setPointIsInGlobalFrame(False)
        self.model.addForce(f)
        return f

    def _spring(self, sp):
        """Spring ``sp`` as an ``ExpressionBasedPointToPointForce``: OpenSim evaluates the tension (positive pulls
        the points together, measured) from the points' distance ``d`` and its rate ``ddot``; the scene's numbers
        are written at full precision (``repr``) into the expression."""
        force = self.osim.ExpressionBasedPointToPointForce(
            _frame_name(sp.body_a), vec3(self.osim, sp.point_a), _frame_name(sp.body_b), vec3(self.osim, sp.point_b),
            spring_expression(sp))
        force.setName(sp.name)
        self.model.addForce(force)
        return force

    def _initial(self, state):
        """The scene's q0, v0 on ``state``, through each joint's coordinates (charts: free and ball start at zero
        angles, F and M coinciding, so their speeds, Simbody's angular velocity of M in F, are the scene's rates
        in M's axes there)."""
        for j in self.scene.joints:
            joint, q0, v0 = self.joints[j.child], np.asarray(j.q0, float), np.asarray(j.v0, float)
            coords = [joint.get_coordinates(k) for k in range(joint.numCoordinates())]
            (_, R_PF), (_, R_CM) = self.frames[j.child]
            if j.kind == "free":  # Simbody's Free speeds: (w_FM_F, v_FM_F); F and M coincide at t = 0
                speeds, values = np.concatenate([R_CM.T @ v0[3:], R_PF.T @ v0[:3]]), np.zeros(6)
            elif j.kind == "ball":  # w_FM_F, F and M coincide at t = 0: the scene's rate (Jc axes) in M's
                speeds, values = R_CM.T @ spatial.quat_to_matrix(j.child_quat) @ v0, np.zeros(3)
            elif j.kind in JOINT_AXIS:
                speeds, values = v0, q0
            else:
                speeds, values = np.zeros(0), np.zeros(0)
            for c, q, v in zip(coords, values, speeds):
                c.setValue(state, float(q), False)
                c.setSpeedValue(state, float(v))
        self.model.realizeVelocity(state)

    @property
    def summary(self):
        """The model in words, one line per body: its OpenSim joint, frames and mass properties."""
        lines = [f"OpenSim {opensim_version()} Model {self.model.getName()!r} (Simbody): gravity "
                 f"{self.model.getGravity()}, defaults={self.defaults}"]
        for j in self.scene.joints:
            joint, b = self.joints[j.child], self.bodies[j.child]
            lines.append(f"  {j.child}: {joint.getConcreteClassName()} from {j.parent}, {joint.numCoordinates()} "
                         f"coordinates, mass {b.getMass()!r} kg, moments {b.getInertia().getMoments()}, products "
                         f"{b.getInertia().getProducts()}")
        for f in self.forces:
            lines.append(f"  {f.getName()}: PrescribedForce on {f.getFrame().getName()}, "
                         f"{'ground' if f.getForceIsInGlobalFrame() else 'body'} axes")
        for f in self.springs:
            lines.append(f"  {f.getName()}: ExpressionBasedPointToPointForce {f.getBody1Name()} - {f.getBody2Name()}, "
                         f"tension {f.get_expression()}")
        return "\n".join(lines)


def spring_expression(sp):
    """The tension (N) of spring ``sp`` in OpenSim's expression language: ``k (d - L) + c ddot``."""
    return f"{sp.stiffness!r}*(d-{sp.rest_length!r})+{sp.damping!r}*ddot"


def _frame_name(body):
    """OpenSim's name of a scene body's frame (the scene's world is OpenSim's ``ground``)."""
    return "ground" if body == WORLD else body


def _inertia(osim, I):
    """``SimTK::Inertia`` of the symmetric tensor ``I`` (3, 3), kg m^2 about the COM in B."""
    I = np.asarray(I, dtype=float)
    return osim.Inertia(I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
