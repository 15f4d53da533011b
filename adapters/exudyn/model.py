"""A scene as an Exudyn system: ``build``.

Free bodies on rigid-body nodes, jointed trees in minimal coordinates
(``ObjectKinematicTree``) or in redundant ones (rigid bodies held by joints).

* Free bodies: ``CreateRigidBody`` with ``RigidBodyInertia(mass, I, com=0,
  inertiaTensorAtCOM=True)`` — the inertia an ``ObjectRigidBody`` takes is
  about the node reference point, so saying "at COM" explicitly matters (the
  reference point is the COM here); ``initialAngularVelocity`` is given in
  world axes and ``initialVelocity`` is the reference point's. Node type by
  option ``node``: ``rotvec-lg`` (``NodeRigidBodyRotVecLG``, default: works
  with explicit and implicit solvers), ``ep`` (Euler parameters: an algebraic
  unit-norm constraint, so implicit solvers only), ``rxyz`` (Tait-Bryan angles,
  singular at +-90 degrees of the middle angle).
* Jointed scenes two ways (option ``joints``):

  - ``minimal`` (default): one ``ObjectKinematicTree`` whose links rotate about
    (revolute: ``RevoluteZ``) or slide along (prismatic: ``PrismaticZ``) their local
    z; each link frame is the scene's child joint frame turned so that z is the
    joint axis (a prismatic joint keeps the parent joint frame's attitude, so the
    link frame is the parent joint frame's turned alike, moved by q along z). It
    runs with every solver. Ball joints and welds are not single-axis joints:
    ``unsupported``. The pivot reaction is read back
    by Newton's law on each link, ``R = m a_com - F_ext - m g + sum R_children``,
    with ``a_com`` from the tree's acceleration sensor;
  - ``redundant``: every body an ``ObjectRigidBody`` (the node type as above),
    each joint an ``ObjectJointGeneric`` (revolute: the five axes other than the
    rotation about the joint axis constrained; prismatic: the five other than the
    translation along it; ball: translations; weld: all six) from a marker on
    the parent (marker 0) to one on the child, each marker frame = joint frame turned so that z is
    the axis (Exudyn measures the generic joint's relative translation in marker 0's frame: a
    prismatic joint's slide along marker 0's z, as in the scene). An index-3 DAE: implicit solvers
    only. The reaction is the joint's ``ForceLocal``: the force on the marker-0
    (parent) side in the marker-0 frame, so the force ON the child in world axes is
    ``-R_WP R_PJ ForceLocal``. Initial body states come from the
    scene's joint coordinates by forward kinematics.
* Loop closures (``Scene.loops``), in either formulation: one constraint object per loop from a
  marker on body a (marker 0; ``MarkerKinematicTreeRigid`` on a tree link, ``MarkerBodyRigid`` on a
  rigid body or the ground) to one on body b, each marker frame = the loop's joint frame (z along a
  revolute loop's axis): ``ObjectJointGeneric`` for ball and revolute loops, constraining only the
  rows independent at the initial state (``loops.loop_axes``: Exudyn's Newton solver stops on
  redundant rows), ``ObjectConnectorDistance`` for distance loops. Constraints make any scene an
  index-3 (or, with trapezoidal-index2, index-2) DAE: implicit solvers only. The loop's force is read
  from its ``ForceLocal`` (ball, revolute) or ``Force`` (distance: the scalar tension).
* Spring-dampers (``Scene.springs``), in either formulation: one ``ObjectConnectorSpringDamper`` from a
  marker at body a's point (marker 0) to one at body b's (``springs``), whose force is read from its
  ``Force`` (the force on body a's point, world axes). They run with every solver.
* Loads: ``LoadForceVector``/``LoadTorqueVector`` on a rigid marker at the
  body point, ``bodyFixed=True`` for follower loads (with ``bodyFixed=False``
  the force stays world-fixed: phi(2 s) = 2.44 rad instead of 12 on the rod).
* Gravity only when the scene has it (Exudyn adds none by default).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from dalembert import spatial
from dalembert.adapters.base import Option, option_value
from dalembert.adapters.exudyn.compat import Markers
from dalembert.adapters.exudyn.contact import add_contacts
from dalembert.adapters.exudyn.joints import CONSTRAINED_AXES, TREE_JOINTS, read_joints
from dalembert.adapters.exudyn.loops import joint_frame, loop_axes
from dalembert.adapters.exudyn.springs import add_springs, read_springs
from dalembert.scene import WORLD

__all__ = ["build", "ExudynSystem", "rigid_bodies", "axis_frame", "NODES", "JOINTS", "MODEL_OPTIONS", "CONSTRAINED_AXES",
           "TREE_JOINTS"]

NODES = {"rotvec-lg": "RotationRotationVector", "ep": "RotationEulerParameters", "rxyz": "RotationRxyz"}
JOINTS = ("minimal", "redundant")
# The options the system is built by, declared here where ``build`` reads them (``ExudynAdapter.options`` adds
# the solver's): their defaults are read from here by the model, the adapter and the audit alike.
MODEL_OPTIONS = {
    "node": Option(tuple(NODES), "rotvec-lg", "rigid-body node: rotation vector (Lie group), Euler parameters "
                   "or Rxyz angles"),
    "joints": Option(JOINTS, JOINTS[0], "joints in minimal coordinates (ObjectKinematicTree) or redundant ones "
                     "(ObjectJointGeneric on rigid bodies)"),
}


def rigid_bodies(scene, redundant):
    """Names of the bodies Exudyn models as ``ObjectRigidBody``: free ones, or all with redundant joints."""
    return [b.name for b in scene.topological_order() if redundant or scene.joint(b.name).kind == "free"]


def axis_frame(axis):
    """A rotation whose third column is the unit ``axis`` (link z = joint axis)."""
    return spatial.frame_with_z(axis)


@dataclass(frozen=True, eq=False)
class ExudynSystem:
    """A scene as an Exudyn system (``build``), and what the read-back and the audit need to know of it.

    Attributes
    ----------
    SC : exudyn.SystemContainer — holds ``mbs`` (kept alive with it)
    mbs : exudyn.MainSystem — the system, assembled unless built for its summary alone
    sensors : dict — body (or ``__q``/``__v``/``__joint:<child>``/``__loop:<loop name>``/``__spring:<spring
        name>``) -> quantity (``p``, ``R``, ``v``, ``w``, ``a``, ``q``, ``v``, ``f``) -> sensor number
    X_EB : dict link name -> (p_EB (3,), R_EB (3, 3)) — the scene's body frame B in the link frame E, m
        (kinematic-tree links only: a rigid body's E is B)
    links : list of str — the kinematic tree's bodies, in link order (empty: no tree)
    tree, tree_node : int or None — the kinematic tree's object and node numbers
    redundant_joints : dict child -> ndarray (3, 3) — each ObjectJointGeneric's frame in the parent's axes,
        ``R_PJ R_A`` (joints=redundant)
    joint_objects : dict child -> int — each ObjectJointGeneric's object number
    loops : dict loop name -> ndarray (3, 3) — its joint frame Ja in body a's scene frame, ``R_BJa``
    loop_rows : dict loop name -> loops.LoopRows — the rows given to Exudyn, and those left out
    springs : dict spring name -> dict(object, markers) — its connector's object and marker numbers
        (``springs.add_springs``)
    owners : dict int -> str — rigid body or ground object number -> scene body name (``WORLD`` for a ground)
    summary : str — one line per object, for reports (``describe``)
    spring_readout : dict — ``springs.read_springs`` right after assembly (empty unassembled)
    joint_readout : dict — ``joints.read_joints`` likewise
    """

    SC: object
    mbs: object
    sensors: dict
    X_EB: dict
    links: list
    tree: int | None
    tree_node: int | None
    redundant_joints: dict
    joint_objects: dict
    loops: dict
    loop_rows: dict
    springs: dict
    owners: dict
    summary: str
    spring_readout: dict
    joint_readout: dict


def build(scene, settings, assemble=True):
    """The Exudyn system of ``scene`` for ``settings.options`` (``node``, ``joints``), assembled
    unless ``assemble`` is False (for the summary alone).

    Returns an ``ExudynSystem``.
    """
    import exudyn as exu
    from exudyn.itemInterface import (LoadForceVector, LoadTorqueVector, MarkerBodyRigid, ObjectConnectorDistance,
                                      MarkerKinematicTreeRigid, NodeGenericODE2, ObjectGround,
                                      ObjectJointGeneric, ObjectKinematicTree, SensorBody, SensorKinematicTree,
                                      SensorNode, SensorObject)
    from exudyn.rigidBodyUtilities import RigidBodyInertia

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    g = np.array(scene.gravity, dtype=float)
    node_type = getattr(exu.NodeType, NODES[option_value(MODEL_OPTIONS, settings, "node")])
    redundant = option_value(MODEL_OPTIONS, settings, "joints") == "redundant"
    OV = exu.OutputVariableType
    summary, sensors, markers, bodies = [], {}, {}, {}
    framed = Markers(mbs)  # markers with frames, and the joints between them, in the installed release's terms
    owners = {}  # rigid body or ground object number -> scene body name (WORLD for a ground)
    # --- rigid bodies: free bodies, and every body with joints=redundant
    rigid = rigid_bodies(scene, redundant)
    state0 = spatial.initial_body_states(scene) if rigid else {}  # world states at t = 0
    for name in rigid:
        body, s0 = scene.body(name), state0[name]
        kwargs = dict(inertia=RigidBodyInertia(body.mass, body.inertia_matrix, [0.0, 0.0, 0.0], True),
                      referencePosition=list(s0["p"]), referenceRotationMatrix=s0["R"],
                      initialVelocity=list(s0["v"]), initialAngularVelocity=list(s0["w"]),
                      nodeType=node_type, returnDict=True)
        if np.any(g):
            kwargs["gravity"] = list(g)
        obj = mbs.CreateRigidBody(**kwargs)["bodyNumber"]
        bodies[name] = obj
        owners[int(obj)] = name
        markers[name] = lambda p, R=np.eye(3), obj=obj: framed.add(MarkerBodyRigid, p, R, bodyNumber=obj)
        sensors[name] = {k: mbs.AddSensor(SensorBody(bodyNumber=obj, outputVariableType=v))
                         for k, v in (("p", OV.Position), ("R", OV.RotationMatrix), ("v", OV.Velocity),
                                      ("w", OV.AngularVelocity))}
        summary.append(f"{name}: ObjectRigidBody on {node_type.name} node, mass {body.mass:g} kg, "
                       f"inertia at COM (inertiaTensorAtCOM=True)")
    # --- joints=redundant: generic joints between rigid bodies (marker 0 on the parent)
    redundant_joints, joint_objects = {}, {}
    if redundant and any(j.kind != "free" for j in scene.joints):
        ground = mbs.AddObject(ObjectGround())
        owners[int(ground)] = WORLD
        for j in scene.joints:
            if j.kind == "free":
                continue
            R_A = axis_frame(j.axis) if j.kind in TREE_JOINTS else np.eye(3)
            R0 = spatial.quat_to_matrix(j.parent_quat) @ R_A  # joint frame in the parent's frame
            R1 = spatial.quat_to_matrix(j.child_quat) @ R_A
            parent = ground if j.parent == WORLD else bodies[j.parent]
            # the marker frames are the joint frames (rotationMarker0/1 are deprecated since 1.12; before, they
            # carry the frames: ``compat.Markers``)
            m0 = framed.add(MarkerBodyRigid, j.parent_point, R0, bodyNumber=parent)
            m1 = framed.add(MarkerBodyRigid, j.child_point, R1, bodyNumber=bodies[j.child])
            joint = framed.generic_joint(ObjectJointGeneric, m0, m1, constrainedAxes=CONSTRAINED_AXES[j.kind])
            sensors[f"__joint:{j.child}"] = {"f": mbs.AddSensor(SensorObject(
                objectNumber=joint, outputVariableType=OV.ForceLocal))}
            redundant_joints[j.child] = R0
            joint_objects[j.child] = joint
            summary.append(f"ObjectJointGeneric {j.parent} -> {j.child} ({j.kind}), constrainedAxes "
                           f"{CONSTRAINED_AXES[j.kind]} (redundant coordinates)")
    # --- joints=minimal: revolute and prismatic tree(s) in one kinematic tree
    links = [] if redundant else [b for b in scene.topological_order() if scene.joint(b.name).kind in TREE_JOINTS]
    X_EB = {}  # link -> (p_EB, R_EB): its scene frame B in its link frame E, x_E = p_EB + R_EB x_B
    tree = node = None
    if links:
        index = {b.name: i for i, b in enumerate(links)}
        Ts, offsets, coms, inertias, masses, parents, q0, v0 = [], [], [], [], [], [], [], []
        for b in links:
            j = scene.joint(b.name)
            R_CJ = spatial.quat_to_matrix(j.child_quat)
            R_A = axis_frame(j.axis)
            R_EB = R_A.T @ R_CJ.T
            p_EB = -R_EB @ np.array(j.child_point)
            X_EB[b.name] = (p_EB, R_EB)
            R_PJ = spatial.quat_to_matrix(j.parent_quat)
            if j.parent == WORLD:
                p_EpP, R_EpP = np.zeros(3), np.eye(3)
            else:
                p_EpP, R_EpP = X_EB[j.parent]  # the parent's scene frame P in its link frame Ep
            Ts.append(R_EpP @ R_PJ @ R_A)
            offsets.append(p_EpP + R_EpP @ np.array(j.parent_point))
            coms.append(p_EB)
            inertias.append(R_EB @ b.inertia_matrix @ R_EB.T)
            masses.append(b.mass)
            parents.append(-1 if j.parent == WORLD else index[j.parent])
            q0.append(j.q0[0])
            v0.append(j.v0[0])
        n = len(links)
        node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n, initialCoordinates=q0,
                                           initialCoordinates_t=v0, numberOfODE2Coordinates=n))
        tree = mbs.AddObject(ObjectKinematicTree(
            nodeNumber=node, jointTypes=[getattr(exu.JointType, TREE_JOINTS[scene.joint(b.name).kind]) for b in links],
            linkParents=parents,
            jointTransformations=exu.Matrix3DList(Ts), jointOffsets=exu.Vector3DList(offsets),
            linkInertiasCOM=exu.Matrix3DList(inertias), linkCOMs=exu.Vector3DList(coms), linkMasses=masses,
            baseOffset=[0.0, 0.0, 0.0], gravity=list(g)))
        outputs = (("p", OV.Position), ("R", OV.RotationMatrix), ("v", OV.Velocity), ("w", OV.AngularVelocity),
                   ("a", OV.Acceleration))
        for b in links:
            i, (p_EB, R_EB) = index[b.name], X_EB[b.name]
            # a marker at scene point p of the body, its frame R in the body's scene frame B (loops), or
            # the link frame E's axes (loads, whose vectors are turned into E)
            markers[b.name] = lambda p, R=None, i=i, p_EB=p_EB, R_EB=R_EB: framed.add(
                MarkerKinematicTreeRigid, p_EB + R_EB @ np.array(p), np.eye(3) if R is None else R_EB @ R,
                objectNumber=tree, linkNumber=i)
            sensors[b.name] = {k: mbs.AddSensor(SensorKinematicTree(
                objectNumber=tree, linkNumber=i, localPosition=list(p_EB), outputVariableType=v))
                for k, v in outputs}
        sensors["__q"] = {"q": mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=OV.Coordinates))}
        sensors["__v"] = {"v": mbs.AddSensor(SensorNode(nodeNumber=node, outputVariableType=OV.Coordinates_t))}
        summary.append(f"ObjectKinematicTree: {n} link(s) "
                       f"{[f'{b.name} ({TREE_JOINTS[scene.joint(b.name).kind]})' for b in links]} "
                       f"(minimal coordinates), gravity {g.tolist()}")
    # --- loop closures: one constraint object from a marker on body a (marker 0) to one on body b,
    # its rows those independent at the initial state (``loops.loop_axes``)
    if scene.loops or scene.springs or scene.planes:  # their ends on the world (a plane is): markers on a ground
        ground = mbs.AddObject(ObjectGround())
        owners[int(ground)] = WORLD
        markers[WORLD] = lambda p, R=np.eye(3): framed.add(MarkerBodyRigid, p, R, bodyNumber=ground)
    loops, rows = {}, {}
    if scene.loops:
        rows = loop_axes(scene)
        for lp in scene.loops:
            R_BJa, R_BJb = joint_frame(lp)
            m0, m1 = markers[lp.body_a](lp.point_a, R_BJa), markers[lp.body_b](lp.point_b, R_BJb)
            dropped = f"; redundant at t = 0, left out: {', '.join(rows[lp.name].dropped)}" if rows[lp.name].dropped else ""
            if lp.kind == "distance":
                obj = mbs.AddObject(ObjectConnectorDistance(markerNumbers=[m0, m1], distance=lp.length))
                summary.append(f"ObjectConnectorDistance {lp.body_a} -> {lp.body_b} (loop {lp.name!r}), "
                               f"distance {lp.length:g} m")
            else:
                obj = framed.generic_joint(ObjectJointGeneric, m0, m1, constrainedAxes=list(rows[lp.name].axes))
                summary.append(f"ObjectJointGeneric {lp.body_a} -> {lp.body_b} (loop {lp.name!r}, {lp.kind}), "
                               f"constrainedAxes {list(rows[lp.name].axes)}{dropped}")
            sensors[f"__loop:{lp.name}"] = {"f": mbs.AddSensor(SensorObject(
                objectNumber=obj, outputVariableType=OV.Force if lp.kind == "distance" else OV.ForceLocal))}
            loops[lp.name] = R_BJa
    # --- spring-dampers: one ObjectConnectorSpringDamper from a marker on body a (marker 0) to one on body b
    springs, lines = add_springs(mbs, scene, markers, sensors)
    summary += lines
    # --- contact: one connector per scene pair (``contact``)
    summary += add_contacts(mbs, scene, settings, markers, sensors)
    # --- loads
    for ld in scene.loads:
        R_EB = X_EB.get(ld.body, (None, np.eye(3)))[1]  # a rigid body's E is B
        marker = markers[ld.body](ld.point)
        follower = ld.frame == "body"
        vec = list(R_EB @ np.array(ld.vector)) if follower else list(ld.vector)
        Load = LoadForceVector if ld.kind == "force" else LoadTorqueVector
        mbs.AddLoad(Load(markerNumber=marker, loadVector=vec, bodyFixed=follower))
        summary.append(f"{Load.__name__} on {ld.body} at {list(ld.point)}, bodyFixed={follower}")
    built = ExudynSystem(SC=SC, mbs=mbs, sensors=sensors, X_EB=X_EB, links=[b.name for b in links], tree=tree,
                         tree_node=node, redundant_joints=redundant_joints, joint_objects=joint_objects, loops=loops,
                         loop_rows=rows, springs=springs, owners=owners, summary="\n".join(summary) + "\n",
                         spring_readout={}, joint_readout={})
    if assemble:
        mbs.Assemble()
        # the springs and joints as Exudyn holds them, at the initial state (its connectors and markers report
        # their outputs in the current configuration only, which is the initial one until the solve)
        built = replace(built, spring_readout=read_springs(mbs, scene, built), joint_readout=read_joints(mbs, scene, built))
    return built
