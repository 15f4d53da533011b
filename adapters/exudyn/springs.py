"""Spring-dampers (``Scene.springs``) as Exudyn connectors: ``add_springs`` builds them, ``read_springs``
reads them back from the system that ran, ``passive_effects`` lists every passive force element it carries.

Each spring is one ``ObjectConnectorSpringDamper`` from a marker at ``point_a`` on body a (marker 0) to one
at ``point_b`` on body b (marker 1): ``MarkerBodyRigid`` on a rigid body or the ground,
``MarkerKinematicTreeRigid`` on a kinematic-tree link (the connector asks for a position marker; both
rigid markers are ones). Exudyn's connector (its documentation, and checked by experiment: a box at
``(0, 0, -1.3)`` m moving at ``-0.5`` m/s on a spring ``k = 50`` N/m, ``c = 2`` N s/m, ``l0 = 1`` m from
the origin reports the force ``(0, 0, -16)`` N and accelerates the box by ``+8`` m/s^2 up) has the tension
``k (L - L0) + c L'`` with ``L`` the distance from marker 0 to marker 1, its ``Force`` output is the tension
times the unit vector from marker 0 to marker 1, which is the force on marker 0, and marker 1 gets its
opposite: ``dalembert.springs``'s convention with a = marker 0, b = marker 1. Its other terms (the constant
``force``, the ``velocityOffset``, a ``springForceUserFunction``) are left at zero and read back as zero.
"""

from __future__ import annotations

import numpy as np

from dalembert import springs as spring_forces
from dalembert.adapters.exudyn.compat import marker_point
from dalembert.adapters.exudyn.contact import ELEMENTS as CONTACT_ELEMENTS
from dalembert.scene import WORLD

__all__ = ["ELEMENT", "POINT_TOL", "OBJECTS", "add_springs", "read_springs", "passive_effects", "unexpected_passive"]

ELEMENT = "ObjectConnectorSpringDamper"
# A point read back from Exudyn (its marker's local frame, or its world position at the initial state) against
# the scene's: the same point through two chains of double-precision rotations on levers below a few metres,
# ~1e-16 m each; a wrong point, body or frame is off by the lever itself.
POINT_TOL = 1e-12
# The object types ``model.build`` makes: bodies, grounds, the kinematic tree, the constraints of joints and
# loops (no force but their reactions), and the springs' connectors. Any other would be an effect the scene
# does not have.
OBJECTS = ("ObjectRigidBody", "ObjectGround", "ObjectKinematicTree", "ObjectJointGeneric", "ObjectConnectorDistance",
           ELEMENT)


def add_springs(mbs, scene, markers, sensors):
    """One ``ObjectConnectorSpringDamper`` per spring of ``scene`` in ``mbs``, with a sensor of its force.

    Parameters
    ----------
    mbs : exudyn.MainSystem, not yet assembled
    scene : Scene
    markers : dict body name (``WORLD`` included) -> callable ``(p, R=...)`` adding a rigid marker at the
        scene point ``p`` (m, body frame) of that body and returning its number
    sensors : dict — gets ``__spring:<name>`` -> ``{"f": sensor}``: Exudyn's ``Force`` of the connector, the
        force on body a's point (N, world, (3,))

    Returns
    -------
    dict spring name -> dict ``object`` (its object number), ``markers`` ([marker 0, marker 1]);
    and the summary lines
    """
    import exudyn as exu
    from exudyn.itemInterface import ObjectConnectorSpringDamper, SensorObject

    built, summary = {}, []
    for sp in scene.springs:
        m0, m1 = markers[sp.body_a](sp.point_a), markers[sp.body_b](sp.point_b)
        obj = mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[m0, m1], referenceLength=sp.rest_length,
                                                        stiffness=sp.stiffness, damping=sp.damping))
        sensors[f"__spring:{sp.name}"] = {"f": mbs.AddSensor(SensorObject(
            objectNumber=obj, outputVariableType=exu.OutputVariableType.Force))}
        built[sp.name] = dict(object=obj, markers=[m0, m1])
        summary.append(f"{ELEMENT} {sp.body_a} -> {sp.body_b} (spring {sp.name!r}), stiffness {sp.stiffness:g} N/m, "
                       f"damping {sp.damping:g} N s/m, referenceLength {sp.rest_length:g} m")
    return built, summary


def read_springs(mbs, scene, built):
    """Each spring as the system ``mbs`` holds it, against the scene: what ``audit`` reports.

    Everything is read from Exudyn: the connector's type and parameters (``GetObject``), its markers'
    bodies and local points (``GetMarker``, turned back into the scene's body frames), their world positions
    and the connector's length and force (``GetMarkerOutput``, ``GetObjectOutput``) in the current
    configuration, which must be the initial state: called by ``model.build`` right after ``Assemble``
    (Exudyn gives a connector's output in its current configuration only). The scene enters only as what
    they are compared with.

    Parameters
    ----------
    mbs : exudyn.MainSystem, assembled, not yet solved
    scene : Scene
    built : dict — what ``model.build`` returned for ``mbs`` (``springs``, ``owners``, ``links``, ``X_EB``)

    Returns
    -------
    dict spring name -> dict: ``element``, ``body_a``, ``body_b``, ``point_a``, ``point_b`` (m, body frames),
    ``stiffness`` (N/m), ``damping`` (N s/m), ``rest_length`` (m), ``preload`` (N), ``velocity_offset`` (m/s),
    ``user_function``, ``active``, ``initial_length`` (m), ``initial_tension`` (N, > 0 pulls), and ``mismatches``: each
    way the engine's spring differs from the scene's (empty: the spring is the scene's)
    """
    import exudyn as exu

    from dalembert import closure, spatial

    OV, current = exu.OutputVariableType, exu.ConfigurationType.Current
    states = {**spatial.initial_body_states(scene), WORLD: closure.world_state()}
    out = {}
    for sp in scene.springs:
        number = built.springs[sp.name]["object"]
        obj = mbs.GetObject(number)
        m0, m1 = obj["markerNumbers"]  # the connector's own markers, as Exudyn holds them
        ends = [_marker_end(mbs, m, built) for m in (m0, m1)]
        length = float(mbs.GetObjectOutput(number, OV.Distance, configuration=current))
        force_a = np.asarray(mbs.GetObjectOutput(number, OV.Force, configuration=current), dtype=float)
        d = np.asarray(mbs.GetObjectOutput(number, OV.Displacement, configuration=current), dtype=float)
        got = dict(element=f"Object{obj['objectType']}", body_a=ends[0][0], body_b=ends[1][0],
                   point_a=ends[0][1].tolist(), point_b=ends[1][1].tolist(), stiffness=float(obj["stiffness"]),
                   damping=float(obj["damping"]), rest_length=float(obj["referenceLength"]),
                   preload=float(obj["force"]), velocity_offset=float(obj["velocityOffset"]),
                   user_function=obj["springForceUserFunction"] != 0, active=bool(obj["activeConnector"]),
                   initial_length=length, initial_tension=float(force_a @ d) / length)
        want = spring_forces.state(sp, states[sp.body_a], states[sp.body_b])
        mismatches = []
        for key, value in (("element", ELEMENT), ("body_a", sp.body_a), ("body_b", sp.body_b),
                           ("stiffness", sp.stiffness), ("damping", sp.damping), ("rest_length", sp.rest_length),
                           ("preload", 0.0), ("velocity_offset", 0.0), ("user_function", False), ("active", True)):
            if got[key] != value:
                mismatches.append(f"{key}: engine {got[key]!r}, scene {value!r}")
        for key, m, body, point in (("point_a", m0, sp.body_a, sp.point_a), ("point_b", m1, sp.body_b, sp.point_b)):
            p_W = np.asarray(mbs.GetMarkerOutput(m, OV.Position, configuration=current), dtype=float)
            p_W_scene = states[body]["p"] + states[body]["R"] @ np.asarray(point, dtype=float)
            if np.abs(np.asarray(got[key]) - point).max() > POINT_TOL:
                mismatches.append(f"{key}: engine {got[key]}, scene {list(point)} (m, body frame)")
            if np.abs(p_W - p_W_scene).max() > POINT_TOL:
                mismatches.append(f"{key} at t = 0: engine {p_W.tolist()}, scene {p_W_scene.tolist()} (m, world)")
        if abs(length - want.length) > POINT_TOL:
            mismatches.append(f"initial_length: engine {length!r}, scene {want.length!r} (m)")
        # a length or rate off by POINT_TOL (m, m/s) moves the tension by stiffness or damping times it
        if abs(got["initial_tension"] - want.tension) > (sp.stiffness + sp.damping) * POINT_TOL:
            mismatches.append(f"initial_tension: engine {got['initial_tension']!r}, scene {want.tension!r} (N)")
        got["mismatches"] = mismatches
        out[sp.name] = got
    return out


def passive_effects(mbs):
    """Every element of ``mbs`` that could exert a passive force, read from Exudyn: object and load types by
    count, and each kinematic tree's joint springs and dampers (its PD control: ``jointPControlVector``,
    ``jointDControlVector``), joint forces and link forces and torques, and user functions.

    Returns
    -------
    dict: ``objects`` (object type -> count), ``loads`` (load type -> count), ``tree_joint_stiffness``,
    ``tree_joint_damping``, ``tree_joint_forces`` (the largest magnitudes, 0.0 when none), ``tree_link_loads``
    (count), ``user_functions`` (the objects that carry one, by number)
    """
    objects, tree = {}, dict(tree_joint_stiffness=0.0, tree_joint_damping=0.0, tree_joint_forces=0.0,
                             tree_link_loads=0)
    user = []
    for i in range(mbs.systemData.NumberOfObjects()):
        obj = mbs.GetObject(i)
        kind = f"Object{obj['objectType']}"
        objects[kind] = objects.get(kind, 0) + 1
        if any(k.endswith("UserFunction") and v != 0 for k, v in obj.items()):
            user.append(i)
        if obj["objectType"] == "KinematicTree":
            for key, field in (("tree_joint_stiffness", "jointPControlVector"),
                               ("tree_joint_damping", "jointDControlVector"),
                               ("tree_joint_forces", "jointForceVector")):
                tree[key] = max(tree[key], float(np.abs(np.asarray(obj[field], dtype=float)).max(initial=0.0)))
            tree["tree_link_loads"] += len(obj["linkForces"]) + len(obj["linkTorques"])
    loads = {}
    for i in range(mbs.systemData.NumberOfLoads()):
        kind = f"Load{mbs.GetLoad(i)['loadType']}"
        loads[kind] = loads.get(kind, 0) + 1
    return dict(objects=dict(sorted(objects.items())), loads=dict(sorted(loads.items())), **tree, user_functions=user)


def unexpected_passive(passive, scene, rigid_bodies):
    """What ``passive`` (``passive_effects``) holds beyond ``scene``'s own forces, one line each (empty: nothing):
    a connector that is no spring of the scene, a load that is none of its loads nor the gravity of one of the
    ``rigid_bodies`` (their number: ``CreateRigidBody`` gives each a ``LoadMassProportional`` when there is
    gravity; the kinematic tree carries its own), an object type ``build`` does not make, a joint spring,
    damper or force or a link load in the kinematic tree, a user function."""
    found = [f"{n} {ELEMENT}(s) for {len(scene.springs)} spring(s)"
             for n in [passive["objects"].get(ELEMENT, 0)] if n != len(scene.springs)]
    want = {"LoadForceVector": sum(ld.kind == "force" for ld in scene.loads),
            "LoadTorqueVector": sum(ld.kind == "torque" for ld in scene.loads),
            "LoadMassProportional": rigid_bodies if any(scene.gravity) else 0}
    found += [f"{n} {kind}(s) for {want.get(kind, 0)}" for kind, n in passive["loads"].items() if n != want.get(kind, 0)]
    found += [f"0 {kind}(s) for {n}" for kind, n in want.items() if n and kind not in passive["loads"]]
    contacts = sum(passive["objects"].get(kind, 0) for kind in CONTACT_ELEMENTS)
    found += [f"{contacts} contact connector(s) for {len(scene.contacts)} contact pair(s)"] if contacts != len(
        scene.contacts) else []
    found += [f"{n} {kind}(s): not made by build" for kind, n in passive["objects"].items()
              if kind not in OBJECTS + CONTACT_ELEMENTS]
    found += [f"{k} {passive[k]!r}" for k in ("tree_joint_stiffness", "tree_joint_damping", "tree_joint_forces",
                                                "tree_link_loads") if passive[k]]
    found += [f"user functions on objects {passive['user_functions']}"] if passive["user_functions"] else []
    return found


def _marker_end(mbs, number, built):
    """The scene body a marker sits on and its point in that body's scene frame (m, (3,))."""
    marker = mbs.GetMarker(number)
    p_E = marker_point(marker)
    if marker["markerType"] == "KinematicTreeRigid":
        name = built.links[marker["linkNumber"]]
        p_EB, R_EB = built.X_EB[name]  # x_E = p_EB + R_EB x_B
        return name, R_EB.T @ (p_E - p_EB)
    return built.owners[int(marker["bodyNumber"])], p_E  # a rigid body's E is B; the ground's is the world

