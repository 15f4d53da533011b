"""Minimal reproduction: Exudyn's joint reaction on a rigid body with a Lie-group rotation-vector node
(NodeRigidBodyRotVecLG) misses part of the centripetal force when the body's rotation is not the
identity. Standalone: needs only exudyn and numpy (python exudyn_rotvec_lg_reaction.py).

The set-up has an exact answer. A body (1 kg, inertia 1 kg m^2 about every axis through its centre
of mass) hangs on a ball joint at the world origin, its centre of mass at c = (0.5, 0, 0) m; no
gravity. Its moments about the pivot are (1, 1.25, 1.25) kg m^2, so a spin about any axis through
the pivot normal to c is a steady rotation about a principal axis: the centre of mass runs on a
circle and the joint pulls it inward with exactly m |w|^2 c, i.e. -(m |w|^2 |c|, 0, 0) N on the body
at t = 0. The body starts turned by an angle `tilt` about c (which leaves c where it is) and spins at
w = (0, 0, 3) rad/s in world axes.

With Euler-parameter nodes Exudyn reports that reaction to ~1e-15 relative. With rotation-vector
Lie-group nodes (the default of CreateRigidBody) the reported force (ForceLocal of an
ObjectJointGeneric with constrainedAxes [1,1,1,0,0,0]) misses the fraction 1 - sin(tilt)/tilt of
it (0.080 at tilt = 0.7 rad, 0.020 at 0.35, 0 at 0), with TrapezoidalIndex2 and GeneralizedAlpha
alike and whatever the step, while the motion itself is right: the centre of mass is where the
steady rotation puts it (printed). Measured with Exudyn 1.13.6.
"""

import exudyn as exu
import numpy as np
from exudyn.itemInterface import MarkerBodyRigid, ObjectGround, ObjectJointGeneric, SensorBody, SensorObject
from exudyn.rigidBodyUtilities import RigidBodyInertia, RotationMatrixX

MASS, RADIUS, W = 1.0, 0.5, np.array([0.0, 0.0, 3.0])
EXACT = -MASS * (W @ W) * RADIUS  # N, x component of the force on the body


def reaction(node_type, tilt, solver, dt=1e-3, t_end=0.01):
    """The joint force ON the body (world axes, N) at t = 0, its magnitude at t_end, and how far the centre of
    mass is from where the steady rotation puts it at t_end (m)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    body = mbs.CreateRigidBody(inertia=RigidBodyInertia(MASS, np.eye(3), [0.0, 0.0, 0.0], True),
                               referencePosition=[RADIUS, 0.0, 0.0], referenceRotationMatrix=RotationMatrixX(tilt),
                               initialVelocity=list(np.cross(W, [RADIUS, 0.0, 0.0])), initialAngularVelocity=list(W),
                               nodeType=node_type, returnDict=True)["bodyNumber"]
    ground = mbs.AddObject(ObjectGround())
    m0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    # the pivot in the body's own axes: -c turned back by the tilt (c is along the tilt axis: unchanged)
    m1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[-RADIUS, 0.0, 0.0]))
    joint = mbs.AddObject(ObjectJointGeneric(markerNumbers=[m0, m1], constrainedAxes=[1, 1, 1, 0, 0, 0]))
    sensor = mbs.AddSensor(SensorObject(objectNumber=joint, storeInternal=True,
                                        outputVariableType=exu.OutputVariableType.ForceLocal))
    com = mbs.AddSensor(SensorBody(bodyNumber=body, storeInternal=True,
                                   outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.solution.file.write = False
    s.solution.sensors.writePeriod = dt
    s.timeIntegration.numberOfSteps = int(round(t_end / dt))
    s.timeIntegration.endTime = t_end
    s.timeIntegration.verboseMode = 0
    s.timeIntegration.newton.relativeTolerance = 1e-12
    s.timeIntegration.newton.absoluteTolerance = 1e-14
    exu.config.printToConsole = False
    mbs.SolveDynamic(s, solverType=solver)
    rows = np.asarray(mbs.GetSensorStoredData(sensor))
    # ForceLocal: the force on the marker-0 (ground) side in marker 0's frame (the world's) -> ON the body: minus
    p = np.asarray(mbs.GetSensorStoredData(com))[-1, 1:4]
    angle = W[2] * t_end  # the steady rotation about z
    miss = float(np.linalg.norm(p - RADIUS * np.array([np.cos(angle), np.sin(angle), 0.0])))
    return -rows[0, 1:4], float(np.linalg.norm(rows[-1, 1:4])), miss


if __name__ == "__main__":
    print(f"exudyn {exu.__version__}; exact force on the body: ({EXACT:.15g}, 0, 0) N at all times")
    for solver in (exu.DynamicSolverType.TrapezoidalIndex2, exu.DynamicSolverType.GeneralizedAlpha):
        for tilt in (0.0, 0.35, 0.7):
            for node in (exu.NodeType.RotationEulerParameters, exu.NodeType.RotationRotationVector):
                start, end, miss = reaction(node, tilt, solver)
                print(f"{solver.name:18s} tilt {tilt:4.2f} rad  {node.name:25s}  F_x(0) = {start[0]:.15g}  "
                      f"relative error {start[0] / EXACT - 1:+.3e}   (1 - sin(tilt)/tilt = "
                      f"{1 - (np.sin(tilt) / tilt if tilt else 1):.3e});  |F|(0.01 s) = {end:.12g};  "
                      f"COM off by {miss:.1e} m")
