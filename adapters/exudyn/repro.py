"""Exudyn's part of a standalone reproduction (``dalembert repro``): the system as Exudyn's API calls, the
solver settings of the run, the solve, and the headline quantity read from sensors at the sample times.

What it writes is ``Adapter.repro``'s contract (``dalembert.adapters.base``), for the systems ``model.build``
makes of

* a jointed tree in minimal coordinates (``joints=minimal``; the quantity: its joint coordinates): one
  ``NodeGenericODE2`` and one ``ObjectKinematicTree``, their parameters read back from the assembled system
  (``GetNode``, ``GetObject``: the numbers Exudyn holds) and written as the calls that make them;
* rigid bodies, free or held by generic joints (``joints=redundant``; the quantity: their orientations):
  ``CreateRigidBody`` with the arguments the adapter passes, the ground, each joint's two markers and its
  ``ObjectJointGeneric`` (from ``GetMarker``, ``GetObject``), each body's ``RotationMatrix`` sensor turned into
  quaternions as the read-back turns it;

each with its loads (a marker at the load's point, a ``LoadForceVector`` or ``LoadTorqueVector``, from
``GetMarker`` and ``GetLoad``). The settings are the adapter's (``ExudynAdapter._settings``: the fixed step as
``numberOfSteps`` over the horizon, generalized-alpha's Newton tolerances and spectral radius; an adaptive
solver's tolerances, initial and minimum steps); the samples are read as ``sampling.solve`` reads them, from
sensors Exudyn stores: a fixed-step solve on a schedule that leads the sample times by
``sampling.SCHEDULE_LEAD`` steps, each read at the step that lands on its sample; an adaptive one driven as
``sampling.solve_per_sample`` drives it, one ``MainSolverExplicit.SolveSteps`` per sample interval, ending on
the sample.

Not covered, with the reason in the error: the joint coordinates of rigid bodies held by generic joints (read
back from both bodies' states through the joint frames, ``spatial.joint_coordinates``), a tree's links'
attitudes, and systems with other objects (a tree's loops, springs, distance loops, contact).
"""

from __future__ import annotations

import numpy as np

from dalembert.adapters.exudyn import sampling
from dalembert.adapters.exudyn.adapter import ADAPTIVE, EXPLICIT, IMPLICIT, newton_tolerances
from dalembert.adapters.exudyn.model import MODEL_OPTIONS, NODES, build
from dalembert.adapters.base import option_value
from dalembert.scene import WORLD

__all__ = ["repro"]


def _matrices(ms):
    """An Exudyn ``Matrix3DList``/``Vector3DList`` as a list literal (indexed: iterating one runs past its end)."""
    return "[" + ", ".join(f"{np.asarray(ms[i], dtype=float).tolist()!r}" for i in range(len(ms))) + "]"


def _connections(mbs, owners):
    """The markers, the generic joints between them and the loads, as the calls that make them, or "".

    ``owners``: object number -> the script's expression for it (``tree``, ``bodies['top']``, ``ground``)."""
    lines = []
    made = set()  # the markers and loads ``CreateRigidBody`` makes itself (gravity: a BodyMass marker, its load)
    for i in range(mbs.systemData.NumberOfMarkers()):
        m = mbs.GetMarker(i)
        if m["markerType"] == "BodyMass" and int(m["bodyNumber"]) in owners:
            made.add(i)
            continue
        HT = np.asarray(m["localHT"], dtype=float)
        at = f"localHT=exu.HT(rotation={HT[:3, :3].tolist()!r}, translation={HT[:3, 3].tolist()!r})"
        if m["markerType"] == "KinematicTreeRigid" and int(m["objectNumber"]) in owners:
            lines.append(f"markers[{i}] = mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber="
                         f"{owners[int(m['objectNumber'])]}, linkNumber={int(m['linkNumber'])}, {at}))  "
                         f"# the load's point in link {int(m['linkNumber'])}'s frame, m")
        elif m["markerType"] == "BodyRigid" and int(m["bodyNumber"]) in owners:
            lines.append(f"markers[{i}] = mbs.AddMarker(MarkerBodyRigid(bodyNumber={owners[int(m['bodyNumber'])]}, "
                         f"{at}))  # a frame in the body's (a joint's, a load's point), m")
        else:
            raise ValueError(f"scene: marker {i} is a {m['markerType']} marker on another object — the repro writes "
                             "markers on a kinematic tree, rigid bodies and the ground only; no repro for this system")
    for i in range(mbs.systemData.NumberOfObjects()):
        o = mbs.GetObject(i)
        if i in owners:  # a body, the tree or a ground, made before
            continue
        if (o["objectType"] != "JointGeneric" or o["offsetUserFunction"] or not o["activeConnector"]
                or o["alternativeConstraints"]
                or any(not np.array_equal(o[k], np.eye(3)) for k in ("rotationMarker0", "rotationMarker1"))):
            raise ValueError(f"scene: object {i} is a {o['objectType']} — the repro writes rigid bodies held by "
                             "generic joints only (no springs, distance loops or contact); no repro for this system")
        a, b = (int(m) for m in o["markerNumbers"])
        lines.append(f"mbs.AddObject(ObjectJointGeneric(markerNumbers=[markers[{a}], markers[{b}]], "
                     f"constrainedAxes={list(map(int, o['constrainedAxes']))!r}))  # 1: a constrained axis "
                     "(translations x, y, z, rotations x, y, z of marker 0's frame)")
    for i in range(mbs.systemData.NumberOfLoads()):
        ld = mbs.GetLoad(i)
        if ld["loadType"] == "MassProportional" and int(ld["markerNumber"]) in made:
            continue
        kind = {"ForceVector": "LoadForceVector", "TorqueVector": "LoadTorqueVector"}.get(ld["loadType"])
        if kind is None or ld["loadVectorUserFunction"]:
            raise ValueError(f"scene: load {i} is a {ld['loadType']} — the repro writes constant force and torque "
                             "vectors only; no repro for this system")
        unit = "N" if kind == "LoadForceVector" else "N m"
        frame = "in the body's frame, turning with it" if ld["bodyFixed"] else "in world axes"
        lines.append(f"mbs.AddLoad({kind}(markerNumber=markers[{int(ld['markerNumber'])}], loadVector="
                     f"{np.asarray(ld['loadVector'], dtype=float).tolist()!r}, bodyFixed={bool(ld['bodyFixed'])}))"
                     f"  # {unit}, {frame}")
    if not lines:
        return ""
    return "\n    ".join(["markers = {}  # by Exudyn's marker number"] + lines) + "\n    "


def _tree(built):
    """A kinematic tree's system, sensor and read-out, as source: (what is read, the calls, the read-out)."""
    mbs = built.mbs
    if mbs.systemData.NumberOfObjects() != 1:
        raise ValueError("scene: the repro writes a kinematic tree with its loads; this system has other objects "
                         "(loops, springs, contact) — no repro for it")
    node, tree = mbs.GetNode(built.tree_node), mbs.GetObject(built.tree)
    joint_types = ", ".join(f"exu.JointType.{t.name}" for t in tree["jointTypes"])
    calls = f"""# One kinematic tree (each link: its joint frame in the parent link's and the joint's offset there, m; its
    # mass, kg, centre of mass, m, and inertia about it, kg m^2, in its own link frame) on one ODE2 node.
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates={np.asarray(node["referenceCoordinates"]).tolist()!r},
                                       initialCoordinates={np.asarray(node["initialCoordinates"]).tolist()!r},
                                       initialCoordinates_t={np.asarray(node["initialCoordinates_t"]).tolist()!r},
                                       numberOfODE2Coordinates={int(node["numberOfODE2Coordinates"])}))
    tree = mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=[{joint_types}], linkParents={list(tree["linkParents"])!r},
        jointTransformations=exu.Matrix3DList({_matrices(tree["jointTransformations"])}),
        jointOffsets=exu.Vector3DList({_matrices(tree["jointOffsets"])}),
        linkInertiasCOM=exu.Matrix3DList({_matrices(tree["linkInertiasCOM"])}),
        linkCOMs=exu.Vector3DList({_matrices(tree["linkCOMs"])}),
        linkMasses={np.asarray(tree["linkMasses"], dtype=float).tolist()!r},
        baseOffset={np.asarray(tree["baseOffset"], dtype=float).tolist()!r},
        gravity={np.asarray(tree["gravity"], dtype=float).tolist()!r}))  # m/s^2, world
    {_connections(mbs, {int(built.tree): "tree"})}sensors = {{"q": mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                            outputVariableType=exu.OutputVariableType.Coordinates))}}"""
    read = "{name: values['q'][:, i:i + 1] for i, name in enumerate(NAMES)}"
    return "the joints' coordinates, one per link, in link order (rad for RevoluteZ, m for PrismaticZ)", calls, read


def _rigid(scene, built, settings):
    """Rigid bodies' system (free, or held by generic joints: ``joints=redundant``), sensors and read-out, as
    source: (what is read, the calls, the read-out)."""
    from dalembert import spatial

    mbs = built.mbs
    node = NODES[option_value(MODEL_OPTIONS, settings, "node")]
    g = np.array(scene.gravity, dtype=float)
    state0 = spatial.initial_body_states(scene)
    lines = ["# Each body (``CreateRigidBody`` as the adapter calls it): mass, kg, and inertia about its centre of mass,",
             "# kg m^2, in its own axes; its initial pose and velocity in world axes (m, m/s, rad/s).",
             "bodies = {}"]
    owners = {}
    for obj, name in built.owners.items():
        if name == WORLD:
            continue
        body, s0 = scene.body(name), state0[name]
        gravity = f", gravity={g.tolist()!r}" if np.any(g) else ""  # (Exudyn adds none by default)
        lines.append(
            f"bodies[{name!r}] = mbs.CreateRigidBody(inertia=RigidBodyInertia({body.mass!r}, "
            f"np.array({np.asarray(body.inertia_matrix).tolist()!r}), [0.0, 0.0, 0.0], True), "
            f"referencePosition={list(map(float, s0['p']))!r}, referenceRotationMatrix=np.array("
            f"{np.asarray(s0['R']).tolist()!r}), initialVelocity={list(map(float, s0['v']))!r}, "
            f"initialAngularVelocity={list(map(float, s0['w']))!r}, nodeType=exu.NodeType.{node}{gravity}, "
            "returnDict=True)['bodyNumber']")
        owners[int(obj)] = f"bodies[{name!r}]"
    grounds = [int(obj) for obj, name in built.owners.items() if name == WORLD]
    for obj in grounds:
        o = mbs.GetObject(obj)
        if np.any(o["referencePosition"]) or not np.array_equal(o["referenceRotation"], np.eye(3)):
            raise ValueError(f"scene: ground {obj} is placed off the world's origin — no repro for this system")
        lines.append("ground = mbs.AddObject(ObjectGround())  # the world, for the joints' and loads' ends on it")
        owners[obj] = "ground"
    calls = "\n    ".join(lines) + "\n    " + _connections(mbs, owners) + (
        "sensors = {name: mbs.AddSensor(SensorBody(bodyNumber=body, storeInternal=True,\n"
        "                                          outputVariableType=exu.OutputVariableType.RotationMatrix))\n"
        "           for name, body in bodies.items()}")
    # the read-back's R_WB = R_WE R_EB, with E = B for a rigid body (R_EB the identity), row-major sensor output
    read = "{name: values[name].reshape(len(TIMES), 3, 3) @ np.eye(3) for name in NAMES}"
    return "each body's R_WB from its RotationMatrix sensor (world axes, row-major)", calls, read


def repro(adapter, scene, times, settings, quantity):
    """The Exudyn part of a reproduction of a run of ``scene`` sampled at ``times`` with ``settings``: Python
    source defining ``simulate()`` (``Adapter.repro``); ValueError "where: what — fix" where it does not apply."""
    rigid = (all(j.kind == "free" for j in scene.joints)
             or option_value(MODEL_OPTIONS, settings, "joints") == "redundant")  # every body a rigid body
    if quantity == "orientation" and not rigid:
        raise ValueError("quantity: the orientation of a kinematic tree's links — no Exudyn repro for it (their "
                         "attitudes are read through the tree's sensors); it reproduces rigid bodies' orientations and "
                         "a kinematic tree's joints")
    if quantity == "joint" and option_value(MODEL_OPTIONS, settings, "joints") != "minimal":
        raise ValueError("options.joints: redundant joints' coordinates are read back from rigid bodies held by "
                         "generic joints — no repro for them; reproduce a run with joints=minimal")
    if quantity not in ("joint", "orientation"):
        raise ValueError(f"quantity: no Exudyn repro of {quantity!r} — it reproduces 'joint' and 'orientation'")
    built = build(scene, settings)
    if quantity == "joint":
        what, calls, read = _tree(built)
        names = list(built.links)
    else:
        what, calls, read = _rigid(scene, built, settings)
        names = [name for name in built.owners.values() if name != WORLD]
    times = np.asarray(times, dtype=float)
    horizon, interval = float(times[-1] - times[0]), float(times[1] - times[0])
    solver = {**IMPLICIT, **EXPLICIT}[settings.integrator]
    adaptive = settings.integrator in ADAPTIVE
    if adaptive:  # ExudynAdapter._settings, sampling.solve: one SolveSteps per sample interval, ending on the sample
        rtol, atol = float(settings.rtol), float(settings.atol if settings.atol is not None else settings.rtol)
        lines = ["s.timeIntegration.automaticStepSize = True",
                 f"s.timeIntegration.relativeTolerance = {rtol!r}",
                 f"s.timeIntegration.absoluteTolerance = {atol!r}",
                 "s.timeIntegration.numberOfSteps = 1  # Exudyn's largest step = horizon / numberOfSteps: the samples "
                 "cap it",
                 f"s.timeIntegration.initialStepSize = {interval!r}  # s, the sample interval",
                 f"s.timeIntegration.minimumStepSize = MIN_STEP  # s",
                 "s.solution.sensors.writePeriod = 2.0 * (TIMES[-1] - TIMES[0])  # beyond the horizon: written where "
                 "each SolveSteps ends only"]
        step = f"MIN_STEP = {sampling.MIN_STEP_FRACTION * interval!r}  # s, the smallest step (sampling.MIN_STEP_FRACTION of the interval)"
        solve = """solver = exu.MainSolverExplicit()
    solver.InitializeSolver(mbs, s)
    try:
        for k in range(1, len(TIMES)):  # no dense output: each sample is where a SolveSteps ends
            solver.it.endTime = float(TIMES[k])
            solver.SolveSteps(mbs, s)
            if solver.it.currentTime < TIMES[k] - TOL:
                break  # the solver gave up (its step below the minimum)
    finally:
        solver.FinalizeSolver(mbs, s)"""
        tol = "TOL = ON_TIME * MIN_STEP  # s"
    else:
        dt = float(settings.dt)
        lines = ["s.timeIntegration.automaticStepSize = False",
                 f"s.timeIntegration.numberOfSteps = {int(round(horizon / dt))}  # dt = {dt!r} s",
                 "s.solution.sensors.writePeriod = (TIMES[1] - TIMES[0]) * (1.0 - SCHEDULE_LEAD * DT / (TIMES[-1] - "
                 "TIMES[0]))"]
        step = f"DT = {dt!r}  # s"
        solve = f"mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.{solver})"
        tol = "TOL = ON_TIME * DT  # s"
    if settings.integrator == "generalized-alpha":
        radius = option_value(adapter.options, settings, "spectral_radius")
        if radius is not None:
            lines.append(f"s.timeIntegration.generalizedAlpha.spectralRadius = {float(radius)!r}")
        rtol, atol = newton_tolerances(scene, settings)
        lines.append(f"s.timeIntegration.newton.relativeTolerance = {rtol!r}")
        lines.append(f"s.timeIntegration.newton.absoluteTolerance = {atol!r}")
    settings_src = "\n    ".join(lines)
    return f'''import exudyn as exu
from exudyn.itemInterface import (LoadForceVector, LoadTorqueVector, MarkerBodyRigid, MarkerKinematicTreeRigid,
                                  NodeGenericODE2, ObjectGround, ObjectJointGeneric, ObjectKinematicTree, SensorBody,
                                  SensorNode)
from exudyn.rigidBodyUtilities import RigidBodyInertia

# Read for each of these: {what}.
NAMES = {names!r}
# Each sample is read at the step that lands on it to within this fraction of a step (Exudyn's accumulated time
# drifts by ulps; the adapter's sampling.ON_TIME).
ON_TIME = {sampling.ON_TIME!r}
# The sensors' write schedule leads the samples by this many steps at the horizon (sampling.SCHEDULE_LEAD).
SCHEDULE_LEAD = {sampling.SCHEDULE_LEAD!r}
{step}
{tol}


def system():
    """The system, assembled, and its sensors (name -> sensor number), stored in memory."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    {calls}
    mbs.Assemble()
    return SC, mbs, sensors


def simulate():
    """The run: Exudyn's {solver} over the horizon; ``{{name: ndarray (n, ...)}}`` read at every sample (NaN from
    the first sample no step landed on)."""
    SC, mbs, sensors = system()
    s = exu.SimulationSettings()
    s.solution.file.write = False
    s.timeIntegration.verboseMode = 0
    s.timeIntegration.startTime = {float(times[0])!r}
    s.timeIntegration.endTime = {float(times[-1])!r}
    s.timeIntegration.solverType = exu.DynamicSolverType.{solver}
    {settings_src}
    exu.config.printToConsole = False
    {solve}
    values = {{}}
    for name, sensor in sensors.items():
        rows = np.asarray(mbs.GetSensorStoredData(sensor), dtype=float)  # time, then the sensor's values
        at = np.minimum(np.searchsorted(rows[:, 0], TIMES - TOL), len(rows) - 1)
        values[name] = rows[at, 1:]
        values[name][np.abs(rows[at, 0] - TIMES) > TOL] = np.nan
    return {read}


ENGINE_VERSION = exu.__version__
'''
