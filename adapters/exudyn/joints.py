"""The scene's joints in Exudyn's terms (``CONSTRAINED_AXES`` of the generic joints, ``TREE_JOINTS`` of the
kinematic tree, both used by ``model.build``) and as the built system holds them: ``read_joints``, what
the audit reports.

Everything is read from the assembled system, before the solve: in minimal coordinates the
kinematic tree's joint type (``RevoluteZ``, ``PrismaticZ``), its joint transformation (whose z column is
the axis, in the parent link's frame), joint offset and the node's initial coordinates; in redundant
coordinates the ``ObjectJointGeneric``'s constrained axes (the kind they leave free), its marker 0
frame (whose z is the axis, in the parent body's frame) and the two markers' world poses and velocities
at the initial state, from which the joint's initial coordinate and rate follow. They are turned back
into the scene's terms (the axis in the parent joint frame, the joint point in the parent's body frame)
and compared with the scene.
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.exudyn.compat import joint_frame, turned
from dalembert.adapters.exudyn.springs import POINT_TOL
from dalembert.scene import WORLD

__all__ = ["read_joints", "JOINT_TOL", "CONSTRAINED_AXES", "TREE_JOINTS"]

# ObjectJointGeneric's constrainedAxes (x, y, z translation; x, y, z rotation) in the
# joint frame, whose z is a revolute or prismatic joint's axis.
CONSTRAINED_AXES = {"revolute": [1, 1, 1, 1, 1, 0], "prismatic": [1, 1, 0, 1, 1, 1], "ball": [1, 1, 1, 0, 0, 0],
                    "weld": [1, 1, 1, 1, 1, 1]}
# The scene's single-axis joints as ObjectKinematicTree joint types (exudyn.JointType), about or along link z.
TREE_JOINTS = {"revolute": "RevoluteZ", "prismatic": "PrismaticZ"}

# An axis (unit vector), a joint point (m), an initial coordinate (m or rad) or rate (m/s, rad/s) read back
# against the scene's: the same quantity through two chains of double-precision rotations (as springs.POINT_TOL);
# a wrong axis, frame or offset is off by O(1).
JOINT_TOL = POINT_TOL
# Exudyn's tree joint type -> (the scene's kind, the link-frame axis it moves about or along, as a column index)
_TREE_TYPES = {name: (kind, "XYZ".index(name[-1])) for kind, name in TREE_JOINTS.items()}
# ObjectJointGeneric's constrained axes -> the scene's kind
_GENERIC_KINDS = {tuple(axes): kind for kind, axes in CONSTRAINED_AXES.items()}


def read_joints(mbs, scene, built):
    """Each non-free joint of ``scene`` as the assembled (not yet solved) ``mbs`` holds it.

    Parameters
    ----------
    mbs : exudyn.MainSystem, assembled, not yet solved (its markers' outputs are the initial state's)
    scene : Scene
    built : dict — what ``model.build`` returned for ``mbs`` (``tree``, ``tree_node``, ``links``, ``X_EB``,
        ``joint_objects``)

    Returns
    -------
    dict child body name -> dict: ``element`` (``ObjectKinematicTree`` or ``ObjectJointGeneric``),
    ``joint_type`` (the tree's ``RevoluteZ``/``PrismaticZ``, or the generic joint's constrained axes as a
    string), ``kind`` (the scene kind that reads as), ``axis`` (unit, in the scene's parent joint frame; None
    for ball and weld), ``parent_point`` (m, the parent's body frame), ``q0``, ``v0`` (the initial coordinate, m
    or rad, and rate, m/s or rad/s, of single-axis joints; else None), and ``mismatches``: each way the engine's
    joint differs from the scene's (empty: the joint is the scene's)
    """
    out = {}
    if built.links:
        out.update(_tree_joints(mbs, scene, built))
    for child, number in built.joint_objects.items():
        out[child] = _generic_joint(mbs, scene.joint(child), number)
    for child, got in out.items():
        got["mismatches"] = _mismatches(scene.joint(child), got)
    return out


def _tree_joints(mbs, scene, built):
    tree = mbs.GetObject(built.tree)
    node = mbs.GetNode(built.tree_node)
    out = {}
    for i, name in enumerate(built.links):
        j = scene.joint(name)
        joint_type = tree["jointTypes"][i].name
        kind, column = _TREE_TYPES.get(joint_type, (joint_type, None))
        # the parent's scene frame P in its link frame Ep (the base: the world)
        p_EpP, R_EpP = (np.zeros(3), np.eye(3)) if j.parent == WORLD else built.X_EB[j.parent]
        T = np.asarray(tree["jointTransformations"][i], dtype=float)  # joint frame in Ep
        R_PJp = spatial.quat_to_matrix(j.parent_quat)
        axis = R_PJp.T @ R_EpP.T @ T[:, column] if column is not None else None
        offset = np.asarray(tree["jointOffsets"][i], dtype=float)
        out[name] = dict(element="ObjectKinematicTree", joint_type=joint_type, kind=kind, axis=axis,
                         parent_point=R_EpP.T @ (offset - p_EpP), q0=float(node["initialCoordinates"][i]),
                         v0=float(node["initialCoordinates_t"][i]))
    return out


def _generic_joint(mbs, j, number):
    import exudyn as exu

    OV, current = exu.OutputVariableType, exu.ConfigurationType.Current
    obj = mbs.GetObject(number)
    axes = tuple(int(a) for a in obj["constrainedAxes"])
    kind = _GENERIC_KINDS.get(axes, f"unknown {list(axes)}")
    m0, m1 = obj["markerNumbers"]
    HT0 = joint_frame(mbs, obj, 0)  # the joint's frame on marker 0 in the parent's body frame

    def pose(m):  # a marker's world position (m), velocity (m/s), rotation, angular velocity (rad/s)
        return [np.asarray(mbs.GetMarkerOutput(m, ov, configuration=current), dtype=float)
                for ov in (OV.Position, OV.Velocity, OV.RotationMatrix, OV.AngularVelocity)]

    (p0, v0, R0, w0), (p1, v1, R1, w1) = pose(m0), pose(m1)
    R0, R1 = turned(R0.reshape(3, 3), obj, 0), turned(R1.reshape(3, 3), obj, 1)  # row-major; the joint frames
    q, rate, axis = None, None, None
    if kind in TREE_JOINTS:  # single-axis: z of the marker frames (model.build)
        a_W = R0[:, 2]
        axis = spatial.quat_to_matrix(j.parent_quat).T @ HT0[:3, 2]
        if kind == "prismatic":
            r = p1 - p0
            q, rate = float(a_W @ r), float(a_W @ (v1 - v0 - np.cross(w0, r)))
        else:
            R_rel = R0.T @ R1  # a turn about z
            q, rate = float(np.arctan2(R_rel[1, 0], R_rel[0, 0])), float(a_W @ (w1 - w0))
    return dict(element="ObjectJointGeneric", joint_type=f"constrainedAxes {list(axes)}", kind=kind, axis=axis,
                parent_point=HT0[:3, 3], q0=q, v0=rate)


def _mismatches(j, got):
    found = []
    if got["kind"] != j.kind:
        found.append(f"kind: engine {got['kind']!r} ({got['joint_type']}), scene {j.kind!r}")
        return found
    if j.kind in TREE_JOINTS:
        a = np.asarray(j.axis, dtype=float) / np.linalg.norm(j.axis)
        if np.abs(got["axis"] - a).max() > JOINT_TOL:
            found.append(f"axis: engine {got['axis'].tolist()}, scene {a.tolist()} (unit, parent joint frame)")
        for key, want in (("q0", j.q0[0]), ("v0", j.v0[0])):
            delta = got[key] - want
            if j.kind == "revolute" and key == "q0":
                delta = (delta + np.pi) % (2.0 * np.pi) - np.pi  # an angle read back modulo whole turns
            if abs(delta) > JOINT_TOL:
                found.append(f"{key}: engine {got[key]!r}, scene {want!r}")
    if np.abs(got["parent_point"] - np.asarray(j.parent_point, dtype=float)).max() > JOINT_TOL:
        found.append(f"parent_point: engine {got['parent_point'].tolist()}, scene {list(j.parent_point)} "
                     "(m, parent body frame)")
    return found
