"""Exudyn's part of a standalone reproduction (``dalembert repro``): the kinematic tree as Exudyn's API
calls, the solver settings of the run, the solve, and the joint coordinates at the sample times.

What it writes is ``Adapter.repro``'s contract (``dalembert.adapters.base``). The system is the one
``model.build`` makes for a jointed tree in minimal coordinates (``joints=minimal``): one
``NodeGenericODE2`` and one ``ObjectKinematicTree``, their parameters read back from the assembled
system (``GetNode``, ``GetObject``: the numbers Exudyn holds) and written as the calls that make them.
The settings are the adapter's (``ExudynAdapter._settings``: the fixed step as ``numberOfSteps`` over
the horizon, the Newton tolerances and spectral radius of generalized-alpha); the samples are read as
``sampling.solve`` reads them, from a sensor stored by Exudyn on a schedule that leads the sample
times by ``sampling.SCHEDULE_LEAD`` steps, each at the step that lands on its sample.

The tree's loads (a ``MarkerKinematicTreeRigid`` at the load's point and a ``LoadForceVector`` or
``LoadTorqueVector``) are written from ``GetMarker`` and ``GetLoad`` alike. Not covered, with the reason in the
error: rigid bodies (free bodies, ``joints=redundant``: their attitude is read through Exudyn's rotation
sensors and turned into quaternions, not a coordinate), other objects (loops, springs, contact), and the
adaptive solvers (driven sample by sample through ``MainSolverExplicit.SolveSteps``).
"""

from __future__ import annotations

import numpy as np

from dalembert.adapters.exudyn import sampling
from dalembert.adapters.exudyn.adapter import ADAPTIVE, EXPLICIT, IMPLICIT, newton_tolerances
from dalembert.adapters.exudyn.model import MODEL_OPTIONS, build
from dalembert.adapters.base import option_value

__all__ = ["repro"]


def _matrices(ms):
    """An Exudyn ``Matrix3DList``/``Vector3DList`` as a list literal (indexed: iterating one runs past its end)."""
    return "[" + ", ".join(f"{np.asarray(ms[i], dtype=float).tolist()!r}" for i in range(len(ms))) + "]"


def _loads(mbs, tree):
    """The loads on the tree's links, as the calls that make them (a marker on the link, then the load), or ""."""
    lines = []
    for i in range(mbs.systemData.NumberOfMarkers()):
        m = mbs.GetMarker(i)
        if m["markerType"] != "KinematicTreeRigid" or int(m["objectNumber"]) != int(tree):
            raise ValueError(f"scene: marker {i} is a {m['markerType']} — the repro writes a kinematic tree's "
                             "loads only; no repro for this system")
        HT = np.asarray(m["localHT"], dtype=float)
        lines.append(f"markers.append(mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=tree, linkNumber="
                     f"{int(m['linkNumber'])}, localHT=exu.HT(rotation={HT[:3, :3].tolist()!r}, "
                     f"translation={HT[:3, 3].tolist()!r}))))  # at the load's point, link {int(m['linkNumber'])}'s "
                     "frame (m)")
    for i in range(mbs.systemData.NumberOfLoads()):
        ld = mbs.GetLoad(i)
        kind = {"ForceVector": "LoadForceVector", "TorqueVector": "LoadTorqueVector"}.get(ld["loadType"])
        if kind is None or ld["loadVectorUserFunction"]:
            raise ValueError(f"scene: load {i} is a {ld['loadType']} — the repro writes constant force and torque "
                             "vectors only; no repro for this system")
        unit = "N" if kind == "LoadForceVector" else "N m"
        frame = "in the link's frame, turning with it" if ld["bodyFixed"] else "in world axes"
        lines.append(f"mbs.AddLoad({kind}(markerNumber=markers[{int(ld['markerNumber'])}], loadVector="
                     f"{np.asarray(ld['loadVector'], dtype=float).tolist()!r}, bodyFixed={bool(ld['bodyFixed'])}))"
                     f"  # {unit}, {frame}")
    if not lines:
        return ""
    return "\n    ".join(["markers = []"] + lines)


def repro(adapter, scene, times, settings, quantity):
    """The Exudyn part of a reproduction of a run of ``scene`` sampled at ``times`` with ``settings``: Python
    source defining ``simulate()`` (``Adapter.repro``); ValueError "where: what — fix" where it does not apply."""
    if settings.integrator in ADAPTIVE:
        raise ValueError(f"integrator: {settings.integrator} is driven sample by sample through SolveSteps — no repro "
                         "for the adaptive solvers; reproduce a fixed-step run")
    if quantity != "joint":
        raise ValueError(f"quantity: no Exudyn repro of {quantity!r} — it reproduces the joint coordinates of a "
                         "kinematic tree ('joint'); rigid bodies' attitudes are read through rotation sensors")
    if option_value(MODEL_OPTIONS, settings, "joints") != "minimal":
        raise ValueError("options.joints: redundant joints are rigid bodies held by generic joints — no repro for them; "
                         "reproduce a run with joints=minimal")
    built = build(scene, settings)
    mbs = built.mbs
    if built.tree is None or mbs.systemData.NumberOfObjects() != 1:
        raise ValueError("scene: the repro writes a kinematic tree with its loads; this system has other objects "
                         "(free bodies, loops, springs, contact) — no repro for it")
    loads_src = _loads(mbs, built.tree)
    node, tree = mbs.GetNode(built.tree_node), mbs.GetObject(built.tree)
    times = np.asarray(times, dtype=float)
    dt = float(settings.dt)
    horizon, interval = float(times[-1] - times[0]), float(times[1] - times[0])
    solver = {**IMPLICIT, **EXPLICIT}[settings.integrator]
    lines = [f"s.timeIntegration.numberOfSteps = {int(round(horizon / dt))}  # dt = {dt!r} s"]
    if settings.integrator == "generalized-alpha":
        radius = option_value(adapter.options, settings, "spectral_radius")
        if radius is not None:
            lines.append(f"s.timeIntegration.generalizedAlpha.spectralRadius = {float(radius)!r}")
        rtol, atol = newton_tolerances(scene, settings)
        lines.append(f"s.timeIntegration.newton.relativeTolerance = {rtol!r}")
        lines.append(f"s.timeIntegration.newton.absoluteTolerance = {atol!r}")
    joint_types = ", ".join(f"exu.JointType.{t.name}" for t in tree["jointTypes"])
    names = list(built.links)
    settings_src = "\n    ".join(lines)
    return f'''import exudyn as exu
from exudyn.itemInterface import (LoadForceVector, LoadTorqueVector, MarkerKinematicTreeRigid, NodeGenericODE2,
                                  ObjectKinematicTree, SensorNode)

# The joints' coordinates, one per link, in link order (rad for RevoluteZ, m for PrismaticZ).
NAMES = {names!r}
# Each sample is read at the step that lands on it to within this fraction of a step (Exudyn's accumulated time
# drifts by ulps; the adapter's sampling.ON_TIME).
ON_TIME = {sampling.ON_TIME!r}
# The sensor's write schedule leads the samples by this many steps at the horizon (sampling.SCHEDULE_LEAD).
SCHEDULE_LEAD = {sampling.SCHEDULE_LEAD!r}
DT = {dt!r}  # s


def system():
    """The system: one kinematic tree (each link: its joint frame in the parent link's, the joint's offset there,
    m; its mass, kg, centre of mass, m, and inertia about it, kg m^2, in its own link frame) on one ODE2 node."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
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
    {loads_src}
    sensor = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                      outputVariableType=exu.OutputVariableType.Coordinates))
    mbs.Assemble()
    return SC, mbs, sensor


def simulate():
    """The run: Exudyn's {solver} over the horizon; ``{{name: ndarray (n, 1)}}`` of each joint's coordinate at every
    sample (NaN from the first sample no step landed on)."""
    SC, mbs, sensor = system()
    s = exu.SimulationSettings()
    s.solution.file.write = False
    s.timeIntegration.verboseMode = 0
    s.timeIntegration.startTime = {float(times[0])!r}
    s.timeIntegration.endTime = {float(times[-1])!r}
    s.timeIntegration.automaticStepSize = False
    {settings_src}
    horizon, interval = TIMES[-1] - TIMES[0], TIMES[1] - TIMES[0]
    s.solution.sensors.writePeriod = interval * (1.0 - SCHEDULE_LEAD * DT / horizon)
    exu.config.printToConsole = False
    mbs.SolveDynamic(s, solverType=exu.DynamicSolverType.{solver})
    rows = np.asarray(mbs.GetSensorStoredData(sensor), dtype=float)  # time, then the coordinates
    tol = ON_TIME * DT
    at = np.minimum(np.searchsorted(rows[:, 0], TIMES - tol), len(rows) - 1)
    values = rows[at, 1:]
    values[np.abs(rows[at, 0] - TIMES) > tol] = np.nan
    return {{name: values[:, i:i + 1] for i, name in enumerate(NAMES)}}


ENGINE_VERSION = exu.__version__
'''
