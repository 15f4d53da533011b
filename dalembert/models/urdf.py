"""URDF files into scenes (``xml.etree``; no URDF library).

Read: ``<link>`` with its ``<inertial>`` (``<origin xyz rpy>``: the COM and the inertial frame's axes in the
link frame; ``<mass>``; ``<inertia ixx ixy ixz iyy iyz izz>`` about the COM in the inertial frame) and
``<joint>`` (``revolute``, ``continuous`` -> revolute, ``prismatic``, ``fixed`` -> weld or merge,
``floating`` -> free from the world; ``planar`` is refused: dalembert has no planar joint) with its
``<origin>`` (the joint frame in the parent link's frame; the child link's frame *is* the joint frame) and
``<axis>`` (default ``1 0 0``). Geometry (``<visual>``, ``<collision>``, meshes) is ignored: these scenes
are contact-free. What else the file calls for — ``<dynamics damping friction>``, ``<limit>``,
``<mimic>``, ``<transmission>`` (actuators), ``<safety_controller>`` — is collected as ``FileEffects``
and left out of the scene. The tree becomes a scene by ``dalembert.models.tree.build_scene``.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import numpy as np

from dalembert.models.tree import FileEffect, JointSpec, LinkSpec, ModelError, build_scene, rpy_to_matrix

__all__ = ["read_urdf", "urdf_tree"]

_KINDS = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic", "fixed": "fixed",
          "floating": "free"}


def _floats(path, element, attr, text, n, default):
    if text is None:
        return default
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        values = ()
    if len(values) != n or not all(np.isfinite(values)):
        raise ModelError(f"{path}: {element} {attr}={text!r} — give {n} finite numbers separated by spaces",
                         "bad number")
    return values


def _origin(path, where, element):
    """``(xyz, R)`` of an ``<origin>`` child of ``element`` (identity when absent)."""
    o = element.find("origin")
    if o is None:
        return (0.0, 0.0, 0.0), np.eye(3)
    xyz = _floats(path, f"{where} <origin>", "xyz", o.get("xyz"), 3, (0.0, 0.0, 0.0))
    rpy = _floats(path, f"{where} <origin>", "rpy", o.get("rpy"), 3, (0.0, 0.0, 0.0))
    return xyz, rpy_to_matrix(rpy)


def _link(path, el):
    name = el.get("name")
    where = f"<link name='{name}'>"
    inertial = el.find("inertial")
    if inertial is None:
        return LinkSpec(name, 0.0)
    com, R = _origin(path, f"{where} <inertial>", inertial)
    mass_el = inertial.find("mass")
    mass = 0.0 if mass_el is None else _floats(path, f"{where} <mass>", "value", mass_el.get("value"), 1, (0.0,))[0]
    if mass < 0.0:
        raise ModelError(f"{path}: {where} <mass value='{mass:g}'> is negative — give the link's mass in kg "
                         "(> 0), or remove the <inertial> of a frame without mass", "bad inertia")
    i = inertial.find("inertia")
    I = np.zeros((3, 3))
    if i is not None:
        vals = {k: _floats(path, f"{where} <inertia>", k, i.get(k), 1, (0.0,))[0]
                for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        I = np.array([[vals["ixx"], vals["ixy"], vals["ixz"]], [vals["ixy"], vals["iyy"], vals["iyz"]],
                      [vals["ixz"], vals["iyz"], vals["izz"]]])
    return LinkSpec(name, mass, com, R, I)


def _joint(path, el, effects):
    name, kind = el.get("name"), el.get("type")
    where = f"<joint name='{name}'>"
    if kind not in _KINDS:
        fix = ("dalembert has no planar joint; make it two prismatic joints and a revolute one through massive "
               "links, or fix it" if kind == "planar" else f"use one of {sorted(_KINDS)}")
        raise ModelError(f"{path}: {where} type {kind!r} — {fix}", f"joint type {kind}")
    parent, child = el.find("parent"), el.find("child")
    if parent is None or child is None:
        raise ModelError(f"{path}: {where} lacks its <parent link=...> or <child link=...> — name both links",
                         "broken tree")
    xyz, R = _origin(path, where, el)
    axis = None
    if _KINDS[kind] in ("revolute", "prismatic"):
        a = el.find("axis")
        axis = _floats(path, f"{where} <axis>", "xyz", None if a is None else a.get("xyz"), 3, (1.0, 0.0, 0.0))
        if not any(axis):
            raise ModelError(f"{path}: {where} <axis xyz='0 0 0'> — give the joint's axis (any non-zero length)",
                             "bad axis")
    for tag, kinds in (("dynamics", ("damping", "friction")), ("limit", ("lower", "upper", "effort", "velocity")),
                       ("mimic", ("joint", "multiplier", "offset")),
                       ("safety_controller", ("soft_lower_limit", "soft_upper_limit", "k_position", "k_velocity"))):
        e = el.find(tag)
        if e is None:
            continue
        values = {k: e.get(k) for k in kinds if e.get(k) is not None}
        if tag == "dynamics":  # a zero coefficient calls for nothing
            for k, v in values.items():
                if float(v) != 0.0:
                    effects.append(FileEffect(where, k, v))
        elif values:
            effects.append(FileEffect(where, "limit" if tag in ("limit", "safety_controller") else tag,
                                      " ".join(f"{k}={v}" for k, v in values.items())))
    return JointSpec(name, _KINDS[kind], parent.get("link"), child.get("link"), xyz, R, axis=axis)


def urdf_tree(path):
    """The links, joints and extra effects of a URDF file: ``(robot name, [LinkSpec], [JointSpec],
    [FileEffect])``; raises ``ModelError`` naming the file, the element and the fix."""
    shown = os.path.basename(path)
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as err:
        raise ModelError(f"{shown}: cannot read it as XML ({err}) — give a URDF file", "not xml") from None
    if root.tag != "robot":
        raise ModelError(f"{shown}: the root element is <{root.tag}>, not <robot> — give a URDF file (an MJCF "
                         "<mujoco> file reads with dalembert.models.read_mjcf)", "not urdf")
    effects = []
    links = [_link(shown, el) for el in root.findall("link")]
    joints = [_joint(shown, el, effects) for el in root.findall("joint")]
    for t in root.findall("transmission"):
        acts = [a.get("name") for a in t.iter("actuator")]
        js = [j.get("name") for j in t.iter("joint")]
        effects.append(FileEffect(f"<transmission name='{t.get('name')}'>", "transmission",
                                  f"joints {js} actuators {acts}"))
    return root.get("name") or os.path.splitext(shown)[0], links, joints, effects


def read_urdf(path, base="fixed", gravity=(0.0, 0.0, -9.81), positions=None, velocities=None, name=None,
              locked=()):
    """The ``Scene`` of a URDF file, with what the file calls for besides.

    Parameters
    ----------
    path : str — the .urdf file
    base : "fixed" (the root link, at the origin, and every link fixed to it are the world's) or "free" (a
        floating base)
    gravity : 3 floats — m/s^2, world
    positions, velocities : dict — joint name (the file's) -> initial angle/slide and rate; ``"base"`` -> the
        free base's 7 coordinates / 6 speeds (``dalembert.kinds.JOINT_KINDS``)
    name : str — the scene's name (default: the robot's)
    locked : iterable of str — joints (the file's names) held at their zero, as if fixed

    Returns
    -------
    dalembert.models.tree.ImportedModel — ``.scene``, ``.effects``, ``.joint_names``
    """
    robot, links, joints, effects = urdf_tree(path)
    return build_scene(os.path.basename(path), name or robot, links, joints, effects, base, gravity, positions,
                       velocities, locked=locked)
