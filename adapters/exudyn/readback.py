"""Exudyn's sampled sensors in body terms: poses, velocities, joint coordinates and reactions.

Once per run, after solving (never timed). Each body's pose and velocity come from
its sensors (a rigid body's frame is B; a kinematic tree's link frame E is turned
into B with ``X_EB``, ``model.build``). Joint coordinates: the tree's own (minimal
coordinates), or from the bodies' states (redundant ones, ``spatial.joint_coordinates``).
Reactions: Newton's law per link from the links' acceleration sensors (minimal
coordinates; ``link_accelerations`` evaluates them again where the solver keeps none
of the sampled state), each ObjectJointGeneric's ForceLocal (redundant ones), and
each loop's constraint force (``loop_forces``); each contact pair's connector force (``contact_force:<pair>``).
"""

from __future__ import annotations

import numpy as np

from dalembert import spatial
from dalembert.adapters.exudyn.model import build
from dalembert.contact import FORCE_PREFIX
from dalembert.scene import WORLD

__all__ = ["read_back", "link_accelerations", "loop_forces", "STALE_ACCELERATIONS"]

# Explicit solvers whose accelerations at a step's end are not those of the state they report:
# VelocityVerlet's are f(q_{n+1}, v_{n+1/2}), of the half-step velocity (measured on the double
# pendulum, against the model evaluated at the run's own sampled states: reactions off by 1.4e-3,
# 1.4e-4, 1.4e-5 relative at dt = 1e-2, 1e-3, 1e-4, every other explicit solver within 1e-15). For
# them the link accelerations are evaluated again at every sample (``link_accelerations``).
STALE_ACCELERATIONS = ("velocity-verlet",)


def link_accelerations(p, values, samples, settings):
    """The kinematic tree's link accelerations at the sampled joint states ``values[("__q", "q")]``,
    ``values[("__v", "v")]`` for the sample indices ``samples``, written over ``values[(link, "a")]``:
    on a fresh system, each state is set and its joint accelerations solved from Exudyn's own mass
    matrix and ODE2 right-hand side (``M q'' = f(q, q')``), then the links' acceleration sensors read.
    ``settings``: a callable returning the run's ``exudyn.SimulationSettings`` (the adapter's)."""
    import exudyn as exu

    built = build(p.scene, p.settings)
    mbs, current = built.mbs, exu.ConfigurationType.Current
    console = exu.config.printToConsole
    exu.config.printToConsole = False
    try:
        solver = exu.MainSolverExplicit()
        solver.InitializeSolver(mbs, settings())
        n = solver.GetODE2size()
        for k in samples:
            mbs.systemData.SetODE2Coordinates(list(values[("__q", "q")][k][:n]), configuration=current)
            mbs.systemData.SetODE2Coordinates_t(list(values[("__v", "v")][k][:n]), configuration=current)
            solver.ComputeMassMatrix(mbs)
            solver.ComputeODE2RHS(mbs)
            mass = np.asarray(solver.GetSystemMassMatrix(), dtype=float)[:n, :n]
            rhs = np.asarray(solver.GetSystemResidual(), dtype=float)[:n]
            mbs.systemData.SetODE2Coordinates_tt(list(np.linalg.solve(mass, rhs)), configuration=current)
            for name in built.links:
                values[(name, "a")][k] = np.array(mbs.GetSensorValues(built.sensors[name]["a"]), dtype=float)
        solver.FinalizeSolver(mbs, settings())
    finally:
        exu.config.printToConsole = console


def read_back(p, built, values):
    """The ``Trajectory`` of the sampled sensor ``values`` ((sensor group, quantity) -> samples) of the system
    ``built``, with every joint's and loop's reaction (N, world axes, ON the child or body b) as extras
    ``reaction_force:<name>``."""
    from dalembert.trajectory import BodyStates, JointStates, Trajectory

    scene, times = p.scene, p.times
    n = len(times)

    def series(body, key, width):  # (n, width): stored rows, or the samples read from Python
        v = values[(body, key)]
        return (v if isinstance(v, np.ndarray) else np.vstack(v))[:, :width]

    bodies, R_WB = {}, {}
    for b in scene.bodies:
        R_WE = series(b.name, "R", 9).reshape(n, 3, 3)  # row-major in sensor output
        R_EB = built.X_EB.get(b.name, (None, np.eye(3)))[1]  # a rigid body's E is B
        R_WB[b.name] = R_WE @ R_EB
        finite = np.all(np.isfinite(R_WB[b.name]), axis=(1, 2))
        quat = np.full((n, 4), np.nan)
        quat[finite] = spatial.matrix_to_quat(R_WB[b.name][finite])
        bodies[b.name] = BodyStates(series(b.name, "p", 3), quat, series(b.name, "v", 3),
                                    series(b.name, "w", 3), rotation=R_WB[b.name])
    joints, reactions = {}, {}
    loop_reactions = loop_forces(scene, built, bodies, R_WB, series)
    if built.links:  # minimal coordinates: the tree's own; reactions by Newton's law per link
        q, v = series("__q", "q", len(built.links)), series("__v", "v", len(built.links))
        for i, name in enumerate(built.links):
            joints[name] = JointStates(q[:, i:i + 1], v[:, i:i + 1])
        for name in reversed(built.links):  # children first
            body = scene.body(name)
            f = body.mass * (series(name, "a", 3) - np.asarray(scene.gravity))
            for ld in scene.loads:
                if ld.body == name and ld.kind == "force":
                    f -= spatial.load_to_world(ld, R_WB[name])
            for child in built.links:
                if scene.joint(child).parent == name:
                    f += reactions[child]
            for lp in scene.loops:  # the loop forces on this link (equal and opposite on a and b)
                if name in (lp.body_a, lp.body_b):
                    f -= loop_reactions[lp.name] if lp.body_b == name else -loop_reactions[lp.name]
            for sp in scene.springs:  # Exudyn's spring force: its Force is the one on a's point
                if name in (sp.body_a, sp.body_b):
                    f_a = series(f"__spring:{sp.name}", "f", 3)
                    f -= f_a if sp.body_a == name else -f_a
            reactions[name] = f
    for child, R0 in built.redundant_joints.items():  # redundant coordinates: from the bodies
        j = scene.joint(child)
        R_WP = np.eye(3) if j.parent == WORLD else R_WB[j.parent]
        zero = np.zeros((n, 3))
        P = None if j.parent == WORLD else bodies[j.parent]
        C = bodies[child]
        joints[child] = spatial.joint_coordinates(
            j, R_WP, R_WB[child], zero if P is None else P.angular_velocity, C.angular_velocity,
            p_WP=zero if P is None else P.position, p_WC=C.position,
            v_WP_W=zero if P is None else P.velocity, v_WC_W=C.velocity)
        f_local = series(f"__joint:{child}", "f", 3)
        reactions[child] = -np.einsum("...ij,...j->...i", R_WP @ R0, f_local)  # ON the child, world axes
    joints = {k: v if isinstance(v, JointStates) else JointStates(*v) for k, v in joints.items()}
    extras = {f"reaction_force:{c}": f for c, f in {**reactions, **loop_reactions}.items()}
    # each pair's connector Force, the force on its marker 0: the pair's subject (``contact.add_contacts``)
    extras.update({FORCE_PREFIX + pair.name: series(f"__contact:{pair.name}", "f", 3) for pair in scene.contacts})
    return Trajectory(times, bodies, joints, extras)


def loop_forces(scene, built, bodies, R_WB, series):
    """Each loop's force ON its body b (N, world), (n, 3) per loop name, from its constraint object's
    sensor: an ObjectJointGeneric's ForceLocal is the force on marker 0's side (body a) in marker 0's
    frame Ja (as a tree joint's, ``model``), so ON b it is ``-R_WB_a R_BJa ForceLocal``; an
    ObjectConnectorDistance's Force is a scalar, the tension, pulling b towards a along the line
    between the points (both checked against the reference's multipliers, tests/test_exudyn_loops.py)."""
    def point(body, p):  # the loop point in world, (n, 3)
        if body == WORLD:
            return np.broadcast_to(np.asarray(p, dtype=float), bodies[next(iter(bodies))].position.shape)
        return bodies[body].position + R_WB[body] @ np.asarray(p, dtype=float)

    out = {}
    for lp in scene.loops:
        f = series(f"__loop:{lp.name}", "f", 1 if lp.kind == "distance" else 3)
        if lp.kind == "distance":
            d_ba = point(lp.body_a, lp.point_a) - point(lp.body_b, lp.point_b)
            out[lp.name] = f * d_ba / np.linalg.norm(d_ba, axis=-1, keepdims=True)
        else:
            R_WJa = (np.eye(3) if lp.body_a == WORLD else R_WB[lp.body_a]) @ built.loops[lp.name]
            out[lp.name] = -np.einsum("...ij,...j->...i", R_WJa, f)
    return out
