"""An engine reading the robot's model file itself: option ``model_file`` (what MuJoCo, Pinocchio and Drake share).

Every adapter builds its model from the ``Scene`` (so every engine runs exactly the same system). With
``--option model_file=PATH`` an adapter instead hands the file the scene was read from to the engine's own
reader (MuJoCo's URDF/MJCF compiler, ``pin.buildModelFromUrdf``, Drake's ``Parser``), with what the file calls
for beyond bodies and joints (damping, friction, armature, limits) as the engine reads and applies it
(``file_effects=on``, the default), or with those zeroed after the reading (``file_effects=off``: then the run
is the scene's motion read by another reader, and within the case's tolerances where the readers agree). The
truth stays the reference's on the scene: a run with the effects on measures what the engine's reading and
those effects change ("what your engine does with your file"), a finding rather than a failure.

What every engine's reading shares, here:

* the file is the scene's: each moving joint of the scene (by its child link's name, the scene body's) is a
  joint of the engine's model whose subtree has the scene's mass (``check_same_model``): otherwise the
  option names the file that was given and the fix;
* geometry (``<visual>``, ``<collision>``) is not read (``bare_urdf``): these cases have no contact, and meshes
  resolve through ROS package paths no engine here has; joints the scene holds at zero (the case's
  ``locked``, a gripper's fingers) are fixed in the engine's model too, found as the file's moving joints whose
  child link moves on no joint of the scene; a fixed joint's ``<mimic>`` is dropped (it moves nothing; Drake's
  parser refuses a 0-dof joint that mimics, as talos_reduced.urdf's grippers do);
* revolute and prismatic joints, and a floating base read from a URDF: the engine then frees the file's root
  link (its frame E at the link's origin, the scene's body frame at the COM of the root with its fixed links
  merged in, the same axes), and ``base_initial`` / ``base_series`` move the state between the two; a ball
  joint's coordinates are not mapped (``why_not``);
* the engine's joint coordinates are read back in the scene's order and turned into body terms by the scene's
  kinematics (``trajectory``: the reference's Kane kinematics, exact for the scene's tree), so every error and
  invariant is measured as for a scene-built run; joint reactions are not read back (they would be the scene's
  dynamics, not the engine's).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from dalembert.adapters.base import Option, Prepared

__all__ = ["SCENE", "NO_REPRO", "free_root", "base_initial", "base_series", "FileOption", "FILE_OPTIONS",
           "FILE_OPTION_NAMES", "FILE_EFFECTS", "FileJoint", "FilePrepared",
           "model_file", "effects_on", "why_not", "urdf_joints", "locked_joints", "bare_urdf", "scene_subtree_masses",
           "check_same_model", "joint_columns", "trajectory", "MASS_MATCH_REL_TOL", "SUFFIXES"]

# The files an engine reads here: URDF (every engine) and MJCF (MuJoCo's own format).
SUFFIXES = (".urdf", ".xml")
# model_file's value for "build the scene" (its default): a sweep model_file=scene,PATH puts both in one store.
SCENE = "scene"
FILE_EFFECTS = ("on", "off")
# The engine's subtree masses against the scene's: the same file's inertials summed in another order (and a
# fixed link merged by another reader) agree to roundoff; a different robot with the same link names (UR5 and
# UR10) differs by kilograms.
MASS_MATCH_REL_TOL = 1e-9


@dataclass(frozen=True)
class FileOption(Option):
    """An option whose value is the path of a model file (``SUFFIXES``); checked to exist before anything runs."""

    def allowed(self):
        return f"{SCENE!r} (the scene built) or the path of the robot's .urdf (or MuJoCo MJCF .xml) file"

    def problem(self, name, value, integrator):
        if self.only and integrator not in self.only:
            return super().problem(name, value, integrator)
        if value == SCENE:
            return None
        if not isinstance(value, str) or not value.lower().endswith(SUFFIXES):
            return f"options.{name}: {value!r} is not a .urdf or .xml file — give {self.allowed()}"
        if not os.path.isfile(value):
            return (f"options.{name}: no file {value!r} — give {self.allowed()}, the one the case's scene was read "
                    "from (its --param model)")
        return None

    def typed(self, value):
        return value


FILE_OPTIONS = {
    "model_file": FileOption(default=SCENE, description="the engine reads this model file itself (its own URDF/MJCF "
                             "reader) instead of building the scene; the file must be the case's"),
    "file_effects": Option(FILE_EFFECTS, FILE_EFFECTS[0], "with model_file: the file's damping, friction, armature "
                           "and limits as the engine reads them (on), or zeroed after the reading (off)"),
}
FILE_OPTION_NAMES = tuple(FILE_OPTIONS)


def model_file(settings):
    """The file the run's engine reads itself, or None (the scene is built: ``SCENE``, the default)."""
    value = settings.options.get("model_file", SCENE)
    return None if value == SCENE else value


def effects_on(settings):
    """Whether the file's effects stay as the engine read them (``file_effects``)."""
    return settings.options.get("file_effects", FILE_OPTIONS["file_effects"].default) == "on"


# ``dalembert repro`` writes the model an engine built from the scene: a file-read run is not that model.
NO_REPRO = ("options.model_file: dalembert repro writes runs of the model an engine built from the scene; this run is "
            "the engine's own reading of a file (its audit's model_source) — dalembert export gives its trajectory")


def beyond(settings):
    """What a run with ``settings`` simulates beyond its scene (``Adapter.beyond_scene``): the file's effects as
    the engine read them, when it reads the file with them on; else None (effects off: the scene's motion)."""
    if model_file(settings) and effects_on(settings):
        return ("the engine read options.model_file itself with file_effects=on: the file's damping, friction, "
                "armature and limits as the engine applies them")
    return None


def why_not(scene, settings):
    """Why a run with ``settings`` cannot read its file (a reason for ``Adapter.unsupported``), or None."""
    if not effects_on(settings) and not model_file(settings):  # (its default, "on", changes nothing: harmless)
        return "options.file_effects: off only with options.model_file — give model_file=PATH, or drop file_effects"
    if not model_file(settings):
        return None
    if free_root(scene) is not None and not model_file(settings).lower().endswith(".urdf"):
        return ("options.model_file: a floating base is mapped from a URDF's root link only — give the robot's .urdf "
                "(an MJCF's own free joints are not mapped)")
    if any(j.kind == "ball" for j in scene.joints):
        return ("options.model_file: the scene has ball joints, whose engine coordinates are not mapped here (hinge "
                "and slide joints are) — run a robot of revolute and prismatic joints, or drop the option")
    if scene.loops or scene.springs or scene.contacts or scene.loads:
        return ("options.model_file: the scene has loops, springs, loads or contact beyond the file's tree — "
                "model_file runs robot scenes read from a file only; drop the option")
    return None


def free_root(scene):
    """The scene's free joint (its floating base), or None."""
    return next((j for j in scene.joints if j.kind == "free"), None)


def base_initial(joint, c_E):
    """The engine's root frame E at the scene's initial state: ``joint`` the scene's free joint (its body frame B at
    the COM, E's axes), ``c_E`` (3,) B's origin in E (m). Returns ``p_WE`` (3,) m, ``q_WE`` (4,) scalar first,
    ``v_WE_W`` (3,) m/s (E's origin, world axes), ``w_B`` (3,) rad/s (body axes, E's and B's alike)."""
    from dalembert import spatial

    q0, v0 = np.asarray(joint.q0, float), np.asarray(joint.v0, float)
    R = spatial.quat_to_matrix(q0[3:] / np.linalg.norm(q0[3:]))
    r_W = R @ np.asarray(c_E, float)
    return q0[:3] - r_W, q0[3:], v0[:3] - np.cross(R @ v0[3:], r_W), v0[3:]


def base_series(p_WE, q_WE, v_WE_W, w_B, c_E):
    """The scene's free-joint coordinates from the engine's root frame E sampled: ``p_WE`` (n, 3), ``q_WE`` (n, 4)
    scalar first as the engine gave it, ``v_WE_W`` (n, 3), ``w_B`` (n, 3) body axes; ``c_E`` (3,) as in
    ``base_initial``. Returns ``q`` (n, 7) ``(p_WB, q_WB)`` and ``v`` (n, 6) ``(v_WB_W, w_B)``."""
    from dalembert import spatial

    R = spatial.quat_to_matrix(q_WE / np.linalg.norm(q_WE, axis=1, keepdims=True))
    r_W = R @ np.asarray(c_E, float)
    w_W = np.einsum("nij,nj->ni", R, w_B)
    return (np.concatenate([p_WE + r_W, q_WE], axis=1),
            np.concatenate([v_WE_W + np.cross(w_W, r_W), w_B], axis=1))


@dataclass(frozen=True)
class FileJoint:
    """A joint of a URDF as written: ``kind`` (URDF's type), ``parent`` and ``child`` link names."""

    name: str
    kind: str
    parent: str
    child: str


def _root(path):
    try:
        return ET.parse(path).getroot()
    except (ET.ParseError, OSError) as err:
        raise ValueError(f"options.model_file: cannot read {path!r} as XML ({err}) — give the robot's URDF or "
                         "MJCF file") from None


def urdf_joints(path):
    """The joints of a URDF file, in file order: list of ``FileJoint``."""
    root = _root(path)
    out = []
    for el in root.findall("joint"):
        parent, child = el.find("parent"), el.find("child")
        out.append(FileJoint(el.get("name"), el.get("type"), None if parent is None else parent.get("link"),
                             None if child is None else child.get("link")))
    return out


def moving_children(scene):
    """The scene's moving joints by their child body's name (a file's child link): ``{name: Joint}``."""
    return {j.child: j for j in scene.joints if j.kind not in ("weld", "free")}


def locked_joints(scene, joints):
    """The file's moving joints (``FileJoint`` list) that the scene holds at zero: their child link moves on no
    joint of the scene (a locked joint is a weld or a merge there). Names, in file order."""
    moving = moving_children(scene)
    return [j.name for j in joints if j.kind in ("revolute", "continuous", "prismatic") and j.child not in moving]


def bare_urdf(path, locked=()):
    """The URDF's text without ``<visual>`` and ``<collision>`` elements, the joints named in ``locked`` made
    ``fixed``, and no ``<mimic>`` on a fixed joint: what the engines read (module docstring)."""
    root = _root(path)
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for el in link.findall(tag):
                link.remove(el)
    for el in root.findall("joint"):
        if el.get("name") in locked:
            el.set("type", "fixed")
        if el.get("type") == "fixed":  # a fixed joint's <mimic> moves nothing (Drake refuses one: Talos has them)
            for mimic in el.findall("mimic"):
                el.remove(mimic)
    return ET.tostring(root, encoding="unicode")


def scene_subtree_masses(scene):
    """The mass (kg) of the subtree of each scene body, the body included: ``{body name: kg}``."""
    mass = {b.name: b.mass for b in scene.bodies}
    out = dict(mass)
    for body in reversed(scene.topological_order()):
        parent = scene.joint(body.name).parent
        if parent in out:
            out[parent] += out[body.name]
    return out


def check_same_model(scene, path, engine_masses, engine):
    """Raise ValueError naming the option where the engine's model of ``path`` is not the scene's.

    ``engine_masses``: ``{child link name: subtree mass (kg)}`` of each moving joint of the engine's model.
    """
    shown = os.path.basename(path)
    subtree = scene_subtree_masses(scene)
    for child in moving_children(scene):
        if child not in engine_masses:
            raise ValueError(f"options.model_file: {engine} read no joint moving link {child!r} from {shown}, which "
                             "the case's scene moves — give the file the case's scene was read from (its --param "
                             "model)")
        got, want = engine_masses[child], subtree[child]
        if abs(got - want) > MASS_MATCH_REL_TOL * want:
            raise ValueError(f"options.model_file: {engine} read {got:.9g} kg below link {child!r} from {shown}; the "
                             f"case's scene has {want:.9g} kg — give the file the case's scene was read from (its "
                             "--param model)")


def joint_columns(scene):
    """The scene's joints with coordinates in the reference's order (``Kane``: topological, the joints' own): a
    list of their child names (revolute, prismatic and a free base: ``why_not`` refuses the others)."""
    return [b.name for b in scene.topological_order() if scene.joint(b.name).kind not in ("weld",)]


def trajectory(scene, times, q, v):
    """Body terms of the engine's joint coordinates: ``q``, ``v`` dicts child link name -> (n,) arrays (rad or m,
    rad/s or m/s) of each scene joint (a free base's: (n, 7) and (n, 6), ``base_series``), through the scene's
    kinematics (the reference's Kane), reactions left out.

    Returns
    -------
    dalembert.trajectory.Trajectory — bodies, joints; no ``reaction_force`` extras
    """
    from dalembert.reference.generalized import Kane
    from dalembert.trajectory import Trajectory

    system = Kane(scene)
    names = joint_columns(scene)
    Q = np.column_stack([q[n] for n in names]) if names else np.zeros((len(times), 0))
    V = np.column_stack([v[n] for n in names]) if names else np.zeros((len(times), 0))
    full = system.trajectory(np.asarray(times, float), Q, V)
    return Trajectory(full.t, full.bodies, full.joints, {})


@dataclass(frozen=True, eq=False)
class FilePrepared(Prepared):
    """A run of the engine's own reading of a file (``Prepared``). Each engine's ``from_file`` fills it.

    Attributes
    ----------
    path : str — the file the engine read
    engine_model : object — the engine's model of the file (``mujoco.MjModel``, ``pin.Model``, a Drake plant)
    q0 : ndarray (nq,), v0 : ndarray (nv,) — the initial state in the engine's coordinates
    steps : ndarray (n - 1,) of int or None — steps per sample interval (fixed-step integrators)
    locked : tuple of str — the file's joints fixed as the scene holds them
    effects : dict — what the engine read of the file's effects and whether it applies them (the audit's)
    extra : object — the engine's own (its data, its diagram)
    """

    path: str
    engine_model: object
    q0: np.ndarray
    v0: np.ndarray
    steps: np.ndarray | None
    locked: tuple
    effects: dict
    extra: object = None


def effects_summary(values, unit, applied):
    """One line on an effect the engine read: ``{joint: value}`` (0 or None: none) -> ``"damping on 7 of 9 joints,
    0.003 to 0.3 N m s/rad, applied"``."""
    given = {k: v for k, v in values.items() if v and np.isfinite(v)}  # inf: URDF's "no limit"
    if not given:
        return "none"
    lo, hi = min(given.values()), max(given.values())
    span = f"{lo:g}" if lo == hi else f"{lo:g} to {hi:g}"
    return f"{len(given)} of {len(values)} joints, {span} {unit}, {applied}"
