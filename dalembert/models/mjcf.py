"""MJCF (MuJoCo's XML) files into scenes: bodies, joints and inertials (``xml.etree``).

Read: ``<compiler angle eulerseq>``; ``<default>`` classes (``class``, ``childclass``, nested defaults) for
``<joint>``, ``<inertial>`` and ``<geom>`` attributes; the ``<worldbody>`` tree of ``<body pos quat|axisangle|
euler|xyaxes|zaxis>``, each with its ``<inertial pos quat|... mass diaginertia|fullinertia>`` and at most one
joint — ``<joint type=hinge|slide|ball|free pos axis>`` (the joint frame sits at ``pos`` in the body with
the body's axes) or ``<freejoint>`` — a body without one welded to its parent. A body without an
``<inertial>`` takes its inertia from its geoms only where that is trivial: spheres and boxes of a given
``mass`` or ``density`` (MuJoCo's default 1000 kg/m^3); meshes and other shapes are refused (give an
``<inertial>``), and so is ``<compiler inertiafromgeom="true">``. What else the file calls for (joint
``damping``, ``frictionloss``, ``armature``, ``stiffness``, ``range``, ``actuatorfrcrange``; ``<actuator>``,
``<tendon>``, ``<equality>``) is collected as ``FileEffects`` and left out. The tree becomes a scene by
``dalembert.models.tree.build_scene``, as a URDF's does.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import numpy as np

from dalembert import spatial
from dalembert.models.tree import FileEffect, JointSpec, LinkSpec, ModelError, build_scene

__all__ = ["read_mjcf", "mjcf_tree", "MJCF_DENSITY"]

# MuJoCo's default geom density (kg/m^3: water), used where a geom gives neither mass nor density.
MJCF_DENSITY = 1000.0
_JOINTS = {"hinge": "revolute", "slide": "prismatic", "ball": "ball", "free": "free"}
_JOINT_EFFECTS = ("damping", "frictionloss", "armature", "stiffness", "range", "actuatorfrcrange", "springref")
_EYE = np.eye(3)


class _Reader:
    def __init__(self, path, root):
        self.path, self.effects = path, []
        compiler = root.find("compiler")
        get = (lambda k, d: d) if compiler is None else compiler.get
        self.degrees = get("angle", "degree") == "degree"
        self.eulerseq = get("eulerseq", "xyz")
        if get("inertiafromgeom", "auto") == "true":
            self.fail("<compiler inertiafromgeom='true'>: every inertia would come from the geoms — dalembert "
                      "reads <inertial> elements: remove the attribute (or set it to 'auto')", "geom inertia")
        self.classes = {"main": {}}
        for d in root.findall("default"):
            self._defaults(d, {}, "main")

    def fail(self, message, reason):
        raise ModelError(f"{self.path}: {message}", reason)

    def _defaults(self, el, inherited, name):
        mine = {tag: dict(inherited.get(tag, {})) for tag in ("joint", "geom", "inertial")}
        for tag in mine:
            for e in el.findall(tag):
                mine[tag].update(e.attrib)
        self.classes[el.get("class", name)] = mine
        for sub in el.findall("default"):
            if sub.get("class") is None:
                self.fail("<default> nested without a class= — name every nested default class", "bad default")
            self._defaults(sub, mine, sub.get("class"))

    def attrs(self, el, cls):
        """The element's attributes over its class's defaults."""
        base = self.classes.get(el.get("class", cls), None)
        if base is None:
            self.fail(f"<{el.tag} class='{el.get('class', cls)}'>: no such default class — define it in <default>",
                      "bad default")
        out = dict(base.get(el.tag, {}))
        out.update(el.attrib)
        return out

    def floats(self, where, key, text, n):
        try:
            values = np.array([float(v) for v in text.split()])
        except ValueError:
            values = np.zeros(0)
        if len(values) != n or not np.all(np.isfinite(values)):
            self.fail(f"{where} {key}={text!r} — give {n} finite numbers separated by spaces", "bad number")
        return values

    def angle(self, value):
        return np.radians(value) if self.degrees else value

    def rotation(self, where, a):
        """The orientation of a frame from MJCF's alternatives (quat, axisangle, euler, xyaxes, zaxis)."""
        given = [k for k in ("quat", "axisangle", "euler", "xyaxes", "zaxis") if k in a]
        if len(given) > 1:
            self.fail(f"{where} gives {given} — give one orientation", "bad orientation")
        if not given:
            return _EYE
        k = given[0]
        if k == "quat":
            q = self.floats(where, k, a[k], 4)
            return spatial.quat_to_matrix(q / np.linalg.norm(q))
        if k == "axisangle":
            v = self.floats(where, k, a[k], 4)
            return spatial.quat_to_matrix(spatial.quat_from_axis_angle(v[:3] / np.linalg.norm(v[:3]),
                                                                       self.angle(v[3])))
        if k == "euler":
            v = self.angle(self.floats(where, k, a[k], 3))
            R = _EYE
            for axis, ang in zip(self.eulerseq, v):  # lower case: axes that turn with the frame (intrinsic)
                e = np.eye(3)["xyz".index(axis.lower())]
                Ri = spatial.quat_to_matrix(spatial.quat_from_axis_angle(e, ang))
                R = R @ Ri if axis.islower() else Ri @ R
            return R
        if k == "xyaxes":
            v = self.floats(where, k, a[k], 6)
            x = v[:3] / np.linalg.norm(v[:3])
            y = v[3:] - (v[3:] @ x) * x
            y /= np.linalg.norm(y)
            return np.column_stack([x, y, np.cross(x, y)])
        z = self.floats(where, k, a[k], 3)
        z /= np.linalg.norm(z)
        axis = np.cross([0.0, 0.0, 1.0], z)  # MuJoCo: the smallest rotation taking (0, 0, 1) to z
        s, c = np.linalg.norm(axis), z[2]
        if s < 1e-15:
            return _EYE if c > 0 else np.diag([1.0, -1.0, -1.0])
        return spatial.quat_to_matrix(spatial.quat_from_axis_angle(axis / s, np.arctan2(s, c)))

    def pos(self, where, a):
        return self.floats(where, "pos", a["pos"], 3) if "pos" in a else np.zeros(3)

    def inertial(self, name, body, cls):
        where = f"<body name='{name}'> <inertial>"
        el = body.find("inertial")
        if el is not None:
            a = self.attrs(el, cls)
            mass = float(a.get("mass", "0"))
            if "fullinertia" in a:
                xx, yy, zz, xy, xz, yz = self.floats(where, "fullinertia", a["fullinertia"], 6)
                inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
            elif "diaginertia" in a:
                inertia = np.diag(self.floats(where, "diaginertia", a["diaginertia"], 3))
            else:
                self.fail(f"{where} has neither diaginertia nor fullinertia — give the inertia about the COM",
                          "bad inertia")
            return LinkSpec(name, mass, tuple(self.pos(where, a)), self.rotation(where, a), inertia)
        parts = []
        for g in body.findall("geom"):
            a = self.attrs(g, cls)
            kind = a.get("type", "sphere")
            gwhere = f"<body name='{name}'> <geom name='{a.get('name', '')}' type='{kind}'>"
            if kind not in ("sphere", "box"):
                self.fail(f"{gwhere}: the body has no <inertial>, and dalembert derives inertia only from spheres "
                          "and boxes — give the body an <inertial> with its mass and inertia", "geom inertia")
            size = self.floats(gwhere, "size", a.get("size", ""), 1 if kind == "sphere" else 3)
            volume = 4.0 / 3.0 * np.pi * size[0] ** 3 if kind == "sphere" else 8.0 * np.prod(size)
            m = float(a["mass"]) if "mass" in a else float(a.get("density", MJCF_DENSITY)) * volume
            if kind == "sphere":
                I = np.eye(3) * 0.4 * m * size[0] ** 2
            else:  # MuJoCo's box size is the half-lengths
                s2 = (2.0 * size) ** 2
                I = np.diag([s2[1] + s2[2], s2[0] + s2[2], s2[0] + s2[1]]) * m / 12.0
            R = self.rotation(gwhere, a)
            parts.append((m, self.pos(gwhere, a), R @ I @ R.T))
        if not parts:
            return LinkSpec(name, 0.0)
        m, c = sum(p[0] for p in parts), sum(p[0] * p[1] for p in parts) / sum(p[0] for p in parts)
        I = sum(p[2] + p[0] * ((p[1] - c) @ (p[1] - c) * np.eye(3) - np.outer(p[1] - c, p[1] - c)) for p in parts)
        return LinkSpec(name, m, tuple(c), _EYE, I)

    def joint(self, name, parent, body, cls, p_PB, R_PB):
        els = [e for e in body if e.tag in ("joint", "freejoint")]
        if len(els) > 1:
            self.fail(f"<body name='{name}'> has {len(els)} joints — dalembert gives each body one joint: split the "
                      "body into bodies with mass, one joint each", "several joints")
        if not els:
            return JointSpec(f"{name}_weld", "fixed", parent, name, tuple(p_PB), R_PB)
        el = els[0]
        a = {"type": "free"} if el.tag == "freejoint" else self.attrs(el, cls)
        jname = a.get("name", f"{name}_joint")
        where = f"<joint name='{jname}'>"
        kind = a.get("type", "hinge")
        if kind not in _JOINTS:
            self.fail(f"{where} type {kind!r} — use one of {sorted(_JOINTS)}", f"joint type {kind}")
        if kind == "free" and parent != "world":
            self.fail(f"{where} is free but its body's parent '{parent}' is not the world — a free joint frees a "
                      "body of the <worldbody>", "inner floating joint")
        for k in _JOINT_EFFECTS:
            if k in a and (k in ("range", "actuatorfrcrange", "springref") or float(a[k]) != 0.0):
                if k == "range" and a.get("limited", "auto") == "false":
                    continue
                self.effects.append(FileEffect(where, {"frictionloss": "friction", "stiffness": "spring",
                                                       "range": "limit", "actuatorfrcrange": "limit",
                                                       "springref": "spring"}.get(k, k), a[k]))
        p_CJ = self.pos(where, a)
        axis = tuple(self.floats(where, "axis", a.get("axis", "0 0 1"), 3)) if kind in ("hinge", "slide") else None
        if axis is not None and not any(axis):
            self.fail(f"{where} axis='0 0 0' — give the joint's axis (any non-zero length)", "bad axis")
        return JointSpec(jname, _JOINTS[kind], parent, name, tuple(p_PB + R_PB @ p_CJ), R_PB, tuple(p_CJ), _EYE,
                         axis)

    def tree(self, worldbody):
        links, joints = [LinkSpec("world", 0.0)], []
        stack = [(b, "world", "main") for b in reversed(worldbody.findall("body"))]
        while stack:
            body, parent, cls = stack.pop()
            cls = body.get("childclass", cls)
            name = body.get("name")
            if not name:
                self.fail(f"a <body> under '{parent}' has no name= — name every body (joints and effects are "
                          "reported by it)", "unnamed body")
            where = f"<body name='{name}'>"
            links.append(self.inertial(name, body, cls))
            joints.append(self.joint(name, parent, body, cls, self.pos(where, body.attrib),
                                     self.rotation(where, body.attrib)))
            stack += [(b, name, cls) for b in reversed(body.findall("body"))]
        return links, joints


def mjcf_tree(path):
    """``(model name, [LinkSpec], [JointSpec], [FileEffect])`` of an MJCF file; the world is the root link
    (``"world"``, massless: a body of the <worldbody> without a joint is welded to it)."""
    shown = os.path.basename(path)
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as err:
        raise ModelError(f"{shown}: cannot read it as XML ({err}) — give an MJCF file", "not xml") from None
    if root.tag != "mujoco":
        raise ModelError(f"{shown}: the root element is <{root.tag}>, not <mujoco> — give an MJCF file (a URDF "
                         "<robot> reads with dalembert.models.read_urdf)", "not mjcf")
    if root.find("include") is not None:
        raise ModelError(f"{shown}: <include> is not read — merge the included file into this one", "include")
    reader = _Reader(shown, root)
    worldbody = root.find("worldbody")
    if worldbody is None:
        reader.fail("no <worldbody> — an MJCF model's bodies live in it", "no links")
    links, joints = reader.tree(worldbody)
    for section, kind in (("actuator", "actuator"), ("tendon", "transmission"), ("equality", "mimic")):
        for s in root.findall(section):
            for e in s:
                reader.effects.append(FileEffect(f"<{section}> <{e.tag} name='{e.get('name', '')}'>", kind,
                                                 " ".join(f"{k}={v}" for k, v in e.attrib.items())))
    return root.get("model") or os.path.splitext(shown)[0], links, joints, reader.effects


def read_mjcf(path, gravity=(0.0, 0.0, -9.81), positions=None, velocities=None, name=None, locked=()):
    """The ``Scene`` of an MJCF file, with what the file calls for besides.

    The world is the file's root: bodies with a ``<freejoint>`` are free, bodies without a joint are welded
    to their parent (or merged into it when not a rigid body alone: ``dalembert.models.tree``).

    Parameters
    ----------
    path : str — the .xml file
    gravity : 3 floats — m/s^2, world (the file's ``<option gravity>`` is not read)
    positions, velocities : dict — joint name (the file's) -> initial coordinates and speeds
        (``dalembert.kinds.JOINT_KINDS``)
    name : str — the scene's name (default: the model's)
    locked : iterable of str — joints (the file's names) held at their zero, as if fixed

    Returns
    -------
    dalembert.models.tree.ImportedModel
    """
    model, links, joints, effects = mjcf_tree(path)
    return build_scene(os.path.basename(path), name or model, links, joints, effects, "fixed", gravity, positions,
                       velocities, tag="body", locked=locked)
