"""A scene as PyBullet multibodies (Featherstone, reduced coordinates), exactly the scene's physics:
``PybulletModel``.

* A free body that roots a tree is the floating base of a multibody of its own; every body reached
  from the world through another joint kind is a link of one fixed-base multibody (a massless base at
  the world origin). Links are added parents first (``Scene.topological_order``).
* Frames. PyBullet reports and sets a body's pose as that of its inertial frame E: the COM, with
  axes along the principal axes of inertia (it takes a diagonal inertia only). E is the scene's
  body frame B turned by ``R_BE`` (the eigenvectors of the scene's inertia; the identity where it
  is diagonal already, as in every built-in case), so ``X_EB = (0, R_BE^T)``
  (``dalembert.adapters.base``). A link's own frame L, where its joint sits, is the scene's child
  joint frame Jc: a revolute axis or prismatic direction is in Jc, as the scene's is, and at q = 0
  Jc coincides with the parent joint frame Jp, so revolute and prismatic q and v go in and out
  unchanged. A spherical joint turns E, not L: its quaternion and rate are the scene's conjugated by
  ``R_LE`` (measured: ``R_WE = R_WJp R_LE R(q_bullet)``, the rate in E axes): ``ball_to_bullet``.
* Nothing the scene does not call for: no collision shapes but the scene's contact geoms and planes, only its
  named pairs colliding (``contact``), and, with option
  ``defaults=scene`` (the default), PyBullet's own defaults switched off — the multibody's linear and
  angular damping (0.04 each: a linear plus a quadratic drag on every body), the velocity motor
  PyBullet puts on every revolute and prismatic joint (target rate 0: it holds the joint still), the
  100 rad/s clamp on every joint rate (``maxJointVelocity``) and sleeping. ``defaults=engine`` keeps
  them all, so that their effect is measured. Joint damping and friction are zero and no joint has a
  limit either way (``createMultiBody``'s defaults; read back in the audit).
* Gravity from the scene (PyBullet's default is zero), the step ``dt`` (``setTimeStep``: PyBullet's one
  integrator is semi-implicit Euler), the constraint solver and its iterations from options ``solver`` and ``solver_iterations``.

PyBullet's quaternions are ``(x, y, z, w)``: converted only through ``dalembert.spatial``. ``import
pybullet`` writes a build-time banner to the process's stderr from C: ``engine`` silences it at the
file-descriptor level (a Python-level redirect does not catch a C library's writes), the contract's
"prints nothing".
"""

from __future__ import annotations

import os
import sys
import weakref
from dataclasses import dataclass

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Option
from dalembert.scene import WORLD

__all__ = ["engine", "PybulletModel", "Part", "build", "MODEL_OPTIONS", "SOLVERS", "NO_VELOCITY_CLAMP",
           "ball_to_bullet", "ball_from_bullet", "summary", "rebuild", "root_of"]

# dalembert name -> PyBullet's constraint solver (setPhysicsEngineParameter constraintSolverType):
# sequential impulse (PyBullet's default), projected Gauss-Seidel, Dantzig's LCP.
SOLVERS = {"si": "CONSTRAINT_SOLVER_LCP_SI", "pgs": "CONSTRAINT_SOLVER_LCP_PGS", "dantzig": "CONSTRAINT_SOLVER_LCP_DANTZIG"}

MODEL_OPTIONS = {
    "defaults": Option(("scene", "engine"), "scene",
                       "scene: PyBullet's damping, joint motors, joint-rate clamp and sleeping off; engine: kept, "
                       "so that their effect is measured"),
    "solver": Option(tuple(SOLVERS), "si",
                     "the constraint solver (it solves only constraint rows: the contacts', and the motors' with "
                     "defaults=engine; none in a tree scene with defaults=scene)"),
    "solver_iterations": Option(default=50, minimum=1.0, integer=True,
                                description="the constraint solver's iterations per step (PyBullet's default 50)"),
}

# The joint-rate clamp with defaults=scene: btMultiBody clamps every joint rate to maxJointVelocity (100 rad/s
# by default: measured, a pendulum set spinning at 200 rad/s runs at 100). Infinity, not merely a large number: a
# finite clamp holds a blow-up at that number (measured with 1e100: the heavy top at dt = 2e-3 ran on at
# 1.6e100 rad/s, finite), where the harness must see it go non-finite.
NO_VELOCITY_CLAMP = float("inf")


def _depth_first(scene, members):
    """``members`` (one multibody's links, parents before children) in depth-first order, each parent's children in
    the order given: ``createMultiBody`` numbers the links depth-first from the base whatever order they are passed
    in (measured: Solo12's twelve leg links passed breadth-first came back with masses swapped between legs), so
    only in this order is link i the i-th passed."""
    names = {b.name for b in members}
    children = {}
    for b in members:
        parent = scene.joint(b.name).parent
        children.setdefault(parent if parent in names else None, []).append(b)
    out, stack = [], list(reversed(children.get(None, [])))
    while stack:  # iterative: a chain may be a thousand links deep
        b = stack.pop()
        out.append(b)
        stack.extend(reversed(children.get(b.name, [])))
    return out


def engine():
    """The ``pybullet`` module, imported with the process's stderr (fd 2) sent to /dev/null for the
    import: the module's C initializer prints ``pybullet build time: ...`` there, which a Python-level
    redirect cannot catch. ImportError when it is not installed."""
    loaded = sys.modules.get("pybullet")
    if loaded is not None:
        return loaded
    sys.stderr.flush()
    saved, null = os.dup(2), os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 2)
        import pybullet
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(null)
    return pybullet


def xyzw(q_wxyz):
    """A scalar-first quaternion as the list PyBullet takes, ``[x, y, z, w]``."""
    return [float(v) for v in spatial.wxyz_to_xyzw(np.asarray(q_wxyz, dtype=float))]


def principal_frame(body):
    """``(d, R_BE)``: the principal moments (3,) kg m^2 and the principal axes in B (3, 3), a right-handed
    rotation; a diagonal inertia keeps B's axes exactly (no eigen-solve roundoff)."""
    I = body.inertia_matrix
    if np.count_nonzero(I - np.diag(np.diag(I))) == 0:
        return np.diag(I).copy(), np.eye(3)
    d, R = np.linalg.eigh(I)
    if np.linalg.det(R) < 0:
        R[:, 2] = -R[:, 2]
    return d, R


def ball_to_bullet(q_JpJc, w_Jc, R_LE):
    """A scene ball joint's ``(q (4,) scalar first, w (3,) child joint axes)`` as PyBullet's spherical
    coordinates ``(quaternion (4,) scalar first, rate (3,) in E axes)``: ``R_b = R_LE^T R_JpJc R_LE``."""
    R = R_LE.T @ spatial.quat_to_matrix(q_JpJc) @ R_LE
    return spatial.matrix_to_quat(R), R_LE.T @ np.asarray(w_Jc, dtype=float)


def ball_from_bullet(q_b, w_E, R_LE):
    """Inverse of ``ball_to_bullet`` for stacks: ``q_b (n, 4)`` scalar first, ``w_E (n, 3)`` ->
    ``(q_JpJc (n, 4), w_Jc (n, 3))``."""
    R = R_LE @ spatial.quat_to_matrix(q_b) @ R_LE.T
    return spatial.matrix_to_quat(R), np.asarray(w_E, dtype=float) @ R_LE.T


@dataclass(frozen=True)
class Part:
    """Where a scene body lives in PyBullet.

    Attributes
    ----------
    body : str — the scene body
    mb : int — PyBullet's multibody id
    link : int — its link index, -1 for a base
    R_EB : ndarray (3, 3) — the scene's body frame B in PyBullet's inertial frame E (``p_EB`` is zero)
    R_LE : ndarray (3, 3) — E in the link frame L (the child joint frame); the identity for a base
    kind : str — the scene joint that carries it: free, revolute, prismatic, ball, weld
    """

    body: str
    mb: int
    link: int
    R_EB: np.ndarray
    R_LE: np.ndarray
    kind: str


@dataclass(frozen=True, eq=False)
class PybulletModel:
    """One scene in one PyBullet client (``connect(DIRECT)``), disconnected when this object is collected.

    Attributes
    ----------
    client : int — PyBullet's physics client id
    parts : dict body name -> Part
    floating : tuple of int — the multibodies with a floating base (one per free root body)
    links : dict multibody id -> tuple of link indices (every link of it, in order)
    link_lists : tuple of (multibody id, list of link indices) — those with links, as PyBullet's calls take them
    planes : dict plane name -> multibody id — the scene's planes, static (``contact``)
    defaults : str — option ``defaults``: scene or engine
    solver : str — option ``solver``
    """

    client: int
    parts: dict
    floating: tuple
    links: dict
    link_lists: tuple
    planes: dict
    defaults: str
    solver: str

    def state0(self, scene):
        """Set the scene's initial state (the joints' ``q0``, ``v0``) into the client."""
        pb = engine()
        c = self.client
        for j in scene.joints:
            part = self.parts[j.child]
            q0, v0 = np.asarray(j.q0, dtype=float), np.asarray(j.v0, dtype=float)
            if j.kind == "free":  # COM and q_WE; linear COM velocity and angular velocity, world axes
                R_WB = spatial.quat_to_matrix(q0[3:] / np.linalg.norm(q0[3:]))
                q_WE = spatial.matrix_to_quat(R_WB @ part.R_EB.T)
                pb.resetBasePositionAndOrientation(part.mb, list(q0[:3]), xyzw(q_WE), physicsClientId=c)
                pb.resetBaseVelocity(part.mb, list(v0[:3]), list(R_WB @ v0[3:]), physicsClientId=c)
            elif j.kind in ("revolute", "prismatic"):
                pb.resetJointState(part.mb, part.link, float(q0[0]), float(v0[0]), physicsClientId=c)
            elif j.kind == "ball":
                q_b, w_E = ball_to_bullet(q0 / np.linalg.norm(q0), v0, part.R_LE)
                pb.resetJointStateMultiDof(part.mb, part.link, xyzw(q_b), list(w_E), physicsClientId=c)


def build(scene, settings):
    """Build ``scene`` in a new PyBullet client with the options of ``settings`` (``MODEL_OPTIONS``), at its
    initial state; a ``PybulletModel``."""
    pb = engine()
    c = pb.connect(pb.DIRECT)
    model = _construct(pb, c, scene, settings)
    weakref.finalize(model, _disconnect, c)
    return model


def rebuild(model, scene, settings):
    """Empty ``model``'s client (``resetSimulation``) and build ``scene`` in it again, at its initial state: the
    world as ``build`` left it. Bullet keeps contact state across steps that no reset of the bodies' states
    clears (persistent contact manifolds, their cached impulses and friction directions: measured, a second run
    of the block on the incline differed from the first from its first step, by 1e-17 m, after the bodies had
    been moved apart and collision detection run); a scene with contact is rebuilt before every run, so that
    each run is the first. The same calls give the same ids (checked)."""
    pb = engine()
    pb.resetSimulation(physicsClientId=model.client)
    again = _construct(pb, model.client, scene, settings)
    if (again.links, again.planes, again.floating) != (model.links, model.planes, model.floating):
        raise RuntimeError(f"PyBullet rebuilt {scene.name!r} with other ids: {again.links} {again.planes}, "
                           f"not {model.links} {model.planes}")


def _construct(pb, c, scene, settings):
    """Build ``scene`` in client ``c`` (empty), at its initial state; a ``PybulletModel``."""
    from dalembert.adapters.base import typed_options
    from dalembert.adapters.pybullet import contact

    opts = typed_options(MODEL_OPTIONS, settings)
    frames = {b.name: principal_frame(b) for b in scene.bodies}
    shapes = contact.base_shapes(pb, c, scene, frames)
    parts, floating, links = {}, [], {}
    # where each body's link frame L sits in its body frame B: X_BL (a base's L is E)
    X_BL = {}
    roots = [b for b in scene.topological_order() if scene.joint(b.name).kind == "free"]
    fixed = [b for b in scene.topological_order() if root_of(scene, b.name) not in {r.name for r in roots}]
    for base in [*roots, None]:
        members = fixed if base is None else [b for b in scene.topological_order()
                                              if b.name != base.name and root_of(scene, b.name) == base.name]
        members = _depth_first(scene, members)
        if base is None and not members:
            continue
        order = {b.name: i for i, b in enumerate(members)}
        kw = dict(linkMasses=[], linkCollisionShapeIndices=[], linkVisualShapeIndices=[], linkPositions=[],
                  linkOrientations=[], linkInertialFramePositions=[], linkInertialFrameOrientations=[],
                  linkParentIndices=[], linkJointTypes=[], linkJointAxis=[])
        if base is not None:
            X_BL[base.name] = (np.zeros(3), frames[base.name][1])
        for b in members:
            j = scene.joint(b.name)
            # the parent joint frame Jp in the parent's link frame (the world's for the fixed base)
            R_Jp, p_Jp = spatial.quat_to_matrix(j.parent_quat), np.asarray(j.parent_point, dtype=float)
            if j.parent != WORLD:
                p_BL, R_BL = X_BL[j.parent]
                R_Jp, p_Jp = R_BL.T @ R_Jp, R_BL.T @ (p_Jp - p_BL)
            R_BJc, p_BJc = spatial.quat_to_matrix(j.child_quat), np.asarray(j.child_point, dtype=float)
            X_BL[b.name] = (p_BJc, R_BJc)
            R_LE = R_BJc.T @ frames[b.name][1]
            kw["linkMasses"].append(b.mass)
            kw["linkCollisionShapeIndices"].append(-1)
            kw["linkVisualShapeIndices"].append(-1)
            kw["linkPositions"].append(list(p_Jp))
            kw["linkOrientations"].append(xyzw(spatial.matrix_to_quat(R_Jp)))
            kw["linkInertialFramePositions"].append(list(-R_BJc.T @ p_BJc))  # the COM in L
            kw["linkInertialFrameOrientations"].append(xyzw(spatial.matrix_to_quat(R_LE)))
            kw["linkParentIndices"].append(0 if j.parent in (WORLD, getattr(base, "name", None))
                                           else order[j.parent] + 1)
            kw["linkJointTypes"].append({"revolute": pb.JOINT_REVOLUTE, "prismatic": pb.JOINT_PRISMATIC,
                                         "ball": pb.JOINT_SPHERICAL, "weld": pb.JOINT_FIXED}[j.kind])
            axis = np.zeros(3) if j.axis is None else np.asarray(j.axis, dtype=float) / np.linalg.norm(j.axis)
            kw["linkJointAxis"].append(list(axis))
        if base is None:
            mb = pb.createMultiBody(baseMass=0.0, basePosition=[0, 0, 0], baseOrientation=[0, 0, 0, 1],
                                    physicsClientId=c, **kw)
        else:
            mb = pb.createMultiBody(baseMass=base.mass, baseCollisionShapeIndex=shapes.get(base.name, -1),
                                    physicsClientId=c, **kw)
            floating.append(mb)
            pb.changeDynamics(mb, -1, localInertiaDiagonal=list(frames[base.name][0]), physicsClientId=c)
            parts[base.name] = Part(base.name, mb, -1, frames[base.name][1].T, np.eye(3), "free")
        for b in members:
            i = order[b.name]
            pb.changeDynamics(mb, i, localInertiaDiagonal=list(frames[b.name][0]), physicsClientId=c)
            R_LE = X_BL[b.name][1].T @ frames[b.name][1]
            parts[b.name] = Part(b.name, mb, i, frames[b.name][1].T, R_LE, scene.joint(b.name).kind)
        links[mb] = tuple(range(len(members)))
        if opts["defaults"] == "scene":
            _defaults_off(pb, c, mb, members, scene)
    planes = contact.build(pb, c, scene, parts)
    pb.setGravity(*scene.gravity, physicsClientId=c)
    pb.setTimeStep(float(settings.dt), physicsClientId=c)
    pb.setPhysicsEngineParameter(constraintSolverType=getattr(pb, SOLVERS[opts["solver"]]),
                                 numSolverIterations=opts["solver_iterations"], physicsClientId=c)
    link_lists = tuple((mb, list(ls)) for mb, ls in links.items() if ls)
    model = PybulletModel(c, parts, tuple(floating), links, link_lists, planes, opts["defaults"], opts["solver"])
    model.state0(scene)
    return model


def summary(model):
    """The multibodies of ``model`` as PyBullet holds them, one line per base and link: mass, principal moments,
    inertial frame, joint type, axis and parent (``getDynamicsInfo``, ``getJointInfo``) and the gravity."""
    pb = engine()
    c = model.client
    names = {(part.mb, part.link): name for name, part in model.parts.items()}
    params = pb.getPhysicsEngineParameters(physicsClientId=c)
    lines = [f"pybullet {pb.getAPIVersion(physicsClientId=c)}: gravity "
             f"{[params[f'gravityAcceleration{a}'] for a in 'XYZ']}, time step {params['fixedTimeStep']!r} s, "
             f"defaults={model.defaults}, solver={model.solver}"]
    for mb, links in model.links.items():
        for link in (-1, *links):
            info = pb.getDynamicsInfo(mb, link, physicsClientId=c)
            name = names.get((mb, link), "(fixed base: the world)")
            line = (f"multibody {mb} link {link} {name}: mass {info[0]!r}, principal moments {list(info[2])}, "
                    f"inertial frame at {list(info[3])} turned {list(info[4])} (x y z w)")
            if link >= 0:
                j = pb.getJointInfo(mb, link, physicsClientId=c)
                line += (f"; joint type {j[2]}, axis {list(j[13])}, parent link {j[16]}, at {list(j[14])} "
                         f"turned {list(j[15])}")
            lines.append(line)
    return "\n".join(lines) + "\n"


def _disconnect(client):
    pb = sys.modules.get("pybullet")
    if pb is not None and pb.isConnected(physicsClientId=client):
        pb.disconnect(physicsClientId=client)


def root_of(scene, name):
    """The body at the root of ``name``'s tree (the one jointed to the world)."""
    while (parent := scene.joint(name).parent) != WORLD:  # iterative: a chain may be a thousand links deep
        name = parent
    return name


def _defaults_off(pb, c, mb, members, scene):
    """PyBullet's defaults that the scene does not call for, off: damping (the multibody's, and each joint's),
    the joint-rate clamp, sleeping, and the motor on every joint: a velocity motor on a revolute or prismatic
    joint, a position motor on a spherical one (measured: a heavy top's ball joint held still), each given a
    zero force."""
    pb.changeDynamics(mb, -1, linearDamping=0.0, angularDamping=0.0, maxJointVelocity=NO_VELOCITY_CLAMP,
                      activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING, physicsClientId=c)
    for i, b in enumerate(members):
        pb.changeDynamics(mb, i, jointDamping=0.0, physicsClientId=c)
        kind = scene.joint(b.name).kind
        if kind in ("revolute", "prismatic"):
            pb.setJointMotorControl2(mb, i, pb.VELOCITY_CONTROL, targetVelocity=0.0, force=0.0, physicsClientId=c)
        elif kind == "ball":
            pb.setJointMotorControlMultiDof(mb, i, pb.POSITION_CONTROL, targetPosition=[0, 0, 0, 1],
                                            targetVelocity=[0, 0, 0], positionGain=0.0, velocityGain=0.0,
                                            force=[0.0, 0.0, 0.0], physicsClientId=c)
